"""Radau IIA of order 5 on the stabilised index-2 equations of Gear, Gupta and Leimkuhler.

The GGL formulation (Gear, Gupta and Leimkuhler 1985; Hairer and Wanner, *Solving ODEs II*,
VII.1-VII.2) keeps both constraint levels as equations, with a second multiplier ``mu`` that moves
the positions back onto ``phi = 0``:

    q_dot = B(q) (v + Phi_v(q)^T mu),   M v_dot = Q(q, v, t) - Phi_v^T lambda,
    0 = phi(q, t),                      0 = Phi_v(q) v - nu(q, t).

``lambda`` and ``mu`` are algebraic variables of index 2; ``mu`` vanishes along exact motions.

**Positions on the group.** Each step works in local coordinates of the positions at its
start, ``q(t) = q_n (+) xi(t)`` (:meth:`Model.integrate`: translations added, rotations
composed in the body frame, ``p <- p * exp(xi'/2)``), so Euler parameters stay unit to
round-off whatever the step. For a spatial body's rotation vector the kinematic equation is
``xi_dot = J_r(xi)^-1 omega``, with the inverse right Jacobian of SO(3) in closed form,

    J_r(x)^-1 = I + [x]/2 + (1/theta^2 - (1 + cos theta) / (2 theta sin theta)) [x]^2,

``theta = |x|`` and ``[x]`` the cross-product matrix (the identity for linear coordinates).
The unknowns of a step are ``y = (xi, v, lambda, mu)``, an ODE-DAE ``M_y y_dot = F(t, y)``
with the constant singular matrix ``M_y = diag(I, M, 0, 0)``.

**The method** is RADAU5 (Hairer and Wanner, IV.8, and VII.4 for index 2): the three-stage
Radau IIA collocation method (order 5, stiffly accurate, L-stable; for index 2 the positions
and velocities keep order 5, the multipliers converge at order 3), whose stage increments
``Z_i = Y_i - y_n`` solve

    (A^-1 / h (x) M_y) Z = F(t_n + c_i h, y_n + Z_i),   i = 1, 2, 3,

by simplified Newton iterations with the Jacobian ``J = dF/dy`` at the start of the step
(CasADi, exact: derivatives of ``phi``, ``Phi_v``, ``nu`` and ``Q`` along ``q (+) dxi``).
``T^-1 A^-1 T = diag(gamma, [[alpha, beta], [-beta, alpha]])`` splits the ``3N x 3N``
iteration matrix into one real and one complex ``N x N`` matrix, ``gamma/h M_y - J`` and
``(alpha - i beta)/h M_y - J``, factorised once per attempted step (dense LU, or SuperLU
for ``N`` above 200: a hexapod's 888 rows in a third of the time); they are scaled (the
first two block rows by ``h``, the multipliers' columns by ``1/h``) so that every block is
of order one whatever the step. The stages start from the previous step's collocation
polynomial (extrapolated, its positions carried over to the new local coordinates), and
Newton's contraction ``theta`` is watched as in RADAU5: a slow or diverging iteration cuts the
step (halved when it diverges) and counts as a rejection. As the Jacobian is frozen at the
start of the step, ``theta`` grows like ``h^2``; the step is not grown past the one where
``theta`` is predicted to reach ``newton_rate`` (0.1 by default, 0 to switch off): a stiff
spring that turns with the motion otherwise has every other step rejected by Newton's method
(measured: 63 rejected for 198 accepted instead of 176 for 179).

**Error and steps.** Hairer's estimate ``err = (gamma/h M_y - J)^-1 (F(y_n) + M_y sum_i e_i
Z_i / h)`` (computed again from ``F(y_n + err)`` after a rejection), in the RMS norm with
weights ``atol + rtol |y_n|`` (rotation vectors: ``|y| = 1``, the norm of the Euler
parameters); the index-2 components ``lambda`` and ``mu`` are weighted by ``h`` as RADAU5
does. The tolerances are mapped as RADAU5 maps them, ``rtol' = 0.1 rtol^(2/3)`` and
``atol' = atol rtol'/rtol``: the estimate is of order 3 but the solution of order 5, and with
this map the global error is of the order of the requested tolerance (2 to 6 times ``rtol``
on the pendulum from 1e-4 to 1e-10). The step size follows
``h_new = h / max(1/8, min(5, err^(1/4) / fac))`` with ``fac`` the safety factor lowered after
many Newton iterations, and Gustafsson's predictive controller after accepted steps.

**Redundant constraints** make the iteration matrix singular: the rank decision of
:mod:`hexapod.algorithms.linalg` at the start of each step keeps the independent rows of both
constraint levels (with their ``lambda``, ``mu``) and drops the others. The rank is decided to
the accuracy of the state: off the constraints by Newton's stopping error ``e``, a redundant row
stands about ``e`` from the others' span, so the tolerance is at least :data:`RANK_MARGIN` times
``e`` (with the model's 1e-9 alone, Bricard's mechanism at rtol = atol = 1e-6 kept its redundant
row, 1.8e-9 from the span, and Newton's method diverged at every step size). The multipliers
reported at an accepted state are those of the dynamics there (:meth:`Integrator._dynamics`,
redundancy policy included); those of the method are kept in ``lam_ggl`` and ``mu``.

**Singular configurations** (the N-four-bar lying flat): the index-2 iteration matrix becomes
singular with ``Phi_v`` and Newton's method fails at every step size; the run stops there with a
message naming the pose (time, smallest singular value) and the methods that cross it.

Work counted: ``rhs`` one per stage residual (three per Newton iteration) and per residual at
the start of a step, ``jacobians`` one per step (plus those of the dynamics at accepted
states), ``factorisations`` two LU per attempted step (real and complex) and the QR of the
rank decision, ``newton`` the iterations.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.linalg import lu_factor, lu_solve
from scipy.sparse.linalg import splu

from hexapod.algorithms.linalg import equilibrate, split_rows
from hexapod.algorithms.saddle import is_large, kept_multipliers
from hexapod.errors import IntegrationError
from hexapod.simulation.integrators.base import RANK_MARGIN, Integrator
from hexapod.simulation.integrators.ggl import ggl_functions
from hexapod.simulation.integrators.interpolants import Interpolant
from hexapod.simulation.integrators.tableaus import RADAU_A, RADAU_C, RADAU_DENSE, RADAU_E
from hexapod.simulation.methods import METHODS
from hexapod.spatial import quaternion_exp, quaternion_log, quaternion_product

# ---------------------------------------------------------------- Radau IIA, three stages

#: Butcher matrix, nodes and error weights (:mod:`~hexapod.simulation.integrators.tableaus`)
A, C, E = RADAU_A, RADAU_C, RADAU_E


def _transformation() -> tuple[np.ndarray, np.ndarray, float, float, float]:
    """``T``, ``T^-1`` and ``gamma, alpha, beta`` with ``T^-1 A^-1 T = [[gamma, 0, 0],
    [0, alpha, beta], [0, -beta, alpha]]``: the real eigenvector of ``A^-1`` and the real and
    imaginary parts of the one of ``alpha + i beta``."""
    inverse = np.linalg.inv(A)
    values, vectors = np.linalg.eig(inverse)
    real, pair = int(np.argmin(np.abs(values.imag))), int(np.argmax(values.imag))
    T = np.column_stack([vectors[:, real].real, vectors[:, pair].real, vectors[:, pair].imag])
    TI = np.linalg.inv(T)
    block = TI @ inverse @ T
    return T, TI, float(block[0, 0]), float(block[1, 1]), float(block[1, 2])


T, TI, GAMMA, ALPHA, BETA = _transformation()


def _extrapolation(ratio: float) -> np.ndarray:
    """Weights ``L`` such that ``L @ Z_old`` is the previous step's collocation polynomial (the
    cubic through 0 and the stage increments at ``0, c1, c2, 1``) at ``1 + c_i ratio``."""
    nodes = np.concatenate([[0.0], C])
    s = 1.0 + C * ratio
    L = np.ones((3, 3))
    for j in range(3):
        for k in range(4):
            if k != j + 1:
                L[:, j] *= (s - nodes[k]) / (nodes[j + 1] - nodes[k])
    return L


class NewtonFailure(Exception):
    """The stage equations could not be solved with this step (internal: the step is cut)."""

    def __init__(self, reason: str, factor: float = 0.5):
        super().__init__(reason)
        self.factor = factor


class RadauIIA5GGL(Integrator):
    """Radau IIA of order 5 (RADAU5) on the GGL index-2 equations, adaptive, positions in
    local Lie-group coordinates of each step (see the module's description).

    ``gustafsson`` (True by default): predictive step-size control after accepted steps.
    ``newton_rate`` (0.1): the Newton contraction the step may grow to (0: no limit).
    ``newton_tol``: Newton's iterations stop when their error is predicted below this fraction
    of the error weights (RADAU5's ``min(0.03, rtol'^(1/2))`` by default). The stopping errors
    of Newton's method add up over the steps and make much of the global error: a hundredth
    of the default lowers the error on the pendulum 20 times at rtol 1e-4, 2 times at 1e-8,
    for 1.7 to 2 times the Newton iterations.
    The method's own multipliers at the current state are ``lam_ggl`` and ``mu`` (``mu`` is
    zero along exact motions).
    """

    name = "radau5-ggl"
    order, index, adaptive, stabilisation = METHODS[name]
    description = "Radau IIA order 5 (RADAU5), adaptive, GGL index 2, Lie-group coordinates"
    max_newton = 7  # RADAU5's NIT
    safety = 0.9
    #: bounds of h_new / h (RADAU5's 1/FACL and 1/FACR)
    min_factor, max_factor = 0.2, 8.0
    #: iteration matrices with more rows than this are factorised as sparse matrices
    sparse_above = 200

    def __init__(self, *args, step: float | None = None, gustafsson: bool = True,
                 newton_rate: float = 0.1, newton_tol: float | None = None, **kwargs):
        if newton_tol is not None and not 0 < newton_tol < 1:
            raise ValueError(f"newton_tol must be in (0, 1), got {newton_tol}")
        if not newton_rate >= 0:
            raise ValueError(f"newton_rate must be at least 0, got {newton_rate}")
        self._given_step = step
        self.gustafsson = bool(gustafsson)
        self.newton_rate = float(newton_rate)
        self.newton_tol = newton_tol
        super().__init__(*args, step=step, **kwargs)

    # ------------------------------------------------------------------ set-up

    def _start(self) -> None:
        model = self.model
        self._fn = ggl_functions(model)
        n_v, n_c = model.n_v, model.n_c
        self._n_full = 2 * n_v + 2 * n_c
        rotations, q_of_v = [], np.full(n_v, -1)  # q_of_v: the coordinate of a translation
        for b in model.bodies:
            q_idx, v_idx = np.arange(b.q.start, b.q.stop), np.arange(b.v.start, b.v.stop)
            if b.kind == "spatial":
                rotations.append(v_idx[3:])
                q_of_v[v_idx[:3]] = q_idx[:3]
            else:
                q_of_v[v_idx] = q_idx
        self._rot = np.array(rotations, dtype=int).reshape(-1, 3)
        self._q_of_v = q_of_v
        self._sparse = self._n_full > self.sparse_above
        # sparse: M x and the iteration matrices cost O(n), not O(n^2); a large model's Phi_v
        # stays sparse too (its rank decision: hexapod.algorithms.saddle)
        self._mass = model.mass.sparse() if self._sparse else model.mass.dense()
        self._large = is_large(model)
        # RADAU5's map of the tolerances (its estimate is of order 3, the solution of order 5)
        self._rtol = 0.1 * self.rtol ** (2.0 / 3.0)
        self._atol = self.atol * self._rtol / self.rtol
        fnewt = min(0.03, self._rtol**0.5) if self.newton_tol is None else self.newton_tol
        self._fnewt = max(10 * np.finfo(float).eps / self._rtol, fnewt)  # not below round-off
        self.lam_ggl = self.lam.copy()
        self.mu = np.zeros(n_c)
        self._faccon = 1.0
        self._kappa = None  # Newton's contraction over h^2, measured last
        self._previous = None  # (h, stage increments) of the last accepted step
        self._h_acc = self._err_acc = None
        if self._given_step is None:
            self.h = self._initial_step()

    def _initial_step(self) -> float:
        """Hairer's starting step (*Solving ODEs I*, II.4) for an error of order 3, from the
        sizes of the state, of its rate and of the rate's change over a trial Euler step."""
        model = self.model
        y0 = np.concatenate([self.q, self.v])
        f0 = np.concatenate([model.call("qdot", self.data, q=self.q, v=self.v), self.v_dot])

        def norm(x):
            return float(np.sqrt(np.mean((x / (self.atol_vector + self.rtol * np.abs(y0))) ** 2)))

        def rate_change(h0: float) -> float:
            q1, v1 = model.integrate(self.q, h0 * self.v), self.v + h0 * self.v_dot
            v_dot1, _ = self._dynamics(self.t + h0, q1, v1)
            return norm(np.concatenate([model.call("qdot", self.data, q=q1, v=v1), v_dot1]) - f0)

        with np.errstate(all="ignore"):
            d0, d1 = norm(y0), norm(f0)
        return self._starting_step(d0, d1, rate_change, 3)

    # ------------------------------------------------------------------ the step

    def _step(self) -> None:
        model = self.model
        n_v, n_c = model.n_v, model.n_c
        t0, q0, v0 = self.t, self.q, self.v
        w0, wd0, _ = model.law_values(t0, self.data)
        F0, J, kept = self._linearise(q0, v0, w0, wd0)
        sel = np.concatenate([np.arange(2 * n_v), 2 * n_v + kept, 2 * n_v + n_c + kept])
        J = J[sel][:, sel] if self._sparse else J[np.ix_(sel, sel)]
        F0 = F0[sel]
        y0 = np.concatenate([np.zeros(n_v), v0, self.lam_ggl[kept], self.mu[kept]])
        magnitude = np.where(self._q_of_v >= 0, np.abs(q0[np.maximum(self._q_of_v, 0)]), 1.0)
        # each coordinate's own atol (translations, rotations and their rates), mapped as _atol
        atol = (np.concatenate([self.atol_tangent, np.full(2 * kept.size, self.atol)])
                * self._rtol / self.rtol)
        base_scale = atol + self._rtol * np.abs(np.concatenate([magnitude, y0[n_v:]]))
        step = _Step(t0, q0, y0, kept, sel)
        first = self.counters.steps == 0
        rejected = False
        reason = ""
        while True:
            h = self.next_step()
            if h < 1e-14 * max(1.0, abs(self.t_bound), abs(t0)):
                # near a singular configuration the iteration matrix is nearly singular: Newton's
                # method fails there at every step size (the N-four-bar lying flat)
                where = self._singular_pose()
                raise IntegrationError(f"the step size fell to {h:.3g} s ({reason})"
                                       + (f": {where}" if where else ""))
            scale = base_scale.copy()
            scale[2 * n_v:] /= h  # index-2 components weighted by h, as in RADAU5
            try:
                solve = self._factorise(h, J, sel.size, kept.size)
                Z, iterations, theta = self._newton(h, step, solve, scale)
            except NewtonFailure as failure:
                reason = str(failure)
                self.counters.rejected += 1
                rejected = True
                self.h = h * failure.factor
                continue
            error = self._error(h, step, solve, scale, Z, F0, first or rejected)
            cfac = self.safety * (1 + 2 * self.max_newton)
            fac = min(self.safety, cfac / (iterations + 2 * self.max_newton))
            quot = max(1.0 / self.max_factor, min(1.0 / self.min_factor, error**0.25 / fac))
            if error < 1.0:
                break
            reason = f"the error test failed, error {error:.3g} at h = {h:.3g} s"
            self.counters.rejected += 1
            self.h = h * 0.1 if first else h / quot  # RADAU5: a tenth until a step is accepted
            rejected = True
        # accepted: Gustafsson's predictive controller, no growth right after a rejection
        if self.gustafsson and self._h_acc is not None:
            predictive = (self._h_acc / h) * (error**2 / self._err_acc) ** 0.25 / self.safety
            quot = max(quot, max(1.0 / self.max_factor, min(1.0 / self.min_factor, predictive)))
        self._h_acc, self._err_acc = h, max(1e-2, error)
        h_new = min(h / quot, h) if rejected else h / quot
        if self._kappa is not None and self.newton_rate:
            # Newton's contraction grows like h^2 (the Jacobian is frozen at the step's start):
            # no growth beyond the step where it is predicted to reach newton_rate
            h_new = min(h_new, max(h, np.sqrt(self.newton_rate / self._kappa)))
        self.h = h_new
        self._accept(h, step, Z)

    def _linearise(self, q, v, w, wd):
        """``F(y_n)``, the Jacobian at the start of the step and the rows kept by the rank
        decision (the multipliers re-expressed on them when some were carried elsewhere)."""
        model, n_c = self.model, self.model.n_c
        F0, J, Phi_v = self._evaluate_start(q, v, w, wd)
        kept = np.arange(n_c)
        if n_c:
            # the rank is decided to the accuracy of the state: off the constraints by e (the
            # Newton iterations' stopping error, 7e-7 on Bricard's mechanism at rtol 1e-6), a
            # redundant row stands about e away from the span of the others (1.8e-9 there, with
            # the model's tolerance 1e-9): kept, it made the iteration matrix singular to
            # within e, and Newton's method diverged at every step size
            n_v = model.n_v
            violation = np.abs(F0[2 * n_v:2 * n_v + n_c] / model.row_scale).max()
            W, d = equilibrate(Phi_v, model.mass_inv_sqrt)
            split = split_rows(W, d, model.row_priority,
                               max(model.rank_tolerance, RANK_MARGIN * violation),
                               groups=model.row_groups)
            self.counters.factorisations += 1
            kept = np.sort(split.independent)
            dropped = np.setdiff1d(np.arange(n_c), kept)
            if dropped.size and (np.any(self.lam_ggl[dropped]) or np.any(self.mu[dropped])):
                # the same forces Phi_v^T lam and rates Phi_v^T mu from the kept rows alone
                for values in (self.lam_ggl, self.mu):
                    on_kept = kept_multipliers(split, Phi_v, values, model.mass_inv_sqrt)
                    values[:] = 0.0
                    values[split.independent] = on_kept
                F0, J, Phi_v = self._evaluate_start(q, v, w, wd)
        return F0, J, kept

    def _evaluate_start(self, q, v, w, wd):
        values = {"q0": q, "xi": np.zeros(self.model.n_v), "v": v, "lam": self.lam_ggl,
                  "mu": self.mu, "w": w, "wd": wd}
        start = self._fn["start"]
        F, J, Phi_v = start(*[values[n] for n in start.name_in()])
        self.counters.rhs += 1
        self.counters.jacobians += 1
        J = J.sparse().tocsr() if self._sparse else J.full()
        if self._large:
            from scipy.sparse import csr_array

            return F.full().reshape(-1), J, csr_array(Phi_v.sparse())
        return F.full().reshape(-1), J, Phi_v.full()

    def _mass_times(self, x: np.ndarray) -> np.ndarray:
        """``M_y x`` for vectors or (3, n) stacks: ``x`` on ``xi``, ``M x`` on ``v``, 0 on the
        multipliers."""
        n_v = self.model.n_v
        out = np.zeros_like(x)
        out[..., :n_v] = x[..., :n_v]
        out[..., n_v:2 * n_v] = x[..., n_v:2 * n_v] @ self._mass.T
        return out

    def _factorise(self, h, J, n, m):
        """LU of the scaled real and complex iteration matrices (dense, or sparse for large
        models); a solver of the unscaled ones."""
        n_v = self.model.n_v
        rows = np.concatenate([np.full(2 * n_v, h), np.ones(2 * m)])
        columns = np.concatenate([np.ones(2 * n_v), np.full(2 * m, 1.0 / h)])
        if self._sparse:
            My = sparse.block_diag([sparse.identity(n_v), self._mass,
                                    sparse.csr_matrix((2 * m, 2 * m))], format="csr")
            R, C_ = sparse.diags(rows), sparse.diags(columns)
        else:
            My = np.zeros((n, n))
            My[:n_v, :n_v] = np.eye(n_v)
            My[n_v:2 * n_v, n_v:2 * n_v] = self._mass
        solvers = []
        for shift in (GAMMA / h, (ALPHA - 1j * BETA) / h):
            self.counters.factorisations += 1
            if self._sparse:
                try:
                    solvers.append(splu((R @ (shift * My - J) @ C_).tocsc()).solve)
                except RuntimeError:  # SuperLU: the factor is exactly singular
                    raise NewtonFailure(
                        f"the iteration matrix is singular at h = {h:.3g} s") from None
                continue
            matrix = rows[:, None] * (shift * My - J) * columns[None, :]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # a singular matrix is caught below
                lu = lu_factor(matrix, check_finite=False)
            if not np.all(np.isfinite(lu[0])) or np.any(np.diag(lu[0]) == 0):
                raise NewtonFailure(f"the iteration matrix is singular at h = {h:.3g} s")
            solvers.append(lambda b, lu=lu: lu_solve(lu, b, check_finite=False))

        def solve(k, b):
            return columns * solvers[k](rows * b)

        return solve

    def _residuals(self, step, Y, times):
        """``F`` at the states ``Y`` (rows: stages) of the kept components, at ``times``."""
        model = self.model
        n_v, n_c, m = model.n_v, model.n_c, step.kept.size
        count = Y.shape[0]
        if self._rot.size:
            xi = Y[:, self._rot]
            if np.any(np.sum(xi * xi, axis=-1) >= np.pi**2):
                raise NewtonFailure("a body turned by more than pi within the step")
        lam, mu = np.zeros((count, n_c)), np.zeros((count, n_c))
        lam[:, step.kept] = Y[:, 2 * n_v:2 * n_v + m]
        mu[:, step.kept] = Y[:, 2 * n_v + m:]
        w, wd, _ = model.law_values(times, self.data)
        values = {"q0": step.q0, "xi": Y[:, :n_v].T, "v": Y[:, n_v:2 * n_v].T, "lam": lam.T,
                  "mu": mu.T, "w": w, "wd": wd}
        function = self._fn["stages" if count == 3 else "residual"]
        F = function(*[values[n] for n in function.name_in()]).full().T
        self.counters.rhs += count
        return F[:, step.sel]

    def _newton(self, h, step, solve, scale):
        """Simplified Newton iterations on the transformed stage increments ``W = T^-1 Z``
        with RADAU5's convergence control; the stage increments and the iterations taken."""
        Z = self._starting_values(h, step)
        W = TI @ Z
        times = step.t0 + C * h
        self._faccon = max(self._faccon, np.finfo(float).eps) ** 0.8
        dyn_old = theta_old = 1.0
        iteration, theta = 0, None
        while True:
            if iteration >= self.max_newton:
                raise NewtonFailure(f"Newton's method does not converge at h = {h:.3g} s")
            F = self._residuals(step, step.y0 + Z, times)
            if not np.all(np.isfinite(F)):
                raise NewtonFailure(f"non-finite residuals at h = {h:.3g} s")
            MW = self._mass_times(W)
            G = TI @ F - np.array([GAMMA * MW[0], ALPHA * MW[1] + BETA * MW[2],
                                   ALPHA * MW[2] - BETA * MW[1]]) / h
            complex_part = solve(1, G[1] + 1j * G[2])
            dW = np.array([solve(0, G[0]), complex_part.real, complex_part.imag])
            iteration += 1
            self.counters.newton += 1
            if not np.all(np.isfinite(dW)):
                raise NewtonFailure(f"Newton's method diverges at h = {h:.3g} s")
            dyn = float(np.sqrt(np.mean((dW / scale) ** 2)))
            if 1 < iteration < self.max_newton:
                ratio = dyn / dyn_old
                theta = ratio if iteration == 2 else np.sqrt(ratio * theta_old)
                theta_old = ratio
                self._kappa = theta / h**2
                if theta >= 0.99:
                    raise NewtonFailure(f"Newton's method diverges at h = {h:.3g} s")
                self._faccon = theta / (1.0 - theta)
                # the error left after the remaining iterations, predicted
                left = self.max_newton - 1 - iteration
                predicted = self._faccon * dyn * theta**left / self._fnewt
                if predicted >= 1.0:
                    qnewt = max(1e-4, min(20.0, predicted))
                    raise NewtonFailure(f"Newton's method converges too slowly at h = {h:.3g} s",
                                        0.8 * qnewt ** (-1.0 / (4 + left)))
            dyn_old = max(dyn, np.finfo(float).eps)
            W = W + dW
            Z = T @ W
            if self._faccon * dyn <= self._fnewt:
                return Z, iteration, theta

    def _starting_values(self, h, step):
        """The previous step's collocation polynomial extrapolated to the new stages, its
        rotations carried over to the new local coordinates; zero on the first step."""
        if self._previous is None:
            return np.zeros((3, step.sel.size))
        h_old, Z_old = self._previous
        P = _extrapolation(h / h_old) @ Z_old  # from the previous step's start
        Z = P - Z_old[2]
        if self._rot.size:
            # R_old Exp(P_i) = R_n Exp(Z_i) with R_n = R_old Exp(Z3_old)
            back = quaternion_exp(-Z_old[2, self._rot])
            Z[:, self._rot] = quaternion_log(quaternion_product(back,
                                                                quaternion_exp(P[:, self._rot])))
        return Z[:, step.sel]

    def _error(self, h, step, solve, scale, Z, F0, again):
        """Hairer's estimate of the local error in the weighted RMS norm (below 1: accept)."""
        mass_part = self._mass_times(E @ Z / h)
        estimate = solve(0, F0 + mass_part)
        error = max(float(np.sqrt(np.mean((estimate / scale) ** 2))), 1e-10)
        if error >= 1.0 and again:
            # after a rejection (and on the first step) the estimate is filtered once more
            # through F at y_n + err, which removes its stiff components (RADAU5)
            try:
                F = self._residuals(step, (step.y0 + estimate)[None, :], np.array([step.t0]))
            except NewtonFailure:
                return np.inf
            estimate = solve(0, F[0] + mass_part)
            error = max(float(np.sqrt(np.mean((estimate / scale) ** 2))), 1e-10)
        return error if np.isfinite(error) else np.inf

    def _accept(self, h, step, Z):
        model = self.model
        n_v, n_c, m = model.n_v, model.n_c, step.kept.size
        full = np.zeros((3, self._n_full))
        full[:, step.sel] = Z
        self._previous = (h, full)
        y = step.y0 + Z[2]  # stiffly accurate: the last stage is the new state
        self._collocation = (step.t0, h, step.q0, step.y0[:2 * n_v], Z[:, :2 * n_v])
        self.t = step.t0 + h
        self.q = model.integrate(step.q0, y[:n_v])
        self.v = y[n_v:2 * n_v]
        self.lam_ggl, self.mu = np.zeros(n_c), np.zeros(n_c)
        self.lam_ggl[step.kept], self.mu[step.kept] = y[2 * n_v:2 * n_v + m], y[2 * n_v + m:]
        self.v_dot, self.lam = self._dynamics(self.t, self.q, self.v)

    def dense_output(self) -> Interpolant:
        """The collocation polynomial of the last step (order 3, the stage order): the cubic
        through the start and the three Radau IIA stages at ``c = (4 - sqrt 6)/10, (4 + sqrt
        6)/10, 1``, in the step's local coordinates ``(xi, v)``, the positions ``q_n (+) xi``
        (:data:`~.tableaus.RADAU_DENSE`, as SciPy's ``Radau`` dense output)."""
        return _CollocationInterpolant(self.model, *self._collocation)


class _CollocationInterpolant(Interpolant):
    """``y(t_old + theta h) = y_old + Z^T P [theta, theta^2, theta^3]`` on ``y = (xi, v)``,
    ``Z`` the stage increments (SciPy's ``RadauDenseOutput``), ``q = q_old (+) xi``."""

    order = 3

    def __init__(self, model, t_old, h, q_old, y_old, Z):
        super().__init__(model, t_old, t_old + h)
        self.q_old, self.y_old, self.Q = q_old, y_old, Z.T @ RADAU_DENSE

    def _evaluate(self, theta):
        y = self.y_old + self.Q @ np.array([theta, theta**2, theta**3])
        n_v = self.model.n_v
        return self.model.integrate(self.q_old, y[:n_v]), y[n_v:]


@dataclass(frozen=True)
class _Step:
    """What the attempts of one step share: its start and the components kept."""

    t0: float
    q0: np.ndarray
    y0: np.ndarray  # (0, v_n, lambda_n, mu_n) on the kept components
    kept: np.ndarray  # constraint rows kept by the rank decision
    sel: np.ndarray  # kept components of y = (xi, v, lambda, mu)
