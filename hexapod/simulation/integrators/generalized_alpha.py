"""The generalized-alpha method on Lie groups, stabilised at index 2.

Arnold and Bruls (2007), Bruls, Cardona and Arnold (2012), and for the stabilised index-2 form
Arnold, Bruls and Cardona (2015): at the end of each step the equations of motion and the
constraints on positions *and* velocities are solved,

    M v_dot + Phi_v^T lambda = Q(q, v, t),   phi(q, t) = 0,   Phi_v v = nu(q, t).

**Groups.** Each body moves on its own group, in twist coordinates: a spatial body on SE(3),
``V = (u, omega')`` with ``u = R^T x_dot`` the centre of mass's velocity in body axes; a planar
body on SE(2) likewise; a particle on R^3. ``v = T(q) V`` (``T`` rotates the linear parts to
world axes), and the equations of motion read, per body, ``M (V_dot + k(V)) + Phi_V^T lambda =
T^T Q`` with ``Phi_V = Phi_v T`` and ``k = (omega' x u, 0)`` the rate of the body axes. A step
composes each body's pose with the exponential of its increment ``xi`` (SE(3): ``R <- R
exp(omega_xi)``, ``x <- x + R J_l(omega_xi) u_xi``, ``J_l`` the left Jacobian of SO(3)). A body
turning about a point fixed in it (a pendulum, a crank) moves on a one-parameter subgroup: the
update follows it exactly and, in body axes, its joint's constraint Jacobian is constant, so
the method reduces to generalized-alpha in the joint coordinate. On R^3 x SO(3) the centre of
mass moves by chords of its circle instead: the pendulum released horizontal at 20 steps per
period gained a third of its energy over 100 periods even with both constraint levels imposed.

**The method** (Chung and Hulbert 1993, on the group):

    q_n+1 = q_n exp(xi),   xi = h (V_n + h (1/2 - beta) a_n + h beta a_n+1) + P eta,
    V_n+1 = V_n + h (1 - gamma) a_n + h gamma a_n+1,
    (1 - alpha_m) a_n+1 + alpha_m a_n = (1 - alpha_f) V_dot_n+1 + alpha_f V_dot_n,

``a`` the pseudo-accelerations, ``eta`` the multipliers of the velocity constraints (GGL: they
move the positions by ``P eta``, ``P = M^-1/2 W_n^T`` with ``W_n`` the equilibrated
``Phi_V(q_n)``, and vanish to ``O(h^3)`` along exact motions). The parameters follow from the
spectral radius at infinity ``rho_inf`` (1 keeps every frequency, 0 damps the highest in one
step): ``alpha_m = (2 rho - 1) / (rho + 1)``, ``alpha_f = rho / (rho + 1)``,
``gamma = 1/2 + alpha_f - alpha_m``, ``beta = (gamma + 1/2)^2 / 4``: second order. The start
is Arnold and Bruls's ``a_0 = V_dot(t0) + (alpha_m - alpha_f) h V_ddot(t0)`` (``V_ddot`` by a
difference of the dynamics): with ``a_0 = V_dot(t0)`` the pseudo-accelerations start ``O(h)``
off and the multipliers oscillate.

Why index 2: at index 3 (positions constrained, velocities not) the velocities' component
across the constraints follows the pseudo-accelerations' recursion, whose roots there are
``-rho_inf`` twice (a Jordan block); on curved constraints it feeds back into the motion, and on
the pendulum released horizontal at 20 and 40 steps per period (rho_inf 0.9) it grew until
Newton's method failed after 21 s.

**Newton's method** on ``(dxi, dlambda, deta)`` with the exact Jacobian (CasADi, through the
exponential): with ``beta' = (1 - alpha_m) / (beta h^2 (1 - alpha_f))`` and
``gamma' = gamma / (beta h)``, the rows of the equations of motion are divided by ``beta'`` (the
multipliers with them) and those of the velocity constraints by ``gamma'``, which keeps the
iteration matrix as well conditioned as the dynamic saddle-point system whatever the step. It
stops when the residuals are ``newton_tol`` of the size of their terms (the constraints' relative
to the characteristic length). When it does not converge the step is halved and retried, then
grown back.

**Redundant and nearly dependent rows.** The rank decision of
:func:`hexapod.algorithms.kinematics.rank_split` at ``q_n`` keeps the independent rows: Newton's
method solves with them (their multipliers carried over from the step before), and the others,
which follow from them, are checked after it to ``redundant_tol``; their multipliers are set by
the redundancy policy. Near a singular configuration (the N-four-bar lying flat) the iteration
matrix is nearly singular: a solve that the LU factorisation cannot trust is done by least
squares instead, which moves along the nearly dependent directions no more than the residuals
ask.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod._support.fastcall import ScatteredFunction
from hexapod.algorithms.dynamics import forward_dynamics
from hexapod.algorithms.kinematics import rank_split
from hexapod.algorithms.liaison import policy_map
from hexapod.algorithms.linalg import as_dense, distribute, solve_or_least_squares
from hexapod.algorithms.saddle import constraint_jacobian, is_large, kept_multipliers, solve_sparse
from hexapod.algorithms.step import sparse_dm
from hexapod.errors import HexapodError
from hexapod.simulation.integrators.base import Integrator
from hexapod.simulation.integrators.interpolants import Interpolant
from hexapod.simulation.methods import METHODS
from hexapod.spatial import quaternion_product, rotation_from_euler_parameters

# ---------------------------------------------------------------- the groups, for CasADi


def _series(x2, small, series, exact):
    """``series(x2)`` below the threshold ``small`` (on ``x2 = |x|^2``), else ``exact(x)`` with
    ``x`` kept away from zero, so that both branches and their derivatives stay finite."""
    safe = ca.sqrt(ca.if_else(small, 1.0, x2))
    return ca.if_else(small, series(x2), exact(safe))


def _so3_exp(x):
    """Unit Euler parameters of the rotation vector ``x`` (SX)."""
    x2 = ca.dot(x, x)
    small = x2 < 1e-6
    c = _series(x2, small, lambda s: 1 - s / 8 + s**2 / 384, lambda t: ca.cos(t / 2))
    s = _series(x2, small, lambda s: 0.5 - s / 48 + s**2 / 3840, lambda t: ca.sin(t / 2) / t)
    return ca.vertcat(c, s * x)


def _so3_left_jacobian(x, u):
    """``J_l(x) u = u + (1 - cos t)/t^2 x cross u + (t - sin t)/t^3 x cross (x cross u)``,
    ``t = |x|`` (the translation of the SE(3) exponential of ``(u, x)``)."""
    x2 = ca.dot(x, x)
    small = x2 < 1e-6
    a = _series(x2, small, lambda s: 0.5 - s / 24 + s**2 / 720,
                lambda t: (1 - ca.cos(t)) / t**2)
    b = _series(x2, small, lambda s: 1.0 / 6 - s / 120 + s**2 / 5040,
                lambda t: (t - ca.sin(t)) / t**3)
    xu = ca.cross(x, u)
    return u + a * xu + b * ca.cross(x, xu)


def _se2_translation(angle, u):
    """The translation of the SE(2) exponential of ``(u, angle)``: ``[[s, -c], [c, s]] u`` with
    ``s = sin(angle)/angle``, ``c = (1 - cos(angle))/angle``."""
    x2 = angle * angle
    small = x2 < 1e-6
    s = _series(x2, small, lambda s: 1 - s / 6 + s**2 / 120, lambda t: ca.sin(t) / t)
    c = angle * _series(x2, small, lambda s: 0.5 - s / 24 + s**2 / 720,
                        lambda t: (1 - ca.cos(t)) / t**2)
    return ca.vertcat(s * u[0] - c * u[1], c * u[0] + s * u[1])


def _planar_rotation(angle):
    c, s = ca.cos(angle), ca.sin(angle)
    return ca.vertcat(ca.horzcat(c, -s), ca.horzcat(s, c))


def step_function(model) -> ca.Function:
    """The residuals of a step and their derivatives, built once per model
    (:meth:`Model.built_once`; each integrator calls it through buffers of its own) on
    arrays: ``(q0, xi, V, A, lam[, w, wd])`` -> the
    positions
    ``q = q0 exp(xi)``, the velocities ``v = T(q) V`` and accelerations ``T (A + k(V))``,
    the residuals ``r = (M (A + k) + Phi_V^T lam - T^T Q, phi, Phi_V V - nu)``, their Jacobians
    in ``xi`` and in ``V``, ``Phi_V`` and ``T^T Q`` (the sizes of the terms)."""
    return model.built_once(("generalized-alpha", "SE(3)"), _build_step_function)


#: the outputs of :func:`step_function`, in order
OUTPUTS = ("q", "v", "v_dot", "r", "r_xi", "r_V", "Phi_V", "TtQ")


def _build_step_function(model) -> ca.Function:
    n_q, n_v, n_c, n_w = model.n_q, model.n_v, model.n_c, model.n_w
    q0, xi = ca.SX.sym("q0", n_q), ca.SX.sym("xi", n_v)
    V, A = ca.SX.sym("V", n_v), ca.SX.sym("A", n_v)
    lam = ca.SX.sym("lam", n_c)
    w, wd = ca.SX.sym("w", n_w), ca.SX.sym("wd", n_w)
    q_parts, v_parts, k_parts = [], [], []
    T = ca.SX.eye(n_v)
    for b in model.bodies:
        qb, xb, Vb = q0[b.q.start:b.q.stop], xi[b.v.start:b.v.stop], V[b.v.start:b.v.stop]
        lin = slice(b.v.start, b.v.start + (2 if b.kind == "planar" else 3))
        if b.kind == "spatial":
            p1 = quaternion_product(qb[3:], _so3_exp(xb[3:]))
            R0, R1 = rotation_from_euler_parameters(qb[3:]), rotation_from_euler_parameters(p1)
            q_parts += [qb[:3] + ca.mtimes(R0, _so3_left_jacobian(xb[3:], xb[:3])), p1]
            v_parts += [ca.mtimes(R1, Vb[:3]), Vb[3:]]
            k_parts += [ca.cross(Vb[3:], Vb[:3]), ca.SX.zeros(3)]
            T[lin, lin] = R1
        elif b.kind == "planar":
            theta1 = qb[2] + xb[2]
            R1 = _planar_rotation(theta1)
            q_parts += [qb[:2] + ca.mtimes(_planar_rotation(qb[2]),
                                           _se2_translation(xb[2], xb[:2])), theta1]
            v_parts += [ca.mtimes(R1, Vb[:2]), Vb[2]]
            k_parts += [Vb[2] * ca.vertcat(-Vb[1], Vb[0]), ca.SX.zeros(1)]
            T[lin, lin] = R1
        else:
            q_parts.append(qb + xb)
            v_parts.append(Vb)
            k_parts.append(ca.SX.zeros(b.v.stop - b.v.start))
    q, v, k = ca.vertcat(*q_parts), ca.vertcat(*v_parts), ca.vertcat(*k_parts)
    symbols = {"q": q, "v": v, "w": w, "wd": wd}

    def call(function):
        return function(*[symbols[name] for name in function.name_in()])

    Phi_V = ca.mtimes(call(model.Phi_v), T)
    TtQ = ca.mtimes(T.T, call(model.Q))
    rate = A + k
    r = ca.vertcat(ca.mtimes(sparse_dm(model.mass.sparse()), rate) + ca.mtimes(Phi_V.T, lam)
                   - TtQ,
                   call(model.phi), ca.mtimes(Phi_V, V) - call(model.nu))
    names = ["q0", "xi", "V", "A", "lam"] + (["w", "wd"] if n_w else [])
    inputs = [q0, xi, V, A, lam] + ([w, wd] if n_w else [])
    outputs = {"q": q, "v": v, "v_dot": ca.mtimes(T, rate), "r": r,
               "r_xi": ca.jacobian(r, xi), "r_V": ca.jacobian(r, V), "Phi_V": Phi_V,
               "TtQ": TtQ}
    assert tuple(outputs) == OUTPUTS
    return ca.Function("generalized_alpha_step", inputs, list(outputs.values()), names,
                       list(outputs))


class _Frames:
    """Twists from the model's velocities and back, in numbers: the linear velocities of
    spatial and planar bodies rotated to body axes (``V = T^T v``)."""

    def __init__(self, model):
        spatial = [b for b in model.bodies if b.kind == "spatial"]
        planar = [b for b in model.bodies if b.kind == "planar"]
        self.quaternions = np.array([np.arange(b.q.start + 3, b.q.stop) for b in spatial],
                                    dtype=int).reshape(-1, 4)
        self.spatial_lin = np.array([np.arange(b.v.start, b.v.start + 3) for b in spatial],
                                    dtype=int).reshape(-1, 3)
        self.spatial_omega = self.spatial_lin + 3
        self.angles = np.array([b.q.start + 2 for b in planar], dtype=int)
        self.planar_lin = np.array([np.arange(b.v.start, b.v.start + 2) for b in planar],
                                   dtype=int).reshape(-1, 2)
        self.planar_omega = self.planar_lin[:, 0] + 2
        self.size = model.n_v

    def to_body(self, q: np.ndarray, x: np.ndarray) -> np.ndarray:
        """``T(q)^T x``."""
        out = np.array(x, dtype=float)
        for p, lin in zip(q[self.quaternions], self.spatial_lin, strict=True):
            out[lin] = rotation_from_euler_parameters(p).T @ out[lin]
        shape = (-1,) + (1,) * (out.ndim - 1)  # x may have columns
        c = np.cos(q[self.angles]).reshape(shape)
        s = np.sin(q[self.angles]).reshape(shape)
        xs, ys = out[self.planar_lin[:, 0]], out[self.planar_lin[:, 1]]
        out[self.planar_lin[:, 0]], out[self.planar_lin[:, 1]] = c * xs + s * ys, c * ys - s * xs
        return out

    def to_body_matrix(self, q: np.ndarray):
        """``T(q)^T`` as a SciPy CSR array (block-diagonal rotations)."""
        from scipy.sparse import coo_array

        n = self.size
        rows, columns, values = [np.arange(n)], [np.arange(n)], [np.ones(n)]
        keep = np.ones(n, dtype=bool)  # the identity outside the rotated blocks
        for p, lin in zip(q[self.quaternions], self.spatial_lin, strict=True):
            keep[lin] = False
            rows.append(np.repeat(lin, 3))
            columns.append(np.tile(lin, 3))
            values.append(rotation_from_euler_parameters(p).T.reshape(-1))
        for angle, lin in zip(q[self.angles], self.planar_lin, strict=True):
            keep[lin] = False
            c, s = np.cos(angle), np.sin(angle)
            rows.append(np.repeat(lin, 2))
            columns.append(np.tile(lin, 2))
            values.append(np.array([c, s, -s, c]))
        rows[0], columns[0], values[0] = rows[0][keep], columns[0][keep], values[0][keep]
        return coo_array((np.concatenate(values), (np.concatenate(rows),
                                                   np.concatenate(columns))),
                         shape=(n, n)).tocsr()

    def rate(self, V: np.ndarray) -> np.ndarray:
        """``k(V)``: the rate of the body axes' turning, ``(omega' x u, 0)`` per body."""
        k = np.zeros_like(V)
        if self.spatial_lin.size:
            k[self.spatial_lin] = np.cross(V[self.spatial_omega], V[self.spatial_lin])
        omega = V[self.planar_omega]
        k[self.planar_lin[:, 0]] = -omega * V[self.planar_lin[:, 1]]
        k[self.planar_lin[:, 1]] = omega * V[self.planar_lin[:, 0]]
        return k


class LieGroupGeneralizedAlpha(Integrator):
    """Generalized-alpha on SE(3) (SE(2), R^3) per body, both constraint levels imposed (index
    2, GGL), fixed step (halved on Newton failure).

    ``rho_inf`` (0.9 by default): spectral radius at infinity. ``newton_tol``: tolerance on the
    residuals relative to the size of their terms (the position constraints': to the
    characteristic length). ``redundant_tol``: how far the rows left out by the rank decision
    may be violated after a step (relative, as ``newton_tol``) before the step is refused.
    """

    name = "generalized-alpha"
    order, index, adaptive, stabilisation = METHODS[name]
    description = ("Lie-group generalized-alpha (Arnold, Bruls, Cardona) on SE(3), "
                   "stabilised index 2")
    max_iterations = 25
    redundant_tol = 1e-8

    def __init__(self, *args, rho_inf: float = 0.9, newton_tol: float = 1e-12, **kwargs):
        if not 0.0 <= rho_inf <= 1.0:
            raise ValueError(f"rho_inf must be in [0, 1], got {rho_inf}")
        if not newton_tol > 0:
            raise ValueError(f"newton_tol must be positive, got {newton_tol}")
        rho = rho_inf
        self.alpha_m = (2 * rho - 1) / (rho + 1)
        self.alpha_f = rho / (rho + 1)
        self.gamma = 0.5 + self.alpha_f - self.alpha_m
        self.beta = 0.25 * (self.gamma + 0.5) ** 2
        self.newton_tol = float(newton_tol)
        super().__init__(*args, **kwargs)

    def _start(self) -> None:
        model = self.model
        self.nominal = self.h
        # a large model's Newton systems are sparse, solved by a sparse LU (see the module's
        # description); the sizes of the residuals' terms through sparse products either way
        self.large = is_large(model)
        self.mass = model.mass.sparse()
        self.mass_abs, self.mass_inv_abs = abs(self.mass), abs(model.mass_inv.sparse())
        self.mass_inv_sqrt = (model.mass_inv_sqrt.sparse() if self.large
                              else model.mass_inv_sqrt.dense())
        self.frames = _Frames(model)
        self.function = ScatteredFunction(step_function(model))
        self.failure = ""  # why the last attempt failed
        self.decision = None  # (q, Phi_v, rank decision) at the last state decided
        self.kept = None  # (rows kept, their multipliers) of the last step
        V = self.frames.to_body(self.q, self.v)
        rate = self._twist_rate(self.q, V, self.v_dot)
        self.a = rate + (self.alpha_m - self.alpha_f) * self.h * self._rate_change(V, rate)

    def _step(self) -> None:
        self._dense_start = (self.t, self.q, self.v, self.v_dot)  # for dense_output
        h, result = self._halving(self._attempt)
        self.t, self.q, self.v, self.v_dot, self.a, self.lam = result
        self.h = min(self.nominal, 2 * h) if h < self.nominal else self.h

    def _twist_rate(self, q: np.ndarray, V: np.ndarray, v_dot: np.ndarray) -> np.ndarray:
        """``V_dot = T^T v_dot - k(V)``."""
        return self.frames.to_body(q, v_dot) - self.frames.rate(V)

    def _rate_change(self, V: np.ndarray, rate: np.ndarray) -> np.ndarray:
        """``V_ddot`` at the start, by a difference of the dynamics over ``1e-3 h`` along the
        motion; zero (``a_0 = V_dot(t0)``) where the dynamics there cannot be solved."""
        delta = 1e-3 * self.h
        try:
            q1, v1 = self._project(self.t + delta, self.model.integrate(self.q, delta * self.v),
                                   self.v + delta * self.v_dot)
            v_dot1 = forward_dynamics(self.model, self.model.create_data(), self.t + delta,
                                      q1, v1)
        except (HexapodError, np.linalg.LinAlgError, ArithmeticError):
            return np.zeros_like(rate)
        self.counters.rhs += 1
        self.counters.jacobians += 1
        self.counters.factorisations += 1
        change = (self._twist_rate(q1, self.frames.to_body(q1, v1), v_dot1) - rate) / delta
        return change if np.all(np.isfinite(change)) else np.zeros_like(rate)

    def _attempt(self, h: float):
        """One step of length ``h``: ``(t, q, v, v_dot, a, lam)``, or None when Newton's method
        fails (``failure`` says why)."""
        model, am, af, beta, gamma = self.model, self.alpha_m, self.alpha_f, self.beta, self.gamma
        beta_p = (1 - am) / (beta * h**2 * (1 - af))
        gamma_p = gamma / (beta * h)
        t = self.t + h
        w, wd, _ = model.law_values(t, self.data)
        laws = [w, wd] if model.n_w else []
        n, n_c = model.n_v, model.n_c
        # the rows kept, decided at the start of the step, and the multipliers carried onto them
        Phi_n, split = self._rank_decision(self.t, self.q)
        I = split.independent
        m = I.size
        lam = np.zeros(n_c)
        if self.kept is not None and np.array_equal(self.kept[0], I):
            lam[I] = self.kept[1]  # the last step's, on the same rows
        elif m:
            lam[I] = kept_multipliers(split, Phi_n, self.lam, model.mass_inv_sqrt)
        # the positions' correction P eta (GGL), P = M^-1/2 W_n^T in twist coordinates
        if self.large:
            P = self.mass_inv_sqrt @ (self.frames.to_body_matrix(self.q) @ split.W[I].T)
        else:
            P = self.mass_inv_sqrt @ self.frames.to_body(self.q, split.W[I].T)
        # predictor: the accelerations as at the start of the step
        V_n = self.frames.to_body(self.q, self.v)
        A_n = self._twist_rate(self.q, V_n, self.v_dot)
        A = A_n.copy()
        a = (af * A_n + (1 - af) * A - am * self.a) / (1 - am)
        V = V_n + h * (1 - gamma) * self.a + h * gamma * a
        # the step on the group, kept as one increment from q_n (composing Newton's corrections
        # one by one would not give q_n exp(xi): the group does not commute)
        xi = h * (V_n + h * (0.5 - beta) * self.a + h * beta * a)
        eta = np.zeros(m)
        d = split.scale[I]
        residual_norm = np.inf
        evaluate = self.function.sparse if self.large else self.function
        for iteration in range(self.max_iterations + 1):
            out = dict(zip(OUTPUTS, evaluate(self.q, xi + P @ eta, V, A, lam, *laws),
                           strict=True))
            self.counters.rhs += 1
            r = out["r"]
            if not np.all(np.isfinite(r)):
                self.failure = f"non-finite residuals at h = {h:.3g} s"
                return None
            Phi_V, TtQ = out["Phi_V"], out["TtQ"]
            errors, speeds = self._errors(h, r, xi, V, A, lam, Phi_V, TtQ, I)
            if max(errors) <= self.newton_tol:
                break
            if iteration == self.max_iterations:
                self.failure = (f"Newton's method does not converge at h = {h:.3g} s "
                                f"(scaled residuals {max(errors):.1e})")
                return None
            if max(errors) > 1e3 * residual_norm and iteration > 2:
                self.failure = f"Newton's method diverges at h = {h:.3g} s"
                return None
            residual_norm = max(errors)
            self.counters.jacobians += 1
            self.counters.newton += 1
            solution = self._newton_correction(out, P, I, d, beta_p, gamma_p)
            self.counters.factorisations += 1
            if solution is None:
                self.failure = f"the iteration matrix is singular at h = {h:.3g} s"
                return None
            dx, dmu, deta = solution[:n], solution[n:n + m], solution[n + m:]
            xi = xi + dx
            V = V + gamma_p * dx
            A = A + beta_p * dx
            a = a + dx / (beta * h**2)
            lam[I] = lam[I] + beta_p * dmu
            eta = eta + deta
        q, v = model.normalize(out["q"]), out["v"]
        if split.redundant.size:
            left_out = max(np.abs(r[n + split.redundant] / model.row_scale[split.redundant]).max(),
                           self._velocity_errors(r, speeds, Phi_V, split.redundant))
            if left_out > self.redundant_tol:
                names = ", ".join(model.rows[i].name for i in split.redundant[:5])
                self.failure = (f"the rows left out by the rank decision ({names}) are violated "
                                f"by {left_out:.1e} at h = {h:.3g} s")
                return None
        self.kept = (I, lam[I].copy())
        if split.redundant.size:
            lam = self._policy(t, q, v, w, lam)
        return t, q, v, out["v_dot"], a, lam

    def _newton_correction(self, out: dict, P, I: np.ndarray, d: np.ndarray, beta_p: float,
                           gamma_p: float) -> np.ndarray | None:
        """Newton's correction ``(dxi, dmu, deta)`` from the step function's outputs ``out``:
        LU, or where the matrix is nearly singular (near a singular configuration) the
        least-squares correction of least norm. A large model's matrix, as sparse as the
        body-joint graph, is assembled and factorised sparse (SuperLU, COLAMD): its LU costs
        a constant per body where the dense one is cubic (3.7 s per step at 300 bodies)."""
        n, n_c = self.model.n_v, self.model.n_c
        r, r_xi, r_V, Phi_V = out["r"], out["r_xi"], out["r_V"], out["Phi_V"]
        dyn, pos, vel = slice(0, n), n + I, n + n_c + I
        rhs = -np.concatenate([r[dyn] / beta_p, r[pos] / d, r[vel] / (gamma_p * d)])
        if self.large:
            from scipy.sparse import bmat, diags

            rows_pos, rows_vel = diags(1.0 / d) @ r_xi[pos], diags(1.0 / (gamma_p * d))
            S = bmat([[self.mass + (r_xi[dyn] + gamma_p * r_V[dyn]) / beta_p, Phi_V[I].T,
                       r_xi[dyn] @ P / beta_p],
                      [rows_pos, None, rows_pos @ P],
                      [rows_vel @ (r_xi[vel] + gamma_p * r_V[vel]), None,
                       rows_vel @ (r_xi[vel] @ P)]], format="csc")
            return solve_sparse(S, rhs)
        m = I.size
        S = np.zeros((n + 2 * m, n + 2 * m))
        S[:n, :n] = self.mass.toarray() + (r_xi[dyn] + gamma_p * r_V[dyn]) / beta_p
        S[:n, n:n + m] = Phi_V[I].T
        S[:n, n + m:] = r_xi[dyn] @ P / beta_p
        S[n:n + m, :n] = r_xi[pos] / d[:, None]
        S[n:n + m, n + m:] = r_xi[pos] @ P / d[:, None]
        S[n + m:, :n] = (r_xi[vel] + gamma_p * r_V[vel]) / (gamma_p * d[:, None])
        S[n + m:, n + m:] = r_xi[vel] @ P / (gamma_p * d[:, None])
        return solve_or_least_squares(S, rhs)

    def _errors(self, h, r, xi, V, A, lam, Phi_V, TtQ, I):
        """The residuals of the equations of motion, of the kept position and of the kept
        velocity constraints, each relative to the size of its terms (round-off leaves about
        ``1e-16`` of it at the solution), and the size of the velocities: their own, their
        change over the step, and the change each force alone would make (a body held at rest
        has only the last)."""
        model, n = self.model, self.model.n_v
        forces = (np.abs(self.mass @ A) + self.mass_abs @ np.abs(self.frames.rate(V))
                  + np.abs(TtQ) + abs(Phi_V).T @ np.abs(lam))
        dynamics = np.abs(r[:n]).max(initial=0.0) / max(forces.max(initial=0.0),
                                                         np.finfo(float).tiny)
        positions = np.abs(r[n + I] / model.row_scale[I]).max(initial=0.0)
        speeds = np.abs(V) + np.abs(xi) / h + h * (self.mass_inv_abs @ forces)
        return (dynamics, positions, self._velocity_errors(r, speeds, Phi_V, I)), speeds

    def _velocity_errors(self, r, speeds, Phi_V, rows) -> float:
        """The largest residual of the velocity constraints on ``rows``, relative to the size of
        the terms of all of them (``|Phi_V| speeds + |nu|``, over the rows' scales)."""
        model = self.model
        n, n_c = model.n_v, model.n_c
        if not rows.size:
            return 0.0
        residuals = r[n + n_c:] / model.row_scale
        size = (abs(Phi_V) @ speeds + np.abs(r[n + n_c:])) / model.row_scale
        return float(np.abs(residuals[rows]).max() / max(size.max(), np.finfo(float).tiny))

    def _rank_decision(self, t: float, q: np.ndarray):
        """``Phi_v`` and the rank decision at ``(t, q)`` (kept for the next step's start)."""
        if self.decision is not None and self.decision[0] is q:
            return self.decision[1:]
        model = self.model
        w, _, _ = model.law_values(t, self.data)
        Phi_v = constraint_jacobian(model, q, w, self.data)
        self.counters.jacobians += 1
        self.counters.factorisations += 1
        self.decision = (q, Phi_v, rank_split(model, Phi_v, w))
        return self.decision[1:]

    def _policy(self, t, q, v, w, lam):
        """The multipliers of redundant rows set by the redundancy policy (the least wrench)."""
        model = self.model
        Phi_v, split = self._rank_decision(t, q)
        if not split.redundant.size or not split.rank:
            return lam
        Q_across = (model.call("Q_across", self.data, q=q, v=v, w=w) if model.Q_across is not None
                    else None)
        wrench_map, offset = policy_map(model, q, w, as_dense(Phi_v), Q_across, self.data)
        return distribute(split, lam, wrench_map, offset)

    def dense_output(self) -> Interpolant:
        """Quintic Hermite interpolation of the positions from ``(q, v, v_dot)`` at both ends of
        the step, cubic of the velocities (:class:`~.interpolants.HermiteInterpolant`), the
        accelerations those of the equations of motion there (not the method's
        pseudo-accelerations ``a``)."""
        return self._hermite(self._dense_start)
