"""One case of a study: its scene, its model (assembled once per process and reused), its job and
its metrics, returned as a row that records a failure instead of raising it.

A parameter is either an argument of the built-in scene's builder (its keyword parameters, found
by introspection: ``period``, ``duty``, ``payload`` ...) or a scene key: a dotted path into the
scene's TOML form (``ground.mu``, ``scene.gravity``, ``body.trunk.mass``, ``scene.gravity.2``),
applied to the scene the builder made (or the scene file) and read back by the scene reader,
which checks it as it checks any file.
"""

from __future__ import annotations

import json
import os
import socket
import time
from collections import OrderedDict
from pathlib import Path
from typing import TYPE_CHECKING

from hexapod.errors import HexapodError, InputFileError
from hexapod.sweeps.spec import Case, Study, builder_parameters, spec_parameters_help

if TYPE_CHECKING:
    from hexapod.scene.scene import Scene

#: Models kept per process (the most recently used), shared by the cases of equal structure.
MODELS_KEPT = 4
_models: OrderedDict = OrderedDict()
_ARRAYS = ("body", "joint", "driver", "force")


class StudyError(InputFileError):
    """A study that cannot run: an unknown parameter, a scene key that leads nowhere."""


def _builder(study: Study):
    """The built-in scene's builder, or None for a scene file."""
    if study.scene_digest:
        return None
    from hexapod.scene.builtin import builtin_scenes

    scenes = builtin_scenes()
    if study.scene not in scenes:
        known = ", ".join(sorted(scenes)) or "none installed"
        raise StudyError(f"{study.source}: study.scene: no built-in scene "
                         f"'{study.scene}' and no such file (built-in: {known})")
    return scenes[study.scene].load()


def case_values(study: Study, builder, params: dict) -> tuple[dict, dict]:
    """A case's values (the study's fixed ones and its own) split into the builder's
    arguments and the scene keys."""
    values = {**study.fixed, **params}
    arguments = builder_parameters(builder) if builder is not None else {}
    return ({k: v for k, v in values.items() if k in arguments},
            {k: v for k, v in values.items() if k not in arguments})


def check_study(study: Study) -> None:
    """Refuse, before any work, a study whose parameters name nothing: every name must be an
    argument of the builder or a scene key that resolves in the base scene; builds the first
    case's scene to check the keys and values as the scene reader does.

    Raises
    ------
    StudyError
        With one message naming the study file, the key and what is wrong.
    """
    builder = _builder(study)
    names = list(study.fixed) + [p.name for p in study.parameters]
    arguments = builder_parameters(builder) if builder is not None else {}
    bad = [n for n in names if n not in arguments and "." not in n]
    if bad:
        accepted = (f"the builder of '{study.scene}' takes {', '.join(arguments)}"
                    if arguments else f"'{study.scene}' is a scene file: no builder arguments")
        raise StudyError(f"{study.source}: unknown parameter {', '.join(map(repr, bad))}: "
                         f"{spec_parameters_help()}; {accepted}")
    first = study.cases()[0]  # there is always one: the product of no lists is one case
    try:
        build_scene(study, builder, *case_values(study, builder, first.params))
    except StudyError:
        raise
    except TypeError as error:
        raise StudyError(f"{study.source}: {error}") from None
    except (HexapodError, ValueError) as error:
        raise StudyError(f"{study.source}: case 0 ({_shown(first.params)}): {error}") from None


def _shown(params: dict) -> str:
    return ", ".join(f"{k}={v}" for k, v in params.items()) or "the base scene"


def base_scene(study: Study, values: dict | None = None) -> Scene:
    """The study's scene with its held values (``[fixed]``) and ``values`` applied: the
    built-in scene's builder called with its arguments, or the scene file read, then the scene
    keys set.

    Parameters
    ----------
    study : Study
    values : dict, optional
        Builder arguments and scene keys set over the held ones (an optimiser's point).

    Returns
    -------
    Scene

    Raises
    ------
    StudyError
        A held value that names nothing.
    """
    builder = _builder(study)
    arguments, keys = case_values(study, builder, dict(values or {}))
    try:
        return build_scene(study, builder, arguments, keys)
    except TypeError as error:
        raise StudyError(f"{study.source}: {error}") from None


def build_scene(study: Study, builder, arguments: dict, keys: dict):
    """The scene of a case: the builder called with its arguments (or the scene file read),
    then the scene keys applied."""
    from hexapod.scene.builtin import load_scene

    if builder is None and str(study.scene).lower().endswith(".toml"):
        from hexapod._support.files import read_toml

        document = read_toml(study.scene, "scene file")
        if "robot" in document:  # a robot description: its own keys before it walks
            from hexapod.scene.robots import robot_scene

            own = {k: v for k, v in keys.items() if k.split(".")[0] in _DESCRIPTION}
            for key, value in own.items():
                set_scene_key(document, key, value, study.source)
            scene = robot_scene(document, Path(study.scene))
            return with_scene_keys(scene, {k: v for k, v in keys.items() if k not in own},
                                   study.source)
    scene = builder(**arguments) if builder is not None else load_scene(study.scene)
    return with_scene_keys(scene, keys, study.source)


def with_scene_keys(scene: Scene, keys: dict, source: str = "") -> Scene:
    """A copy of ``scene`` with the dotted scene keys ``keys`` set (``body.femur.mass``,
    ``ground.mu``, ``scene.gravity.2``: :func:`set_scene_key`), read back by the scene reader,
    which checks it as it checks any file.

    Parameters
    ----------
    scene : Scene
    keys : dict
        Scene key -> value.
    source : str
        What gave the keys, for the messages.

    Returns
    -------
    Scene
        ``scene`` itself when ``keys`` is empty.

    Raises
    ------
    StudyError
        A key that leads nowhere.
    InputFileError
        A value the scene reader refuses.
    """
    if not keys:
        return scene
    import tomllib

    from hexapod.scene.reader import scene_from_document
    from hexapod.scene.writer import scene_text

    document = tomllib.loads(scene_text(scene))
    for key, value in keys.items():
        set_scene_key(document, key, value, source)
    return scene_from_document(document, f"{scene.name} ({_shown(keys)})")


#: The tables of a robot description a study's keys set before the robot walks
#: (``gait.duty``, ``ground.slope``, ``robot.rest.*_knee``); its scene's keys are set after.
_DESCRIPTION = ("robot", "gait", "ground")


def set_scene_key(document: dict, key: str, value, source: str = "") -> None:
    """Set the dotted ``key`` of a scene document: ``section.key`` for the tables ``scene`` and
    ``ground`` (and a robot description's ``robot`` and ``gait``), ``section.NAME.key`` for the
    arrays of elements, more parts into an element's inline tables
    (``joint.fti.parent_frame.position``), an integer last part for an entry of a list
    (``scene.gravity.2``)."""
    parts = key.split(".")
    where = f"{source}: {key}" if source else key
    section = parts[0]
    if section in _ARRAYS:
        if len(parts) < 3:
            raise StudyError(f"{where}: name an element and its key, {section}.NAME.KEY")
        elements = document.get(section, [])
        names = [e.get("name") for e in elements]
        if parts[1] not in names:
            shown = ", ".join(map(str, names[:8])) + (", ..." if len(names) > 8 else "")
            raise StudyError(f"{where}: the scene has no {section} named '{parts[1]}' "
                             f"({section}s: {shown or 'none'})")
        table, rest = elements[names.index(parts[1])], parts[2:]
    elif section in ("scene", "ground") or (section in _DESCRIPTION and "robot" in document):
        if len(parts) < 2:
            raise StudyError(f"{where}: name a key of [{section}], {section}.KEY")
        table, rest = document.setdefault(section, {}), parts[1:]
    else:
        raise StudyError(f"{where}: a scene key starts with scene, ground, "
                         f"{', '.join(_ARRAYS)}; {spec_parameters_help()}")
    for k, part in enumerate(rest[:-1]):  # into inline tables: joint.J.parent_frame.position
        inner = table.get(part)
        if isinstance(inner, list) and k == len(rest) - 2 and rest[-1].isdigit():
            if int(rest[-1]) >= len(inner):
                raise StudyError(f"{where}: '{part}' has no entry {rest[-1]}")
            inner[int(rest[-1])] = value
            return
        if not isinstance(inner, dict):
            raise StudyError(f"{where}: '{'.'.join(rest[:k + 1])}' is not a table of the "
                             "element")
        table = inner
    table[rest[-1]] = value


def model_for(study: Study, arguments: dict, keys: dict, scene):
    """The assembled model of ``scene``, from this process's cache when a case of the same
    structure was run here before: cases whose scenes differ only in ground-force settings
    share one model (compiled functions included), with its ground settings replaced (not
    the ground's shape: the feet's footholds are built on it)."""
    from hexapod.algorithms.assembly import assemble
    from hexapod.scene.contacts import SHAPE_KEYS

    structure = json.dumps([study.scene, study.scene_digest, arguments,
                            {k: v for k, v in keys.items() if not k.startswith("ground.")
                             or k.split(".")[1] in SHAPE_KEYS}],
                           sort_keys=True, default=repr)
    model = _models.get(structure)
    if model is None:
        model = assemble(scene)
        _models[structure] = model
        while len(_models) > MODELS_KEPT:
            _models.popitem(last=False)
    else:
        _models.move_to_end(structure)
    si = scene.in_si()
    if model.ground != si.ground:
        from hexapod.model.digest import scene_digest

        model = model.with_ground(si.ground, scene_digest(si, model.rank_tolerance))
    return model


def run_case(study: Study, case: Case) -> dict:
    """Run one case; never raises for the case's own failure.

    Returns
    -------
    dict
        ``case``, ``key``, ``params``, ``status`` (``ok``; ``infeasible``: computed, but the
        ground cannot give the feet their forces at some sample, the count and the first time
        in ``message``; or ``failed``), ``message``,
        ``metrics`` (column -> float), ``units`` (column -> unit), and the run's cost:
        ``cpu_s``, ``wall_s``, ``worker``.
    """
    wall, cpu = time.perf_counter(), time.process_time()
    row = {"case": case.index, "key": case.key, "params": case.params, "status": "ok",
           "message": "", "metrics": {}, "units": {}}
    try:
        builder = _builder(study)
        arguments, keys = case_values(study, builder, case.params)
        scene = build_scene(study, builder, arguments, keys)
        model = model_for(study, arguments, keys, scene)
        row["status"], row["message"], row["metrics"] = _run_job(study.job, model)
        from hexapod.sweeps.metrics import metric_unit

        row["units"] = {c: metric_unit(model, c) for c in row["metrics"]}
    except KeyboardInterrupt:
        raise
    except (HexapodError, ValueError) as error:
        row["status"], row["message"] = "failed", str(error)
    except Exception as error:  # an internal error: still a row, named as such
        row["status"], row["message"] = "failed", f"internal error: {type(error).__name__}: {error}"
    row["cpu_s"] = time.process_time() - cpu
    row["wall_s"] = time.perf_counter() - wall
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    return row


def inverse_window(model, job: dict):
    """The samples of an inverse job (``job["duration"]`` s, or ``job["strides"]`` cycles of
    the scene's periodic laws, from ``job["start"]``) and the window in strides."""
    import numpy as np

    cycle = model.cycle_time()
    duration = job["duration"] or job["strides"] * (cycle or 1.0)
    start = job["start"]
    return (np.linspace(start, start + duration, job["samples"]),
            duration / cycle if cycle else 1.0)


def _run_job(job: dict, model) -> tuple[str, str, dict]:
    import numpy as np

    from hexapod.sweeps.metrics import FAMILIES, inverse_metrics, simulation_metrics

    families = job.get("metrics") or FAMILIES[job["kind"]]
    cycle = model.cycle_time()
    if job["kind"] == "inverse":
        from hexapod.algorithms.inverse import inverse_dynamics, motion_model

        times, strides = inverse_window(model, job)
        result = inverse_dynamics(model, times)
        model = motion_model(model, result)  # a guided scene's laws: the motion found
        metrics = inverse_metrics(model, result, families, strides)
        if not result.feasible:
            bad = np.flatnonzero(result.infeasible)
            return "infeasible", (f"the ground cannot give the feet's forces at {bad.size} of "
                                  f"{times.size} samples, first at t = {times[bad[0]]:.4g} s (a "
                                  "foot slips or is pulled)"), metrics
        return "ok", "", metrics
    from hexapod.simulation.loop import simulate

    duration = job["duration"] or cycle or 1.0
    options = {k: job[k] for k in ("method", "rtol", "atol", "step", "cpu_budget")
               if job.get(k) is not None}
    result = simulate(model, duration, forces=job["forces"], **options)
    status = "ok" if result.success else "failed"
    return status, result.message if not result.success else "", \
        simulation_metrics(model, result, families)
