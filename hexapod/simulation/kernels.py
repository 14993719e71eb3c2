"""Compiled kernels of the integrators: the state derivatives ``(q_dot, v_dot)``, and the
projection of a state onto the constraints, each one CasADi call.

Integrators evaluate the right-hand side many times per step and need only the accelerations
there, not multipliers by the redundancy policy. :class:`CompiledRates` builds, once per model
and row set, a single CasADi ``MX`` Function

    rates(q, v, w, wd, wdd, alpha) -> (q_dot, v_dot, lam, residual)

that forms ``Phi_v, gamma, Q`` and solves the equilibrated saddle-point system

    [[I, W^T], [W, 0]] [y; mu] = [M^-1/2 Q; D^-1 gamma],   W = D^-1 Phi_v M^-1/2,
    v_dot = M^-1/2 y

with a sparse QR factorisation (CasADi's ``qr`` linear solver, symbolic analysis done once), or,
compiled to C and in the saddle-point form, an LU with pivots chosen at the state where the
kernel is built (:func:`pivots_near`), on the independent rows chosen by the rank decision at a
reference state. Equilibration makes the
rows dimensionless and of unit length, so that the conditioning is the mechanism's, not its
units'. The matrix and every node of the Function are as sparse as ``Phi_v`` and the
factorisation follows the body-joint graph, so a call costs time linear in the number of
bodies (:mod:`hexapod.algorithms.saddle` builds them and says how). ``alpha`` is Baumgarte's
rate (``alpha = beta``, 0 to switch it off).

The fixed row set is what makes one compiled Function possible, so every call also returns the
``residual``, ``max |D^-1 (Phi_v v_dot - gamma)|`` relative to the size of the solution, of the
kept rows and of the rows left out: a singular configuration, or a change of rank, shows there,
and :meth:`CompiledRates.__call__` then returns None so that the caller falls back on the exact,
rank-deciding solve of :func:`hexapod.algorithms.dynamics.forward_dynamics`.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod._support.compiled import compiled_graph
from hexapod._support.execution import current
from hexapod._support.fastcall import FastFunction
from hexapod._support.recent import Recent
from hexapod.algorithms.ground import ground_policy
from hexapod.algorithms.static_lu import StaticLU
from hexapod.algorithms.step import (
    KeptFactors,
    equilibrated,
    kept_pivots,
    kept_values,
    mass_factors,
    newton,
    retract,
    solve_kept,
)
from hexapod.model.data import kept
from hexapod.model.model import Model

#: relative residual above which a compiled solve is refused (the rank changed, or a
#: configuration is singular); far above round-off, far below any integrator's tolerance
RESIDUAL_TOLERANCE = 1e-9
#: relative residual of the rows left out as redundant above which a compiled solve is refused.
#: Redundancy holds exactly on the constraint manifold only: at the stage states of a step,
#: off it by the truncation error, left-out rows (Bricard's mechanism) disagree with the kept
#: ones by about that error and are rightly ignored (the step's end is projected); a row that
#: has become independent (leaving a singular pose) disagrees by far more
REDUNDANT_TOLERANCE = 1e-3
#: relative residual of the rows left out above which the policy's multipliers are refused:
#: the exact solve's default (``consistency_tol`` of
#: :func:`~hexapod.algorithms.dynamics.forward_dynamics`), which then says which rows disagree
CONSISTENCY_TOLERANCE = 1e-6
#: how many states' pivots a model keeps (:func:`pivots_near`)
RECENT_PIVOTS = 8


class CompiledRates:
    """``(q_dot, v_dot)`` at a state in one call (see the module's description).

    Parameters
    ----------
    model : Model
    rows : ndarray of int
        The independent constraint rows to solve with (indices into ``model.rows``); the other
        rows are redundant and only checked.
    reference : (ndarray, ndarray), optional
        Positions and law values ``(q, w)`` near the states to come: compiled to C, the
        solve is then an LU with pivots chosen there (:func:`pivots_near`).
    """

    def __init__(self, model: Model, rows: np.ndarray, reference: tuple | None = None,
                 left_out: np.ndarray = ()):
        self.model = model
        self.rows = np.asarray(rows, dtype=int)
        self.left_out = np.asarray(left_out, dtype=int)
        # the Function once per model, row set, execution and pivots; the buffers are this
        # object's
        to_c = current().compiled
        lu = pivots_near(model, self.rows, reference) if to_c else None
        self._key = ("rates", tuple(self.rows.tolist()), to_c, pivot_key(lu))
        self.function = model.built_once(self._key,
                                         lambda m: evaluated_as_set(self._build(lu), to_c))
        self._fast = FastFunction(self.function)
        self._args = [n for n in ("q", "v", "w", "wd", "wdd") if n in ("q", "v") or model.n_w]
        self._policy = None  # the multipliers by the redundancy policy, built when first asked

    def _build(self, lu: StaticLU | None) -> ca.Function:
        model, rows = self.model, self.rows
        symbols = {"q": ca.MX.sym("q", model.n_q), "v": ca.MX.sym("v", model.n_v),
                   "w": ca.MX.sym("w", model.n_w), "wd": ca.MX.sym("wd", model.n_w),
                   "wdd": ca.MX.sym("wdd", model.n_w)}
        alpha = ca.MX.sym("alpha")
        args = [n for n in ("q", "v", "w", "wd", "wdd") if n in ("q", "v") or model.n_w]

        def call(function):
            return function(*[symbols[n] for n in function.name_in()])

        v = symbols["v"]
        Phi_v, gamma, Q = call(model.dynamics_terms)
        q_dot = call(model.qdot)
        m_inv_sqrt, _ = mass_factors(model)
        y0 = ca.mtimes(m_inv_sqrt, Q)
        if model.n_c == 0:
            v_dot = ca.mtimes(m_inv_sqrt, y0)
            lam = ca.MX(0, 1)
            residual = ca.MX.zeros(2)
        else:
            # Baumgarte: Phi_v v_dot = gamma - 2 alpha (Phi_v v - nu) - alpha^2 phi, its terms
            # evaluated only when alpha is not 0 (phi alone is a tenth of the call's cost)
            drift = (2 * alpha * (ca.mtimes(Phi_v, v) - call(model.nu))
                     + alpha**2 * call(model.phi))
            gamma = gamma - ca.if_else(alpha == 0, ca.MX.zeros(model.n_c), drift, True)
            W_all, d_all, zero = equilibrated(Phi_v, m_inv_sqrt)
            y, mu = solve_kept(W_all, d_all, zero, rows.tolist(), y0, gamma, lu)
            # the kept rows' multipliers (lambda_I = mu / d_I); the others are zero
            lam = ca.MX(model.n_c, 1)
            lam[rows.tolist()] = mu / d_all[rows.tolist()]
            v_dot = ca.mtimes(m_inv_sqrt, y)
            scaled = ca.fabs(ca.mtimes(Phi_v, v_dot) - gamma) / d_all
            size = ca.norm_inf(y) + ca.norm_inf(y0) + 1e-300
            kept = set(rows.tolist())
            others = [i for i in range(model.n_c) if i not in kept]
            residual = ca.vertcat(
                ca.mmax(scaled[rows.tolist()]) / size,
                ca.mmax(scaled[others]) / size if others else ca.MX(0.0))
        inputs = [symbols[n] for n in args] + [alpha]
        return ca.Function("rates", inputs, [q_dot, v_dot, lam, residual], args + ["alpha"],
                           ["q_dot", "v_dot", "lam", "residual"])

    def dynamics(self, t: float, q: np.ndarray,
                 v: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """``(v_dot, lam)`` at ``(t, q, v)``, the multipliers by the redundancy policy
        (:func:`~hexapod.algorithms.dynamics.forward_dynamics`'s), in one kernel call, or None
        where this kernel cannot give them as the exact solve would: those of :meth:`solve`
        when every row is kept; with rows left out and feet on the ground, the ground-force
        policy's (:class:`PolicyMultipliers`), refused (None) where a row left out has left the
        span of the kept ones by more than the rank tolerance, or the rows disagree by more
        than the exact solve allows. A mechanism without feet keeps the exact solve's
        least-wrench choice."""
        if self.complete:
            solution = self.solve(t, q, v)
            return None if solution is None else (solution[1], solution[2])
        policy = self.policy
        return None if policy is None else policy(t, q, v)

    @property
    def policy(self) -> PolicyMultipliers | None:
        """The ground-force policy's kernel of this decision, where :meth:`dynamics` takes the
        multipliers from it (rows left out and feet on the ground), else None."""
        if self.complete or not (self.left_out.size and self.model.contacts):
            return None  # every row kept; no redundant rows; or solve_saddle's least wrench
        if self._policy is None:
            self._policy = policy_multipliers(self.model, self.rows, self.left_out)
        return self._policy

    def stages(self, A: np.ndarray, c: np.ndarray, t: float, h: float, y0: np.ndarray,
               f0: np.ndarray, left_out: float = REDUNDANT_TOLERANCE, until: float = np.inf,
               weights: np.ndarray | None = None, tolerances: tuple | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The stages after the first of an explicit Runge-Kutta step ``h`` from ``(t, y0)``
        (``f0`` its rate there; ``A``, ``c`` the tableau), as rows, in one call of a Function
        that evaluates this kernel once per stage (:class:`CompiledStages`): the same numbers
        as the stages called one by one, without their Python overhead; with the stages'
        combinations ``weights @ K`` (``K`` every stage, ``f0`` first: the propagated
        solution's, ``y1 = y0 + h`` times the first, and the error estimate's, formed in the
        same call), as rows (empty without ``weights``), and the error test's sums of those
        after the first (:func:`weighted_squares` at ``y0, y1`` with ``tolerances``, the
        absolute tolerances' vector and the relative one; by default 1 and 0, the plain sums
        of squares). None when a
        stage's solve would be refused (see :meth:`solve`): the caller then takes its stages
        one by one, each refused one by the exact solve. The laws are read at the stages'
        times, none later than ``until`` (a step that ends on a break of the laws reads them
        before it)."""
        weights = np.zeros((0, c.size)) if weights is None else np.asarray(weights, dtype=float)
        key = (A.tobytes(), c.tobytes(), weights.tobytes())
        stages = self.__dict__.setdefault("_stages", {})
        if key not in stages:
            stages[key] = CompiledStages(self, A, c, weights)
        return stages[key](t, h, y0, f0, left_out, until, tolerances)

    @property
    def complete(self) -> bool:
        """True when every row is solved with (none redundant): the multipliers are then
        unique, and those of the compiled solve are the policy's."""
        return self.rows.size == self.model.n_c

    def __call__(self, t: float, q: np.ndarray, v: np.ndarray, alpha: float = 0.0,
                 left_out: float = REDUNDANT_TOLERANCE) -> tuple[np.ndarray, np.ndarray] | None:
        """``(q_dot, v_dot)``, or None (see :meth:`solve`)."""
        solution = self.solve(t, q, v, alpha, left_out)
        return None if solution is None else solution[:2]

    def solve(self, t: float, q: np.ndarray, v: np.ndarray, alpha: float = 0.0,
              left_out: float = REDUNDANT_TOLERANCE
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """``(q_dot, v_dot, lam)`` at ``(t, q, v)``, or None when the compiled solve cannot be
        trusted there (non-finite, or the rows it solves with no longer span the constraints:
        the rows left out violated by more than ``left_out``, relative). ``lam`` holds the
        kept rows' multipliers, zero on the others."""
        values = {"q": q, "v": v}
        if self.model.n_w:
            values["w"], values["wd"], values["wdd"] = self.model.law_values(t)
        try:
            q_dot, v_dot, lam, residual = self._fast(*[values[n] for n in self._args], alpha)
        except RuntimeError:  # the factorisation failed: a singular matrix, or NaN in it
            return None
        # the residuals' maxima skip NaN (C's fmax): a singular matrix (a kept row that a
        # lift-off zeroed, at the end of a step on the lift-off) shows in the outputs
        if not (residual[0] <= RESIDUAL_TOLERANCE and residual[1] <= left_out
                and np.isfinite(v_dot).all() and np.isfinite(lam).all()):
            return None
        return q_dot, v_dot, lam


class CompiledStages:
    """The stages of an explicit Runge-Kutta step in one call: one MX Function that applies
    the tableau (:func:`explicit_stages`, as the stages one by one do) and calls the rates
    kernel's Function at each stage, the laws' values at the stage times given. A call of a
    stage one by one costs Python some 80 us besides the kernel's own time (the 10-link
    chain's: 40 us compiled); DOP853 takes 11 such calls a step. The combinations of the
    stages an embedded pair needs (its solution's and its error estimate's) come with them
    (three products in NumPy cost some 10 us an attempt), and so do the error test's
    weighted sums of squares (9 us an attempt in NumPy)."""

    def __init__(self, rates: CompiledRates, A: np.ndarray, c: np.ndarray,
                 weights: np.ndarray):
        self.model, self.c = rates.model, np.asarray(c, dtype=float)
        A = np.asarray(A, dtype=float)
        # built once per model, kernel, tableau and combinations (a run's start would
        # otherwise pay it)
        self.function = rates.model.built_once(
            ("stages", rates._key, A.tobytes(), self.c.tobytes(), weights.tobytes()),
            lambda m: _stages_function(rates.function, A, self.c, weights, m))
        self._fast = FastFunction(self.function)

    def __call__(self, t: float, h: float, y0: np.ndarray, f0: np.ndarray,
                 left_out: float, until: float = np.inf, tolerances: tuple | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The stages after the first and the combinations, as rows, and the error test's
        sums, or None (see :meth:`CompiledRates.stages`); the laws read at the stages' times,
        none later than ``until``."""
        model = self.model
        arguments = [h, y0, f0]
        if model.n_w:  # the laws at the stages' times, read together (the same bits)
            times = np.minimum(t + self.c[1:] * h, until)
            arguments.append(np.concatenate(model.law_values(times)))
        atol, rtol = (1.0, 0.0) if tolerances is None else tolerances
        try:
            K, residual, combined, sums = self._fast(*arguments, atol, rtol)
        except RuntimeError:  # a factorisation failed: a singular matrix, or NaN in it
            return None
        residual = residual.reshape(2, -1, order="F")
        if not (np.all(residual[0] <= RESIDUAL_TOLERANCE) and np.all(residual[1] <= left_out)
                and np.isfinite(K).all()):
            return None
        return (K.reshape(y0.size, -1, order="F").T,
                combined.reshape(y0.size, -1, order="F").T, sums)


def explicit_stages(derivative, h, y0, f0, A: np.ndarray) -> list:
    """The stages ``k_i = derivative(i, y0 + h sum_j a_ij k_j)`` of an explicit Runge-Kutta
    step, ``k_0 = f0``: on NumPy arrays (the stages one by one) or on CasADi symbols (one
    Function of them all, :class:`CompiledStages`) alike, the sums in one order (from zero, the
    stages in turn: on symbols one product of the stages' matrix with the tableau's row, which
    CasADi evaluates in that order, where a node per term cost 30 us each to build, 12 ms per
    contact set for DOP853's stages)."""
    stages = [f0]
    for i in range(1, A.shape[0]):
        if isinstance(f0, ca.MX):
            weighted = ca.mtimes(ca.horzcat(*stages), ca.DM(A[i, :i].reshape(-1, 1)))
        else:
            weighted = sum(float(a) * k for a, k in zip(A[i, :i], stages, strict=True))
        stages.append(derivative(i, y0 + h * weighted))
    return stages


def weighted_squares(x, y0, y1, atol, rtol):
    """``sum((x / weight)^2)``, ``weight = atol + rtol max(|y0|, |y1|)``: the error test's
    weights (Hairer's), between a step's start ``y0`` and end ``y1``; on NumPy arrays (a
    float) or CasADi symbols (an expression) alike, as :func:`explicit_stages`: one formula,
    C's ``fmax`` and ``fabs`` from either library."""
    symbolic = isinstance(x, ca.MX)
    library = ca if symbolic else np
    z = x / (atol + rtol * library.fmax(library.fabs(y0), library.fabs(y1)))
    return ca.dot(z, z) if symbolic else float(z @ z)


def _stages_function(rates: ca.Function, A: np.ndarray, c: np.ndarray, weights: np.ndarray,
                     model: Model) -> ca.Function:
    n_q, n_w, s = model.n_q, model.n_w, c.size
    h = ca.MX.sym("h")
    y0, f0 = ca.MX.sym("y0", n_q + model.n_v), ca.MX.sym("f0", n_q + model.n_v)
    atol, rtol = ca.MX.sym("atol", n_q + model.n_v), ca.MX.sym("rtol")
    laws = ca.MX.sym("laws", 3 * n_w, s - 1)
    residuals = []

    def derivative(i, y):
        at = [laws[j * n_w:(j + 1) * n_w, i - 1] for j in range(3)] if n_w else []
        q_dot, v_dot, _, residual = rates(y[:n_q], y[n_q:], *at, 0.0)
        residuals.append(residual)
        return ca.vertcat(q_dot, v_dot)

    stages = explicit_stages(derivative, h, y0, f0, A)
    inputs = [h, y0, f0] + ([laws] if n_w else []) + [atol, rtol]
    combined = (ca.mtimes(ca.horzcat(*stages), ca.DM(weights.T)) if weights.shape[0]
                else ca.MX(y0.size1(), 0))
    y1 = y0 + h * combined[:, 0] if weights.shape[0] else y0
    sums = [weighted_squares(combined[:, j], y0, y1, atol, rtol)
            for j in range(1, weights.shape[0])]
    return ca.Function("stages", inputs, [ca.horzcat(*stages[1:]), ca.horzcat(*residuals),
                                          combined, ca.vertcat(ca.MX(0, 1), *sums)])


class PolicyMultipliers:
    """The multipliers by the ground-force policy at a state, for a rank decision (the kept
    ``rows`` and the redundant ``left_out`` ones): one call gives the kept rows' solve of
    :class:`CompiledRates` and, with one more right-hand side per row left out, the
    multipliers that change no constraint force, ``N = [e_R - C^T]`` with ``Phi_R = C Phi_I``
    (the saddle-point system with ``M^-1/2 Phi_R^T`` on top and zero below returns ``C^T``
    in its lower part and, in its upper part, the rows' components off the span of the kept
    ones: zero while the decision holds); the policy's choice among ``lam0 + N z`` is then
    the exact solve's own, :func:`hexapod.algorithms.ground.ground_policy`. A simulation saves
    its states' multipliers by it: the exact solve (a rank decision, dense factorisations)
    cost the walking robot some 12 ms a save, a third of its run. Always interpreted (by
    CasADi's virtual machine, the sparse QR): it serves the saved states only, a fraction of
    the stages' calls, and compiling it would cost as much as the rates kernel's compiling."""

    def __init__(self, model: Model, rows: np.ndarray, left_out: np.ndarray):
        self.model, self.rows, self.left_out = model, rows, left_out
        key = ("policy multipliers", tuple(rows.tolist()), tuple(left_out.tolist()))
        self.function = model.built_once(key, lambda m: self._build())
        self._fast = FastFunction(self.function)
        self.data = model.create_data()  # the objective's and Q_across's call buffers
        self._last = None  # (t, q, v, terms) of the last call (see terms)

    def _build(self) -> ca.Function:
        model, rows, left = self.model, self.rows.tolist(), self.left_out.tolist()
        n_c, m = model.n_c, len(left)
        symbols = {n: ca.MX.sym(n, size) for n, size in (
            ("q", model.n_q), ("v", model.n_v), ("w", model.n_w), ("wd", model.n_w),
            ("wdd", model.n_w))}
        Phi_v, gamma, Q = model.dynamics_terms(*[symbols[n]
                                                 for n in model.dynamics_terms.name_in()])
        m_inv_sqrt, _ = mass_factors(model)
        W_all, d_all, zero = equilibrated(Phi_v, m_inv_sqrt)
        top = ca.horzcat(ca.mtimes(m_inv_sqrt, Q), ca.mtimes(m_inv_sqrt, Phi_v[left, :].T))
        y, mu = solve_kept(W_all, d_all, zero, rows, top,
                           ca.horzcat(gamma, ca.MX.zeros(n_c, m)))
        mu = mu / ca.repmat(d_all[rows], 1, m + 1)
        lam0 = ca.MX(n_c, 1)
        lam0[rows] = mu[:, 0]
        N = ca.MX(n_c, m)
        N[rows, :] = -mu[:, 1:]
        N[left, :] = ca.MX(ca.DM.eye(m))
        # the dynamics' residual on the rows kept and left out, relative; the rows left out's
        # distances from the span of those kept (their rows of W are of unit length)
        scaled = ca.fabs(ca.mtimes(Phi_v, ca.mtimes(m_inv_sqrt, y[:, 0])) - gamma) / d_all
        size = ca.norm_inf(y[:, 0]) + ca.norm_inf(top[:, 0]) + 1e-300
        off_span = ca.sqrt(ca.sum1(y[:, 1:] ** 2)).T / d_all[left]
        checks = ca.vertcat(ca.mmax(scaled[rows]) / size, ca.mmax(scaled[left]) / size,
                            ca.mmax(off_span))
        args = [n for n in ("q", "v", "w", "wd", "wdd") if n in ("q", "v") or model.n_w]
        return ca.Function("policy_terms", [symbols[n] for n in args],
                           [ca.mtimes(m_inv_sqrt, y[:, 0]), lam0, ca.densify(N), Phi_v.nz[:],
                            checks], args, ["v_dot", "lam0", "N", "Phi", "checks"])

    def holds(self, t: float, q: np.ndarray, v: np.ndarray) -> bool:
        """Whether :meth:`terms` keeps this state's (the same arrays)."""
        last = self._last
        return last is not None and last[0] == t and last[1] is q and last[2] is v

    def terms(self, t: float, q: np.ndarray, v: np.ndarray) -> tuple | None:
        """The kernel's part at ``(t, q, v)``: ``(v_dot, lam0, N, Phi)`` (the accelerations,
        a particular solution for the multipliers, the multipliers that change no constraint
        force, ``Phi_v``'s nonzeros), or None where refused (see
        :meth:`CompiledRates.dynamics`). The last state's are kept (by the identity of its
        arrays): a step's end takes its accelerations here, and the multipliers saved there
        come from the same call."""
        if self.holds(t, q, v):
            return self._last[3]
        model = self.model
        w, wd, wdd = model.law_values(t) if model.n_w else ((),) * 3
        found = None
        try:
            v_dot, lam0, N, Phi, checks = self._fast(
                *[q, v, *((w, wd, wdd) if model.n_w else ())])
        except RuntimeError:  # the factorisation failed: a singular matrix, or NaN in it
            v_dot = None
        if v_dot is not None and (
                checks[0] <= RESIDUAL_TOLERANCE and checks[1] <= CONSISTENCY_TOLERANCE
                and checks[2] <= model.rank_tolerance and np.isfinite(N).all()
                and np.isfinite(lam0).all() and np.isfinite(v_dot).all()):
            found = v_dot, lam0, N.reshape(model.n_c, -1, order="F"), Phi
        # (else refused: the maxima skip NaN, C's fmax, and the outputs say it)
        self._last = (t, q, v, found)
        return found

    def __call__(self, t: float, q: np.ndarray,
                 v: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """``(v_dot, lam)``, or None (see :meth:`CompiledRates.dynamics`)."""
        terms = self.terms(t, q, v)
        if terms is None:
            return None
        model = self.model
        v_dot, lam0, N, Phi = terms
        Q_across = (model.call("Q_across", self.data, q=q, v=v, w=model.law_values(t)[0])
                    if model.Q_across is not None else None)
        return v_dot, ground_policy(model, self.data, t, q, Phi, Q_across, lam0, N)


def policy_multipliers(model: Model, rows: np.ndarray,
                       left_out: np.ndarray) -> PolicyMultipliers:
    """The :class:`PolicyMultipliers` of a rank decision: its Function built once per model,
    its buffers the caller's."""
    return PolicyMultipliers(model, np.asarray(rows, dtype=int),
                             np.asarray(left_out, dtype=int))


class CompiledProjection:
    """The nearest consistent state in the kinetic-energy norm, as :func:`assemble_positions`
    and :func:`solve_velocities` compute it from a state near the constraints (the end of an
    integration step): ``newton`` Newton iterations on ``phi = 0`` with the Jacobian at the
    given positions (a chord method: the corrections are small), each the least-``M``-norm
    correction through the equilibrated saddle-point system, then the velocities projected
    onto ``Phi_v v = nu``, in one call. Interpreted, the velocities are projected exactly, by
    the Jacobian at the positions found (CasADi's QR factorises at every solve; two Jacobians
    where Newton's method proper took three: the walking robot's projection 0.69 -> 0.59 ms).
    Compiled, the LU's factors at the given positions serve all of them
    (:class:`~hexapod.algorithms.step.KeptFactors`): the velocities are then
    projected along the rows' directions there rather than at the positions found, apart
    from the exact projection by the product of the two corrections (5e-9 of the speeds for
    corrections of 1e-6 and 1e-5 on a four-bar; a second of DOP853 at rtol 1e-6 on chains and
    the 18-joint robot ended 5e-13 to 4e-12 from where it did with three factorisations), on
    the constraints to round-off all the same. Returns None when the result cannot be
    trusted (the largest scaled residual above ``tol``, a change of rank): the caller then
    projects with the exact, rank-deciding functions.
    """

    def __init__(self, model: Model, rows: np.ndarray, newton: int = 2, tol: float = 1e-12,
                 reference: tuple | None = None):
        self.model, self.rows, self.newton, self.tol = model, np.asarray(rows, int), newton, tol
        to_c = current().compiled
        lu = pivots_near(model, self.rows, reference) if to_c else None
        self.function = model.built_once(("projection", tuple(self.rows.tolist()), newton, to_c,
                                          pivot_key(lu)),
                                         lambda m: evaluated_as_set(self._build(lu), to_c))
        self._fast = FastFunction(self.function)
        self._args = ["q", "v"] + (["w", "wd"] if model.n_w else [])

    def _build(self, lu: StaticLU | None) -> ca.Function:
        model, rows = self.model, self.rows.tolist()
        q, v = ca.MX.sym("q", model.n_q), ca.MX.sym("v", model.n_v)
        w, wd = ca.MX.sym("w", model.n_w), ca.MX.sym("wd", model.n_w)
        laws = [w, wd] if model.n_w else []
        symbols = {"q": q, "v": v, "w": w, "wd": wd}
        m_inv_sqrt, m_sqrt = mass_factors(model)
        scale = ca.DM(model.row_scale)

        def call(function, **values):
            return function(*[values.get(n, symbols[n]) for n in function.name_in()])

        if model.n_c == 0:  # nothing to project on
            return ca.Function("project", [q, v, *laws], [q, v] + [ca.MX(0.0)] * 3)

        if lu is None:
            # the Jacobian at the given positions serves the Newton steps (a chord method, as
            # compiled); CasADi's QR factorises at every solve, so the velocities are
            # projected exactly at the positions found, their Jacobian's own factorisation
            position = newton(model, q, lambda x: call(model.phi, q=x),
                              lambda x: call(model.Phi_v, q=x), rows, m_inv_sqrt, self.newton)
            nu, Phi_v = call(model.nu, q=position), call(model.Phi_v, q=position)
            y, _ = solve_kept(*equilibrated(Phi_v, m_inv_sqrt), rows, ca.mtimes(m_sqrt, v), nu)
        else:
            # factors kept (the compiled LU): the Newton steps and the velocities all solve
            # with those at the given positions, a chord method, the velocities corrected
            # twice by the constraints' residual at the positions found (each correction
            # multiplies it by the change of the Jacobian between the two, some 1e-8)
            factors = KeptFactors(*equilibrated(call(model.Phi_v), m_inv_sqrt), rows, lu)
            zeros, position = ca.MX.zeros(model.n_v), q
            for _ in range(self.newton):
                y, _ = factors.solve(zeros, -call(model.phi, q=position))
                position = retract(model, position, ca.mtimes(m_inv_sqrt, y))
            nu, Phi_v = call(model.nu, q=position), call(model.Phi_v, q=position)
            y = ca.mtimes(m_sqrt, v)
            for _ in range(2):
                residual = nu - ca.mtimes(Phi_v, ca.mtimes(m_inv_sqrt, y))
                y = y + factors.solve(zeros, residual)[0]
        phi_error = ca.mmax(ca.fabs(call(model.phi, q=position) / scale))
        velocity = ca.mtimes(m_inv_sqrt, y)
        rate_error = (ca.mtimes(Phi_v, velocity) - nu) / scale
        size = ca.norm_inf(velocity) + ca.norm_inf(nu / scale) + 1e-300
        rate_error = ca.mmax(ca.fabs(rate_error))
        return ca.Function("project", [q, v, *laws], [position, velocity, phi_error,
                                                      rate_error / size, rate_error])

    def __call__(self, t: float, q: np.ndarray, v: np.ndarray,
                 data=None) -> tuple[np.ndarray, np.ndarray] | None:
        """The projected ``(q, v)``, or None (see the class's description); ``data``: the run's
        workspace, whose laws kept ahead serve ``t``. :attr:`residuals` then holds the
        projected state's largest scaled residuals of the positions and velocities (what a
        run's watch measures)."""
        values = {"q": q, "v": v}
        if self.model.n_w:
            values["w"], values["wd"], _ = self.model.law_values(t, data)
        try:
            position, velocity, phi_error, relative, rate_error = self._fast(
                *[values[n] for n in self._args])
        except RuntimeError:  # the factorisation failed: a singular matrix, or NaN in it
            return None
        if not (phi_error[0] <= self.tol and relative[0] <= RESIDUAL_TOLERANCE
                and np.isfinite(position).all() and np.isfinite(velocity).all()):
            return None  # the maxima skip NaN (C's fmax): the outputs say it
        self.residuals = (float(phi_error[0]), float(rate_error[0]))
        return position, velocity


def row_gram(model: Model, data, q: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``W W^T`` of the equilibrated ``Phi_v`` (every row, :func:`~hexapod.algorithms.step.
    equilibrated`) at ``(q, w)``: one call of a Function built once per model and evaluated as
    the execution setting says, through the call buffers of ``data``. What a rejected step's
    check of its rows takes (``Integrator._every_row_clear``), without ``Phi_v``, its scaling
    and their product in NumPy (the 18-joint robot: 54 against 240 us a check in its run,
    compiled)."""
    to_c = current().compiled
    key = ("row gram", to_c)
    function = model.built_once(key, lambda built: evaluated_as_set(_row_gram(built), to_c))
    fast = kept(data, key, lambda: FastFunction(function))
    gram = fast(q, w)[0] if model.n_w else fast(q)[0]
    return gram.reshape(model.n_c, model.n_c)  # a single row's comes back 1-D


def _row_gram(model: Model) -> ca.Function:
    symbols = {"q": ca.MX.sym("q", model.n_q), "w": ca.MX.sym("w", model.n_w)}
    inputs = [symbols[n] for n in model.Phi_v.name_in()]
    W_all, d, _ = equilibrated(model.Phi_v(*inputs), mass_factors(model)[0])
    W = ca.mtimes(ca.diag(1.0 / d), W_all)
    return ca.Function("row_gram", inputs, [ca.densify(ca.mtimes(W, W.T))],
                       model.Phi_v.name_in(), ["gram"])


def evaluated_as_set(function: ca.Function, to_c: bool) -> ca.Function:
    """``function`` as the execution setting evaluates it: compiled to C (the library kept in
    the cache under its graph's hash: the laws are inputs, so a kernel serves any laws) or by
    CasADi's virtual machine."""
    return compiled_graph(function, "forward", f"forward {function.name()}") if to_c \
        else function


def pivots_near(model: Model, rows: np.ndarray, reference: tuple | None) -> StaticLU | None:
    """The pivots of a compiled kernel's LU (:func:`~hexapod.algorithms.step.kept_pivots`) at
    ``reference = (q, w)``, for the saddle-point form (fewer rows kept than velocities); None
    without a reference, without a row, or for a square ``W_I`` (CasADi's sparse QR then).
    Written out as straight-line code, the saddle-point matrix's LU costs 40 % of the compiled
    sparse QR's time (the 10-link chain's right-hand side: 39 against 94 us); in CasADi's
    virtual machine it gains nothing, and is not used there. A fully driven mechanism's square
    ``W_I`` keeps the QR: on the walking robot, building the LU's code for each contact set
    (its pivots, its SX expressions) cost a run 4 s more than its kernels saved."""
    if reference is None or not rows.size or rows.size == model.n_v:
        return None
    q, w = (np.asarray(x, dtype=float) for x in reference)
    # the pivots of a state are part of its kernels (their libraries are keyed by them): kept
    # for the model's last few states, so that the rates' and the projection's kernels, and
    # runs from the same state, choose them once (symbolic analysis in Python: 8 ms for a
    # 10-link chain, 26 ms for 30 links)
    recent = model.built_once(("recent pivots",), lambda m: Recent(RECENT_PIVOTS))
    key = (rows.tobytes(), q.tobytes(), w.tobytes())
    lu = recent.get(key)
    if lu is None:
        # the pivots first chosen for these rows, where they serve this state too: the same
        # kernels then (compiled once), where new pivots at each contact change of a walk
        # made new kernels, and compiled them, stride after stride
        first = model.built_once(("first pivots",), lambda m: {})
        held = first.get(rows.tobytes())
        if held is None:
            # the pivots of the model's reference positions where they serve: the same in
            # every run and process whatever its start (and so are the kernels' libraries)
            held = _reference_pivots(model, rows, w)
        if held is not None and held.serves(kept_values(model, rows.tolist(), q, w)[3]):
            lu = held
        else:
            lu = kept_pivots(model, rows.tolist(), q, w)
        first.setdefault(rows.tobytes(), lu)
        recent.keep(key, lu)
    return lu


def _reference_pivots(model: Model, rows: np.ndarray, w: np.ndarray) -> StaticLU | None:
    """:func:`~hexapod.algorithms.step.kept_pivots` at the model's reference positions ``q0``
    (None where the rows are singular there)."""
    try:
        return kept_pivots(model, rows.tolist(), np.asarray(model.q0, dtype=float), w)
    except RuntimeError:
        return None


def pivot_key(lu: StaticLU | None) -> tuple:
    """What a kernel built with ``lu`` is known by: its pivot orders."""
    return () if lu is None else (lu.row_order.tobytes(), lu.column_order.tobytes())


def compiled_projection(model: Model, rows: np.ndarray,
                        reference: tuple | None = None) -> CompiledProjection:
    """The :class:`CompiledProjection` of ``model`` for a row set (and, compiled, pivots
    chosen at ``reference``): its Function built once per model, its buffers the caller's."""
    return CompiledProjection(model, rows, reference=reference)


def compiled_rates(model: Model, rows: np.ndarray, reference: tuple | None = None,
                   left_out: np.ndarray = ()) -> CompiledRates:
    """The :class:`CompiledRates` of ``model`` for a row set (and, compiled, pivots chosen at
    ``reference``; ``left_out`` the rows the rank decision found redundant, for the policy's
    multipliers): its Function built once per model, its buffers the caller's."""
    return CompiledRates(model, rows, reference, left_out)
