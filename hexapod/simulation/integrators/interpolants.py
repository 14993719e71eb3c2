"""The continuous extensions of the integrators' steps (their dense output)."""

from __future__ import annotations

import numpy as np

from hexapod.model.data import Data
from hexapod.model.model import Model
from hexapod.simulation.integrators.tolerances import state_units


class Interpolant:
    """A method's continuous extension over one accepted step ``[t_old, t_new]``: called at a
    time of the step, it returns the positions and velocities there, ``(q, v)``, as the
    method's own polynomial gives them, Euler parameters renormalised (not yet on the
    constraints: :meth:`Integrator.dense_state` puts them there). Subclasses implement
    :meth:`_evaluate` of ``theta = (t - t_old) / h``; ``order`` is the interpolation's (its
    error is ``O(h^(order + 1))`` over a step).
    """

    order: int = 0

    def __init__(self, model: Model, t_old: float, t_new: float):
        self.model, self.t_old, self.t_new = model, float(t_old), float(t_new)
        self.h = self.t_new - self.t_old

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        theta = (float(t) - self.t_old) / self.h
        if not -1e-9 <= theta <= 1 + 1e-9:
            raise ValueError(f"t = {t:.10g} s is outside the step [{self.t_old:.10g}, "
                             f"{self.t_new:.10g}] s")
        q, v = self._evaluate(theta)
        return self.model.normalize(q), np.array(v, dtype=float)

    def _evaluate(self, theta: float) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError


class PolynomialInterpolant(Interpolant):
    """``y(t_old + theta h) = y_old + h Q [theta, theta^2, ...]`` on the state ``y = (q, v)``
    of a Runge-Kutta method integrating the ODE ``y' = (B(q) v, v_dot)`` (SciPy's
    ``RkDenseOutput``): ``Q = K^T P``, the stages ``K`` weighed by the polynomials of the
    method's continuous extension, ``P`` their coefficients (rows: stages; columns: powers)."""

    def __init__(self, model: Model, t_old: float, h: float, y_old: np.ndarray,
                 K: np.ndarray, P: np.ndarray):
        super().__init__(model, t_old, t_old + h)
        self.y_old, self.Q = y_old, np.asarray(K).T @ P
        self.order = P.shape[1]  # the polynomial's degree

    def _evaluate(self, theta):
        y = self.y_old + self.h * (self.Q @ np.cumprod(np.full(self.Q.shape[1], theta)))
        return y[:self.model.n_q], y[self.model.n_q:]


class HermiteInterpolant(Interpolant):
    """Quintic Hermite interpolation of the positions from ``(q, q', q'')`` at both ends of a
    step, cubic Hermite interpolation of the velocities from ``(v, v_dot)``: for the
    second-order methods, whose steps carry no continuous extension of their own. ``q' = B(q)
    v`` and ``q'' = B(q) v_dot + B(q') v`` on Euler parameters (``B`` is linear in them), ``v_dot``
    on the others; the positions are interpolated as coordinates, Euler parameters then
    renormalised. Order 5 on positions, 3 on velocities (the methods' own error is of order 2).

    ``start`` and ``end`` are ``(t, q, v, v_dot)``; ``data`` the integrator's workspace (its
    call buffers).
    """

    order = 3

    def __init__(self, model: Model, start: tuple, end: tuple, data: Data | None = None):
        super().__init__(model, start[0], end[0])
        units = state_units(model)[:model.n_q]
        euler = np.array([unit == "1" for unit in units])
        self.ends = []
        for _, q, v, v_dot in (start, end):
            q_dot = model.call("qdot", data, q=q, v=v)
            q_ddot = model.call("qdot", data, q=q, v=v_dot)
            q_ddot[euler] += model.call("qdot", data, q=q_dot, v=v)[euler]
            self.ends.append((np.asarray(q, dtype=float), q_dot, q_ddot,
                              np.asarray(v, dtype=float), np.asarray(v_dot, dtype=float)))

    def _evaluate(self, theta):
        (q0, dq0, ddq0, v0, a0), (q1, dq1, ddq1, v1, a1) = self.ends
        h, s = self.h, theta
        s2, s3 = s * s, s * s * s
        s4, s5 = s3 * s, s3 * s2
        q = ((1 - 10 * s3 + 15 * s4 - 6 * s5) * q0 + (10 * s3 - 15 * s4 + 6 * s5) * q1
             + h * ((s - 6 * s3 + 8 * s4 - 3 * s5) * dq0 + (-4 * s3 + 7 * s4 - 3 * s5) * dq1)
             + h * h * ((s2 - 3 * s3 + 3 * s4 - s5) / 2 * ddq0 + (s3 - 2 * s4 + s5) / 2 * ddq1))
        v = ((2 * s3 - 3 * s2 + 1) * v0 + (3 * s2 - 2 * s3) * v1
             + h * ((s3 - 2 * s2 + s) * a0 + (s3 - s2) * a1))
        return q, v
