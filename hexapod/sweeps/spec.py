"""A study file: the base scene, the parameters held and varied, the job run per case.

A study is a TOML file (``docs/sweeps.md``)::

    [study]
    name = "tripod-speed"
    scene = "hexapod"          # a built-in scene, or a scene file (relative to this file)
    seed = 1                   # random draws (see samples)
    samples = 0                # cases drawn at random over the `range`s given without `steps`

    [fixed]                    # held in every case
    gait = "tripod"            # an argument of the built-in scene's builder
    "ground.policy" = "friction"   # or a scene key: a dotted path into the scene's TOML

    [vary.speed]               # varied: a list ...
    values = [0.1, 0.2, 0.3]
    [vary.duty]                # ... a grid ...
    range = [0.55, 0.75]
    steps = 5
    [vary."ground.mu"]         # ... or random draws (study.samples of them), optionally "log"
    range = [0.2, 1.0]

    [job]
    kind = "inverse"           # or "simulate"
    samples = 51               # inverse: samples over the window (default one stride)
    metrics = ["peak_effort", "peak_ground"]   # the families kept (default: all of the job's)

The cases are the product of the lists and grids, in the order written (the last varies
fastest), times the random draws; every case has an index, and a key that hashes everything its
result depends on (the scene, the held and varied values, the job and the code's version), by
which a study resumes.
"""

from __future__ import annotations

import hashlib
import inspect
import itertools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from hexapod._support.files import read_text, read_toml
from hexapod._version import __version__
from hexapod.errors import InputFileError

#: The job kinds and their keys: name -> (type, default, check, what it is).
JOB_KEYS = {
    "inverse": {
        "samples": (int, 51, lambda x: x >= 2, "samples over the window, at least 2"),
        "strides": (float, 1.0, lambda x: x > 0, "the window in strides (cycles of the "
                                                  "scene's periodic laws), positive"),
        "duration": (float, None, lambda x: x > 0, "the window in seconds, positive "
                                                    "(instead of strides)"),
        "start": (float, 0.0, math.isfinite, "the window's start, s"),
    },
    "simulate": {
        "method": (str, None, None, "an integrator of the registry"),
        "duration": (float, None, lambda x: x > 0, "seconds simulated, positive (default "
                                                    "one stride, or 1 s)"),
        "rtol": (float, None, lambda x: 0 < x < 1, "relative tolerance, in (0, 1)"),
        "atol": (float, None, lambda x: x > 0, "absolute tolerance, positive"),
        "step": (float, None, lambda x: x > 0, "the step of fixed-step methods, s, positive"),
        "cpu_budget": (float, None, lambda x: x > 0, "CPU seconds per case, positive"),
        "forces": (bool, True, None, "joint wrenches at the saved states, for the force "
                                     "metrics"),
    },
}
_STUDY_KEYS = ("name", "description", "scene", "seed", "samples")
_VARY_KEYS = ("values", "range", "steps", "spacing")
_SECTIONS = ("study", "fixed", "vary", "job")


@dataclass(frozen=True)
class Parameter:
    """One varied parameter: its values on a list or grid, or a range drawn at random."""

    name: str
    values: tuple = ()  # a list or a grid; empty for random draws
    low: float = math.nan
    high: float = math.nan
    spacing: str = "linear"  # "linear" | "log"

    @property
    def random(self) -> bool:
        return not self.values


@dataclass(frozen=True)
class Study:
    """A parsed study file (see the module's docstring); :meth:`cases` lists its cases."""

    name: str
    scene: str  # a built-in scene's name, or a scene file's absolute path
    fixed: dict = field(default_factory=dict)
    parameters: tuple[Parameter, ...] = ()
    job: dict = field(default_factory=dict)  # "kind", the job's keys, "metrics"
    seed: int = 0
    samples: int = 0
    description: str = ""
    source: str = ""  # the study file, for messages
    scene_digest: str = ""  # sha256 of a scene file's text ("" for a built-in scene)

    def count(self) -> int:
        """The number of cases, without listing them."""
        return math.prod(len(p.values) for p in self.parameters if not p.random) * \
            (self.samples if any(p.random for p in self.parameters) else 1)

    def cases(self) -> list[Case]:
        """Every case, in index order (:meth:`count` of them: see
        :func:`hexapod._support.limits.check_cases`)."""
        listed = [p for p in self.parameters if not p.random]
        drawn = [p for p in self.parameters if p.random]
        draws = _draws(drawn, self.samples, self.seed) if drawn else [{}]
        names = [p.name for p in self.parameters]
        out = []
        for combination in itertools.product(*[p.values for p in listed]):
            for draw in draws:
                values = dict(zip([p.name for p in listed], combination, strict=True)) | draw
                params = {name: values[name] for name in names}
                out.append(Case(len(out), params, self.case_key(params)))
        return out

    def identity(self) -> dict:
        """What every case's result depends on besides its own values (JSON-ready)."""
        return {"version": __version__, "scene": self.scene if not self.scene_digest
                else self.scene_digest, "fixed": self.fixed, "job": self.job}

    def case_key(self, params: dict) -> str:
        text = json.dumps({**self.identity(), "params": params}, sort_keys=True,
                          default=repr)
        return hashlib.sha256(text.encode()).hexdigest()[:20]


@dataclass(frozen=True)
class Case:
    index: int
    params: dict
    key: str


def _draws(parameters: list[Parameter], samples: int, seed: int) -> list[dict]:
    """``samples`` joint draws of the random parameters (uniform, or log-uniform)."""
    import numpy as np

    rng = np.random.default_rng(seed)
    columns = {}
    for p in parameters:
        u = rng.random(samples)
        if p.spacing == "log":
            columns[p.name] = np.exp(np.log(p.low) + u * (np.log(p.high) - np.log(p.low)))
        else:
            columns[p.name] = p.low + u * (p.high - p.low)
    return [{name: float(values[k]) for name, values in columns.items()}
            for k in range(samples)]


# ------------------------------------------------------------------ reading


class _Problems:
    def __init__(self, source: str):
        self.source = source
        self.items: list[str] = []

    def add(self, key: str, message: str) -> None:
        self.items.append(f"{key}: {message}")

    def raise_if_any(self) -> None:
        if self.items:
            body = "\n  ".join(self.items)
            raise InputFileError(f"{self.source}: not a valid study:\n  {body}")


def read_study(path: str | Path, max_cases: int | None = None) -> Study:
    """Read a study file; every problem is reported at once, naming its key. A study of more
    cases than ``max_cases`` (default: :func:`hexapod._support.limits.max_cases`) is refused
    before they are listed.

    Raises
    ------
    InputFileError
        The file cannot be read, is not TOML, or is not a valid study.
    HexapodError
        The study has more cases than the limit.
    """
    path = Path(path)
    document = read_toml(path, "study file")
    return study_from_document(document, path, max_cases)


def study_from_document(document: dict, path: str | Path = "<study>",
                        max_cases: int | None = None) -> Study:
    """The study of a parsed TOML document; ``path`` names it and anchors a relative scene
    file. Checks the study's own keys and values (the scene's keys and the builder's
    arguments are checked against the scene by :func:`hexapod.sweeps.cases.check_study`), and
    its number of cases against ``max_cases`` before any grid is made."""
    path = Path(path)
    from hexapod._support.limits import check_cases

    check_cases(_count(document), f"the study {path}", max_cases)
    problems = _Problems(str(path))
    for key in document:
        if key not in _SECTIONS:
            problems.add(key, f"unknown section (expected {', '.join(_SECTIONS)})")
    study = _table(document, "study", problems)
    for key in study:
        if key not in _STUDY_KEYS:
            problems.add(f"study.{key}", f"unknown key (expected {', '.join(_STUDY_KEYS)})")
    scene = study.get("scene")
    if not isinstance(scene, str) or not scene:
        problems.add("study.scene", "required: a built-in scene's name or a scene file")
        scene = ""
    seed = _integer(study.get("seed", 0), "study.seed", problems, lowest=0)
    samples = _integer(study.get("samples", 0), "study.samples", problems, lowest=0)
    fixed = _table(document, "fixed", problems)
    for key, value in fixed.items():
        if not _scalar(value) and not _vector(value):
            problems.add(f"fixed.{key}", f"must be a number, a string, a boolean or a list of "
                         f"numbers, got {value!r}")
        elif _number_like(value) and not math.isfinite(value):
            problems.add(f"fixed.{key}", f"must be finite, got {value}")
    parameters = [_parameter(name, table, problems)
                  for name, table in _table(document, "vary", problems).items()]
    parameters = [p for p in parameters if p is not None]
    for name in set(fixed) & {p.name for p in parameters}:
        problems.add(f"vary.{name}", "is also in [fixed]: hold it or vary it, not both")
    if any(p.random for p in parameters) and samples < 1:
        problems.add("study.samples", "a [vary] range without steps is drawn at random: give "
                     "the number of draws, samples = N")
    if samples and not any(p.random for p in parameters):
        problems.add("study.samples", "no [vary] range is drawn at random (a range without "
                     "steps): remove samples, or drop steps from a range")
    job = _job(_table(document, "job", problems), problems)
    problems.raise_if_any()
    name = study.get("name", path.stem)
    scene_path = (path.parent / scene) if scene else Path()
    digest = ""
    if scene and (scene_path.suffix.lower() in (".toml", ".urdf", ".xml") or scene_path.is_file()):
        text = read_text(scene_path, "scene file")
        scene, digest = str(scene_path.resolve()), hashlib.sha256(text.encode()).hexdigest()
    return Study(str(name), scene, fixed, tuple(parameters), job, seed, samples,
                 str(study.get("description", "")), str(path), digest)


def _count(document: dict) -> int:
    """The cases a study document asks for, counted from its lists, grid steps and samples
    before any is made (an entry written wrong counts one: it is reported later)."""
    vary = document.get("vary")
    tables = [t for t in vary.values() if isinstance(t, dict)] if isinstance(vary, dict) else []
    count, drawn = 1, False
    for table in tables:
        values, steps = table.get("values"), table.get("steps")
        if isinstance(values, list):
            count *= max(len(values), 1)
        elif isinstance(steps, int) and not isinstance(steps, bool) and steps > 1:
            count *= steps
        elif "range" in table and "steps" not in table:
            drawn = True
    study = document.get("study")
    samples = study.get("samples") if isinstance(study, dict) else None
    if drawn and isinstance(samples, int) and not isinstance(samples, bool) and samples > 1:
        count *= samples
    return count


def _table(document: dict, key: str, problems: _Problems) -> dict:
    value = document.get(key, {})
    if not isinstance(value, dict):
        problems.add(key, f"must be a table, written [{key}]")
        return {}
    return value


def _scalar(value) -> bool:
    return isinstance(value, bool | int | float | str)


def _number_like(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _vector(value) -> bool:
    return isinstance(value, list) and value and all(_number_like(x) and math.isfinite(x)
                                                      for x in value)


def _integer(value, key: str, problems: _Problems, lowest: int) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or value < lowest:
        problems.add(key, f"must be an integer, at least {lowest}, got {value!r}")
        return lowest
    return value


def _parameter(name: str, table, problems: _Problems) -> Parameter | None:
    key = f"vary.{name}"
    if not isinstance(table, dict):
        problems.add(key, 'must be a table: values = [...], or range = [low, high] '
                     '(with steps = N for a grid)')
        return None
    for k in table:
        if k not in _VARY_KEYS:
            problems.add(f"{key}.{k}", f"unknown key (expected {', '.join(_VARY_KEYS)})")
    if ("values" in table) == ("range" in table):
        problems.add(key, "give either values = [...] or range = [low, high]")
        return None
    spacing = table.get("spacing", "linear")
    if spacing not in ("linear", "log"):
        problems.add(f"{key}.spacing", f"must be 'linear' or 'log', got {spacing!r}")
        return None
    if "values" in table:
        values = table["values"]
        if not isinstance(values, list) or not values or not all(map(_scalar, values)):
            problems.add(f"{key}.values", "must be a non-empty list of numbers or strings")
            return None
        if any(_number_like(v) and not math.isfinite(v) for v in values):
            problems.add(f"{key}.values", f"must be finite, got {values}")
            return None
        if len(set(map(repr, values))) < len(values):
            problems.add(f"{key}.values", f"lists a value twice: {values}")
            return None
        for k in ("steps", "spacing"):
            if k in table:
                problems.add(f"{key}.{k}", "goes with range, not values")
        return Parameter(name, tuple(values))
    return _range(name, key, table, spacing, problems)


def _range(name: str, key: str, table: dict, spacing: str, problems: _Problems):
    bounds = table["range"]
    if not (isinstance(bounds, list) and len(bounds) == 2 and all(map(_number_like, bounds))
            and all(map(math.isfinite, bounds))):
        problems.add(f"{key}.range", f"must be two finite numbers [low, high], got {bounds!r}")
        return None
    low, high = map(float, bounds)
    if not low < high:
        problems.add(f"{key}.range", f"low must be below high, got [{low}, {high}]")
        return None
    if spacing == "log" and low <= 0:
        problems.add(f"{key}.range", f"a log spacing needs a positive range, got [{low}, {high}]")
        return None
    if "steps" not in table:
        return Parameter(name, (), low, high, spacing)
    steps = table["steps"]
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 2:
        problems.add(f"{key}.steps", f"must be an integer, at least 2, got {steps!r}")
        return None
    if spacing == "log":
        grid = [math.exp(math.log(low) + k * (math.log(high) - math.log(low)) / (steps - 1))
                for k in range(steps)]
    else:
        grid = [low + k * (high - low) / (steps - 1) for k in range(steps)]
    grid[0], grid[-1] = low, high  # the ends as written, not as rounded
    return Parameter(name, tuple(grid), low, high, spacing)


def _job(table: dict, problems: _Problems) -> dict:
    kind = table.get("kind", "inverse")
    if kind not in JOB_KEYS:
        problems.add("job.kind", f"must be one of {', '.join(JOB_KEYS)}, got {kind!r}")
        return {"kind": "inverse", "metrics": None}
    keys = JOB_KEYS[kind]
    job = {"kind": kind}
    for name, (kind_of, default, check, what) in keys.items():
        value = table.get(name, default)
        if value is None:
            job[name] = None
            continue
        if kind_of is float and _number_like(value):
            value = float(value)
        if not isinstance(value, kind_of) or (kind_of is int and isinstance(value, bool)) \
                or (check is not None and not check(value)):
            problems.add(f"job.{name}", f"{what}; got {value!r}")
            continue
        job[name] = value
    if kind == "inverse" and "duration" in table and "strides" in table:
        problems.add("job.duration", "give strides or duration, not both")
    metrics = table.get("metrics")
    if metrics is not None:
        from hexapod.sweeps.metrics import FAMILIES

        known = FAMILIES[kind]
        if not isinstance(metrics, list) or not all(isinstance(m, str) for m in metrics):
            problems.add("job.metrics", "must be a list of metric names")
            metrics = None
        else:
            for m in metrics:
                if m not in known:
                    problems.add("job.metrics", f"unknown metric {m!r} for a {kind} job "
                                 f"(known: {', '.join(known)})")
    job["metrics"] = metrics
    for name in table:
        if name not in keys and name not in ("kind", "metrics"):
            problems.add(f"job.{name}", f"unknown key for a {kind} job (expected kind, "
                         f"metrics, {', '.join(keys)})")
    return job


def spec_parameters_help() -> str:
    """For messages: how a study names what it varies."""
    return ("a parameter is an argument of the built-in scene's builder (e.g. period, duty) "
            "or a scene key, a dotted path into the scene's TOML (e.g. ground.mu, "
            "body.trunk.mass)")


#: Units of the parameters a study names most (builder arguments of the robots, scene keys).
_PARAMETER_UNITS = {"period": "s", "speed": "m/s", "payload": "kg", "ground.min_normal": "N",
                    "scene.gravity": "m/s^2", "scene.characteristic_length": "m"}


def parameter_unit(name: str) -> str:
    """The unit of a parameter column ("" when it is a pure number or not known)."""
    if name in _PARAMETER_UNITS:
        return _PARAMETER_UNITS[name]
    parts = name.split(".")
    if parts[0] == "scene" and parts[1:2] == ["gravity"]:
        return "m/s^2"
    if parts[0] == "body" and parts[-1] == "mass":
        return "kg"
    return ""


def builder_parameters(builder) -> dict[str, inspect.Parameter]:
    """The keyword arguments a built-in scene's builder takes."""
    return {name: p for name, p in inspect.signature(builder).parameters.items()
            if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)}
