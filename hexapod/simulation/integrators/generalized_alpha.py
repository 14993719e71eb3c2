"""The generalized-alpha method in its Lie-group form, on the index-3 equations.

Arnold and Bruls (2007) and Bruls, Cardona and Arnold (2012): the equations of motion and the
position constraints are solved at the end of each step,

    M v_dot + Phi_v^T lambda = Q(q, v, t),   phi(q, t) = 0,

with the positions updated on the group, ``q_n+1 = q_n (+) h dq``,
``dq = v_n + h (1/2 - beta) a_n + h beta a_n+1``, the velocities
``v_n+1 = v_n + h (1 - gamma) a_n + h gamma a_n+1``, and the pseudo-accelerations ``a`` of
Chung and Hulbert (1993), ``(1 - alpha_m) a_n+1 + alpha_m a_n = (1 - alpha_f) v_dot_n+1 +
alpha_f v_dot_n``. The parameters follow from the spectral radius at infinity ``rho_inf``
(high-frequency damping; 1 keeps all, 0 damps all): ``alpha_m = (2 rho - 1) / (rho + 1)``,
``alpha_f = rho / (rho + 1)``, ``gamma = 1/2 + alpha_f - alpha_m``,
``beta = (gamma + 1/2)^2 / 4``: second order.

Newton's method on ``(Delta x, Delta lambda)``, ``Delta x`` the tangent increment of the
positions, with the iteration matrix

    [[M + (gamma'/beta') C + K / beta',  Phi_v^T], [Phi_v, 0]],
    beta' = (1 - alpha_m) / (beta h^2 (1 - alpha_f)),   gamma' = gamma / (beta h),

``K`` and ``C`` the tangent stiffness and damping of :meth:`Model.tangent_matrices`; the
equations are divided by ``beta'`` (and the multipliers with them), which keeps the matrix as
well conditioned as the dynamic saddle-point system whatever the step. The constraints hold to
Newton's tolerance at every step; the velocity constraints are not imposed (their residual is
``O(h^2)``). Redundant rows are dropped by the rank decision of :mod:`hexapod.algorithms.linalg`,
and their multipliers set by the redundancy policy. When Newton's method does not converge the step
is halved and retried, then grown back.
"""

from __future__ import annotations

import numpy as np

from hexapod.algorithms.liaison import policy_map
from hexapod.algorithms.linalg import distribute, equilibrate, split_rows
from hexapod.simulation.integrators.base import Integrator


class LieGroupGeneralizedAlpha(Integrator):
    """Generalized-alpha on the Lie group, index 3, fixed step (halved on Newton failure).

    ``rho_inf`` (0.9 by default): spectral radius at infinity. ``newton_tol``: tolerance on the
    scaled residuals of the equations of motion and of the constraints.
    """

    name = "generalized-alpha"
    order = 2
    index = 3
    stabilisation = "none needed: position constraints solved every step (Newton)"
    adaptive = False
    description = "Lie-group generalized-alpha (Bruls, Cardona, Arnold), index 3"
    max_iterations = 25

    def __init__(self, *args, rho_inf: float = 0.9, newton_tol: float = 1e-12, **kwargs):
        if not 0.0 <= rho_inf <= 1.0:
            raise ValueError(f"rho_inf must be in [0, 1], got {rho_inf}")
        rho = rho_inf
        self.alpha_m = (2 * rho - 1) / (rho + 1)
        self.alpha_f = rho / (rho + 1)
        self.gamma = 0.5 + self.alpha_f - self.alpha_m
        self.beta = 0.25 * (self.gamma + 0.5) ** 2
        self.newton_tol = newton_tol
        super().__init__(*args, **kwargs)

    def _start(self) -> None:
        self.a = self.v_dot.copy()  # pseudo-accelerations, consistent at the start
        self.nominal = self.h
        self.mass = self.model.mass.dense()

    def _step(self) -> None:
        h, result = self._halving(self._attempt)
        self.t, self.q, self.v, self.v_dot, self.a, self.lam = result
        self.h = min(self.nominal, 2 * h) if h < self.nominal else self.h

    def _attempt(self, h: float):
        """One step of length ``h``, or None when Newton's method fails."""
        model, am, af = self.model, self.alpha_m, self.alpha_f
        beta_p = (1 - am) / (self.beta * h**2 * (1 - af))
        gamma_p = self.gamma / (self.beta * h)
        t = self.t + h
        w, _, _ = model.law_values(t)
        # predictor: accelerations and multipliers as at the start of the step
        v_dot, lam = self.v_dot.copy(), self.lam.copy()
        a = (af * self.v_dot + (1 - af) * v_dot - am * self.a) / (1 - am)
        v = self.v + h * (1 - self.gamma) * self.a + h * self.gamma * a
        # the step on the group, h dq: kept as one increment from q_n, so that q_n+1 =
        # q_n (+) h dq holds exactly (composing Newton's corrections one by one would not: the
        # group does not commute, and that mismatch makes fast-spinning bodies unstable)
        increment = h * (self.v + h * (0.5 - self.beta) * self.a + h * self.beta * a)
        q = model.integrate(self.q, increment)
        da_dv_dot = (1 - af) / (1 - am)
        for _ in range(self.max_iterations):
            Phi_v = model.call("Phi_v", q=q, w=w)
            Q = model.call("Q", q=q, v=v, w=w)
            residual = self.mass @ v_dot + Phi_v.T @ lam - Q
            phi = model.call("phi", q=q, w=w)
            self.counters.rhs += 1
            force_scale = max(np.abs(self.mass @ v_dot).max(initial=0.0),
                              np.abs(Q).max(initial=0.0),
                              np.abs(Phi_v.T @ lam).max(initial=0.0), np.finfo(float).tiny)
            if (np.abs(residual).max(initial=0.0) <= self.newton_tol * force_scale
                    and np.abs(phi / model.row_scale).max(initial=0.0) <= self.newton_tol):
                return t, q, v, v_dot, a, self._policy(q, v, w, Phi_v, lam)
            if not (np.all(np.isfinite(residual)) and np.all(np.isfinite(phi))):
                return None
            args = [q, v, lam] + ([w] if model.n_w else [])
            K, C = (np.array(m) for m in model.tangent_matrices(*args))
            self.counters.jacobians += 1
            self.counters.newton += 1
            try:
                dx, dmu = self._solve(self.mass + (gamma_p / beta_p) * C + K / beta_p, Phi_v,
                                      -residual / beta_p, -phi)
            except np.linalg.LinAlgError:  # a singular iteration matrix: as a failed Newton
                return None
            increment = increment + dx
            q = model.integrate(self.q, increment)
            v = v + gamma_p * dx
            v_dot = v_dot + beta_p * dx
            a = a + da_dv_dot * beta_p * dx
            lam = lam + beta_p * dmu
        return None

    def _solve(self, A, Phi_v, r, s):
        """The iteration's saddle-point system on the independent rows (LU)."""
        model = self.model
        W, d = equilibrate(Phi_v, model.mass_inv_sqrt)
        split = split_rows(W, d, model.row_priority, model.rank_tolerance,
                           groups=model.row_groups)
        I = split.independent
        n, m = A.shape[0], I.size
        S = np.zeros((n + m, n + m))
        S[:n, :n] = A
        S[:n, n:] = Phi_v[I].T
        S[n:, :n] = Phi_v[I]
        solution = np.linalg.solve(S, np.concatenate([r, s[I]]))
        self.counters.factorisations += 1
        dmu = np.zeros(Phi_v.shape[0])
        dmu[I] = solution[n:]
        return solution[:n], dmu

    def _policy(self, q, v, w, Phi_v, lam):
        """The multipliers of redundant rows set by the redundancy policy (the least wrench)."""
        model = self.model
        W, d = equilibrate(Phi_v, model.mass_inv_sqrt)
        split = split_rows(W, d, model.row_priority, model.rank_tolerance,
                           groups=model.row_groups)
        if not split.redundant.size or not split.rank:
            return lam
        Q_across = (model.call("Q_across", q=q, v=v, w=w) if model.Q_across is not None
                    else None)
        wrench_map, offset = policy_map(model, q, Phi_v, Q_across)
        return distribute(split, lam, wrench_map, offset)
