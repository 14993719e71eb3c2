"""One sample of the compiled closed-loop inverse dynamics, for one rank decision.

A :class:`PhasePlan` holds a rank decision (the kept rows ``I``, square and independent since
the drivers fix every degree of freedom, and the rows left out ``R``) and builds one CasADi
Function per sample,

    step(x, h, w, wd, wdd, feet, mask) -> (x, lam, wrench, frames, checks),  x = [q; v; v_dot]

evaluated over the samples of a phase with ``mapaccum`` (each sample starts from the one
before; in blocks, :func:`blocks`), or, interpreted past :data:`EXPAND_AFTER` samples, over
samples apart (:meth:`PhasePlan.evaluate`). One sample:

1. positions: ``q_p = q (+) (h v + h^2/2 v_dot)`` predicted from the sample before (or known:
   a guided model's, an input ``known``), then a few Newton steps (:data:`NEWTON_STEPS`) on
   ``phi_I = 0`` (none from known positions) with the Jacobian of ``q_p`` (one
   factorisation), each step applied with the retraction;
2. ``J = Phi_v[I]`` at the positions found, factorised once (:class:`StaticLU`: pivots chosen
   once for the rows (see :func:`plan_for`), the elimination written out as straight-line
   code, about 1 400 multiply-adds for the walking hexapod where a sparse QR of the same
   matrix takes some 25 000; the checks below catch pivots gone stale): ``v = J^-1 nu_I``,
   ``v_dot = J^-1 gamma_I`` (or both known: a guided model's twin's), ``lam_I = J^-T (Q - M
   v_dot)``;
3. the redundancy policy (when rows are left out): every multiplier vector that balances the
   bodies is ``lam0 + N z`` with ``N = [e_R - L_I J^-T Phi_R^T]``; ``z`` minimises the policy's
   ``|A (lam0 + N z) + b|^2`` (the least joint wrenches, each foot's block over the square root
   of its weight, or the least actuator efforts; see :mod:`hexapod.algorithms.ground`), with
   the entries of ``z`` of idle rows (``mask``: feet that carry nothing) held at zero; solved by
   the normal equations, scaled, and with feet on the ground refined once (corrected
   semi-normal equations);
4. the joint wrenches in the joint frames;
5. ``checks``: the largest scaled position residual, the relative residuals of the velocity and
   acceleration constraints on the kept rows and on the rows left out, the size of the rows
   the decision has neither kept nor left out (those of feet in swing: zero), and an estimate
   (from above) of the smallest singular value of the equilibrated kept rows. A sample whose
   checks fail is redone by the exact path (:mod:`hexapod.algorithms.phase_inverse`).

The model's Functions (``phi``, ``Phi_v``, ``gamma``...) come from
:class:`hexapod.algorithms.step_terms.StepTerms`, built once per model; a plan adds only the
linear algebra of its row set (some tens of thousands of operations), so a new rank decision
costs little to build or compile.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod._support.across_samples import across_samples, in_groups
from hexapod._support.fastcall import InPlaceFunction
from hexapod.algorithms.static_lu import StaticLU
from hexapod.algorithms.step import sparse_dm
from hexapod.algorithms.step_terms import StepTerms, sx_function
from hexapod.model.data import kept
from hexapod.model.model import Data

#: Newton steps on the positions per sample, from the positions predicted by the sample before:
#: the first count while the samples converge in it (two reach round-off on the walking hexapod
#: with samples up to 2 ms apart: a scaled residual of 3e-14 against the 1e-13 asked, 1e-15 at
#: 1 ms), the next ones from the first sample that did not on (samples a hundredth of a second
#: apart; each step contracts the error by a factor of about 100 there).
NEWTON_STEPS = (2, 3, 6)
#: Samples after which a plan, when it is not compiled, evaluates its step expanded into one
#: SX Function (one loop of CasADi's virtual machine instead of an MX graph calling some
#: thirty Functions) and its samples apart, :data:`ACROSS` at a time, by the MX virtual
#: machine (:mod:`hexapod._support.across_samples`): the walking robot's samples cost some
#: 230 us instead of 850. Expanding and writing the step over samples cost some 0.3 to 0.6 s
#: a plan, what 500 to 1,000 samples gain, so a plan does it once the samples it has evaluated
#: and those it is asked for reach this.
EXPAND_AFTER = 1_000
#: Samples evaluated together once a plan evaluates samples apart (see
#: :meth:`PhasePlan.evaluate`): the width of one row of the MX virtual machine's work
#: (:mod:`hexapod._support.across_samples`); wider rows leave the processor's caches.
ACROSS = 32
#: The most time between two samples of the chain that starts the others when samples are
#: evaluated apart (s): the walking robot's positions converge to round-off from 4 ms in the
#: next count of Newton steps (3: a scaled residual of 2e-14), and from 2 ms, half of it, in
#: the first (2: 3e-14).
CHAIN_SPACING = 4e-3
#: The most samples one evaluation takes (see :func:`blocks`): the MX graph of the step mapped
#: over a block holds one call per sample, so that a block of 64 costs what one of 500 does a
#: sample to evaluate, and an eighth to build.
BLOCK = 64
#: ``checks`` entries, in order.
CHECKS = ("position", "kept_velocity", "kept_acceleration", "left_velocity",
          "left_acceleration", "outside", "sigma")


class PhasePlan:
    """The compiled inverse dynamics of one sample for one rank decision.

    Parameters
    ----------
    terms : StepTerms
        The model's Functions.
    kept, left_out : sequence of int
        The rows ``I`` (``len(kept) == n_v``) and the redundant rows ``R``.
    lu : StaticLU
        The factorisation's pattern and pivots for ``Phi_v[kept]`` (see :func:`plan_for`).
    to_c : bool
        Compile the plan's own SX Functions to C (kept in the execution setting's cache).
    motion : bool
        The motion alone (steps 1, 2 without the multipliers, and 5): a kinematics run, such as
        a guided model's guides' (:func:`hexapod.algorithms.phase_inverse.phase_motion`).
    """

    def __init__(self, terms: StepTerms, kept, left_out, lu: StaticLU, to_c: bool = False,
                 motion: bool = False):
        self.terms, self.model, self.motion = terms, terms.model, motion
        self.kept = np.asarray(kept, dtype=int)
        self.left_out = np.asarray(left_out, dtype=int)
        self.lu, self.to_c = lu, to_c
        position = {(int(r), int(c)): k for k, (r, c) in enumerate(
            zip(terms.pattern_rows, terms.pattern_columns, strict=True))}
        self._J_entries = [position[int(self.kept[r]), int(c)]
                           for r, c in zip(lu.rows, lu.columns, strict=True)]
        left = set(self.left_out.tolist())
        self._left_entries = [k for k, r in enumerate(terms.pattern_rows) if int(r) in left]
        self._build_linear_algebra()

    # ---------------------------------------------------------------- the plan's SX Functions

    def _sx(self, name, inputs, outputs):
        return sx_function(name, inputs, outputs, self.to_c)

    def _build_linear_algebra(self) -> None:
        """The plan's own Functions: the factorisation of ``Phi_v[I]`` and its solves (shared by
        the model's plans of the same kept rows and pivots, :meth:`_shared`), the
        coefficients of the left-out rows, the policy's small solve and the checks."""
        lu, model, terms = self.lu, self.model, self.terms
        n_v, n_c = model.n_v, model.n_c
        Phi = ca.SX.sym("Phi", terms.pattern.nnz())
        packed = ca.SX.sym("F", lu.nnz)
        b, y = ca.SX.sym("b", n_c), ca.SX.sym("y", n_v)
        self.factor = self._shared("factor", lambda: self._sx(
            "phase_lu", [Phi], [lu.factor(Phi[self._J_entries])]))
        # the transposed solve, formed once and called (inlined) where needed
        solve_t = self._shared("transposed solve", lambda: ca.Function(
            "solve_t", [packed, y], [lu.solve(packed, y, True)]))
        self.solve = self._shared("solve", lambda: self._sx(
            "phase_solve", [packed, b], [lu.solve(packed, b[self.kept])]))
        if not self.motion:
            self._build_multipliers(Phi, packed, solve_t)
        self._build_checks()

    def _shared(self, name: str, build):
        """``build()``, once per model for the kept rows, the pivots and the compiling of this
        plan (plans that leave out other rows, or that a later run decided again, share the
        factorisation's Functions: the walking robot's seven plans of a stride hold three)."""
        key = ("phase plan part", name, self.kept.tobytes(), self.lu.row_order.tobytes(),
               self.lu.column_order.tobytes(), self.to_c)
        return self.model.built_once(key, lambda m: build())

    def _build_multipliers(self, Phi, packed, solve_t) -> None:
        """The multipliers of the kept rows and the coefficients of the left-out ones."""
        model, terms = self.model, self.terms
        n_v, n_c = model.n_v, model.n_c
        Q, a = ca.SX.sym("Q", n_v), ca.SX.sym("a", n_v)

        def multipliers() -> ca.Function:
            lam = ca.SX(n_c, 1)
            lam[self.kept.tolist()] = solve_t(
                packed, Q - ca.mtimes(sparse_dm(model.mass.dense()), a))
            return self._sx("phase_multipliers", [packed, Q, a], [lam])
        self.multipliers = self._shared("multipliers", multipliers)
        if self.left_out.size:
            place = {int(r): i for i, r in enumerate(self.left_out)}
            Phi_R = ca.SX(self.left_out.size, n_v)
            for k in self._left_entries:
                Phi_R[place[int(terms.pattern_rows[k])], int(terms.pattern_columns[k])] = Phi[k]
            C = ca.horzcat(*[solve_t(packed, Phi_R[i, :].T)
                             for i in range(self.left_out.size)])
            N = ca.SX(n_c, self.left_out.size)
            N[self.kept.tolist(), :] = -C
            for i, row in enumerate(self.left_out):
                N[int(row), i] = 1.0
            # its entries that are zero whatever the state dropped (half of them): the policy
            # is written for what is left (:meth:`StepTerms.policy`)
            self.null_space = self._sx("phase_null_space", [packed, Phi], [ca.sparsify(N)])

    def _build_checks(self) -> None:
        model = self.model
        n_v, n_c = model.n_v, model.n_c
        self._probe = np.zeros(n_c)
        probe = np.random.default_rng(0).standard_normal(n_v)
        self._probe[self.kept] = probe / np.linalg.norm(probe)
        x = ca.SX.sym("x", n_v)
        velocity, acceleration = ca.SX.sym("velocity", n_c), ca.SX.sym("acceleration", n_c)
        position, phi = ca.SX.sym("position"), ca.SX.sym("phi", n_c)
        Phi = ca.SX.sym("Phi", self.terms.pattern.nnz())
        root_mass = sparse_dm(np.linalg.inv(model.mass_inv_sqrt.dense()))
        I, R = self.kept.tolist(), self.left_out.tolist()
        outside = sorted(set(range(n_c)) - set(I) - set(R))  # feet in swing: zero rows
        # the size of those rows, |Phi_v row|_1 + |phi|: of them alone (of every row it was a
        # fifth of the twin's residuals, for the nine rows of three feet in swing)
        presence = (ca.sum2(ca.fabs(ca.SX(self.terms.pattern, Phi)[outside, :]))
                    + ca.fabs(phi[outside]))

        def largest(r, rows_):
            return ca.mmax(r[rows_]) if rows_ else ca.SX(0.0)
        checks = ca.vertcat(position, largest(velocity, I), largest(acceleration, I),
                            largest(velocity, R), largest(acceleration, R),
                            ca.mmax(presence) if outside else ca.SX(0.0),
                            1.0 / ca.norm_2(ca.mtimes(root_mass, x)))
        self.checks = self._sx("phase_checks",
                               [x, velocity, acceleration, position, Phi, phi], [checks])

    # ---------------------------------------------------------------- one sample

    def step(self, newton: int = NEWTON_STEPS[0], expanded: bool = False,
             known: bool = False) -> ca.Function:
        """The Function of one sample with ``newton`` Newton steps (built once per count), or
        the same expanded into one SX Function (see :data:`EXPAND_AFTER`); ``known``: a last
        input ``known``, the motion ``[q; v; v_dot]`` known at the sample (a guided model's
        twin's, from its guides' kinematics): Newton's steps start from its positions instead
        of those predicted from the sample before, and a plan with forces takes its velocities
        and accelerations as they are (the constraints' velocity residuals still checked),
        leaving out the acceleration constraints' right-hand side and two solves, a fifth of
        the walking robot's sample."""
        cache = self.__dict__.setdefault("_steps", {})
        key = (newton, expanded, known)
        if key not in cache:
            cache[key] = (self.step(newton, False, known).expand() if expanded else
                          self._build_step(newton, known))
        return cache[key]

    @property
    def function(self) -> ca.Function:
        return self.step()

    def _build_step(self, newton: int, known: bool) -> ca.Function:
        model, terms = self.model, self.terms
        n_q, n_v, n_w = model.n_q, model.n_v, model.n_w
        x = ca.MX.sym("x", n_q + 2 * n_v)
        h, w, wd, wdd = ca.MX.sym("h"), *(ca.MX.sym(n, n_w) for n in ("w", "wd", "wdd"))
        feet = ca.MX.sym("feet", len(model.contacts))
        mask = ca.MX.sym("mask", self.left_out.size)
        inputs, names = [x, h, w, wd, wdd, feet, mask], ["x", "h", "w", "wd", "wdd", "feet",
                                                          "mask"]
        if known:
            state = ca.MX.sym("known", n_q + 2 * n_v)
            q = state[:n_q]
            inputs, names = [*inputs, state], [*names, "known"]
        else:
            q = terms.predict(x[:n_q], x[n_q:n_q + n_v], x[n_q + n_v:], h)
        if newton:
            phi, Phi = terms.jacobian(q, w)
            F = self.factor(Phi)
        for step in range(newton):
            if step:
                phi = terms.residual(q, w)
            q = terms.correct(q, self.solve(F, phi))
        phi, Phi = terms.jacobian(q, w)
        F = self.factor(Phi)
        nu = terms.rates(q, w, wd)
        d = terms.row_norms(Phi)  # the rows' scales at this sample
        if known and not self.motion:
            # the guides' kinematics solved this sample's velocities and accelerations on the
            # same bodies already (a twin's laws are exact at its samples): its dynamics alone,
            # the velocities checked against these rows
            v, a = state[n_q:n_q + n_v], state[n_q + n_v:]
            Q, offset = terms.loads(q, v, w)
            velocity, acceleration, position = terms.velocity_residuals(Phi, phi, v, nu, d)
        else:
            v = self.solve(F, nu)
            if self.motion:
                gamma = terms.gamma(q, v, w, wd, wdd)
            else:
                gamma, Q, offset = terms.forces(q, v, w, wd, wdd)
            a = self.solve(F, gamma)
            velocity, acceleration, position = terms.residuals(Phi, phi, v, nu, a, gamma, d)
        checks = self.checks(self.solve(F, d * ca.DM(self._probe)), velocity,
                             acceleration, position, Phi, phi)
        if self.motion:
            return ca.Function("phase_motion_step", inputs,
                               [ca.densify(ca.vertcat(q, v, a)), ca.densify(checks)],
                               names, ["x_next", "checks"])
        lam = self.multipliers(F, Q, a)
        W, frames = terms.wrench_terms(q, w, Phi)  # once, for the policy and the wrenches
        if self.left_out.size:
            lam = self._policy(W, F, Phi, offset, lam, feet, mask, w)
        wrench = terms.joint_wrenches(W, frames, lam, offset, w)
        outputs = [ca.densify(y) for y in (ca.vertcat(q, v, a), lam, wrench, frames, checks)]
        return ca.Function("phase_step", inputs, outputs, names,
                           ["x_next", "lam", "wrench", "frames", "checks"])

    # ---------------------------------------------------------------- evaluation

    def _evaluator(self, data: Data, n: int, newton: int, expanded: bool, known: bool):
        """The step mapped over ``n`` samples (each from the one before), built once per plan,
        and its buffer, made once per workspace ``data``."""
        cache = self.__dict__.setdefault("_mapped", {})
        key = (n, newton, expanded, known)
        if key not in cache:
            cache[key] = self.step(newton, expanded, known).mapaccum("phase_steps", n)
        return kept(data, ("phase-buffer", id(self), *key), lambda: InPlaceFunction(cache[key]))

    def _across(self, data: Data, newton: int, known: bool):
        """The expanded step over :data:`ACROSS` independent samples (each from its own
        state; :func:`~hexapod._support.across_samples.across_samples`), built once per plan,
        and its buffer, made once per workspace ``data``."""
        cache = self.__dict__.setdefault("_mapped", {})
        key = ("across", newton, known)
        if key not in cache:
            cache[key] = across_samples(self.step(newton, True, known), ACROSS)
        return kept(data, ("phase-buffer", id(self), *key), lambda: InPlaceFunction(cache[key]))

    def evaluate(self, data: Data, x0, h, w, wd, wdd, feet, mask, newton: int = NEWTON_STEPS[0],
                 state_known=None):
        """The samples of one run: ``x0`` the state ``[q; v; v_dot]`` of the sample before,
        ``h`` (N,) the time steps, laws and per-foot inputs (rows x N), and ``state_known``
        (N, n_q + 2 n_v) the motion ``[q; v; v_dot]`` at the samples when it is known (its
        positions are Newton's start; a plan with forces takes its velocities and
        accelerations as they are, see :meth:`step`). Returns arrays with the
        samples first: states (N, n_q + 2 n_v), multipliers (N, n_c), wrenches (N, J, 6) in
        the joint frames, the joint frames' rotations (N, J, 9, column-major) and the checks
        (N, 6), NaN from the block of samples where the evaluation fails on; a motion plan's
        multipliers, wrenches and rotations are empty (N, 0, ...).

        Compiled, or for a plan's first :data:`EXPAND_AFTER` samples, each sample starts from
        the one before, in blocks (:func:`blocks`). Past that, interpreted, the samples are
        evaluated :data:`ACROSS` at a time (:meth:`_across`): from known positions each sample
        alone; else a chain of every few samples (:func:`chain_stride`, with the next count
        of Newton steps) starts the others, each from the nearest sample of the chain, at
        most half the chain's spacing away. Every sample is checked as before; a sample that
        fails is redone by the caller, with those after it."""
        model, n = self.model, h.size
        done = self.__dict__.get("_evaluated", 0)
        self._evaluated = done + n
        expanded = not self.to_c and done + n >= EXPAND_AFTER
        # CasADi's column-major (rows x n) is NumPy's C-order (n x rows)
        mapped = [np.ascontiguousarray(np.reshape(h, (n, 1)), dtype=float)]
        mapped += [np.ascontiguousarray(np.asarray(x, dtype=float).T)
                   for x in (w, wd, wdd, feet, mask)]
        known = state_known is not None
        if known:
            mapped.append(np.ascontiguousarray(state_known, dtype=float))
        J, n_c = (0, 0) if self.motion else (len(model.joints), model.n_c)
        outputs = [np.empty((n, model.n_q + 2 * model.n_v)), np.empty((n, n_c)),
                   np.empty((n, J, 6)), np.empty((n, J, 9)), np.empty((n, len(CHECKS)))]
        x0 = np.ascontiguousarray(x0, dtype=float)
        if not expanded:
            self._chain(data, x0, mapped, outputs, newton, False, known)
            return outputs
        if known:  # every sample from its own known positions
            self._apart(data, np.broadcast_to(x0, (n, x0.size)), mapped, outputs, newton,
                        known)
            return outputs
        m = chain_stride(h)
        if m == 1:
            self._chain(data, x0, mapped, outputs, newton, True, known)
            return outputs
        chain = np.arange(0, n, m)
        # the chain, each from the one before over its spacing ...
        times = np.cumsum(h)
        on = [mapped[0][chain].copy()]
        on[0][:, 0] = np.diff(times[chain], prepend=0.0)
        on += [y[chain] for y in mapped[1:]]
        results = [np.empty((chain.size, *y.shape[1:])) for y in outputs]
        more = min((steps for steps in NEWTON_STEPS if steps > newton), default=newton)
        self._chain(data, x0, on, results, more, True, known)
        for y, r in zip(outputs, results, strict=True):
            y[chain] = r
        # ... then the others, each from the nearest of the chain
        rest = np.setdiff1d(np.arange(n), chain)
        nearest = chain[np.minimum((rest + m // 2) // m, chain.size - 1)]
        off = [np.ascontiguousarray((times[rest] - times[nearest])[:, None])]
        off += [y[rest] for y in mapped[1:]]
        found = [np.empty((rest.size, *y.shape[1:])) for y in outputs]
        self._apart(data, outputs[0][nearest], off, found, newton, known)
        for y, r in zip(outputs, found, strict=True):
            y[rest] = r
        return outputs

    def _chain(self, data: Data, x0, mapped, outputs, newton: int, expanded: bool,
               known: bool) -> None:
        """The samples of ``mapped`` each from the one before (the first from ``x0``), in
        blocks, into ``outputs``; NaN from a block that fails on."""
        x, start = x0, 0
        for size in blocks(mapped[0].shape[0]):
            span = slice(start, start + size)
            written = [outputs[0][span], outputs[4][span]] if self.motion else [
                y[span] for y in outputs]
            try:
                self._evaluator(data, size, newton, expanded, known)(
                    [x, *(y[span] for y in mapped)], written)
            except RuntimeError:  # a singular solve: the samples are redone exactly
                for y in outputs:
                    y[start:] = np.nan
                break
            x, start = outputs[0][start + size - 1], start + size

    def _apart(self, data: Data, states, mapped, outputs, newton: int, known: bool) -> None:
        """The samples of ``mapped``, sample ``i`` from ``states[i]`` (each alone),
        :data:`ACROSS` at a time, into ``outputs`` (the last group filled up with copies of
        its last sample)."""
        written = [0, 4] if self.motion else range(len(outputs))
        in_groups(self._across(data, newton, known), [states, *mapped],
                  [outputs[i] for i in written], ACROSS)

    def _policy(self, W, F, Phi, offset, lam0, feet, mask, w):
        """``lam0 + N z`` of least policy objective, ``z`` zero where ``mask`` is."""
        policy = self.terms.policy(self.null_space.sparsity_out(0))
        return policy(W, offset, feet, lam0, self.null_space(F, Phi), mask, w)


def chain_stride(h: np.ndarray) -> int:
    """Every how many samples of a run (time steps ``h``) the chain takes one, when samples
    are evaluated apart (:meth:`PhasePlan.evaluate`): the most of the run's typical spacing
    within :data:`CHAIN_SPACING` (1: the chain is the run)."""
    typical = float(np.median(h[1:])) if h.size > 1 else 0.0
    return max(1, int(CHAIN_SPACING / typical * (1 + 1e-9))) if typical > 0 else 1


def blocks(n: int) -> list[int]:
    """The sizes of the blocks ``n`` samples are evaluated in: :data:`BLOCK` samples, then the
    rest's binary digits (100 -> 64, 32, 4), so that a plan maps its step over a few sizes
    only, whatever the runs' lengths (building the step mapped over ``n`` samples costs in
    proportion to ``n``: some 0.25 ms a sample for the walking robot)."""
    sizes = [BLOCK] * (n // BLOCK)
    rest = n % BLOCK
    return sizes + [1 << bit for bit in reversed(range(rest.bit_length())) if rest >> bit & 1]


def plan_for(terms: StepTerms, kept, left_out, make, generation: int = 0,
             to_c: bool = False, motion: bool = False) -> PhasePlan:
    """The :class:`PhasePlan` of a rank decision, built once per model and ``generation``:
    ``make()`` gives the factorisation's pivots (:class:`StaticLU`) when it is built. A later
    decision with the same rows reuses it, whatever the positions it was taken at (its pivots
    are checked at every sample); a new ``generation`` takes new pivots. The pivots are
    ``make()``'s: those of the model's reference positions where they serve, the same in every
    run and process (and so is the plan's compiled code), else those of the first decision of
    these rows the model saw, so that results may then differ from run to run by round-off
    (never more: every sample is checked against the constraints). ``motion``: the plan of
    the motion alone (see :class:`PhasePlan`)."""
    key = ("phase-plan", tuple(int(r) for r in kept), tuple(int(r) for r in left_out),
           generation, to_c, motion)
    return terms.model.built_once(key, lambda m: PhasePlan(terms, kept, left_out, make(), to_c,
                                                           motion))
