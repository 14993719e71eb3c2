"""Design optimisation (``hexapod optimize STUDY.toml``): a figure of merit minimised over
masses and inertias within bounds, subject to bounds on other figures, by IPOPT through CasADi
with the exact gradients of :mod:`hexapod.sweeps.metric_derivatives`.

The study file shares the sweep's format (``docs/sweeps.md``): ``[study]`` (name, scene),
``[fixed]`` (builder arguments and scene keys held), ``[job]`` (the inverse-dynamics window);
``[vary.KEY]`` gives each optimised parameter's bounds as the sweep's ``range``, and an optional
``start``; ``[optimize]`` the figure of merit and the constraints (``docs/design.md``)::

    [study]
    name = "counterweight"
    scene = "lever.toml"

    [vary."body.weight.mass"]
    range = [0.0, 3.0]
    start = 0.5                       # default: the scene's value (clipped to the range)

    [optimize]
    minimize = "rms_effort:hinge"
    constraints = { "peak_effort:*" = { max = 40.0 } }   # '*': any element
    actuators = "motors.toml"         # optional: each driven joint's peak effort below its motor's
    tolerance = 1e-10                 # IPOPT's, on the scaled problem (default: see TOLERANCE)
    max_iterations = 200

    [job]
    samples = 201

Along a prescribed motion the forces are affine in the masses and inertias (see
:mod:`hexapod.algorithms.sensitivity`): one inverse-dynamics run and its sensitivities give the
forces, and so every figure of merit and its gradient, at any values of the parameters, exactly
(:class:`AffineDesign`). A joint's position or the gait's period moves the motion itself:
each evaluation then runs the scene built again with the values
(:class:`~hexapod.sweeps.rerun_design.RerunDesign`; the period at fixed phase). The optimum is
checked by a run of the scene built again with the optimal values.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from fnmatch import fnmatchcase
from pathlib import Path

import numpy as np

from hexapod._support.files import read_toml
from hexapod.algorithms.sensitivity import FrameChange, InertiaChange, ScaleChange
from hexapod.errors import HexapodError, InputFileError
from hexapod.sweeps.cases import StudyError
from hexapod.sweeps.metric_derivatives import SENSITIVE_FAMILIES, metric_sensitivities
from hexapod.sweeps.metrics import body_masses, inverse_metrics
from hexapod.sweeps.rerun_design import RerunDesign, held_length, run_at
from hexapod.sweeps.spec import Study, study_from_document

#: IPOPT's tolerance on the scaled problem by default: the gradients of masses and inertias
#: along a fixed motion are exact to round-off ...
TOLERANCE = 1e-10
#: ... and those of parameters that move the motion (the gait's period, its step height, a
#: joint's position: each evaluation a run of the scene built again) carry the inverse
#: dynamics' own accuracy (the motion solved by Newton's method: 3.7e-10 of the scaled
#: gradient at the walking robot's optimum of a knee's RMS torque over the period, where the
#: objective no longer changes), so that IPOPT asked for 1e-10 searched its line for hundreds
#: of evaluations there
MOVING_TOLERANCE = 1e-8
#: ... and there the optimiser stops once the objective changes by less than this (relative)
#: over three iterations, the scaled gradient within a hundred times the tolerance
ACCEPTABLE_CHANGE = 1e-10

_OPTIMIZE_KEYS = ("minimize", "constraints", "actuators", "tolerance", "max_iterations")
_BOUND_KEYS = ("range", "start")


@dataclass(frozen=True)
class Bound:
    """An optimised parameter: its scene key, bounds and start (NaN: the scene's value)."""

    name: str
    low: float
    high: float
    start: float = math.nan


@dataclass(frozen=True)
class Limit:
    """A constraint: the figures of merit ``pattern`` matches (``*``: any element) between
    ``low`` and ``high``."""

    pattern: str
    low: float = -math.inf
    high: float = math.inf


@dataclass(frozen=True)
class OptimizationStudy:
    """A parsed optimisation study: the sweep's :class:`~hexapod.sweeps.spec.Study` (scene,
    held values, job) and what is optimised."""

    study: Study
    minimize: str
    bounds: tuple[Bound, ...]
    limits: tuple[Limit, ...] = ()
    tolerance: float | None = None  # None: TOLERANCE, or MOVING_TOLERANCE (a moving motion)
    max_iterations: int = 200
    source: str = ""
    actuators: str = ""  # an actuator table: every driven joint's peak effort below its motor's


def read_optimization(path: str | Path) -> OptimizationStudy:
    """Read an optimisation study; every problem of the file is reported at once, naming its
    key (the parameters and figures of merit are checked against the scene by
    :func:`optimize`).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    OptimizationStudy

    Raises
    ------
    InputFileError
        The file cannot be read, is not TOML, or is not a valid study.
    """
    path = Path(path)
    document = read_toml(path, "study file")
    problems: list[str] = []
    optimize = document.pop("optimize", None)
    vary = document.pop("vary", {})
    if not isinstance(optimize, dict):
        problems.append("optimize: required, a table: minimize = \"FAMILY:ELEMENT\"")
        optimize = {}
    if not isinstance(vary, dict) or not vary:
        problems.append("vary: required, a table per parameter: [vary.\"body.NAME.mass\"] "
                        "range = [low, high]")
        vary = {}
    bounds = [b for b in (_bound(n, t, problems) for n, t in vary.items()) if b is not None]
    for key in optimize:
        if key not in _OPTIMIZE_KEYS:
            problems.append(f"optimize.{key}: unknown key (expected "
                            f"{', '.join(_OPTIMIZE_KEYS)})")
    minimize = optimize.get("minimize")
    if optimize and not (isinstance(minimize, str) and minimize):
        problems.append(f"optimize.minimize: a figure of merit, FAMILY or FAMILY:ELEMENT "
                        f"(families: {', '.join(SENSITIVE_FAMILIES)}), got {minimize!r}")
    limits = _limits(optimize.get("constraints", {}), problems)
    actuators = optimize.get("actuators", "")
    if not isinstance(actuators, str):
        problems.append(f"optimize.actuators: an actuator table's file, got {actuators!r}")
        actuators = ""
    elif actuators:
        actuators = str(path.parent / actuators)
    tolerance = optimize.get("tolerance")
    if tolerance is not None and not (isinstance(tolerance, int | float)
                                      and not isinstance(tolerance, bool) and 0 < tolerance < 1):
        problems.append(f"optimize.tolerance: a number in (0, 1), got {tolerance!r}")
    iterations = optimize.get("max_iterations", 200)
    if not (isinstance(iterations, int) and not isinstance(iterations, bool)
            and iterations >= 1):
        problems.append(f"optimize.max_iterations: an integer, at least 1, got {iterations!r}")
    try:
        study = study_from_document(document, path)
    except InputFileError as error:  # its own problems, listed with these
        problems += [line.strip() for line in str(error).splitlines()[1:]]
        study = None
    if study is not None and study.job["kind"] != "inverse":
        problems.append("job.kind: an optimisation runs the inverse dynamics (kind = "
                        "\"inverse\")")
    if problems:
        body = "\n  ".join(problems)
        raise InputFileError(f"{path}: not a valid optimisation study:\n  {body}")
    return OptimizationStudy(study, minimize, tuple(bounds), tuple(limits),
                             None if tolerance is None else float(tolerance), iterations,
                             str(path), actuators)


def _number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) \
        and math.isfinite(value)


def _bound(name: str, table, problems: list[str]) -> Bound | None:
    key = f"vary.{name}"
    if not isinstance(table, dict):
        problems.append(f"{key}: must be a table: range = [low, high], optional start")
        return None
    for k in table:
        if k not in _BOUND_KEYS:
            problems.append(f"{key}.{k}: unknown key (expected {', '.join(_BOUND_KEYS)})")
    bounds = table.get("range")
    if not (isinstance(bounds, list) and len(bounds) == 2 and all(map(_number, bounds))):
        problems.append(f"{key}.range: must be two finite numbers [low, high], got {bounds!r}")
        return None
    low, high = map(float, bounds)
    if not low < high:
        problems.append(f"{key}.range: low must be below high, got [{low:g}, {high:g}]")
        return None
    start = table.get("start", math.nan)
    if "start" in table and not (_number(start) and low <= start <= high):
        problems.append(f"{key}.start: a number within the range [{low:g}, {high:g}], got "
                        f"{start!r}")
        return None
    return Bound(name, low, high, float(start))


def _limits(table, problems: list[str]) -> list[Limit]:
    if not isinstance(table, dict):
        problems.append("optimize.constraints: a table, FIGURE = { min = A, max = B }")
        return []
    out = []
    for pattern, limit in table.items():
        key = f"optimize.constraints.{pattern}"
        if not isinstance(limit, dict) or not limit or set(limit) - {"min", "max"}:
            problems.append(f"{key}: a table with min, max or both, got {limit!r}")
            continue
        low, high = limit.get("min", -math.inf), limit.get("max", math.inf)
        if not all(_number(v) for v in limit.values()):
            problems.append(f"{key}: min and max must be finite numbers, got {limit!r}")
        elif not low < high:
            problems.append(f"{key}: min must be below max, got {limit!r}")
        else:
            out.append(Limit(pattern, float(low), float(high)))
    return out


@dataclass
class AffineDesign:
    """The figures of merit and their gradients at any values of mass and inertia
    parameters, from one inverse-dynamics run (at ``values``) and its sensitivities: exact,
    since the forces are affine in these parameters.

    Attributes
    ----------
    model : Model
    result : InverseResult
    sensitivity : InverseSensitivity
    strides : float
    values : ndarray (P,)
        The parameters' values of the run.
    """

    model: object
    result: object
    sensitivity: object
    strides: float
    values: np.ndarray
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def changes(self) -> tuple:
        """The parameters."""
        return self.sensitivity.parameters

    def at(self, p: np.ndarray) -> tuple[dict, dict]:
        """``(metrics, derivatives)`` at the parameters' values ``p``."""
        key = tuple(np.asarray(p, dtype=float).tolist())
        if key not in self._cache:
            self._cache.clear()
            self._cache[key] = self._evaluate(np.asarray(p, dtype=float))
        return self._cache[key]

    def _evaluate(self, p: np.ndarray) -> tuple[dict, dict]:
        model, s, dp = self.model, self.sensitivity, p - self.values
        fields = {name: getattr(self.result, name) + getattr(s, name) @ dp
                  for name in ("effort", "force", "torque")}
        if model.contacts:
            fields["ground_force"] = self.result.ground_force + s.ground_force @ dp
        result = replace(self.result, **fields)
        masses = body_masses(model).copy()
        for change, delta in zip(s.parameters, dp, strict=True):
            masses[model.body_index[change.body]] += change.mass * delta
        return (inverse_metrics(model, result, SENSITIVE_FAMILIES, self.strides, masses),
                metric_sensitivities(model, result, s, SENSITIVE_FAMILIES, self.strides,
                                     masses))


def constrained_figures(metrics: dict, limits, source: str = "") -> list[tuple[str, Limit]]:
    """Each figure of merit a limit matches, with its limit; a limit that matches none is
    refused."""
    out = []
    for limit in limits:
        matched = [c for c in metrics if fnmatchcase(c, limit.pattern)]
        if not matched:
            raise StudyError(f"{source}: optimize.constraints: '{limit.pattern}' matches no "
                             f"figure of merit ({_figures_help(metrics)})")
        out += [(c, limit) for c in matched]
    return out


def _figures_help(metrics: dict) -> str:
    families = sorted({c.partition(":")[0] for c in metrics})
    example = next(iter(metrics), "")
    return f"families {', '.join(families)}; e.g. {example}"


def check_objective(metrics: dict, name: str, source: str = "") -> None:
    """Refuse a figure of merit the run does not have."""
    if name not in metrics:
        raise StudyError(f"{source}: optimize.minimize: no figure of merit '{name}' "
                         f"({_figures_help(metrics)})")
    if not math.isfinite(metrics[name]):
        raise HexapodError(f"{source}: optimize.minimize: '{name}' is not a number for this "
                           "scene (a cost of transport of a scene that does not travel)")


@dataclass
class Evaluation:
    """One evaluation of the problem by the optimiser: the parameters' values, the figure of
    merit, and the largest constraint excess relative to its bound (0: every one met)."""

    index: int
    values: np.ndarray
    objective: float
    violation: float


@dataclass
class OptimizationRun:
    """What :func:`optimize` found.

    Attributes
    ----------
    spec : OptimizationStudy
    scene : Scene
        The study's scene (its held values applied), at whose values the run was made.
    parameters : tuple of InertiaChange
        The optimised parameters.
    design : AffineDesign
        The figures of merit at any values.
    start, optimum : ndarray (P,)
        The parameters' values, SI (the bounds of ``spec`` are in the scene's units:
        ``InertiaChange.scene_scale`` converts).
    status : str
        IPOPT's return status; ``success`` whether it reports success.
    iterations : int
        IPOPT's iterations.
    log : list of Evaluation
        Every evaluation, in order.
    checked : dict
        The figures of merit of a run of the scene re-read with the optimal values.
    agreement : float
        The largest relative difference between those and the predicted ones (the objective
        and the constrained figures).
    optimum_scene, optimum_model, optimum_result :
        That run.
    limits : tuple of Limit
        The constraints: the study's and its motors'.
    start_objective : float
        The figure of merit at ``start``.
    """

    spec: OptimizationStudy
    scene: object
    parameters: tuple
    design: AffineDesign
    start: np.ndarray
    optimum: np.ndarray
    status: str
    success: bool
    iterations: int
    log: list
    checked: dict
    agreement: float
    optimum_scene: object = None
    optimum_model: object = None
    optimum_result: object = None
    limits: tuple = ()
    start_objective: float = math.nan


def optimize(spec: OptimizationStudy,
             progress: Callable[[str], None] | None = None) -> OptimizationRun:
    """Minimise the study's figure of merit over its parameters within their bounds,
    subject to its constraints, by IPOPT (limited-memory Hessian) with exact gradients, then
    check the optimum by a run of the scene re-read with the optimal values.

    Parameters
    ----------
    spec : OptimizationStudy
    progress : callable, optional
        Called with a line of text as the work goes on.

    Returns
    -------
    OptimizationRun

    Raises
    ------
    StudyError
        A parameter that names no mass or inertia of the scene, a figure of merit that does
        not exist, a constraint that matches none (before the optimisation).
    """
    from hexapod.algorithms.assembly import assemble
    from hexapod.algorithms.inverse import inverse_dynamics
    from hexapod.algorithms.sensitivity import inverse_sensitivities
    from hexapod.sweeps.cases import base_scene, inverse_window
    from hexapod.sweeps.design_parameters import moved_model

    say = progress or (lambda line: None)
    study, source = spec.study, spec.source
    scene = base_scene(study)
    changes = _parameters(scene, spec.bounds, source)
    model = assemble(scene)
    times, strides = inverse_window(model, study.job)
    say(f"inverse dynamics of {times.size} samples and its sensitivities")
    result = inverse_dynamics(model, times)
    sensitivity = inverse_sensitivities(model, result, changes,
                                        moved=moved_model(scene, model, changes))
    values = np.array([c.value for c in changes])
    if all(isinstance(c, InertiaChange) for c in changes):
        design = AffineDesign(model, result, sensitivity, strides, values)
    else:  # the motion moves with the joints or the period: a run per evaluation
        design = RerunDesign(study, changes, times, strides, values,
                             held_length(changes, model))
    metrics, _ = design.at(values)
    check_objective(metrics, spec.minimize, source)
    limits = spec.limits + _motor_limits(model, spec.actuators)
    constrained = constrained_figures(metrics, limits, source)
    si = np.array([c.scene_scale for c in changes])  # the bounds are in the scene's units
    low, high = np.array([b.low for b in spec.bounds]) * si, \
        np.array([b.high for b in spec.bounds]) * si
    start = np.array([v if math.isnan(b.start) else b.start * k  # the scene's value, clipped
                      for v, b, k in zip(values, spec.bounds, si, strict=True)])
    start = np.clip(start, low, high)
    start_objective = design.at(start)[0][spec.minimize]  # _solve's first call: kept
    optimum, status, iterations, log = _solve(spec, design, constrained, start, low, high,
                                              say)
    run = _checked(spec, scene, changes, design, start, optimum, status, iterations, log,
                   constrained, times, strides, values)
    run.limits, run.start_objective = limits, start_objective
    return run


def _motor_limits(model, table: str) -> tuple[Limit, ...]:
    """Every driven joint's peak effort below its motor's at the joint (stall or rated torque
    times the gear ratio), from the actuator table ``table`` ("" for none)."""
    if not table:
        return ()
    from hexapod.scene.actuators import read_actuators

    driven = [model.joints[d.joint].name for d in model.drivers if d.kind == "joint"]
    motors = read_actuators(table).assign(driven)
    return tuple(Limit(f"peak_effort:{joint}", -math.inf, motor.joint_limits()[0])
                 for joint, motor in motors.items())


def _parameters(scene, bounds, source: str):
    from hexapod.sweeps.design_parameters import inertia_parameters

    changes = inertia_parameters(scene, [b.name for b in bounds], source=f"{source}: vary")
    if any(isinstance(c, ScaleChange) for c in changes):
        raise StudyError(f"{source}: vary: geometric_scale is a sensitivity relative to the "
                         "scene as given, not a value a scene can be built with: vary the "
                         "builder's scale (a built-in robot's 'scale') instead")
    if any(getattr(c, "key", "") in ("gait.duty", "gait.stride") for c in changes) and any(
            isinstance(c, FrameChange) for c in changes):
        raise StudyError(f"{source}: vary: the duty factor and the stride hold the scene's "
                         "characteristic length (its legs' pose at t = 0 moves with them, no "
                         "segment does), which a joint's position moves: vary them in "
                         "separate studies")
    if [c.name for c in changes] != [b.name for b in bounds]:
        named = ", ".join(c.name for c in changes)
        raise StudyError(f"{source}: vary: each [vary] key names one parameter, as it is "
                         f"written in full (body.NAME.mass, body.NAME.inertia.K); these name "
                         f"{named}")
    return changes


def _solve(spec, design, constrained, start, low, high, say):
    """IPOPT on the scaled problem: parameters over their bounds' size, the objective over
    its starting value, each constraint over its bound."""
    import casadi as ca

    scale = np.maximum(np.abs(low), np.abs(high))
    first = design.at(start)[0][spec.minimize]
    f_scale = abs(first) if first else 1.0
    g_scale = np.array([max(abs(v) for v in (lim.low, lim.high) if math.isfinite(v))
                        for _, lim in constrained])
    log: list[Evaluation] = []

    def evaluate(x):
        p = x * scale
        metrics, derivatives = design.at(p)
        f = metrics[spec.minimize] / f_scale
        df = derivatives[spec.minimize] * scale / f_scale
        g = np.array([metrics[c] for c, _ in constrained]) / g_scale if constrained \
            else np.zeros(0)
        dg = (np.array([derivatives[c] for c, _ in constrained]) * scale / g_scale[:, None]
              if constrained else np.zeros((0, x.size)))
        if not log or not np.array_equal(log[-1].values, p):
            excess = [max(lim.low - metrics[c], metrics[c] - lim.high, 0.0) / s
                      for (c, lim), s in zip(constrained, g_scale, strict=True)]
            log.append(Evaluation(len(log), p, metrics[spec.minimize], max(excess, default=0.0)))
            say(f"evaluation {len(log)}: {spec.minimize} = {metrics[spec.minimize]:.10g}")
        return f, g, df, dg

    n, m = scale.size, len(constrained)
    merit = _merit(evaluate, n, m)
    tolerance = spec.tolerance or (MOVING_TOLERANCE if isinstance(design, RerunDesign)
                                   else TOLERANCE)
    x = ca.MX.sym("x", n)
    f, g = merit(x)
    problem = {"x": x, "f": f} | ({"g": g} if m else {})
    options = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes",
               "ipopt.hessian_approximation": "limited-memory", "ipopt.tol": tolerance,
               "ipopt.constr_viol_tol": tolerance, "ipopt.max_iter": spec.max_iterations}
    if isinstance(design, RerunDesign) and spec.tolerance is None:
        # a run's figures carry its round-off (some 1e-11 of them): once the objective stops
        # changing above that for a few iterations, IPOPT's line search only chases it (the
        # walking robot's femur length for a knee's RMS torque: converged in 6 evaluations of
        # 193, the rest a search among values equal to 5e-12)
        options |= {"ipopt.acceptable_tol": 100 * tolerance,
                    "ipopt.acceptable_obj_change_tol": ACCEPTABLE_CHANGE,
                    "ipopt.acceptable_iter": 3}
    solver = ca.nlpsol("design", "ipopt", problem, options)
    bounds = {"lbx": low / scale, "ubx": high / scale}
    if m:
        bounds |= {"lbg": [lim.low / s for (_, lim), s in zip(constrained, g_scale,
                                                               strict=True)],
                   "ubg": [lim.high / s for (_, lim), s in zip(constrained, g_scale,
                                                                strict=True)]}
    solution = solver(x0=start / scale, **bounds)
    stats = solver.stats()
    optimum = np.clip(np.array(solution["x"]).ravel() * scale, low, high)
    return optimum, str(stats["return_status"]), int(stats["iter_count"]), log


def _merit(evaluate, n: int, m: int):
    """``x -> (f, g)`` as a CasADi Function of Python callbacks, with its exact Jacobian."""
    import casadi as ca

    class Jacobian(ca.Callback):
        def __init__(self, name, opts):
            ca.Callback.__init__(self)
            self.construct(name, opts)

        def get_n_in(self):
            return 3  # x, and the nominal f and g

        def get_n_out(self):
            return 2

        def get_sparsity_in(self, i):
            return ca.Sparsity.dense((n, 1, m)[i], 1)

        def get_sparsity_out(self, i):
            return ca.Sparsity.dense((1, m)[i], n)

        def eval(self, arg):
            _, _, df, dg = evaluate(np.array(arg[0], dtype=float).ravel())
            return [ca.DM(df.reshape(1, n)), ca.DM(dg.reshape(m, n))]

    class Merit(ca.Callback):
        def __init__(self):
            ca.Callback.__init__(self)
            self.construct("design_merit", {"enable_fd": False})

        def get_n_in(self):
            return 1

        def get_n_out(self):
            return 2

        def get_sparsity_in(self, i):
            return ca.Sparsity.dense(n, 1)

        def get_sparsity_out(self, i):
            return ca.Sparsity.dense((1, m)[i], 1)

        def eval(self, arg):
            f, g, _, _ = evaluate(np.array(arg[0], dtype=float).ravel())
            return [ca.DM(f), ca.DM(g.reshape(m, 1))]

        def has_jacobian(self):
            return True

        def get_jacobian(self, name, inames, onames, opts):
            self.jacobian = Jacobian(name, opts)  # CasADi keeps no reference to it
            return self.jacobian

    return Merit()


def _checked(spec, scene, changes, design, start, optimum, status, iterations, log,
             constrained, times, strides, values) -> OptimizationRun:
    """The run, with the optimum checked by the study's scene built again with the optimal
    values."""
    optimum_scene, optimum_model, optimum_result = run_at(
        spec.study, changes, times, values, optimum, f"{spec.source}: the optimum",
        getattr(design, "length", None))
    checked = inverse_metrics(optimum_model, optimum_result, SENSITIVE_FAMILIES, strides)
    predicted, _ = design.at(optimum)
    compared = [spec.minimize] + [c for c, _ in constrained]
    agreement = max(abs(checked[c] - predicted[c]) / (abs(checked[c]) or 1.0)
                    for c in compared)
    return OptimizationRun(spec, scene, tuple(changes), design, start, optimum, status,
                           status in ("Solve_Succeeded", "Solved_To_Acceptable_Level"),
                           iterations, log, checked, agreement, optimum_scene, optimum_model,
                           optimum_result)
