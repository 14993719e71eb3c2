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

from collections import deque
from dataclasses import asdict, dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np

from hexapod.algorithms.dynamics import forward_dynamics
from hexapod.algorithms.kinematics import assemble_positions, solve_velocities
from hexapod.errors import HexapodError, IntegrationError
from hexapod.model.model import Model
from hexapod.simulation.integrators.interpolants import HermiteInterpolant, Interpolant
from hexapod.simulation.integrators.singular import FORESIGHT_STEPS, SingularPoses
from hexapod.simulation.integrators.step_ends import StepEnds
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
    motion_scales,
)

#: the rank decision's tolerance at a state off the constraints by ``e`` (scaled by the row
#: scales) is at least this times ``e``: a redundant row's distance from the others' span grows
#: like ``e`` there (the methods that leave the constraints by a drift or a Newton error)
RANK_MARGIN = 10.0


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


class Integrator(SingularPoses, StepEnds):
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
    #: True for a contact scheme: its velocities jump at impacts, and unilateral contacts
    #: (``ground-contact`` force elements) are its to integrate; the other methods refuse them
    impulsive: ClassVar[bool] = False
    #: True when the method reads nothing at its start but the state, its rates and the
    #: compiled kernels: the start's accelerations then come from the kernels' solve (built
    #: first, from the projection's rank decision) where it serves, not from the exact one
    starts_by_kernels: ClassVar[bool] = False

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
        touching = [f.name for f in model.forces if f.contact is not None]
        if touching and not self.impulsive:
            raise HexapodError(f"{self.name} does not integrate unilateral contacts ("
                               + ", ".join(f"'{n}'" for n in touching[:5])
                               + "): simulate this scene with a contact scheme "
                               "(method moreau-jean, or event-driven)")
        if step is not None and not step > 0:
            raise ValueError(f"step must be positive, got {step}")
        # a mapping gives each kind of coordinate its own (see absolute_tolerances); the scalar
        # ``atol`` is then the smallest of them
        self.atol_kinds = absolute_tolerances(model, atol)
        atol = min(self.atol_kinds.values())
        if not (rtol > 0 and atol > 0):
            raise ValueError(f"rtol and atol must be positive, got {rtol} and {atol}")
        self.model = model
        model.retraction()  # made here, not at the first step: no compiler inside the time loop
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
        self._recent_steps: deque[float] = deque(maxlen=FORESIGHT_STEPS)  # and those before
        self._kinetic_peak = 0.0  # the largest kinetic energy of the run so far (J)
        # (q, v, q_dot) of the last step end's compiled solve; (q, v, energies) of the last
        # state weighed: the same arrays are asked again (the next step, the run's watch)
        self._position_rates_at: tuple | None = None
        self._energy_at: tuple | None = None
        q, v = self._project(self.t0, q0, v0)  # guesses of None: the scene's initial state
        self.t, self.q, self.v = self.t0, q, v
        self._q_start = q
        # the projection's rank decision, taken at this state, serves the dynamics there (two
        # workspaces, one decision: a fifth of a small model's start)
        decided = self._kinematics.built.get("state decision")
        if decided is not None:
            self.data.built["state decision"] = decided
        by_kernels = self.starts_by_kernels and decided is not None
        if by_kernels:
            split = decided[3]
            self.data.independent_rows, self.data.redundant_rows = (split.independent,
                                                                    split.redundant)
        else:
            self.v_dot, self.lam = self._dynamics(self.t, q, v)
        # the stages' right-hand sides and the projection, compiled for the rows independent
        # at the start
        here = self._here()
        self._compiled = compiled_rates(model, self.data.independent_rows, here,
                                        self.data.redundant_rows)
        self._compiled_projection = compiled_projection(model, self.data.independent_rows, here)
        self._feet_down = self._contact_set(self.t)
        if by_kernels:
            # the kernels' solve (its checks passed), else the exact one (which says why not)
            self.v_dot, self.lam = self._end_rates(self.t, q, v)
        self._start()

    @property
    def lam(self) -> np.ndarray:
        """The multipliers at the current state (by the least-wrench redundancy policy); a method
        that advances with the compiled right-hand side solves for them only when asked."""
        if self._lam is None:
            self._lam = self.multipliers(self.t, self.q, self.v)
        return self._lam

    def multipliers(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The multipliers at a state by the redundancy policy, counted as a solve: the
        compiled kernel's where it can give them
        (:meth:`~hexapod.simulation.kernels.CompiledRates.dynamics`, see
        :meth:`_kernels_serve`), else the exact solve's."""
        serve = self._kernels_serve(t)
        policy = self._compiled.policy if serve else None
        solved = policy is not None and policy.holds(t, q, v)  # by _end_rates
        solution = self._compiled.dynamics(t, q, v) if serve else None
        if solution is not None:
            self.counters.rhs += 0 if solved else 1
            return np.asarray(solution[1], dtype=float)
        return self._dynamics(t, q, v)[1]

    def _end_rates(self, t: float, q: np.ndarray, v: np.ndarray) -> tuple:
        """A step end's accelerations (:meth:`_rates`) and, where the same compiled solve gives
        them as :meth:`multipliers` would (every row kept; the kernels serve ``t``), its
        multipliers: saving every step then costs one solve a step, not two. With rows left
        out and feet on the ground, the accelerations come from the ground-force policy's
        kernel, whose call the multipliers then reuse (:meth:`PolicyMultipliers.terms`);
        the policy's choice is made only if they are asked for. Else None."""
        serve = self._kernels_serve(t)
        policy = self._compiled.policy if serve else None
        if policy is not None:
            terms = policy.terms(t, q, v)
            if terms is not None:
                self.counters.rhs += 1
                return terms[0], None
        solution = self._compiled.solve(t, q, v) if self._compiled.complete and serve else None
        if solution is None:
            return self._rates(t, q, v)[1], None
        self.counters.rhs += 1
        self._position_rates_at = (q, v, solution[0])  # the next step's first stage
        return solution[1], solution[2]

    def _position_rates(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``q_dot`` at ``(q, v)``: the one the step end's compiled solve gave with the
        accelerations (:meth:`_end_rates`), where the state is that one, else evaluated."""
        kept = self._position_rates_at
        if kept is not None and kept[0] is q and kept[1] is v:
            return kept[2]
        return self.model.call("qdot", self.data, q=q, v=v)

    def _kernels_serve(self, t: float) -> bool:
        """Whether the compiled kernels give the accelerations and multipliers of a state to
        be saved at ``t``: not while a singular pose is crossed (the rows left out are
        violated by design), nor at a touch-down or lift-off the kernels were not built for
        (a step that ends on one: their rows, held by the old set's solve alone, moved the
        walking robot's multipliers by 2e-8 of the largest at a touch-down, against 1e-12
        elsewhere)."""
        return self._crossing is None and self._contact_set(t) == self._feet_down

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
            blew_up = "non-finite" in str(error) or not np.isfinite(self.q).all()
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
        self._recent_steps.append(self._accepted_step)
        # a fixed smooth step is weighed: a jump of its velocities or energy is not an impact
        weighed = not (self.adaptive or self.impulsive)
        if not np.isfinite(self.q).all() or not np.isfinite(self.v).all():
            self.status = "failed"
            self.message = (f"{self.name}: non-finite state at t = {self.t:.6g} s (the step is "
                            "too large for this method, or the motion is unstable)")
        elif weighed and self._jumps_branch(self.t - t_before, v_before, a_before,
                                            self.v, self.v_dot):
            # a fixed step cannot shorten itself through a singular pose: it says so
            where = self._singular_pose()
            self.status = "failed"
            self.message = (f"{self.name}: the step from t = {t_before:.6g} s changed the "
                            "velocities by more than its accelerations explain: it left the "
                            "motion's branch" + (f"; {where}" if where else
                                                 " (take a smaller step)"))
            return
        elif weighed and self._energy_jump(q_before, v_before, self.q,
                                           self.v) > ENERGY_JUMP:
            self.status = "failed"
            self.message = (f"{self.name}: the step from t = {t_before:.6g} s changed the "
                            f"energy of this conservative scene by "
                            f"{self._energy_jump(q_before, v_before, self.q, self.v):.2g} of "
                            "its largest kinetic energy: the step is too long for the motion"
                            + (f"; {where}" if (where := self._singular_pose()) else ""))
            return
        elif self._at_end(self.t):
            self.t = self.t_bound
            self.status = "finished"
        elif self.adaptive:  # a step cut to end at a break ends on it, not an ulp before
            self.t = self._on_break(self.t)
        if self.model.energy_conserved:
            self._kinetic_peak = max(self._kinetic_peak, self._energy(self.q, self.v)[0])

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

    # ------------------------------------------------------------------ services

    def _contact_set(self, t: float) -> tuple[bool, ...]:
        """Which of the model's feet are on the ground at ``t`` (their gates)."""
        if not self.model.contacts:
            return ()
        w = self.model.law_values(t, self.data)[0]
        return tuple(bool(w[c.gate] > 0.5) for c in self.model.contacts)

    def _follow_contacts(self, q: np.ndarray | None = None) -> None:
        """When feet have touched down or lifted off since the compiled kernels were built,
        build them (once per contact set) for the rows independent at ``(t, q)`` (default
        the current positions): a foot in swing has no rows, and one that touched down has
        rows the old set leaves out. A method whose step ends on a touch-down or lift-off
        calls it with the step's end positions before projecting them, so that the new set's
        kernels project, solve and save that state."""
        feet = self._contact_set(self.t)
        if feet == self._feet_down:
            return
        self._feet_down = feet
        split = self._rank_split(q)
        rows = split.independent
        here = self._here(q)
        self._compiled = compiled_rates(self.model, rows, here, split.redundant)
        self._compiled_projection = compiled_projection(self.model, rows, here)

    def _here(self, q: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The positions (default the current ones) and the current law values: where compiled
        kernels choose their factorisation's pivots."""
        return self.q if q is None else q, self.model.law_values(self.t, self.data)[0]

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
        v_dot = forward_dynamics(self.model, data, t, q, v, baumgarte=baumgarte,
                                 open_contacts=self.impulsive, **options)
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
        return self.model.call("qdot", self.data, q=q, v=v), v_dot

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
        kinetic0, potential0 = self._energy(q0, v0)
        kinetic1, potential1 = self._energy(q1, v1)
        # at rest the energy's round-off, not the kinetic energy, sets the scale
        peak = max(self._kinetic_peak, kinetic0, kinetic1, ROUND_OFF * self._scales[2])
        return abs(kinetic1 + potential1 - kinetic0 - potential0) / peak

    def _energy(self, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
        """Kinetic and potential energy (J), through the method's call buffers (a plain
        CasADi call costs some 100 microseconds, several times a step of a small model); the
        last state's again without a call (states are replaced, never changed in place)."""
        kept = self._energy_at
        if kept is not None and kept[0] is q and kept[1] is v:
            return kept[2]
        kinetic, potential = self.model.fast("energy", self.data)(q, v)
        self._energy_at = (q, v, (float(kinetic[0]), float(potential[0])))
        return self._energy_at[2]

    def state_energy(self) -> tuple[float, float]:
        """Kinetic and potential energy (J) of the current state (the run's watch asks for
        the state the step's own check weighed)."""
        return self._energy(self.q, self.v)

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
            state = projector(t, q, v, self.data)
            if state is not None:
                self._projected = (t, *state, projector.residuals)
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

    def state_residuals(self) -> tuple[float, float] | None:
        """The current state's largest scaled residuals of ``phi = 0`` and ``Phi_v v = nu``
        when its compiled projection measured them (the state is the one it returned), else
        None: a run's watch then measures them itself."""
        projected = getattr(self, "_projected", None)
        if projected is None:
            return None
        t, q, v, residuals = projected
        return residuals if t == self.t and q is self.q and v is self.v else None

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
        """The compiled kernel's accelerations and multipliers (one call, as for the saved
        states, :meth:`multipliers`), else :meth:`_dynamics` on data of its own (``data``
        holds the method's current state, which some methods read again in their next
        step)."""
        solution = self._compiled.dynamics(t, q, v) if self._kernels_serve(t) else None
        if solution is None:
            solution = self._dynamics(t, q, v, data=self._dense_data)
        else:
            self.counters.rhs += 1
        return np.array(solution[0], dtype=float), np.array(solution[1], dtype=float)

    @cached_property
    def _dense_data(self):
        """The data the dense output's solves work in, made when first needed."""
        return self.model.create_data()

    def _hermite(self, start: tuple) -> HermiteInterpolant:
        """The quintic Hermite interpolant (:class:`HermiteInterpolant`) of the last step from
        its start ``(t, q, v, v_dot)`` to the current state (second-order methods)."""
        return HermiteInterpolant(self.model, start, (self.t, self.q, self.v, self.v_dot),
                                  self.data)

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
