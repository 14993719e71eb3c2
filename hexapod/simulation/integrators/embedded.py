"""Embedded Runge-Kutta pairs with adaptive steps and coordinate projection.

The acceleration-level equations are integrated as an ODE in ``(q, v)`` (``q_dot = B(q) v``);
the difference between the pair's two solutions estimates the local error, and the step is
accepted when its weighted RMS norm, with weights ``atol + rtol max(|y_n|, |y_n+1|)``, is at
most one (Hairer, Norsett and Wanner, *Solving ODEs I*, II.4); the next step's size is chosen
by Gustafsson's PI control (ibid., IV.2). After every accepted step the state is projected
back onto the constraints, positions onto ``phi = 0`` by Newton's method and velocities onto
``Phi_v v = nu``, both in the kinetic-energy norm (Hairer and Wanner, *Solving ODEs II*,
VII.2): the constraints then hold to round-off at every step, and the projection does not
lower the order.
"""

from __future__ import annotations

import numpy as np

from hexapod.errors import IntegrationError
from hexapod.simulation.integrators.base import Integrator
from hexapod.simulation.integrators.interpolants import Interpolant, PolynomialInterpolant
from hexapod.simulation.integrators.stability import largest_stable_step, runge_kutta_stability
from hexapod.simulation.integrators.tableaus import (
    DOP853_A,
    DOP853_B,
    DOP853_C,
    DOP853_D,
    DOP853_E3,
    DOP853_E5,
    DOP853_INTERPOLATOR_POWER,
    DOP853_STAGES,
    DOP853_STAGES_EXTENDED,
    DOPRI5_A,
    DOPRI5_B,
    DOPRI5_B_HAT,
    DOPRI5_C,
    DOPRI5_DENSE,
)
from hexapod.simulation.kernels import REDUNDANT_TOLERANCE, explicit_stages, weighted_squares
from hexapod.simulation.methods import METHODS


class EmbeddedRungeKutta(Integrator):
    """An explicit embedded pair ``(A, b, b_hat, c)`` with error-per-step control; subclasses
    give the tableau, what they are (``order``, that of the propagated solution, ``index``,
    ``adaptive``, ``stabilisation``: from :data:`~hexapod.simulation.methods.METHODS`) and
    ``error_order`` (that of the embedded solution, which sets the step controller's
    exponent)."""

    A: np.ndarray
    b: np.ndarray
    b_hat: np.ndarray
    c: np.ndarray
    error_order: int
    #: the next step is ``safety`` times the one the error estimate predicts (at most
    #: ``max_factor`` times longer, at least ``min_factor`` times). 0.8 rather than Hairer's
    #: 0.9: the multibody motions' error estimates jump from step to step (a chain's whip), and
    #: steps aimed nearer the tolerance were rejected one attempt in four. The right-hand
    #: sides to reach a position error of 1e-6, over the forward benchmarks' five problems
    #: (``scripts/studies/step_controller.py``): -15 to +1 % with DOP853, -10 to +1 % with
    #: DOPRI5
    safety, min_factor, max_factor = 0.8, 0.2, 10.0
    #: the start's accelerations by the compiled kernels' solve (see Integrator): a fifth of a
    #: small model's start, which is a tenth of its run to 1e-6
    starts_by_kernels = True
    #: the step controller's memory of the last accepted error (Gustafsson's PI control with
    #: Hairer's coefficients, *Solving ODEs I*, IV.2 and the codes DOPRI5 and DOP853: 0.04 and
    #: 0): a step grows less after one whose error was large, which damps the alternation of
    #: accepted and rejected steps where the error per step is near the tolerance (the walking
    #: robot's swings: 19 of its 101 steps a stride rejected without it)
    beta = 0.0

    @classmethod
    def largest_stable_step(cls, eigenvalues, constrained: bool = False,
                            **options) -> float | None:
        """On the scene's modes: projection removes the drift, so only they count."""
        R = runge_kutta_stability(cls.A, cls.b)
        return largest_stable_step(lambda z: abs(R(z)), eigenvalues)

    def __init__(self, *args, step: float | None = None, **kwargs):
        self._given_step = step
        self._error_before = 1e-4  # the last accepted step's error (at least 1e-4, as Hairer's)
        self._dense_step = None  # (t_old, h, y0, K, y1) of the last accepted step
        # the stages' combinations a step reads (rows): the solution's and the error's
        self._combinations = np.vstack([self.b.reshape(1, -1), self.error_weights()])
        super().__init__(*args, step=step, **kwargs)

    def _start(self) -> None:
        if self._given_step is None:
            self.h = self._initial_step()

    def _derivative(self, t, q, v):
        return np.concatenate(self._rates(t, q, v))

    def _norm(self, x: np.ndarray, y0: np.ndarray, y1: np.ndarray) -> float:
        return float(np.sqrt(weighted_squares(x, y0, y1, self.atol_vector, self.rtol) / x.size))

    @classmethod
    def error_weights(cls) -> np.ndarray:
        """The combinations of the stages the error estimate reads (rows): ``b - b_hat``."""
        return (cls.b - cls.b_hat).reshape(1, -1)

    def _error(self, h: float, sums: np.ndarray, size: int) -> float:
        """The step's error in the weighted RMS norm (at most 1: accepted), from the error
        test's sums (:func:`~hexapod.simulation.kernels.weighted_squares`) of the stages'
        combinations ``error_weights() @ K`` (``size``: the state's)."""
        return float(h * np.sqrt(sums[0] / size))

    def _growth(self, error: float, rejected: bool) -> float:
        """The factor of the next step after one accepted with ``error``: Gustafsson's PI
        control, ``safety * error^-(1/(k+1) - 0.75 beta) * error_before^beta`` (``k`` the
        error's order), within the factors' bounds, and no growth right after a rejection."""
        exponent = 1.0 / (self.error_order + 1) - 0.75 * self.beta
        factor = self.max_factor if error == 0 else min(self.max_factor, max(
            self.min_factor, self.safety * error ** -exponent * self._error_before ** self.beta))
        self._error_before = max(error, 1e-4)
        return min(factor, 1.0) if rejected else factor

    def _initial_step(self) -> float:
        """Hairer's starting step: from the sizes of the state, of its rate and of the rate's
        change over a trial Euler step."""
        y0 = np.concatenate([self.q, self.v])
        f0 = np.concatenate([self.model.call("qdot", self.data, q=self.q, v=self.v), self.v_dot])
        n_q = self.model.n_q

        def rate_change(h0: float) -> float:
            y1 = y0 + h0 * f0
            f1 = self._derivative(self.t + h0, y1[:n_q], y1[n_q:])
            return self._norm(f1 - f0, y0, y0)

        with np.errstate(all="ignore"):
            d0, d1 = self._norm(y0, y0, y0), self._norm(f0, y0, y0)
        return self._starting_step(d0, d1, rate_change, self.error_order)

    def _stages(self, t: float, h: float, y0: np.ndarray,
                f0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The stages ``K`` of a step ``h`` from ``(t, y0)``, ``f0`` the rate there, the
        propagated solution ``y1`` and the error test's sums (:func:`~hexapod.simulation.
        kernels.weighted_squares`) of the error estimate's combinations of the stages
        (:meth:`error_weights`): in one call of the compiled kernel
        (:meth:`~hexapod.simulation.kernels.CompiledRates.stages`), else one by one."""
        kernel, left_out = ((self._compiled, REDUNDANT_TOLERANCE) if self._crossing is None
                            else (self._crossing_rates, np.inf))
        until = self._laws_until(t + h)
        found = kernel.stages(self.A, self.c, t, h, y0, f0, left_out, until,
                              self._combinations, (self.atol_vector, self.rtol))
        if found is not None:
            later, combined, sums = found
            self.counters.rhs += later.shape[0]
            return np.vstack([f0, later]), y0 + h * combined[0], sums
        return self._stages_one_by_one(t, h, y0, f0, until)

    def _stages_one_by_one(self, t: float, h: float, y0: np.ndarray, f0: np.ndarray,
                           until: float = np.inf
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`_stages`, each stage's rate from :meth:`_derivative` (its laws read no later
        than ``until``)."""
        n_q = self.model.n_q
        K = np.array(explicit_stages(
            lambda i, y: self._derivative(min(t + self.c[i] * h, until), y[:n_q], y[n_q:]),
            h, y0, f0,
            self.A))
        combined = self._combinations @ K
        y1 = y0 + h * combined[0]
        return K, y1, np.array([weighted_squares(e, y0, y1, self.atol_vector, self.rtol)
                                for e in combined[1:]])

    def _step(self) -> None:
        model, n_q = self.model, self.model.n_q
        y0 = np.concatenate([self.q, self.v])
        f0 = np.concatenate([self._position_rates(self.q, self.v), self.v_dot])
        nudged, rejected = False, False
        while True:
            h = self.next_step()
            if h < 1e-14 * max(1.0, abs(self.t)):
                raise IntegrationError(f"the step size fell to {h:.3g} s (the error test cannot be "
                                  "met: the motion may be singular or too stiff for an "
                                  "explicit method)")
            K, y1, sums = self._stages(self.t, h, y0, f0)
            error = self._error(h, sums, y0.size) if np.isfinite(y1).all() else np.inf
            if error <= 1.0:
                if not nudged and self._lands_on_pose(self.t + h, y1[:n_q]):
                    # a crossing's step ending at the pose: the projection there is as badly
                    # conditioned as the pose (2e-4 J of 620 lost at once); one past it instead
                    nudged, self.h = True, self._over_pose(h)
                    self.counters.rejected += 1
                    continue
                factor = self._growth(error, rejected)
                break
            self.counters.rejected += 1
            rejected = True
            # a rejection near a singular configuration, approaching it, begins its crossing
            # (see Integrator._cross_singular): waiting for more, the steps crept towards the
            # pose, each one's projection costing energy
            if self._cross_singular():
                f0 = np.concatenate(self._rates(self.t, self.q, self.v))
                continue
            factor = self.min_factor if not np.isfinite(error) else max(
                self.min_factor, self.safety * error ** (-1.0 / (self.error_order + 1)))
            self.h = h * factor
        self._dense_step = (self.t, h, y0, K, y1)  # for dense_output
        self.t = self._on_break(self.t + h)
        q1 = model.normalize(y1[:n_q])
        self._follow_contacts(q1)  # ended on a touch-down or lift-off: the new set's kernels
        self.q, self.v = self._project(self.t, q1, y1[n_q:])
        self._end_crossing()
        # the accelerations start the next step; the multipliers come with them or are solved
        # when asked
        self.v_dot, self.lam = self._end_rates(self.t, self.q, self.v)
        # a crossing's steps stay within its cap (Integrator._cross_singular), the one that
        # jumped over the pose too
        self.h = h * factor if self._crossing is None else min(h * factor, self._crossing_cap)


class DormandPrince5(EmbeddedRungeKutta):
    """Dormand and Prince's 5(4) pair (DOPRI5), the solution propagated at order 5."""

    name = "dopri5-projection"
    order, index, adaptive, stabilisation = METHODS[name]
    error_order = 4
    beta = 0.04
    description = "Dormand-Prince 5(4), adaptive step, acceleration level"
    c, A, b, b_hat = DOPRI5_C, DOPRI5_A, DOPRI5_B, DOPRI5_B_HAT

    def dense_output(self) -> Interpolant:
        """The classical continuous extension of DOPRI5, of order 4 (Shampine's coefficients,
        :data:`~.tableaus.DOPRI5_DENSE`), from the step's seven stages; exact at both ends of
        the step (at its end, the state before the projection)."""
        t_old, h, y0, K, _ = self._dense_step
        return PolynomialInterpolant(self.model, t_old, h, y0, K, DOPRI5_DENSE)


class DormandPrince853(EmbeddedRungeKutta):
    """Dormand and Prince's 8(5,3) pair (DOP853, Hairer, Norsett and Wanner, *Solving ODEs I*,
    II.10): order 8, its error estimated from embedded solutions of orders 5 and 3 combined
    (the stiffer the problem, the more the third-order one weighs), twelve stages and one more
    right-hand side at the new state. For tight tolerances and long horizons.

    The tableau is Hairer's (:mod:`~hexapod.simulation.integrators.tableaus`), SciPy's
    ``scipy.integrate.DOP853`` too (``tests/test_tableaus.py`` compares them).
    """

    name = "dop853-projection"
    order, index, adaptive, stabilisation = METHODS[name]
    error_order = 7
    description = "Dormand-Prince 8(5,3), adaptive step, acceleration level"
    c = DOP853_C[:DOP853_STAGES]
    A = DOP853_A[:DOP853_STAGES, :DOP853_STAGES]
    b = DOP853_B
    b_hat = DOP853_B  # unused: the error comes from the embedded 5th and 3rd order solutions
    E3, E5 = DOP853_E3, DOP853_E5

    @classmethod
    def error_weights(cls) -> np.ndarray:
        # from the twelve stages: the rate at y1 has no weight in either estimate (the last
        # coefficient of E3 and E5 is zero), and only the dense output needs it
        return np.vstack([cls.E5[:DOP853_STAGES], cls.E3[:DOP853_STAGES]])

    def _error(self, h, sums, size):
        err5, err3 = sums
        if err5 == 0.0 and err3 == 0.0:
            return 0.0
        return float(h * err5 / np.sqrt((err5 + 0.01 * err3) * size))

    def dense_output(self) -> Interpolant:
        """DOP853's continuous extension of order 7 (Hairer, Norsett and Wanner, II.6), as
        ``scipy.integrate.DOP853`` builds it: three more stages (the rows of
        :data:`~.tableaus.DOP853_A` and ``DOP853_C`` after the twelve stages and the rate at
        the new state) and the coefficients :data:`~.tableaus.DOP853_D`; exact at both ends
        of the step (at its end, the state before the projection). Made once per step: the
        event-driven scheme asks for it at each event it locates."""
        step = self._dense_step
        kept = getattr(self, "_interpolant", None)  # this step's, when asked before
        if kept is not None and kept[0] is step:
            return kept[1]
        t_old, h, y0, K, y1 = step
        n_q, n = self.model.n_q, DOP853_STAGES
        extended = np.empty((DOP853_STAGES_EXTENDED, y0.size))
        extended[:n] = K
        # the rate at y1, in the step's regime (before a break the step ends on)
        extended[n] = self._derivative(self._laws_until(t_old + h), y1[:n_q], y1[n_q:])
        for s, (a, c) in enumerate(zip(DOP853_A[n + 1:], DOP853_C[n + 1:], strict=True),
                                   start=n + 1):
            y = y0 + h * (a[:s] @ extended[:s])
            extended[s] = self._derivative(t_old + c * h, y[:n_q], y[n_q:])
        interpolant = _Dop853Interpolant(self.model, t_old, h, y0, y1, extended)
        self._interpolant = (step, interpolant)
        return interpolant


class _Dop853Interpolant(Interpolant):
    """DOP853's dense output (as SciPy's ``DOP853`` evaluates it): ``y_old`` plus nested products of
    ``F_k`` with ``theta`` and ``1 - theta`` in turn."""

    order = 7

    def __init__(self, model, t_old, h, y0, y1, K):
        super().__init__(model, t_old, t_old + h)
        F = np.empty((DOP853_INTERPOLATOR_POWER, y0.size))
        delta = y1 - y0
        F[0] = delta
        F[1] = h * K[0] - delta
        F[2] = 2 * delta - h * (K[DOP853_STAGES] + K[0])
        F[3:] = h * (DOP853_D @ K)
        self.y0, self.F = y0, F

    def _evaluate(self, theta):
        y = np.zeros_like(self.y0)
        for i, f in enumerate(self.F[::-1]):
            y += f
            y *= theta if i % 2 == 0 else 1 - theta
        y += self.y0
        return y[:self.model.n_q], y[self.model.n_q:]
