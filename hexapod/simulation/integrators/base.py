"""The contract every integrator of the registry keeps (as SciPy's ``OdeSolver`` writes its own).

An integrator advances the constrained equations of motion

    q_dot = B(q) v,   M v_dot + Phi_v^T lambda = Q(q, v, t),   phi(q, t) = 0

from a consistent state, one accepted step per call of :meth:`Integrator.step`, until
``t_bound``. A subclass declares what it is (class attributes ``name``, ``order``, ``index``,
``stabilisation``, ``adaptive``, ``description``; the registered methods read the four in
between from :data:`hexapod.simulation.methods.METHODS`) and implements
:meth:`Integrator._step`, which advances ``t, q, v, v_dot, lam`` by one accepted step and
counts its work in ``counters`` through the services of this class (:meth:`_dynamics`,
:meth:`_project`). The base class makes the initial state consistent (positions assembled,
velocities projected, accelerations and multipliers solved), keeps the last step inside
``t_bound``, and turns any failure into data: ``status = "failed"`` and a ``message`` naming
the time and the cause, never an exception escaping :meth:`step`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np
from scipy.linalg import qr

from hexapod.algorithms.dynamics import forward_dynamics
from hexapod.algorithms.kinematics import assemble_positions, rank_split, solve_velocities
from hexapod.algorithms.linalg import as_dense
from hexapod.algorithms.saddle import constraint_jacobian, is_large
from hexapod.errors import HexapodError, IntegrationError
from hexapod.model.model import Model
from hexapod.simulation.integrators.interpolants import HermiteInterpolant, Interpolant
from hexapod.simulation.integrators.tolerances import (
    KIND_OF_UNIT,
    absolute_tolerances,
    state_units,
)
from hexapod.simulation.kernels import (
    REDUNDANT_TOLERANCE,
    compiled_projection,
    compiled_rates,
)
from hexapod.simulation.methods import (
    DEFAULT_ATOL,
    DEFAULT_RTOL,
)
from hexapod.simulation.scales import (
    BRANCH_JUMP,
    ENERGY_JUMP,
    ROUND_OFF,
    characteristic_time,
    motion_scales,
)

#: smallest singular value of the equilibrated ``Phi_v`` (rows of unit length, so 1 is
#: well-conditioned) below which a state counts as near a singular configuration. Approaching
#: such a pose, the motion's derivatives off the constraints grow as ``1 / sigma`` and the error
#: test lets steps shrink with the distance to it, never reaching it (the N-four-bar at rtol
#: 1e-10 stalled 3e-7 from its flat pose, the step at 7e-15 s); so the crossing leaves the
#: nearly dependent rows out there
SINGULAR_BAND = 1e-4
#: the crossing's tolerance over the smallest singular value where it begins (or widens)
CROSSING_FACTOR = 10.0
#: the rank decision's tolerance at a state off the constraints by ``e`` (scaled by the row
#: scales) is at least this times ``e``: a redundant row's distance from the others' span grows
#: like ``e`` there (the methods that leave the constraints by a drift or a Newton error)
RANK_MARGIN = 10.0
#: the largest singular value a crossing leaves out with a cluster of smaller ones (rows of
#: unit length: a well-posed row's are of order 0.1 to 1); the N-four-bar's 40 windows spread
#: theirs over a factor 26, 8e-5 to 2e-3 where DOPRI5 at rtol 1e-9 begins to cross
CLUSTER_CEILING = 1e-2
#: a crossing's step may not end nearer the pose than where the smallest singular value is
#: this fraction of the one where the crossing began (see :meth:`Integrator._lands_on_pose`)
POSE_CLEARANCE = 0.1
#: a crossing begins only where the pose is foreseen (its distance over the smallest singular
#: value's rate) within this many of the last accepted steps (none before the first) and within
#: this fraction of the model's characteristic time. At the N-four-bars (10 and 40 windows, 2-D
#: and 3-D) and the anti-parallelograms from rtol 1e-6 to 1e-10, the rejections that begin
#: crossings foresee their poses within 4.5 steps and 5.5e-4 characteristic times; the walking
#: hexapod, whose smallest singular value is 5e-5 where nothing is singular and drifts at 3e-5
#: per second, foresaw one 330 steps and 10 characteristic times ahead, and crept on the
#: crossing's capped steps to the end of its run (647 steps instead of 31)
FORESIGHT_STEPS = 50
FORESIGHT_TIME = 1e-2


@dataclass
class Counters:
    """The work of a run.

    Attributes
    ----------
    steps, rejected :
        Accepted steps; steps rejected by the error test or by a failed Newton iteration.
    rhs :
        Evaluations of the equations of motion (a saddle-point solve, or an implicit residual).
    jacobians :
        Evaluations of the constraint Jacobian ``Phi_v`` (with the tangent matrices, for
        implicit methods).
    factorisations :
        Matrix factorisations (QR of the equilibrated ``Phi_v``, or LU of an iteration matrix).
    newton :
        Newton iterations, of projections and of implicit solves.
    crossings :
        Singular configurations crossed with nearly dependent rows left out.
    """

    steps: int = 0
    rejected: int = 0
    rhs: int = 0
    jacobians: int = 0
    factorisations: int = 0
    newton: int = 0
    crossings: int = 0

    def as_dict(self) -> dict[str, int]:
        return asdict(self)


class Integrator:
    """Base class of the integrators (see the module's description of the contract).

    Parameters
    ----------
    model : Model
    t0, t_bound : float
        Start and end times (s).
    q0, v0 : ndarray, optional
        Guesses of the initial positions and velocities (default: the scene's); they are made
        consistent first.
    rtol, atol : float
        Tolerances of adaptive methods (relative; absolute in SI units of ``q`` and ``v``).
    step : float, optional
        The step of fixed-step methods, the first step of adaptive ones (s).
    max_step : float
        Largest step of adaptive methods (s).
    """

    name: ClassVar[str] = ""
    order: ClassVar[int] = 0
    #: 1: the acceleration-level equations integrated as an ODE in (q, v); 3: position-level
    #: constraints solved at every step
    index: ClassVar[int] = 1
    stabilisation: ClassVar[str] = ""
    adaptive: ClassVar[bool] = False
    description: ClassVar[str] = ""
    #: fixed-step methods without a ``step``: this many steps over the run
    default_steps: ClassVar[int] = 1000
    #: True when the method counts its accepted steps itself: a call of :meth:`step` then
    #: returns one state but may stand for many steps of an underlying solver
    counts_own_steps: ClassVar[bool] = False

    @classmethod
    def largest_stable_step(cls, eigenvalues, constrained: bool = False,
                            **options) -> float | None:
        """The largest step stable on linear modes ``exp(lambda t)`` (:mod:`.stability`), for
        the scene's ``eigenvalues`` (of its linearisation on the constraint manifold, see
        :func:`hexapod.simulation.diagnostics.diagnose`); ``constrained`` when the scene has
        constraints, ``options`` those of the constructor. None for methods without such a limit
        (implicit ones)."""
        return None

    def __init__(self, model: Model, t0: float, t_bound: float, q0: np.ndarray | None = None,
                 v0: np.ndarray | None = None, *, rtol: float = DEFAULT_RTOL,
                 atol: float = DEFAULT_ATOL,
                 step: float | None = None, max_step: float = np.inf):
        if not t_bound > t0:
            raise ValueError(f"t_bound must be after t0, got {t0} and {t_bound}")
        if step is not None and not step > 0:
            raise ValueError(f"step must be positive, got {step}")
        # a mapping gives each kind of coordinate its own (see absolute_tolerances); the scalar
        # ``atol`` is then the smallest of them
        self.atol_kinds = absolute_tolerances(model, atol)
        atol = min(self.atol_kinds.values())
        if not (rtol > 0 and atol > 0):
            raise ValueError(f"rtol and atol must be positive, got {rtol} and {atol}")
        self.model = model
        self.t0, self.t_bound = float(t0), float(t_bound)
        self.rtol, self.atol, self.max_step = float(rtol), float(atol), float(max_step)
        self.h = float(step) if step is not None else (self.t_bound - self.t0) / self.default_steps
        self.counters = Counters()
        self.data = model.create_data()
        self._kinematics = model.create_data()  # the exact projection's, apart from ``data``
        self.status = "running"
        self.message = ""
        self._crossing: float | None = None  # the raised rank tolerance, while crossing
        self._crossing_from = np.inf  # the smallest singular value where the crossing began
        self._crossing_rate = 0.0  # and its rate along the motion there
        self._crossing_start = self.t0  # and the time
        self._crossing_cap = np.inf  # the longest step of the crossing under way
        self._accepted_step = 0.0  # the last accepted step's length (s)
        self._kinetic_peak = 0.0  # the largest kinetic energy of the run so far (J)
        q, v = self._project(self.t0, q0, v0)  # guesses of None: the scene's initial state
        self.t, self.q, self.v = self.t0, q, v
        self._q_start = q
        self.v_dot, self.lam = self._dynamics(self.t, q, v)
        # the stages' right-hand sides and the projection, compiled for the rows independent
        # at the start
        self._compiled = compiled_rates(model, self.data.independent_rows)
        self._compiled_projection = compiled_projection(model, self.data.independent_rows)
        self._feet_down = self._contact_set(self.t)
        self._start()

    @property
    def crossing(self) -> bool:
        """Whether a crossing of a singular configuration is under way (its steps are short for
        a while: :meth:`_cross_singular`)."""
        return self._crossing is not None

    @property
    def lam(self) -> np.ndarray:
        """The multipliers at the current state (by the least-wrench redundancy policy); a method
        that advances with the compiled right-hand side solves for them only when asked."""
        if self._lam is None:
            self._lam = self.multipliers(self.t, self.q, self.v)
        return self._lam

    def multipliers(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The multipliers at a state by the redundancy policy, counted as a solve: the
        compiled solve's when every row is kept (they are then unique), else the exact solve's."""
        if self._compiled.complete:
            solution = self._compiled.solve(t, q, v)
            if solution is not None:
                self.counters.rhs += 1
                return np.asarray(solution[2], dtype=float)
        return self._dynamics(t, q, v)[1]

    @lam.setter
    def lam(self, value: np.ndarray | None) -> None:
        self._lam = value

    # ------------------------------------------------------------------ the contract

    def _start(self) -> None:
        """Set up the method's own state from the consistent initial state (optional)."""

    def _step(self) -> None:
        """Advance ``t, q, v, v_dot, lam`` by one accepted step, no further than ``t_bound``;
        raise :class:`IntegrationError` (or any :class:`HexapodError`) when it cannot."""
        raise NotImplementedError

    def step(self) -> None:
        """One accepted step; sets ``status`` to ``"finished"`` at ``t_bound``, or to
        ``"failed"`` with a ``message``."""
        if self.status != "running":
            raise RuntimeError(f"the integrator is {self.status}: nothing to step")
        t_before, q_before, v_before, a_before = self.t, self.q, self.v, self.v_dot
        try:
            with np.errstate(over="ignore", invalid="ignore"):  # a blow-up is reported below
                self._follow_contacts()
                self._step()
        except (HexapodError, np.linalg.LinAlgError) as error:
            self.status = "failed"
            self.message = f"{self.name} failed after t = {t_before:.6g} s: {error}"
            # the cause behind the symptom, unless the state itself blew up (its pose is noise)
            blew_up = "non-finite" in str(error) or not np.all(np.isfinite(self.q))
            known = "singular configuration" in str(error)
            where = "" if blew_up or known else self._singular_pose()
            if where:
                self.message += f"; {where}"
            return
        except ArithmeticError as error:  # Python's floats overflow (h**2) or divide by zero
            self.status = "failed"
            self.message = (f"{self.name} failed after t = {t_before:.6g} s: the arithmetic "
                            f"overflowed ({error or type(error).__name__}): the step or the "
                            "scene's magnitudes are too large")
            return
        if not self.counts_own_steps:
            self.counters.steps += 1
        self._accepted_step = self.t - t_before
        if not np.all(np.isfinite(self.q)) or not np.all(np.isfinite(self.v)):
            self.status = "failed"
            self.message = (f"{self.name}: non-finite state at t = {self.t:.6g} s (the step is "
                            "too large for this method, or the motion is unstable)")
        elif not self.adaptive and self._jumps_branch(self.t - t_before, v_before, a_before,
                                                      self.v, self.v_dot):
            # a fixed step cannot shorten itself through a singular pose: it says so
            where = self._singular_pose()
            self.status = "failed"
            self.message = (f"{self.name}: the step from t = {t_before:.6g} s changed the "
                            "velocities by more than its accelerations explain: it left the "
                            "motion's branch" + (f"; {where}" if where else
                                                 " (take a smaller step)"))
            return
        elif not self.adaptive and self._energy_jump(q_before, v_before,
                                                     self.q, self.v) > ENERGY_JUMP:
            self.status = "failed"
            self.message = (f"{self.name}: the step from t = {t_before:.6g} s changed the "
                            f"energy of this conservative scene by "
                            f"{self._energy_jump(q_before, v_before, self.q, self.v):.2g} of "
                            "its largest kinetic energy: the step is too long for the motion"
                            + (f"; {where}" if (where := self._singular_pose()) else ""))
            return
        elif self.t >= self.t_bound - 1e-12 * max(1.0, abs(self.t_bound)):
            self.t = self.t_bound
            self.status = "finished"
        if self.model.energy_conserved:
            self._kinetic_peak = max(self._kinetic_peak,
                                     float(self.model.energy(self.q, self.v)[0]))

    def _starting_step(self, d0: float, d1: float, rate_change, error_order: int) -> float:
        """Hairer's starting step (*Solving ODEs I*, II.4): from the weighted norms of the state
        ``d0`` and of its rate ``d1``, and ``rate_change(h0)``, the norm of the rate's change
        over a trial step ``h0``; ``error_order`` that of the error estimate. Safe for zero,
        huge and non-finite norms: it never divides by zero, and a step it cannot compute is
        the trial step (the first step then fails, or succeeds, as data)."""
        remaining = self.t_bound - self.t
        with np.errstate(all="ignore"):
            h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
            if not (np.isfinite(h0) and h0 > 0):  # d1 infinite or NaN: an overflowing rate
                h0 = 1e-6 * min(1.0, remaining)
            h0 = min(h0, remaining)
            try:
                d2 = rate_change(h0) / h0
            except (HexapodError, np.linalg.LinAlgError, ArithmeticError):
                d2 = np.inf  # the trial state has no dynamics: the first step will say why
            largest = max(d1, d2) if np.isfinite(d2) else np.inf
            if largest <= 1e-15:
                h1 = max(1e-6, h0 * 1e-3)
            else:
                h1 = (0.01 / largest) ** (1.0 / (error_order + 1))
        h = min(100 * h0, h1, self.max_step, remaining)
        return h if np.isfinite(h) and h > 0 else h0

    def next_step(self) -> float:
        """The step to take now: the method's current step, cut to end at ``t_bound`` (and a
        step that would leave a sliver of less than 1 % is stretched to the end)."""
        remaining = self.t_bound - self.t
        h = min(self.h, self.max_step)
        return remaining if h >= 0.99 * remaining else h

    # ------------------------------------------------------------------ services

    def _contact_set(self, t: float) -> tuple[bool, ...]:
        """Which of the model's feet are on the ground at ``t`` (their gates)."""
        if not self.model.contacts:
            return ()
        w = self.model.law_values(t)[0]
        return tuple(bool(w[c.gate] > 0.5) for c in self.model.contacts)

    def _follow_contacts(self) -> None:
        """When feet have touched down or lifted off since the compiled kernels were built,
        build them (once per contact set) for the rows independent now: a foot in swing has
        no rows, and one that touched down has rows the old set leaves out."""
        feet = self._contact_set(self.t)
        if feet == self._feet_down:
            return
        self._feet_down = feet
        rows = self._rank_split().independent
        self._compiled = compiled_rates(self.model, rows)
        self._compiled_projection = compiled_projection(self.model, rows)

    def _dynamics(self, t: float, q: np.ndarray, v: np.ndarray,
                  baumgarte: tuple[float, float] | None = None,
                  consistency_tol: float = 1e-6, data=None,
                  rank_tolerance: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Accelerations and multipliers at a state (one saddle-point solve; rows nearly
        dependent are left out while a singular configuration is crossed). Redundant rows may
        disagree with the others by ``consistency_tol`` (relative) before the solve refuses.
        ``data``: where the solve works (default ``self.data``, the method's current state).
        ``rank_tolerance``: the rank decision's (default the model's)."""
        data = self.data if data is None else data
        # while crossing, the rows left out are violated by design (the projection restores them)
        options = ({"rank_tolerance": rank_tolerance, "consistency_tol": consistency_tol}
                   if self._crossing is None else
                   {"rank_tolerance": self._crossing, "consistency_tol": np.inf})
        v_dot = forward_dynamics(self.model, data, t, q, v, baumgarte=baumgarte, **options)
        self.counters.rhs += 1
        self.counters.jacobians += 1
        self.counters.factorisations += 1
        return v_dot, data.lam

    def _rates(self, t: float, q: np.ndarray, v: np.ndarray,
               alpha: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """``(q_dot, v_dot)`` at a state, without multipliers (the stages of explicit methods):
        one compiled call, or the exact solve of :meth:`_dynamics` where the compiled one is
        refused (a change of rank, a singular configuration). ``alpha``: Baumgarte's rate."""
        if self._crossing is None:
            rates = self._compiled(t, q, v, alpha)
        else:
            rates = self._crossing_rates(t, q, v, alpha, left_out=np.inf)
        if rates is not None:
            self.counters.rhs += 1
            return rates
        # a stage state is off the constraints by the step's truncation error, and redundant
        # rows disagree with the others by as much: as far as the compiled solve allows
        v_dot, _ = self._dynamics(t, q, v, (alpha, alpha) if alpha else None,
                                  consistency_tol=REDUNDANT_TOLERANCE)
        return self.model.call("qdot", q=q, v=v), v_dot

    def _cross_singular(self) -> bool:
        """Begin crossing a singular configuration if the state is near one (see
        :data:`SINGULAR_BAND`) and moving towards it, or widen the crossing under way; returns
        whether it did. Moving away from a singular pose, the rows are all kept: the steps then
        grow back as the distance to the pose does, and a crossing begun there would leave rows
        out over a band ten times as wide as the state's, for nothing.

        While crossing, the rows nearly dependent on the others (as many as there are singular
        values of the equilibrated ``Phi_v`` below the crossing's tolerance, ``CROSSING_FACTOR``
        times the smallest where it began) are left out: the stages then solve one smooth
        system of fewer rows, compiled for them, and the projection after each step puts the
        state back on every constraint. Widening (the error test still failing) multiplies the
        tolerance by ``CROSSING_FACTOR`` again, up to ``CROSSING_FACTOR * SINGULAR_BAND``."""
        if not self.model.n_c:
            return False
        split = self._rank_split()
        # the smallest singular value alone (ARPACK on a large model's sparse factor) decides
        # whether to go on: all of them (a dense SVD, cubic in the bodies) only near a pose
        smallest = split.smallest_singular_value()
        if not smallest < SINGULAR_BAND:
            return False
        base = smallest if self._crossing is None else self._crossing
        if base >= SINGULAR_BAND:
            return False  # as wide as it goes
        if self._crossing is None:
            rate = self._singular_rate(smallest)
            if not rate < 0:
                return False  # moving away
            horizon = min(FORESIGHT_STEPS * self._accepted_step,
                          FORESIGHT_TIME * characteristic_time(self.model))
            if smallest > -rate * horizon:
                return False  # the pose far ahead, or sigma small for another reason
            self.counters.crossings += 1
            self._crossing_from, self._crossing_rate = smallest, rate
            self._crossing_start = self.t
        starting = self._crossing is None
        self._crossing = CROSSING_FACTOR * base
        # the rows left out: those a rank-revealing (column-pivoted) QR factorisation takes last
        rows = split.independent
        dependent = _collapsing(split.singular_values(), self._crossing)
        pivots = qr(as_dense(split.W[rows]).T, mode="r", pivoting=True)[1]
        kept = np.sort(rows[pivots[:rows.size - dependent]])
        self._crossing_rates = compiled_rates(self.model, kept)
        if starting:
            # no step longer than the way to the pose and as far again (one much longer lands
            # far out of the band on the rows left out), nor than their forces' absence allows
            self._crossing_cap = min(2 * smallest / -self._crossing_rate,
                                     self._crossing_step_limit())
            self.h = min(self.h, self._crossing_cap)
        return True

    def _crossing_step_limit(self) -> float:
        """The longest step a crossing may take: the one over which the rows it leaves out,
        their forces missing, move the positions by the step's tolerance, ``h^2 / 2`` times the
        gap between the accelerations of the reduced and the full system at the current state
        (in the error test's weighted RMS norm). Without this cap a crossing took the
        steps of the motion around it, and the energy its projections cost (about 5e-8 J of 620
        per pose of the N-four-bar) did not fall with the tolerance."""
        rates = self._crossing_rates(self.t, self.q, self.v, 0.0, left_out=np.inf)
        if rates is None:  # the reduced solve refused: no estimate, no cap
            return np.inf
        n_q = self.model.n_q
        gap = self.model.call("qdot", q=self.q, v=rates[1] - self.v_dot)
        weight = self.atol_vector[:n_q] + self.rtol * np.abs(self.q)
        size = float(np.sqrt(np.mean((gap / weight) ** 2)))
        return np.sqrt(2.0 / size) if size > 0 else np.inf

    def _over_pose(self, h: float) -> float:
        """The step to take instead of ``h``, a crossing's step that would end near the pose
        (:meth:`_lands_on_pose`): one long enough to pass it by as much as the current state
        is before it (from the rate of the smallest singular value where the crossing began),
        at least half as long again as ``h``."""
        rate = self._crossing_rate
        if not rate < 0:
            return 1.5 * h
        return max(1.5 * h, 2 * self._smallest_singular_value() / -rate)

    def _end_crossing(self) -> None:
        """End the crossing once the state has left the band it began in, or has passed the
        pose and is as far from it as where the crossing began (the steps that follow keep
        every row and grow back with the distance to the pose; steps leaving rows out further
        on, long ones especially, let the state leave the constraints they hold by more than
        the projection puts right without a loss of energy)."""
        if self._crossing is None:
            return
        if -self._crossing_rate * (self.t - self._crossing_start) < 1.9 * self._crossing_from:
            return  # foreseen before the pose or not yet nine tenths of its way back: no rank split
        smallest = self._smallest_singular_value()
        if not smallest <= self._crossing or (smallest >= self._crossing_from
                                              and self._singular_rate(smallest) > 0):
            self._crossing = None

    def _lands_on_pose(self, t: float, q: np.ndarray) -> bool:
        """Whether a crossing's step ending at ``(t, q)`` ends near the pose: the smallest
        singular value there below :data:`POSE_CLEARANCE` times the one where it began."""
        if (self._crossing is None
                or self._foreseen_singular_value(t) > 2 * POSE_CLEARANCE * self._crossing_from):
            return False  # far from it: no rank split
        return bool(self._smallest_singular_value(self.model.normalize(q))
                    < POSE_CLEARANCE * self._crossing_from)

    def _foreseen_singular_value(self, t: float) -> float:
        """The smallest singular value at ``t`` as the crossing under way foresees it, falling
        at its starting rate to the pose and rising as fast beyond: a crossing's steps are short
        (see :meth:`_crossing_step_limit`), and a rank split at each to see where they are cost
        four fifths of the run."""
        return abs(self._crossing_from + self._crossing_rate * (t - self._crossing_start))

    def _singular_rate(self, smallest: float) -> float:
        """The rate of change along the motion of the smallest singular value of the
        equilibrated ``Phi_v`` (``smallest`` at the current state), negative approaching a
        singular pose: a difference over a thousandth of the step, close enough never to jump
        over the pose."""
        delta = 1e-3 * self.h
        return (self._smallest_singular_value(self._positions_ahead(delta)) - smallest) / delta

    def _positions_ahead(self, delta: float) -> np.ndarray:
        """The positions ``delta`` seconds along the current motion, to first order (for the
        rates of singular values, as differences)."""
        q_dot = self.model.call("qdot", q=self.q, v=self.v)
        return self.model.normalize(self.q + delta * q_dot)

    def _rank_split(self, q: np.ndarray | None = None, t: float | None = None):
        """The rank decision on the equilibrated ``Phi_v`` at positions ``q`` (default the
        current ones), with the laws at ``t`` (default the current time)."""
        w, _, _ = self.model.law_values(self.t if t is None else t)
        self.counters.jacobians += 1
        self.counters.factorisations += 1
        return rank_split(self.model,
                          constraint_jacobian(self.model, self.q if q is None else q, w), w)

    def _jumps_branch(self, h: float, v0: np.ndarray, a0: np.ndarray, v1: np.ndarray,
                      a1: np.ndarray) -> bool:
        """Whether a step of ``h`` from velocities ``v0`` (accelerations ``a0``) to ``v1``
        (``a1``) changed them by more than its accelerations explain (see
        :data:`BRANCH_JUMP`), in the kinetic-energy norm (a change of any unit, metres or
        radians, weighs what it costs in energy)."""
        mass = self.model.mass

        def size(x):
            return float(np.sqrt(max(float(x @ (mass @ x)), 0.0)))

        # round-off of a scene at rest (its accelerations are that of its forces' balance)
        floor = ROUND_OFF * self._scales[1]
        allowed = (BRANCH_JUMP * h * max(size(a0), size(a1), floor)
                   + ROUND_OFF * max(size(v0), size(v1)))
        return not size(v1 - v0) <= allowed  # NaN jumps

    def _energy_jump(self, q0: np.ndarray, v0: np.ndarray, q1: np.ndarray,
                     v1: np.ndarray) -> float:
        """The change of energy from ``(q0, v0)`` to ``(q1, v1)`` relative to the largest
        kinetic energy of the run so far, that of both states included (see
        :data:`ENERGY_JUMP`); 0 on a scene that does not conserve energy."""
        if not self.model.energy_conserved:
            return 0.0
        kinetic0, potential0 = (float(x) for x in self.model.energy(q0, v0))
        kinetic1, potential1 = (float(x) for x in self.model.energy(q1, v1))
        # at rest the energy's round-off, not the kinetic energy, sets the scale
        peak = max(self._kinetic_peak, kinetic0, kinetic1, ROUND_OFF * self._scales[2])
        return abs(kinetic1 + potential1 - kinetic0 - potential0) / peak

    @cached_property
    def _scales(self) -> tuple[float, float, float]:
        return motion_scales(self.model)

    def _halving(self, attempt):
        """Take one step by ``attempt(h)``, which returns the new state or None when Newton's
        method fails: then the step is halved (a rejection) and tried again. Returns the step
        taken and the attempt's result; the caller grows the step back."""
        while True:
            h = self.next_step()
            if h < 1e-12 * max(1.0, self.t_bound - self.t0):
                why = getattr(self, "failure", "")  # the attempt's own words, when it has some
                where = self._singular_pose()
                raise IntegrationError(f"Newton's method does not converge even with a step of "
                                       f"{h:.3g} s" + (f" ({why})" if why else "")
                                       + (f": {where}" if where else ""))
            result = attempt(h)
            if result is not None:
                return h, result
            self.counters.rejected += 1
            self.h = h / 2

    def _project(self, t: float, q: np.ndarray | None,
                 v: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """The nearest consistent state in the kinetic-energy norm: positions onto
        ``phi = 0`` (Newton's method), then velocities onto ``Phi_v v = nu``."""
        projector = getattr(self, "_compiled_projection", None)  # None: the start
        if projector is not None and q is not None and v is not None:
            state = projector(t, q, v)
            if state is not None:
                self.counters.newton += projector.newton
                self.counters.jacobians += projector.newton + 1
                self.counters.factorisations += projector.newton + 1
                return state
        counts: dict = {}
        q = assemble_positions(self.model, self._kinematics, t, q, counts=counts)
        v = solve_velocities(self.model, self._kinematics, t, q, v)
        iterations = counts.get("newton", 0)  # each a Jacobian and a factorisation
        self.counters.newton += iterations
        self.counters.jacobians += iterations + 1
        self.counters.factorisations += iterations + 1
        return q, v

    @classmethod
    def describe(cls) -> dict:
        return {"name": cls.name, "order": cls.order, "index": cls.index,
                "stabilisation": cls.stabilisation, "adaptive": cls.adaptive,
                "description": cls.description}

    # ------------------------------------------------------------------ dense output

    def dense_output(self) -> Interpolant:
        """The method's own continuous extension over its last accepted step ``[t_old, t]``
        (an :class:`Interpolant`), valid from the end of :meth:`step` until the next call.
        A method that counts its own steps returns states at output times instead
        (:meth:`set_output_times`).

        Raises
        ------
        NotImplementedError
            The method has none (:meth:`has_dense_output`).
        """
        raise NotImplementedError(f"{self.name or type(self).__name__} has no dense output: it "
                                  "cannot give states between its steps")

    def set_output_times(self, times: np.ndarray) -> None:
        """A method that counts its own steps (:attr:`counts_own_steps`) returns its states at
        ``times`` (increasing, after ``t0``, at most ``t_bound``; ``t_bound`` is added),
        interpolated by its solver, instead of at its own output times. Call before the first
        :meth:`step`.

        Raises
        ------
        NotImplementedError
            The method cannot (:meth:`has_dense_output`).
        """
        raise NotImplementedError(f"{self.name or type(self).__name__} cannot return states "
                                  "at given output times")

    @classmethod
    def has_dense_output(cls) -> bool:
        """Whether the method gives states at any time of the run: by its continuous extension
        (:meth:`dense_output`), or for one that counts its own steps, at output times
        (:meth:`set_output_times`)."""
        name = "set_output_times" if cls.counts_own_steps else "dense_output"
        return getattr(cls, name) is not getattr(Integrator, name)

    def dense_state(self, t: float, q: np.ndarray,
                    v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """A state of the dense output made consistent: positions onto ``phi = 0`` and
        velocities onto ``Phi_v v = nu`` (:meth:`_project`), then the accelerations and
        multipliers there (:meth:`_dense_dynamics`). Counted as those services count."""
        q, v = self._project(t, self.model.normalize(q), v)
        return (q, v, *self._dense_dynamics(t, q, v))

    def _dense_dynamics(self, t: float, q: np.ndarray,
                        v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_dynamics` on data of its own (``data`` holds the method's current state,
        which some methods read again in their next step)."""
        v_dot, lam = self._dynamics(t, q, v, data=self._dense_data)
        return np.array(v_dot, dtype=float), np.array(lam, dtype=float)

    @cached_property
    def _dense_data(self):
        """The data the dense output's solves work in, made when first needed."""
        return self.model.create_data()

    def _hermite(self, start: tuple) -> HermiteInterpolant:
        """The quintic Hermite interpolant (:class:`HermiteInterpolant`) of the last step from
        its start ``(t, q, v, v_dot)`` to the current state (second-order methods)."""
        return HermiteInterpolant(self.model, start, (self.t, self.q, self.v, self.v_dot))

    # ------------------------------------------------------------------ tolerances per kind

    @cached_property
    def atol_vector(self) -> np.ndarray:
        """The absolute tolerance of each component of the state ``(q, v)`` (n_q + n_v), by
        its kind (:attr:`atol_kinds`, see :func:`absolute_tolerances`)."""
        columns = state_units(self.model)
        return np.array([self.atol_kinds[KIND_OF_UNIT[unit]] for unit in columns])

    @cached_property
    def atol_tangent(self) -> np.ndarray:
        """The absolute tolerance of each component of ``(dq, v)`` (2 n_v), ``dq`` an increment
        of the positions in the velocity space (:meth:`Model.integrate`): lengths for the
        translations, angles for the rotations."""
        n_q = self.model.n_q
        rates = self.atol_vector[n_q:]
        units = state_units(self.model)[n_q:]
        increments = np.array([self.atol_kinds["position" if unit == "m/s" else "angle"]
                               for unit in units])
        return np.concatenate([increments, rates])

    # ------------------------------------------------------------------ singular poses

    #: a failure is reported as one at a singular configuration (:meth:`_singular_pose`) where
    #: a singular value of the equilibrated ``Phi_v`` has fallen below this fraction of its
    #: value at the start (:attr:`_spectrum_start`, the singular values compared in sorted
    #: order): their values away from such poses depend on the mechanism and its masses (5e-5
    #: on a hexapod, 0.08 on the N-four-bar standing up), so only their fall tells one
    near_singular = 0.05
    #: the methods that cross singular configurations (the crossing of :meth:`_cross_singular`)
    crossing_methods = ("dopri5-projection", "dop853-projection")

    def _smallest_singular_value(self, q: np.ndarray | None = None,
                                 t: float | None = None) -> float:
        """Of the kept rows of the equilibrated ``Phi_v`` at ``(t, q)`` (default the current
        state; ``inf`` without rows)."""
        if not self.model.n_c:
            return np.inf
        return self._rank_split(q, t).smallest_singular_value()

    @cached_property
    def _spectrum_start(self) -> np.ndarray:
        """The singular values of the kept rows of the equilibrated ``Phi_v`` at the start, in
        increasing order (a large model's smallest alone: a dense SVD is cubic in the bodies),
        computed when a failure first needs them. Measured against the start, not against 1:
        the flyball governor's smallest is 9e-4 where nothing is singular, and measured
        against 1 its failures were blamed on a singular pose."""
        return self._spectrum(self._q_start, self.t0)

    def _spectrum(self, q: np.ndarray | None = None, t: float | None = None) -> np.ndarray:
        if not self.model.n_c:
            return np.zeros(0)
        split = self._rank_split(q, t)
        if is_large(self.model):
            return np.array([split.smallest_singular_value()])
        return np.sort(split.singular_values())

    def _singular_pose(self) -> str:
        """When the current positions are near a singular configuration (see
        :attr:`near_singular`), or on the way to one foreseen close ahead, a sentence that
        names it (time, the singular value that fell) and the methods that cross it; else the
        empty string. For the messages of failures.

        The smallest singular value is compared first; where it has not fallen, the others in
        sorted order (the k-th smallest falls only where k values do): the spatial
        N-four-bar's smallest stands near 1.4e-4 all along, and the ten that collapse at its
        flat pose are the next ten (to 0.06 to 0.08 of their values at the start, which is
        near the pose already, where Radau5 fails). A method may fail before they have fallen
        that far (Radau5 at rtol 1e-8, 1.7e-3 s before that pose, the ten at 0.55 to 0.96 of
        their values at the start, 4e-3 to 8e-3): the pose is then foreseen from the rate at
        which the values fall (:meth:`_foreseen_pose`)."""
        try:
            now = self._spectrum()
            start = self._spectrum_start
        except (HexapodError, np.linalg.LinAlgError, ValueError):
            return ""
        n = min(now.size, start.size)
        if n == 0:
            return ""
        reference = np.where(np.isfinite(start[:n]) & (start[:n] > 0), start[:n], 1.0)
        ratios = now[:n] / reference
        k = 0 if ratios[0] < self.near_singular else int(np.argmin(ratios))
        which = "smallest singular value" if k == 0 else "a singular value"
        where = (f"at a singular configuration at t = {self.t:.6g} s ({which} of the "
                 f"equilibrated constraint Jacobian {now[k]:.2g}, {ratios[k]:.2g} of its value "
                 "at the start)")
        # the smallest fallen, or within the band where crossings begin with others fallen
        # tenfold (the spatial N-four-bar: its smallest 1.1e-4, ten more fallen 12 to 16 times)
        if not (ratios[0] < self.near_singular
                or (now[0] < CROSSING_FACTOR * SINGULAR_BAND
                    and ratios[k] < 1.0 / CROSSING_FACTOR)):
            foreseen = self._foreseen_pose(now[:n])
            if foreseen is None:
                return ""
            k, ahead = foreseen
            where = (f"near a singular configuration at t = {self.t:.6g} s (a singular value "
                     f"of the equilibrated constraint Jacobian, {now[k]:.2g}, falls to zero "
                     f"{ahead:.2g} s ahead at its present rate)")
        return (f"the mechanism is {where}, which {self.name} cannot pass; "
                f"{' and '.join(self.crossing_methods)} cross such poses")

    def _foreseen_pose(self, now: np.ndarray) -> tuple[int, float] | None:
        """``(k, seconds)``: the singular value (in sorted order) that, falling along the
        motion at its present rate, reaches zero soonest, and in how long, when it is one a
        crossing could leave out (below :data:`CLUSTER_CEILING`) and reaches zero within the
        crossings' horizon (:data:`FORESIGHT_STEPS` accepted steps and :data:`FORESIGHT_TIME`
        characteristic times); else None. The rates are differences over a thousandth of the
        last accepted step."""
        delta = 1e-3 * self._accepted_step
        if not delta > 0 or not now[0] < CLUSTER_CEILING:
            return None
        ahead = self._spectrum(self._positions_ahead(delta))[:now.size]
        rates = (ahead - now) / delta
        falling = (rates < 0) & (now < CLUSTER_CEILING)
        seconds = np.where(falling, now / -np.minimum(rates, -1e-300), np.inf)
        k = int(np.argmin(seconds))
        horizon = min(FORESIGHT_STEPS * self._accepted_step,
                      FORESIGHT_TIME * characteristic_time(self.model))
        return (k, float(seconds[k])) if seconds[k] <= horizon else None


def _collapsing(sigma: np.ndarray, tolerance: float) -> int:
    """How many rows a crossing leaves out: the singular values below ``tolerance`` and those
    just above that belong to the same cluster (each within :data:`CROSSING_FACTOR` of the
    next smaller, below :data:`CLUSTER_CEILING`). Identical loops flattening at
    once (the N-four-bar's N windows) make such a cluster, spread over decades by their places
    in the chain: leaving out only its smallest members left the others to fail the error test
    one by one, each failure widening the crossing tenfold."""
    ordered = np.sort(sigma)
    count = int(np.sum(ordered < tolerance))
    while (0 < count < ordered.size and ordered[count] < CROSSING_FACTOR * ordered[count - 1]
           and ordered[count] < CLUSTER_CEILING):
        count += 1
    return count
