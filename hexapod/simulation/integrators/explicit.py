"""Classical Runge-Kutta on the acceleration-level equations, with Baumgarte stabilisation.

The state ``(q, v)`` is integrated as an ODE, ``q_dot = B(q) v`` and ``v_dot`` from the
saddle-point system whose acceleration constraints are stabilised (Baumgarte 1972),

    Phi_v v_dot = gamma - 2 alpha (Phi_v v - nu) - beta^2 phi,

so that the drift of the positions and velocities away from the constraints decays like a
critically damped oscillator of rate ``alpha = beta`` instead of growing. The Euler parameters
are renormalised after each step. Fourth order, fixed step; the constraints hold to the
method's truncation error, not to round-off.

Redundant rows: every stage, the first included (the accelerations at the end of the previous
step), is solved on the rows independent at the start (the compiled kernel); the multipliers of
the saved states, and the stages the compiled solve refuses, by the exact solve with the rank
and the redundant rows' agreement decided to the accuracy of the state, which is off the
constraints by the drift (:meth:`RungeKutta4Baumgarte._dynamics`).
"""

from __future__ import annotations

import numpy as np

from hexapod.errors import IntegrationError
from hexapod.simulation.integrators.base import RANK_MARGIN, Integrator
from hexapod.simulation.integrators.interpolants import Interpolant, PolynomialInterpolant
from hexapod.simulation.integrators.stability import largest_stable_step, runge_kutta_stability
from hexapod.simulation.integrators.tableaus import RK4_A, RK4_B, RK4_DENSE
from hexapod.simulation.methods import METHODS
from hexapod.simulation.scales import characteristic_time

#: RK4's stability function
_R = runge_kutta_stability(RK4_A, RK4_B)
#: the position drift (relative to the row scales) past which a state is no longer a motion
#: of the mechanism and the run fails: healthy runs of the extreme-case suite drift by 1e-7 to
#: 7e-5 (6e-4 on the anti-parallelogram's dead points), a pendulum at a coarse 20 steps per
#: period over 100 periods to 1e-2; the flyball governor at 30 times its stable step drifted
#: to 4e7 and once ended "finished", 6e11 off
DRIFT_LIMIT = 0.1
#: the drift is checked every this many steps (one evaluation of ``phi``)
DRIFT_CHECK_EVERY = 10


class RungeKutta4Baumgarte(Integrator):
    """RK4 on ``(q, v)`` with Baumgarte stabilisation.

    ``alpha`` (1/s): the stabilisation rate ``alpha = beta``, 10/s by default (a violation
    decays in about 0.1 s). It is a property of the stabilised equations, not of the step: a
    rate tied to the step (say ``0.2 / h``) changes the equations with the step and costs the
    method its order. It must keep ``alpha h`` inside the stability region (``alpha h < 2``).
    """

    name = "rk4-baumgarte"
    order, index, adaptive, stabilisation = METHODS[name]
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
        self._dense_step = None  # (t, h, q, v, dq stages, dv stages) of the last step
        super().__init__(*args, **kwargs)

    def _step(self) -> None:
        h = self.next_step()
        t, q, v = self.t, self.q, self.v
        # the accelerations at the current state come from the end of the last step, with the
        # same stabilisation (at the start the state is consistent and the terms vanish)
        dq1, dv1 = self.model.call("qdot", self.data, q=q, v=v), self.v_dot
        dq2, dv2 = self._rates(t + h / 2, q + h / 2 * dq1, v + h / 2 * dv1, self.alpha)
        dq3, dv3 = self._rates(t + h / 2, q + h / 2 * dq2, v + h / 2 * dv2, self.alpha)
        dq4, dv4 = self._rates(t + h, q + h * dq3, v + h * dv3, self.alpha)
        self._dense_step = (t, h, q, v, (dq1, dq2, dq3, dq4), (dv1, dv2, dv3, dv4))
        self.q = self.model.normalize(q + h / 6 * (dq1 + 2 * dq2 + 2 * dq3 + dq4))
        self.v = v + h / 6 * (dv1 + 2 * dv2 + 2 * dv3 + dv4)
        self.t = t + h
        # the first stage of the next step: the same stabilised equations, on the same rows,
        # as the stages (the compiled kernel); the multipliers are solved when asked. An exact
        # solve here decided the rank afresh with the model's tolerance: on Bricard's mechanism
        # at h = 1e-2 the drift (phi 4e-8) set the redundant row more than 1e-9 from the
        # others' span at t = 1.47 s, it was kept in a system singular to within the drift, the
        # accelerations came out 10 to 700 off, and the mechanism swung on at another energy
        # (an error of 1.3 of the motion at 10 s, the run "finished")
        self.v_dot, self.lam = self._rates(self.t, self.q, self.v, self.alpha)[1], None
        if (self.counters.steps + 1) % DRIFT_CHECK_EVERY == 0:  # this step is counted after
            self._check_drift()

    def _position_drift(self, t: float, q: np.ndarray) -> float:
        """``max |phi|`` scaled by the row scales (0 without rows)."""
        model = self.model
        if not model.n_c:
            return 0.0
        w, _, _ = model.law_values(t, self.data)
        return float(np.abs(model.call("phi", self.data, q=q, w=w) / model.row_scale).max())

    def _check_drift(self) -> None:
        """Fail past :data:`DRIFT_LIMIT` of position drift (relative to the scene's size)."""
        drift = self._position_drift(self.t, self.q)
        if not drift <= DRIFT_LIMIT:
            raise IntegrationError(
                f"the constraints drifted by {drift:.2g} of the scene's size by t = "
                f"{self.t:.6g} s: the step h = {self.h:.3g} s is too large for Baumgarte's "
                "stabilisation here (take a smaller step, or a projection method)")

    def _dynamics(self, t: float, q: np.ndarray, v: np.ndarray,
                  baumgarte: tuple[float, float] | None = None,
                  consistency_tol: float = 1e-6, data=None) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`Integrator._dynamics` to the accuracy of the state, which Baumgarte's
        stabilisation leaves off the constraints by its drift: positions by ``e`` (``phi``
        scaled by the row scales), velocities by ``e_v`` (``Phi_v v - nu`` so scaled, times
        :func:`characteristic_time`). There a redundant row stands about ``e`` from the span
        of the others, so the rank decision's tolerance is at least :data:`RANK_MARGIN` times
        ``e`` (the model's 1e-9 alone kept Bricard's redundant row at a drift of 4e-8, in a
        system singular to within it: multipliers of 5e9 to 7e9); and the redundant rows disagree
        with the others by about ``max(e, e_v)``, so they are checked to at least
        :data:`RANK_MARGIN` times that (Bricard's redundant row disagreed by 1e-6 at h = 0.05
        s, ``e = 1e-5``, and the multipliers of the saved states were refused as those of
        contradicting constraints). At a consistent state both are the model's. Used by the
        multipliers of the saved states and where the compiled solve is refused."""
        model = self.model
        if self._crossing is not None or not model.n_c:
            return super()._dynamics(t, q, v, baumgarte, consistency_tol, data)
        w, wd, _ = model.law_values(t, self.data)
        e = self._position_drift(t, q)
        rates = (model.call("Phi_v", self.data, q=q, w=w) @ v
                 - model.call("nu", self.data, q=q, w=w, wd=wd))
        e_v = float(np.abs(rates / model.row_scale).max()) * characteristic_time(model)
        rank_tolerance, tol = model.rank_tolerance, consistency_tol
        if np.isfinite(e) and np.isfinite(e_v):  # else the solve says what is wrong
            rank_tolerance = max(rank_tolerance, RANK_MARGIN * e)
            tol = max(tol, RANK_MARGIN * max(e, e_v))
        return super()._dynamics(t, q, v, baumgarte, tol, data, rank_tolerance=rank_tolerance)

    def dense_output(self) -> Interpolant:
        """RK4's continuous extension of order 3 from the step's four stages (Baumgarte terms
        included); at the step's end it is the state before the Euler parameters are
        renormalised."""
        t, h, q, v, dq, dv = self._dense_step
        K = np.hstack([np.array(dq), np.array(dv)])
        return PolynomialInterpolant(self.model, t, h, np.concatenate([q, v]), K, RK4_DENSE)
