"""RATTLE in Lie-group form: a symplectic, time-reversible method for constrained multibody
systems, with the rotations of spatial bodies advanced by the discrete Moser–Veselov map.

Flat coordinates (particles, planar bodies, the centres of mass of spatial bodies) follow the
classical RATTLE (Andersen 1983; Hairer, Lubich and Wanner, *Geometric Numerical Integration*,
2nd ed., VII.1): with ``F`` the applied forces without the gyroscopic terms and ``G = Phi_v``,

    v_n+1/2 = v_n + h/2 M^-1 (F_n - G_n^T Lambda),        a half kick
    q_n+1   = q_n + h v_n+1/2,                            the drift
    phi(q_n+1, t_n+1) = 0                                 solved for Lambda (Newton),
    v_n+1   = v_n+1/2 + h/2 M^-1 (F_n+1 - G_n+1^T mu),    a half kick
    G_n+1 v_n+1 = nu(q_n+1, t_n+1)                        solved for mu (linear).

The rotation of a spatial body is advanced in the same pattern on SO(3), with its body-frame
angular momentum ``Pi = J omega'``: the half kick adds the body-frame torques of ``F`` and of the
constraints, ``Pi_n+1/2 = Pi_n + h/2 (tau_n - (G_n^T Lambda)_omega)``; the drift is the rotation
``R_n+1 = R_n F_k`` whose relative rotation ``F_k`` solves the implicit equation of the discrete
Moser–Veselov rigid body (Moser and Veselov 1991) as the Lie-group variational integrator of
Lee, Leok and McClamroch (2005, 2007) writes it,

    h hat(Pi_n+1/2) = F_k J_d - J_d F_k^T,     J_d = tr(J)/2 I - J,

solved by Newton's method for the Cayley vector ``f`` of ``F_k = (I + hat f)(I - hat f)^-1``,
``h Pi + h Pi x f + h (Pi . f) f - 2 J f = 0``; the momentum is carried to the new body frame,
``F_k^T Pi_n+1/2``, and receives the second half kick. The gyroscopic term ``-omega' x J omega'``
of ``Q`` is not a force here: the Moser–Veselov map produces it. This is RATTLE applied to the
rotation matrix as nine coordinates under the constraints ``R^T R = I`` and ``phi = 0``, with
the orthogonality multipliers eliminated (HLW VII.5: RATTLE on ``R`` is the Moser–Veselov
algorithm), the holonomic constraints entering as in Leyendecker, Marsden and Ortiz (2008); so
the whole step is symplectic and symmetric (time-reversible) for conservative scenes. The
rotation is applied as :meth:`Model.integrate` applies one, ``p <- p * exp(theta'/2)``, here in
closed form from the Cayley vector, ``exp(theta'/2) = (1, f) / sqrt(1 + |f|^2)``
(``tan(|theta'|/2) = |f|``): Euler parameters stay unit to round-off.

Forces. When every force element derives from a potential (gravity, springs and torsion springs
without dampers; rheonomic drivers allowed), ``F(q) = -B(q)^T dV/dq`` is formed by CasADi from
the potential of :attr:`Model.energy`: an exact gradient, and the method is symplectic.
Otherwise ``F = Q(q, v, t) + omega' x J omega'`` (dampers, applied loads, efforts) enters the
kicks explicitly, the second kick at the velocity ``v^+ + (v_n+1/2 - v_n) = v_n+1 + O(h^2)``
(``v^+`` the velocity after the drift): the method is then second order, not symplectic.

Newton's method for ``Lambda`` on the independent rows (the rank decision of
:mod:`hexapod.algorithms.linalg` at ``q_n``) uses the exact Jacobian
``d phi / d Lambda = -(h^2 / 2) G_n+1 T G_n^T``, ``T`` equal to ``M^-1`` on flat coordinates and,
per spatial body, to ``A_F^-1`` with ``A_F x = vee(F_k hat(x) J_d + J_d hat(x) F_k^T)`` (the
derivative of the Moser–Veselov equation along ``F_k exp(hat(dpsi'))``). Its convergence is
judged on those rows, the only ones it moves; the rows left out follow from them (to their
residual over the smallest singular value, and to the round-off of the unit Euler parameters,
renormalised after every step) and are checked afterwards to ``redundant_tol``. Judged on every
row, Newton's method stalled on Bricard's mechanism once the redundant row's round-off had grown
past its tolerance (after 2.5 s at h = 1e-3 s). Near a singular configuration, where the
iteration matrix is nearly singular, the correction is the least-squares one of least norm.
The velocity stage is the projection of the kicked velocities onto ``G v = nu`` in the
kinetic-energy norm, redundant rows dropped by the same rank decision. When Newton's method does
not converge the step is halved and retried, then grown back, as in
:mod:`hexapod.simulation.integrators.generalized_alpha`; a failure names a singular
configuration when the run stands at one.

One CasADi Function, built once per model, forms a whole iterate (kick, Moser–Veselov solves,
drift, constraints, forces and the Newton matrix); NumPy keeps the rank decisions and the small
linear solves. The accelerations and multipliers reported at a state (``v_dot``, ``lam``) are
those of the dynamics there, redundancy policy included, solved at the end of every step: the
kicks do not need them, but a step whose velocities change by more than its accelerations at
both ends explain is refused and halved (Newton's method found a solution on another branch of
the constraints, see :meth:`Integrator._jumps_branch`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod.algorithms.linalg import (
    check_consistency,
    equilibrate,
    solve_or_least_squares,
    split_rows,
)
from hexapod.algorithms.saddle import force_multipliers, is_large, solve_sparse
from hexapod.algorithms.step import sparse_dm
from hexapod.simulation.integrators.base import Integrator
from hexapod.simulation.integrators.interpolants import Interpolant
from hexapod.simulation.integrators.stability import largest_stable_step, oscillator_parameters
from hexapod.simulation.methods import METHODS
from hexapod.simulation.scales import ENERGY_JUMP
from hexapod.spatial import quaternion_product, skew

#: Newton iterations of each Moser–Veselov equation, unrolled in the step Function: from the
#: guess ``f = h omega / 2`` (exact to ``O(h^2 |omega|^2)``) they reach round-off for rotations
#: per step well beyond those of an accurate step; the residual is checked, and a step that
#: leaves it above ROTATION_TOL (relative to ``h |Pi|``) is halved.
ROTATION_ITERATIONS = 6
ROTATION_TOL = 1e-12


def _kick_drift_kick_growth(z: complex) -> float:
    """Spectral radius of one step on ``x'' + c x' + k x = 0`` (``z = h lambda``), in the
    variables ``(x, h x')``, with the damper in the kicks as :class:`Rattle` applies it."""
    k, c = oscillator_parameters(z)
    step = np.zeros((2, 2))
    for column, (x, u) in enumerate(((1.0, 0.0), (0.0, 1.0))):
        u_half = u + 0.5 * (-k * x - c * u)
        x1 = x + u_half
        u1 = u_half + 0.5 * (-k * x1 - c * (2 * u_half - u))
        step[:, column] = x1, u1
    return float(np.max(np.abs(np.linalg.eigvals(step))))


class Rattle(Integrator):
    """RATTLE with Moser–Veselov rotations (Lie-group form), index 3, fixed step (halved when
    Newton's method fails). Symplectic and time-reversible for conservative scenes.

    ``newton_tol``: tolerance on the position constraints, ``|phi_i| / s_i`` (``s_i`` the
    characteristic length of length rows, 1 for angle rows).
    """

    name = "rattle"
    order, index, adaptive, stabilisation = METHODS[name]
    description = ("RATTLE in Lie-group form (Moser-Veselov rotations): symplectic and "
                   "time-reversible, index 3")
    max_iterations = 25
    #: how far the rows left out by the rank decision may be violated after a step (as
    #: ``newton_tol``) before the step is refused: they follow the kept rows to round-off
    redundant_tol = 1e-8

    @classmethod
    def largest_stable_step(cls, eigenvalues, constrained: bool = False,
                            **options) -> float | None:
        """On each mode, the kick-drift-kick map of its oscillator (Stormer-Verlet, ``h omega
        < 2``, when undamped; a damper enters the kicks explicitly)."""
        return largest_stable_step(_kick_drift_kick_growth, eigenvalues)

    def __init__(self, *args, newton_tol: float = 1e-13, **kwargs):
        if not newton_tol > 0:
            raise ValueError(f"newton_tol must be positive, got {newton_tol}")
        self.newton_tol = float(newton_tol)
        super().__init__(*args, **kwargs)

    # ------------------------------------------------------------ set-up

    def _start(self) -> None:
        model = self.model
        self.nominal = self.h
        # a large model's matrices stay sparse (Phi_v and the Newton matrix travel as their
        # nonzeros; see hexapod.algorithms.saddle), a small one's are made dense as before
        self.large = is_large(model)
        start, stage, self.conservative, self.velocity_forces, self.patterns = \
            _functions(model)
        self.start_terms, self.stage = _Buffered(start), _Buffered(stage)
        n_q, n_v, n_c, n_w = model.n_q, model.n_v, model.n_c, model.n_w
        nnz = {name: pattern.nnz() for name, pattern in self.patterns.items()}
        self.inputs = _layout({"q": n_q, "v": n_v, "F": n_v, "Phi_v": nnz["Phi_v"], "h": 1,
                               "w": n_w, "wd": n_w, "lam": n_c})
        self.layout = _layout({"q": n_q, "v": n_v, "phi": n_c, "Phi_v": nnz["Phi_v"],
                               "nu": n_c, "F": n_v, "S": nnz["S"], "rotation": 1})
        self.row_names = [r.name for r in model.rows]
        # the constraint forces Phi_v^T Lambda of the last steps
        self.history: list[np.ndarray] = []
        self.cache = None  # (q, (Phi_v, its nonzeros), F, rank decision) at the current state
        self.failure = ""  # why the last attempt failed

    def _laws(self, t: float, derivative: bool) -> list[np.ndarray]:
        if not self.model.n_w:
            return []
        w, wd, _ = self.model.law_values(t, self.data)
        return [w, wd] if derivative else [w]

    def _matrix(self, name: str, values: np.ndarray):
        """The matrix ``name`` (``Phi_v`` or ``S``) from its nonzeros: SciPy CSR for a large
        model, else a NumPy array."""
        from scipy.sparse import csc_array

        pattern = self.patterns[name]
        matrix = csc_array((np.array(values), np.asarray(pattern.row()),
                            np.asarray(pattern.colind())), shape=pattern.shape).tocsr()
        return matrix if self.large else matrix.toarray()

    def _split(self, Phi_v: np.ndarray):
        W, d = equilibrate(Phi_v, self.model.mass_inv_sqrt)
        self.counters.factorisations += 1
        return split_rows(W, d, self.model.row_priority, self.model.rank_tolerance,
                          groups=self.model.row_groups)

    def _start_state(self):
        """``Phi_v``, the force and the rank decision at the current state: those of the end of
        the last step, unless the forces depend on the velocities."""
        cache = self.cache
        if cache is not None and cache[0] is self.q and not self.velocity_forces:
            return cache[1:]
        self.start_terms.input[:] = np.concatenate([self.q, self.v, *self._laws(self.t, False)])
        out = self.start_terms()
        self.counters.rhs += 1
        self.counters.jacobians += 1
        size = self.patterns["Phi_v"].nnz()
        Phi_v = self._matrix("Phi_v", out[:size])
        split = self._split(Phi_v)
        self.cache = (self.q, (Phi_v, out[:size].copy()), out[size:].copy(), split)
        return self.cache[1:]

    # ------------------------------------------------------------ the step

    def _step(self) -> None:
        self._dense_start = (self.t, self.q, self.v, self.v_dot)  # for dense_output
        h, result = self._halving(self._attempt_or_forget)
        self.t, self.q, self.v, self.v_dot, self.lam = result
        self.h = min(self.nominal, 2 * h) if h < self.nominal else self.h

    def _attempt_or_forget(self, h: float):
        """:meth:`_attempt`; after a failure the multipliers of the last steps no longer
        predict those of the shorter step: forgotten."""
        result = self._attempt(h)
        if result is None:
            self.history.clear()
        return result

    def _predict(self, Phi_v, split) -> np.ndarray:
        """Starting multipliers on the independent rows: those whose constraint force
        ``Phi_v^T Lambda`` is the one extrapolated from the last two steps (``O(h^2)``), else
        that of the dynamics at the start (``O(h)``). Extrapolated as forces, not multipliers:
        the force is smooth where the multipliers are not (near a singular pose they grow as
        one over the smallest singular value, and the rank decision may keep other rows from
        one step to the next), and the starting guess decides which root Newton's method finds
        there. Extrapolating the multipliers, RATTLE at h = 4e-2 s on the N-four-bar with 20
        windows found a spurious root that lost a quarter of the energy in one step, and on the
        driven stretched leg the knee's bounce instead of its flip (0.48 off, reported
        finished); now the first ends 2e-3 off and the second stops at the pose, naming it."""
        if len(self.history) == 2:
            force = 2 * self.history[-1] - self.history[-2]
        else:
            force = np.asarray(Phi_v.T @ self.lam)
        return force_multipliers(split, Phi_v, force, self.model.mass_inv_sqrt)

    def _attempt(self, h: float):
        """One step of length ``h``: ``(t, q, v)``, or None when Newton's method fails."""
        model = self.model
        t1 = self.t + h
        (Phi0, Phi0_values), force0, split0 = self._start_state()
        I = split0.independent
        d = split0.scale[I]
        lam = self._predict(Phi0, split0)
        # the stage's input; only the multipliers change below
        z, where = self.stage.input, self.inputs
        z[where["q"]], z[where["v"]], z[where["F"]] = self.q, self.v, force0
        z[where["Phi_v"]], z[where["h"]] = Phi0_values, h
        if model.n_w:
            z[where["w"]], z[where["wd"]] = self._laws(t1, True)
        multipliers = z[where["lam"]]
        multipliers[:] = 0.0
        layout = self.layout
        for iteration in range(self.max_iterations + 1):
            multipliers[I] = lam
            out = self.stage()
            self.counters.rhs += 1
            self.counters.jacobians += 1
            phi = out[layout["phi"]]
            scaled = np.abs(phi / model.row_scale)
            if not (np.all(scaled < np.inf) and out[-1] <= ROTATION_TOL):  # NaN fails both
                self.failure = (f"non-finite constraints or unsolved rotations at h = {h:.3g} s"
                                f" (rotation residual {out[-1]:.1e})")
                return None
            # Newton's method moves the kept rows only: the others follow from them (checked
            # below), to the kept rows' residual over the smallest singular value and to the
            # round-off of the unit Euler parameters, which the tolerance need not see
            residual = scaled[I].max(initial=0.0)
            # converged after one correction at least: a predictor within the tolerance still
            # leaves an O(tolerance) offset from the constraints, which the potential of the
            # forces they balance would see at first order (one correction takes it to
            # round-off)
            if residual <= self.newton_tol and (iteration or I.size == 0):
                break
            if iteration == self.max_iterations or I.size == 0:
                self.failure = (f"Newton's method does not converge at h = {h:.3g} s "
                                f"(scaled residual {residual:.1e})")
                return None
            self.counters.newton += 1
            self.counters.factorisations += 1
            step = self._newton_step(out[layout["S"]], I, d, phi[I] / d)
            if step is None:
                self.failure = f"the iteration matrix is singular at h = {h:.3g} s"
                return None
            lam = lam + (2 / h**2) * (step / d)
        left_out = scaled[split0.redundant].max(initial=0.0)
        if left_out > self.redundant_tol:
            names = ", ".join(self.row_names[i] for i in split0.redundant[:5])
            self.failure = (f"the rows left out by the rank decision ({names}) are violated by "
                            f"{left_out:.1e} at h = {h:.3g} s")
            return None
        # copies: the stage's output is overwritten by its next call
        q1, v_plus, nu, force1 = (out[layout[k]].copy() for k in ("q", "v", "nu", "F"))
        q1 = model.normalize(q1)  # Euler parameters: their round-off would add up over steps
        Phi1_values = out[layout["Phi_v"]].copy()
        Phi1 = self._matrix("Phi_v", Phi1_values)
        self.history = [*self.history[-1:], np.asarray(Phi0[I].T @ lam)]
        # the second half kick, and the velocities onto Phi_v v = nu (kinetic-energy norm)
        v_star = v_plus + (h / 2) * (model.mass_inv @ force1)
        split1 = self._split(Phi1)
        gap = nu - Phi1 @ v_star
        dy = split1.min_norm_correction(gap)
        # relative to the velocities themselves (at rest the gap is round-off)
        size = np.linalg.norm(model.mass @ (model.mass_inv_sqrt @ v_star))  # |M^1/2 v|
        check_consistency(split1, dy, gap, size, row_names=self.row_names,
                          what="velocity constraints")
        v1 = v_star + model.mass_inv_sqrt @ dy
        self.cache = (q1, (Phi1, Phi1_values), force1, split1)
        # the dynamics at the step's end: the accelerations the loop reports there, and the
        # check that Newton's method has not landed on another branch of the constraints
        v_dot1, lam1 = self._dynamics(t1, q1, v1)
        if self._jumps_branch(h, self.v, self.v_dot, v1, v_dot1):
            self.failure = (f"the velocities changed by more than the accelerations explain at "
                            f"h = {h:.3g} s: Newton's method found a solution on another branch")
            return None
        jump = self._energy_jump(self.q, self.v, q1, v1)
        if jump > ENERGY_JUMP:
            self.failure = (f"the energy changed by {jump:.2g} of the largest kinetic energy at "
                            f"h = {h:.3g} s")
            return None
        return t1, q1, v1, v_dot1, lam1

    def _newton_step(self, S_values: np.ndarray, I: np.ndarray, d: np.ndarray,
                     rhs: np.ndarray) -> np.ndarray | None:
        """Newton's correction on the kept rows ``I``, scaled as the equilibrated ``Phi_v`` (``S /
        (d d^T) ~ W W^T``): LU, or near a singular configuration the least-squares correction of
        least norm; a large model's ``S``, sparse along the body-joint graph, by a sparse LU."""
        S = self._matrix("S", S_values)
        if self.large:
            from scipy.sparse import diags

            scale = diags(1.0 / d)
            return solve_sparse(scale @ S[I][:, I] @ scale, rhs)
        return solve_or_least_squares(S[np.ix_(I, I)] / np.outer(d, d), rhs)

    def dense_output(self) -> Interpolant:
        """Quintic Hermite interpolation of the positions from ``(q, v, v_dot)`` at both ends of
        the step, cubic of the velocities (:class:`~.interpolants.HermiteInterpolant`)."""
        return self._hermite(self._dense_start)


# ---------------------------------------------------------------- the CasADi Functions

def _layout(sizes: dict[str, int]) -> dict[str, slice]:
    """Slices of consecutive named parts of a vector."""
    ends = np.cumsum([0, *sizes.values()])
    return {k: slice(a, b) for k, a, b in zip(sizes, ends[:-1], ends[1:], strict=True)}


class _Buffered:
    """A packed Function evaluated in place on two NumPy arrays through CasADi's function
    buffer: fill ``input``, call, read the returned ``output`` (overwritten by the next call).
    A call then costs no conversion (a fifth of an ordinary call on small models)."""

    def __init__(self, function: ca.Function):
        self.input = np.zeros(function.size1_in(0))
        self.output = np.zeros(function.size1_out(0))
        self._buffer, self._trigger = function.buffer()
        self._buffer.set_arg(0, memoryview(self.input))
        self._buffer.set_res(0, memoryview(self.output))

    def __call__(self) -> np.ndarray:
        self._trigger()
        return self.output


def _mv_residual(hp, f, J):
    """Moser–Veselov in Cayley form: ``h Pi + h Pi x f + h (Pi . f) f - 2 J f``."""
    return hp + ca.cross(hp, f) + ca.dot(hp, f) * f - 2 * ca.mtimes(J, f)


def _mv_jacobian(hp, f, J):
    return skew(hp) + ca.mtimes(f, hp.T) + ca.dot(hp, f) * ca.DM.eye(3) - 2 * J


def _vee(S):
    return ca.vertcat(S[2, 1], S[0, 2], S[1, 0])


def _force(model, q, v, laws):
    """The force of the kicks, and whether it is conservative."""
    drivers = {d.name for d in model.drivers}
    if all(name in drivers for name in model.working_elements):
        # F = -B^T dV/dq: the exact gradient of the potential along the group
        _, potential = model.energy(q, v)
        B = ca.jacobian(model.qdot(q, v), v)
        return -ca.mtimes(B.T, ca.gradient(potential, q)), True
    force = model.Q(q, v, *laws)  # without its gyroscopic terms -omega' x J omega'
    for body in model.bodies:
        if body.kind == "spatial":
            rows = slice(body.v.start + 3, body.v.start + 6)
            omega = v[rows]
            force[rows] = force[rows] + ca.cross(omega, ca.mtimes(ca.DM(body.inertia), omega))
    return force, False


def _packed(name: str, inputs: list, outputs: list) -> ca.Function:
    """A Function of one vector (the inputs stacked) to one vector (the outputs likewise): a
    call then costs one conversion each way, not one per argument. Vectors are stacked whole,
    matrices by their nonzeros (in CasADi's column order): ``Phi_v`` and the Newton matrix of
    a large model would otherwise be written densely, ``O(n^2)`` entries per call. A row
    vector (``Phi_v`` of a single row) is a matrix: its nonzeros, made a column."""
    def size(x):
        return x.numel() if x.size2() == 1 else x.nnz()

    z = ca.SX.sym("z", sum(size(x) for x in inputs))
    parts, k = [], 0
    for x in inputs:
        chunk = z[k:k + size(x)]
        parts.append(chunk if x.size2() == 1 else ca.SX(x.sparsity(), chunk))
        k += size(x)
    inner = ca.Function(name + "_inner", inputs, outputs)
    return ca.Function(name, [z], [ca.vertcat(*[ca.densify(x) if x.size2() == 1
                                                 else ca.vec(x.nz[:]) for x in inner(*parts)])])


def _functions(model):
    """``start(q, v[, w]) -> (Phi_v, F)`` and ``stage(q0, v0, F0, Phi0, h[, w, wd], Lambda)``
    (packed, see :func:`_packed`), built once per model, whether the force is conservative, and
    whether it depends on ``v``.

    ``stage`` forms one Newton iterate from the kick force ``F0 - Phi0^T Lambda``: the
    positions ``q1`` and the velocities ``v^+`` after the drift, ``phi``, ``Phi_v``, ``nu`` and
    the force at ``q1`` (at the predicted ``v_n+1``), ``S = Phi_v(q1) T Phi0^T`` and the largest
    relative residual of the Moser–Veselov equations. The matrices travel as their nonzeros;
    their patterns are returned last, ``{"Phi_v": ..., "S": ...}``.
    """
    return model.built_once(("rattle",), _build_functions)


def _build_functions(model):
    n_q, n_v, n_c, n_w = model.n_q, model.n_v, model.n_c, model.n_w
    q, v = ca.SX.sym("q", n_q), ca.SX.sym("v", n_v)
    w, wd = ca.SX.sym("w", n_w), ca.SX.sym("wd", n_w)
    laws = [w] if n_w else []
    force, conservative = _force(model, q, v, laws)
    force_at = ca.Function("rattle_force", [q, v, *laws], [force])
    start = _packed("rattle_start", [q, v, *laws], [model.Phi_v(q, *laws), force])

    force0, h = ca.SX.sym("F0", n_v), ca.SX.sym("h")
    Phi0, lam = ca.SX.sym("Phi0", model.Phi_v.sparsity_out(0)), ca.SX.sym("Lambda", n_c)
    mass_inv = sparse_dm(model.mass_inv.sparse())
    kick = (h / 2) * ca.mtimes(mass_inv, force0 - ca.mtimes(Phi0.T, lam))
    v_half = v + kick
    q1 = q + 0  # a copy, its rows replaced below
    v_plus = v_half + 0
    T = ca.SX(mass_inv)
    rotation_residual = ca.SX(0.0)
    for body in model.bodies:
        if body.kind != "spatial":
            q1[body.q] = q[body.q] + h * v_half[body.v]
            continue
        lin_q = slice(body.q.start, body.q.start + 3)
        lin_v = slice(body.v.start, body.v.start + 3)
        rot_v = slice(body.v.start + 3, body.v.start + 6)
        J = ca.DM(body.inertia)
        J_d = 0.5 * float(np.trace(body.inertia)) * ca.DM.eye(3) - J
        hp = h * ca.mtimes(J, v_half[rot_v])
        cayley = 0.5 * h * v_half[rot_v]
        for _ in range(ROTATION_ITERATIONS):
            cayley = cayley - ca.solve(_mv_jacobian(hp, cayley, J),
                                       _mv_residual(hp, cayley, J))
        rotation_residual = ca.fmax(rotation_residual,
                                    ca.norm_inf(_mv_residual(hp, cayley, J))
                                    / ca.fmax(ca.norm_inf(hp), np.finfo(float).tiny))
        c2 = ca.dot(cayley, cayley)
        S = skew(cayley)
        F = ca.DM.eye(3) + 2 / (1 + c2) * (S + ca.mtimes(S, S))
        q1[lin_q] = q[lin_q] + h * v_half[lin_v]
        q1[body.q.start + 3:body.q.stop] = quaternion_product(
            q[body.q.start + 3:body.q.stop], ca.vertcat(1, cayley) / ca.sqrt(1 + c2))
        v_plus[rot_v] = ca.solve(J, ca.mtimes(F.T, hp / h))
        A = ca.horzcat(*[_vee(ca.mtimes([F, skew(e), J_d]) + ca.mtimes([J_d, skew(e), F.T]))
                         for e in (ca.DM([1, 0, 0]), ca.DM([0, 1, 0]), ca.DM([0, 0, 1]))])
        T[rot_v, rot_v] = ca.inv(A)
    Phi1 = model.Phi_v(q1, *laws)
    nu = model.nu(q1, *laws, *([wd] if n_w else []))
    S = ca.mtimes([Phi1, T, Phi0.T])
    outputs = [q1, v_plus, model.phi(q1, *laws), Phi1, nu,
               force_at(q1, v_plus + kick, *laws), S, rotation_residual]
    stage = _packed("rattle_stage", [q, v, force0, Phi0, h, *laws, *([wd] if n_w else []),
                                     lam], outputs)
    patterns = {"Phi_v": model.Phi_v.sparsity_out(0), "S": S.sparsity()}
    return start, stage, conservative, bool(ca.depends_on(force, v)), patterns
