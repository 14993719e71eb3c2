"""The time loop: run an integrator to the end, save states, watch the constraints and the energy.

:func:`simulate` makes the initial state consistent (through the integrator), steps until the
end or a failure, saves every ``every``-th accepted step (and always the first and the last
state) or, given output times (``t_eval``), the states at those times from the method's own
continuous extension of the step that holds each (:meth:`Integrator.dense_output`), put back
on the constraints; it measures at **every** accepted step the constraint residuals of positions and
velocities and, when the scene conserves energy, the energy drift, and returns a
:class:`~hexapod.simulation.results.SimulationResult`. A failure is a result too: ``status =
"failed"`` with the message and the states up to it; so is an interruption (``status =
"interrupted"``). The run is weighed against the limits of :mod:`hexapod._support.limits`
(steps, memory of the saved states) before or while it runs.
"""

from __future__ import annotations

import math
import os
import time
import warnings
from collections.abc import Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike

from hexapod._support import limits, signals
from hexapod.algorithms.liaison import wrenches_from_multipliers
from hexapod.errors import HexapodError
from hexapod.model.model import Model
from hexapod.model.tabulation import TOLERANCE_PER_RTOL, tabulated_model
from hexapod.simulation.integrators import Integrator
from hexapod.simulation.methods import DEFAULT_ATOL, DEFAULT_RTOL
from hexapod.simulation.registry import default_method, get_integrator
from hexapod.simulation.results import SimulationResult
from hexapod.simulation.tracking import controller_names, tracking_errors
from hexapod.simulation.watch import Watch

#: steps tried (accepted or rejected) after which a run's pace is measured, then weighed each
#: time they double: the pace since this first weighing, so that the starting transient (a
#: small first step growing, a stiff solver's first call) does not count. A run is stopped on
#: its pace when two weighings in a row find it over a limit with estimates that agree (see
#: :data:`STEADY_PACE`), and at once when what it holds already passes the memory limit
WEIGH_AFTER = 20
#: the largest ratio of two successive estimates of a run's work for its pace to count as
#: steady. Where the steps shrink for a while (a crossing of a singular pose), time hardly
#: advances while the steps tried double, and each estimate doubles the one before: the
#: N-four-bar with 40 windows, 14 steps into 20 s and 800 short steps from its flat pose, was
#: estimated to need 44 GiB; it needs 0.3. A steady pace keeps its estimate.
STEADY_PACE = 1.5
#: bytes a saved state costs per number until the run's files are written: the state's array,
#: the result's copy, and its CSV text (about 24 characters per number, built in pieces and
#: joined). The peak memory of 'hexapod simulate' (rk4-baumgarte) grows by 75 to 87 bytes per
#: number and saved state: the pendulum with 1e5 and 2e5 states, the front leg with 5e4
BYTES_PER_SAVED_NUMBER = 100
#: what a user may do about a run that would take too many steps or too much memory, said by
#: the messages of the limits (a command line says its own options instead)
ADVICE = {"steps": "shorten the run (t_end) or take larger steps (step, or looser rtol and "
                   "atol)",
          "memory": "save fewer states (a larger every)",
          "output": "give fewer output times (t_eval)"}
#: what :class:`_Weighing` is told of ``every`` when output times are given: the states saved
#: are then those times (weighed before the run by :func:`weigh_output_times`), not the steps
_NO_STEP_SAVED = 2**62


def simulate(model: Model, t_end: float, *, method: str | type[Integrator] | None = None,
             t0: float = 0.0, q0: np.ndarray | None = None, v0: np.ndarray | None = None,
             rtol: float | None = None, atol: float | Mapping[str, float] | None = None,
             step: float | None = None, every: int = 1, t_eval: ArrayLike | None = None,
             forces: bool | None = None, max_steps: int | None = None,
             max_memory: int | None = None, cpu_budget: float | None = None,
             progress: Callable[[float, float], None] | None = None,
             options: dict | None = None, advice: dict[str, str] | None = None,
             exact_laws: bool = False) -> SimulationResult:
    """Integrate the motion of ``model`` from ``t0`` to ``t_end``.

    Parameters
    ----------
    model : Model
    t_end : float
        The end of the run, s.
    t0 : float
        Its start, s.
    q0, v0 : ndarray, shape (n_q,) and (n_v,), optional
        Guesses of the initial state (default: the scene's), made consistent first.
    method : str or type, optional
        A registered integrator name (:data:`hexapod.simulation.registry.INTEGRATORS`, or a
        contact scheme of :data:`~hexapod.simulation.registry.CONTACT_SCHEMES`), its short
        name (:data:`~hexapod.simulation.methods.ALIASES`: ``rk4``, ``dopri5``, ``dop853``,
        ``radau``, ``idas``, ``gen-alpha``) or class; the result records the registered name.
        Default: :func:`~hexapod.simulation.registry.default_method` (``dop853-projection``,
        or ``moreau-jean`` for a scene with unilateral contacts).
    rtol, atol, step : float, float or mapping, float; optional
        Tolerances of adaptive methods (default :data:`~hexapod.simulation.methods.DEFAULT_RTOL`
        and ``DEFAULT_ATOL``; a fixed-step method given them warns that it ignores them); the
        step of fixed-step methods (the first step of adaptive ones). See
        :class:`~hexapod.simulation.integrators.Integrator`. ``atol`` is a number (SI units of
        every coordinate) or a mapping per kind of coordinate, keys ``position`` (m),
        ``angle`` (rad, and the Euler parameters), ``velocity`` (m/s) and
        ``angular_velocity`` (rad/s), each weighing its coordinates in the error norm; the
        kinds it leaves out take the defaults of
        :func:`~hexapod.simulation.integrators.tolerances.default_tolerances` (scaled by the
        scene's characteristic length and time). The result's ``options["atol"]`` holds the
        tolerance used per kind.
    every : int
        Save every ``every``-th accepted step (every ``every``-th state a method returns, for
        a method that returns states at output times and counts its own steps). Not with
        ``t_eval``.
    t_eval : array_like, shape (K,), optional
        Output times (s, increasing, within ``[t0, t_end]``): the states saved are those at
        these times (``t0`` and ``t_end`` only when they are among them), each from the
        method's own continuous extension of the step that holds it (for ``idas-bdf``, IDAS's
        interpolation at its output times), positions and velocities projected onto the
        constraints and the accelerations and multipliers solved there. The steps are not
        changed by them. See :func:`output_times` and :func:`uniform_times`.
    forces : bool, optional
        Also compute the joint wrenches at the saved states (report convention); default: as
        the scene asks (``[scene] report_forces``).
    max_steps, max_memory : int, optional
        The limits the run is weighed against (default: those of
        :mod:`hexapod._support.limits`, ``HEXAPOD_MAX_STEPS`` and ``HEXAPOD_MAX_MEMORY``): the
        steps, and the memory of the saved states. A fixed-step run is weighed before it starts
        (a :class:`HexapodError` refuses it); every run each time its steps tried double from
        :data:`WEIGH_AFTER` on, by extrapolating its pace since the last weighing to ``t_end``:
        one that would pass a limit ends as failed, its states kept. The run also stops, as
        failed, after ``max_steps`` steps.
    cpu_budget : float, optional
        Stop the run, as failed, once its time loop has used this many CPU seconds (the states
        up to there are kept).
    progress : callable, optional
        Called as ``progress(t, t_end)`` after each accepted step.
    options : dict, optional
        Further keyword arguments of the integrator (e.g. ``rho_inf``, ``alpha``).
    advice : dict of str to str, optional
        What the messages of the limits suggest to ask for less (keys ``"steps"`` and
        ``"memory"``; default :data:`ADVICE`): a command line names its options.
    exact_laws : bool
        Evaluate every time law exactly at every stage. By default the laws that cost far more
        than interpolating them (a gait's inverse kinematics) are tabulated once and
        interpolated to a hundredth of ``rtol`` (:mod:`hexapod.model.tabulation`); the
        result's ``options["laws"]`` says how, and with what error.

    Returns
    -------
    SimulationResult
        The saved states and the run's statistics. A run that fails is a result too
        (``status``, ``message``): a ``KeyboardInterrupt`` during the time loop ends it with
        ``status = "interrupted"`` and the states saved up to there; a state, acceleration or
        multiplier that becomes non-finite ends it as failed, with the time.

    Raises
    ------
    HexapodError
        When the initial state cannot be made consistent (the run has not started), or a
        fixed-step run, or the states at the output times, would pass a limit.
    ValueError
        Bad arguments: ``every`` below 1, or with ``t_eval``; output times not finite, not
        increasing or outside the run; ``t_eval`` for a method without dense output.
    """
    if every < 1:
        raise ValueError(f"every must be at least 1, got {every}")
    if not (np.isfinite(t0) and np.isfinite(t_end) and np.isfinite(t_end - t0)):
        raise ValueError(f"t0 and t_end must be finite and their difference too, got {t0} and "
                         f"{t_end}")
    grid = None if t_eval is None else output_times(t_eval, t0, t_end)
    if grid is not None and every != 1:
        raise ValueError("every and t_eval cannot be given together: with output times the "
                         "states saved are those at the times")
    cls = get_integrator(default_method(model) if method is None else method)
    if grid is not None and not cls.has_dense_output():
        raise ValueError(f"{cls.name} has no dense output: it cannot save states at t_eval")
    options = {**_tolerances(cls, rtol, atol), "step": step, **(options or {})}
    advice = {**ADVICE, **(advice or {})}
    weigh = _Weighing(model, cls, t0, t_end, every if grid is None else _NO_STEP_SAVED,
                      max_steps, max_memory, advice)
    if grid is not None:
        weigh_output_times(model, grid.size, max_steps, max_memory, advice)
    weigh.before(step)
    run_model, laws = (model, None) if exact_laws else tabulated_model(
        model, t0, t_end, TOLERANCE_PER_RTOL * options.get("rtol", DEFAULT_RTOL))
    integrator = cls(run_model, t0, t_end, q0, v0, **options)
    if grid is not None and cls.counts_own_steps:
        integrator.set_output_times(grid)
    watch = Watch(run_model, integrator, grid)
    wall, cpu = time.perf_counter(), cpu_seconds()
    reached = _run(integrator, watch, weigh, every, cpu_budget, progress)
    wall, cpu = time.perf_counter() - wall, cpu_seconds() - cpu
    watch.complete()
    arrays, levels = watch.arrays()
    worst = watch.worst
    # the tolerances used, per kind (a fixed-step method ignores them)
    options = {**options, "atol": dict(integrator.atol_kinds)}
    if grid is not None:
        options["output_times"] = int(grid.size)
    if laws is not None:
        options["laws"] = laws
    result = SimulationResult(
        model=model, method=cls.name, t=arrays["t"], q=arrays["q"], v=arrays["v"],
        v_dot=arrays["v_dot"], lam=arrays["lam"],
        status=integrator.status, message=integrator.message, counters=integrator.counters,
        wall_time=wall, cpu_time=cpu, max_position_violation=worst["phi"],
        max_velocity_violation=worst["velocity"],
        energy=levels,
        energy_drift=(worst["drift"] / max(worst["kinetic"], np.finfo(float).tiny)
                      if watch.conserved else None),
        options=options, t_bound=float(t_end), t_start=float(t0),
        t_reached=float(reached) if grid is not None else None,
        contact_forces=arrays.get("contact_forces"), events=getattr(integrator, "events", None))
    if controller_names(model):
        result.tracking = tracking_errors(model, result.t, result.q)
    if forces or (forces is None and model.report_forces):
        _add_wrenches(result)
    return result


def _run(integrator: Integrator, watch: Watch, weigh: _Weighing, every: int,
         cpu_budget: float | None, progress) -> float:
    """Step until the end, a failure, a limit or an interruption; every outcome is said by the
    integrator's ``status`` and ``message``. Returns the time of the last step completed."""
    name = integrator.name
    cpu = cpu_seconds()
    returned = 0  # states returned (one per step, or per call for some methods)
    reached = integrator.t  # the time of the last step completed
    try:
        while integrator.status == "running":
            if signals.received() is not None:  # an interruption a library call swallowed
                raise KeyboardInterrupt
            stop = weigh.during(integrator, returned)
            if stop is None and cpu_budget is not None and cpu_seconds() - cpu > cpu_budget:
                stop = f"by the CPU budget of {cpu_budget:g} s"
            if stop is not None:
                integrator.status = "failed"
                integrator.message = f"{name}: stopped at t = {integrator.t:.6g} s {stop}"
                break
            integrator.step()
            if integrator.status == "failed":
                break
            returned += 1
            _take_step(watch, integrator, returned, every)
            reached = integrator.t
            if progress is not None:
                progress(integrator.t, integrator.t_bound)
    except KeyboardInterrupt:
        integrator.status = "interrupted"
        integrator.message = f"{name}: interrupted at t = {reached:.6g} s"
    except Exception:
        # a library that turns an interruption into an error of its own (CasADi does)
        if signals.received() is None:
            raise
        integrator.status = "interrupted"
        integrator.message = f"{name}: interrupted at t = {reached:.6g} s"
    return reached


def _take_step(watch: Watch, integrator: Integrator, returned: int, every: int) -> None:
    """Watch the state one step returned, and save it when it is due."""
    watch.watch()
    if watch.grid is not None:
        watch.save_grid()
    elif integrator.status == "finished" or returned % every == 0:
        watch.save()


class _Weighing:
    """The run weighed against the limits of steps and memory: before it starts (fixed-step
    methods, whose steps are known), and while it runs, on its pace."""

    def __init__(self, model: Model, cls: type[Integrator], t0: float, t_end: float,
                 every: int, max_steps: int | None, max_memory: int | None, advice: dict):
        self.cls, self.t0, self.t_end, self.every = cls, t0, t_end, every
        self.max_steps = limits.max_steps(max_steps)
        self.max_memory = limits.max_memory(max_memory)
        self.advice = advice
        forces = 7 * len(model.joints) if model.report_forces else 0
        numbers = 1 + model.n_q + 2 * model.n_v + model.n_c + forces
        self.state_bytes = BYTES_PER_SAVED_NUMBER * numbers
        self.next_weighing = WEIGH_AFTER
        # steps tried, states returned and time at the first weighing
        self.first: tuple[int, int, float] | None = None
        # the work the last weighing estimated, when it found the run over a limit
        self.over: float | None = None

    def _check(self, steps: float, states: float, what: str) -> None:
        limits.check_steps(steps, what, self.advice["steps"], self.max_steps)
        saved = states / self.every + 2
        limits.check_memory(saved * self.state_bytes, f"{what}, saving about {saved:.3g} "
                            "states,", self.advice["memory"], self.max_memory)

    def before(self, step: float | None) -> None:
        """Refuse a run that would pass a limit (a :class:`HexapodError`): the steps and states
        of a fixed-step method, the states of one that returns them at output times ``step``
        apart (its steps are its own)."""
        if self.cls.adaptive and not self.cls.counts_own_steps:
            return
        span = self.t_end - self.t0
        states = self.cls.default_steps if step is None else span / step
        states = math.ceil(states) if math.isfinite(states) else math.inf
        what = f"{self.cls.name} from t = {self.t0:.6g} to {self.t_end:.6g} s"
        self._check(0 if self.cls.adaptive else states, states, what)

    def during(self, integrator: Integrator, returned: int) -> str | None:
        """Why the run must stop now, or None: past the step limit, holding states past the
        memory limit, or (weighed each time the steps tried double from :data:`WEIGH_AFTER`
        on) on a steady pace that would pass a limit before ``t_end``."""
        counters = integrator.counters
        if counters.steps >= self.max_steps:
            return (f"after {counters.steps} steps, the limit: {self.advice['steps']}, or raise "
                    "the limit (--max-steps, HEXAPOD_MAX_STEPS)")
        # the work: steps tried, rejected ones too (a fixed-step method halves its step when
        # Newton's method fails, and may crawl)
        tried = counters.steps + counters.rejected
        if tried < self.next_weighing:
            return None
        self.next_weighing = 2 * tried
        try:
            self._check(counters.steps, returned, f"at t = {integrator.t:.6g} s")
        except HexapodError as error:
            return f"after {counters.steps} steps: {error}"
        if self.first is None:  # the pace is measured from here: not over a starting transient
            self.first = (tried, returned, integrator.t)
            return None
        if integrator.crossing:  # short steps for a while, not the run's pace: weighed later
            self.over = None
            return None
        first_tried, first_returned, first_t = self.first
        elapsed = integrator.t - first_t
        if not elapsed > 0:
            return None
        left = (self.t_end - integrator.t) / elapsed  # the spans of time still to go
        work = tried + left * (tried - first_tried)
        try:
            self._check(counters.steps + left * (tried - first_tried),
                        returned + left * (returned - first_returned),
                        f"at its pace, reaching t = {self.t_end:.6g} s")
        except HexapodError as error:
            over, self.over = self.over, work
            if over is not None and work <= STEADY_PACE * over:
                return f"after {counters.steps} steps: {error}"
            return None
        self.over = None
        return None


def cpu_seconds() -> float:
    """CPU seconds of this process and of the children it has waited for: a compiler that
    builds a kernel during the time loop counts in its time."""
    times = os.times()
    return time.process_time() + times.children_user + times.children_system


def output_times(t_eval, t0: float, t_end: float) -> np.ndarray:
    """The output times of a run from ``t0`` to ``t_end``, checked: at least one, finite,
    increasing, within ``[t0, t_end]`` (a time past an end by round-off, 1e-12 relative, is
    taken as that end).

    Raises
    ------
    ValueError
        Saying which time is wrong and why.
    """
    try:
        times = np.array(t_eval, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("the output times must be numbers") from None
    if times.ndim != 1:
        raise ValueError("the output times must be a sequence of numbers")
    if not times.size:
        raise ValueError("no output time given")
    bad = np.flatnonzero(~np.isfinite(times))
    if bad.size:
        raise ValueError(f"the output times must be finite, got {times[bad[0]]}")
    slack = 1e-12 * max(1.0, abs(t0), abs(t_end))
    outside = np.flatnonzero((times < t0 - slack) | (times > t_end + slack))
    if outside.size:
        raise ValueError(f"{times[outside[0]]:.10g} s is outside the run, from {t0:.10g} to "
                         f"{t_end:.10g} s")
    times = np.clip(times, t0, t_end)
    back = np.flatnonzero(np.diff(times) <= 0)
    if back.size:
        raise ValueError(f"the output times must increase: {times[back[0] + 1]:.10g} s after "
                         f"{times[back[0]]:.10g} s")
    return times


def uniform_count(t0: float, t_end: float, dt: float) -> int:
    """How many times ``t0, t0 + dt, ...`` fall within ``[t0, t_end]`` (one past ``t_end`` by
    round-off counts), computed before any array is made."""
    return math.floor((t_end - t0) / dt * (1 + 1e-12)) + 1


def uniform_times(t0: float, t_end: float, dt: float) -> np.ndarray:
    """The output times ``t0, t0 + dt, ...`` up to ``t_end`` (which is among them when the
    duration is a multiple of ``dt``, to round-off)."""
    times = t0 + dt * np.arange(uniform_count(t0, t_end, dt))
    if abs(times[-1] - t_end) <= 1e-9 * dt:
        times[-1] = t_end
    return np.minimum(times, t_end)


def weigh_output_times(model: Model, count: int, max_steps: int | None = None,
                       max_memory: int | None = None, advice: dict | None = None) -> None:
    """Refuse (:class:`HexapodError`), before any work, more output times than the limit of
    steps allows, or whose states would pass the memory limit (a state weighed as
    :class:`_Weighing` weighs one)."""
    advice = {**ADVICE, **(advice or {})}
    bound = limits.max_steps(max_steps)
    if count > bound:
        raise HexapodError(f"{count:,} output times are more than the limit of steps "
                           f"({bound:,}), which bounds them too: {advice['output']}, or raise "
                           "the limit with --max-steps (or HEXAPOD_MAX_STEPS)")
    forces = 7 * len(model.joints) if model.report_forces else 0
    numbers = 1 + model.n_q + 2 * model.n_v + model.n_c + forces
    limits.check_memory(float(count) * BYTES_PER_SAVED_NUMBER * numbers,
                        f"saving the states at {count:,} output times", advice["output"],
                        max_memory)


def _tolerances(cls: type[Integrator], rtol: float | None, atol) -> dict:
    """The tolerances a run uses: the defaults where not given; a fixed-step method that was
    given some says it ignores them."""
    if not cls.adaptive and (rtol is not None or atol is not None):
        warnings.warn(f"{cls.name} is a fixed-step method: it ignores rtol and atol (set its "
                      "step with step=)", UserWarning, stacklevel=3)
    return {"rtol": DEFAULT_RTOL if rtol is None else rtol,
            "atol": DEFAULT_ATOL if atol is None else atol}


def _add_wrenches(result: SimulationResult) -> None:
    """Joint wrenches at the saved states, from the saved multipliers."""
    model = result.model
    n, J = result.t.size, len(model.joints)
    force, torque, effort = np.zeros((n, J, 3)), np.zeros((n, J, 3)), np.zeros((n, J))
    data = model.create_data()
    if n > 1:
        model.law_values(result.t, data)  # all at once, kept in data for the samples below
    for k in range(n):
        q, v = result.q[k], result.v[k]
        w, _, _ = model.law_values(result.t[k], data)
        Phi_v = model.call("Phi_v", data, q=q, w=w)
        Q_across = (model.call("Q_across", data, q=q, v=v, w=w) if model.Q_across is not None
                    else None)
        wrenches = wrenches_from_multipliers(model, q, result.lam[k], Phi_v, Q_across,
                                             data=data)
        force[k], torque[k], effort[k] = wrenches.force, wrenches.torque, wrenches.effort
    result.force, result.torque, result.effort = force, torque, effort

