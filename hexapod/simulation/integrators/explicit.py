"""Classical Runge-Kutta on the acceleration-level equations, with Baumgarte stabilisation.

The state ``(q, v)`` is integrated as an ODE, ``q_dot = B(q) v`` and ``v_dot`` from the
saddle-point system whose acceleration constraints are stabilised (Baumgarte 1972),

    Phi_v v_dot = gamma - 2 alpha (Phi_v v - nu) - beta^2 phi,

so that the drift of the positions and velocities away from the constraints decays like a
critically damped oscillator of rate ``alpha = beta`` instead of growing. The Euler parameters
are renormalised after each step. Fourth order, fixed step; the constraints hold to the
method's truncation error, not to round-off.
"""

from __future__ import annotations

import numpy as np

from hexapod.simulation.integrators.base import Integrator, Interpolant, PolynomialInterpolant
from hexapod.simulation.integrators.stability import largest_stable_step, runge_kutta_stability

#: the classical tableau, for the stability function
_A = np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1, 0]], dtype=float)
_B = np.array([1, 2, 2, 1], dtype=float) / 6
_R = runge_kutta_stability(_A, _B)
#: the continuous extension of order 3 (Hairer, Norsett and Wanner, *Solving ODEs I*, II.6):
#: the weights ``b_i(theta)`` of the four stages, coefficients of theta, theta^2 and theta^3
_DENSE = np.array([[1, -3 / 2, 2 / 3], [0, 1, -2 / 3], [0, 1, -2 / 3], [0, -1 / 2, 2 / 3]])


class RungeKutta4Baumgarte(Integrator):
    """RK4 on ``(q, v)`` with Baumgarte stabilisation.

    ``alpha`` (1/s): the stabilisation rate ``alpha = beta``, 10/s by default (a violation
    decays in about 0.1 s). It is a property of the stabilised equations, not of the step: a
    rate tied to the step (say ``0.2 / h``) changes the equations with the step and costs the
    method its order. It must keep ``alpha h`` inside the stability region (``alpha h < 2``).
    """

    name = "rk4-baumgarte"
    order = 4
    index = 1
    stabilisation = "Baumgarte (alpha = beta), Euler parameters renormalised"
    adaptive = False
    description = "classical Runge-Kutta, fixed step, acceleration level"

    DEFAULT_ALPHA = 10.0

    @classmethod
    def largest_stable_step(cls, eigenvalues, constrained: bool = False,
                            **options) -> float | None:
        """On the scene's modes and, with constraints, on the stabilisation's own: a drift
        decays like ``exp(-alpha t)`` (a double root), which the step must resolve too."""
        modes = list(np.asarray(eigenvalues, dtype=complex))
        if constrained:
            modes.append(-float(options.get("alpha", cls.DEFAULT_ALPHA)) + 0j)
        return largest_stable_step(lambda z: abs(_R(z)), modes)

    def __init__(self, *args, alpha: float = DEFAULT_ALPHA, **kwargs):
        if not alpha >= 0:
            raise ValueError(f"alpha must be non-negative, got {alpha}")
        self.alpha = float(alpha)
        super().__init__(*args, **kwargs)

    def _step(self) -> None:
        h = self.next_step()
        t, q, v = self.t, self.q, self.v
        # the accelerations at the current state come from the end of the last step, with the
        # same stabilisation (at the start the state is consistent and the terms vanish)
        dq1, dv1 = self.model.call("qdot", q=q, v=v), self.v_dot
        dq2, dv2 = self._rates(t + h / 2, q + h / 2 * dq1, v + h / 2 * dv1, self.alpha)
        dq3, dv3 = self._rates(t + h / 2, q + h / 2 * dq2, v + h / 2 * dv2, self.alpha)
        dq4, dv4 = self._rates(t + h, q + h * dq3, v + h * dv3, self.alpha)
        self._dense_step = (t, h, q, v, (dq1, dq2, dq3, dq4), (dv1, dv2, dv3, dv4))
        self.q = self.model.normalize(q + h / 6 * (dq1 + 2 * dq2 + 2 * dq3 + dq4))
        self.v = v + h / 6 * (dv1 + 2 * dv2 + 2 * dv3 + dv4)
        self.t = t + h
        self.v_dot, self.lam = self._dynamics(self.t, self.q, self.v, (self.alpha, self.alpha))

    def dense_output(self) -> Interpolant:
        """RK4's continuous extension of order 3 from the step's four stages (Baumgarte terms
        included); at the step's end it is the state before the Euler parameters are
        renormalised."""
        t, h, q, v, dq, dv = self._dense_step
        K = np.hstack([np.array(dq), np.array(dv)])
        return PolynomialInterpolant(self.model, t, h, np.concatenate([q, v]), K, _DENSE)
