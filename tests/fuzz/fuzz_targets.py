"""What ``tests/fuzz/fuzz_inputs.py`` runs its inputs through: the valid files they are made from,
one input (``Case``), the readers and the command line, and how a run is judged (``Outcome``)."""

from __future__ import annotations

import contextlib
import io
import random
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from fuzz_mutations import mutate_motion, mutate_urdf
from fuzz_toml import mutate_toml

ROOT = Path(__file__).resolve().parents[2]
SCENES = sorted((ROOT / "data" / "scenes").glob("*.toml"))
FIXTURES = sorted(p for p in (ROOT / "tests" / "data" / "pinocchio-fixtures").iterdir()
                  if p.is_dir())
URDFS = [p / "model.urdf" for p in FIXTURES]
MOTIONS = [p / "motion.csv" for p in FIXTURES]

#: the kinds of input: the valid files they start from, and their mutation
KINDS = {"scene": (SCENES, mutate_toml, ".toml"), "urdf": (URDFS, mutate_urdf, ".urdf"),
         "motion": (MOTIONS, mutate_motion, ".csv")}


# ------------------------------------------------------------------ one input


@dataclass
class Case:
    """One malformed input: its kind, what it was made from and how, its bytes."""

    kind: str
    seed_file: Path
    mutations: list[str]
    data: bytes

    @property
    def suffix(self) -> str:
        return KINDS[self.kind][2]

    @property
    def model(self) -> Path:
        """The URDF a motion drives (the fixture it came from)."""
        return self.seed_file.parent / "model.urdf"


def make_case(rng: random.Random, kind: str | None = None) -> Case:
    kind = kind or rng.choice(tuple(KINDS))
    seeds, mutate, _ = KINDS[kind]
    seed_file = rng.choice(seeds)
    mutations, data = mutate(rng, seed_file.read_bytes())
    return Case(kind, seed_file, mutations, data)


@dataclass
class Outcome:
    """How one run ended: accepted, rejected, traceback or partial; with the evidence."""

    status: str
    detail: str = ""
    leftovers: list[str] = field(default_factory=list)
    unnamed: bool = False  # rejected by a message that does not name the input
    command: list[str] | None = None  # the command line run, as a template (cli_arguments)


def quiet():
    """Numerical warnings of extreme inputs are not failures: the result is judged."""
    stack = contextlib.ExitStack()
    stack.enter_context(warnings.catch_warnings())
    warnings.simplefilter("ignore")
    return stack


def read_and_assemble(case: Case, path: Path) -> None:
    """What a user's first call does: read, validate, assemble, find a consistent state."""
    import hexapod as hx
    from hexapod import apply_motion, read_motion, read_scene, read_urdf

    t = 0.0
    if case.kind == "scene":
        scene = read_scene(path)
    elif case.kind == "urdf":
        scene = read_urdf(path)
    else:
        motion = read_motion(path)
        scene = apply_motion(read_urdf(case.model), motion)
        t = float(motion.times[0])
    data = hx.assemble(scene).create_data()
    hx.consistent_state(hx.assemble(scene), data, t)


def check_library(case: Case, path: Path) -> Outcome:
    """Read and assemble in process: accepted, rejected naming the file, or a traceback."""
    from hexapod import HexapodError

    try:
        with quiet():
            read_and_assemble(case, path)
    except HexapodError as error:
        if path.name not in str(error):
            return Outcome("traceback", f"{type(error).__name__} without the file name: {error}")
        return Outcome("rejected", str(error).splitlines()[0])
    except Exception as error:  # anything else is what this script is looking for
        return Outcome("traceback", "".join(traceback.format_exception(error)))
    return Outcome("accepted")


def cli_arguments(case: Case, rng: random.Random) -> list[str]:
    """A command that reads the input, with ``{input}``, ``{model}`` (the URDF a motion drives,
    or the motion of a URDF) and ``{out}`` (an empty directory) to fill in."""
    if case.kind == "scene":
        command = rng.choice(("validate", "info", "dynamics", "simulate"))
        if command == "simulate":  # ten fixed steps: a bounded cost whatever the scene
            return ["simulate", "{input}", "--method", "rk4-baumgarte", "--t-end", "0.01",
                    "--step", "0.001", "--out", "{out}/run"]
        return [command, "{input}"]
    if case.kind == "urdf":
        if rng.random() < 0.5:
            return ["info", "{input}"]
        return ["inverse", "{input}", "--motion", "{model}", "--out", "{out}/out.csv"]
    return ["inverse", "{model}", "--motion", "{input}", "--out", "{out}/out.csv"]


def companion(case: Case) -> Path | None:
    """The other file a command needs: the URDF of a motion, the motion of a URDF."""
    if case.kind == "scene":
        return None
    return case.model if case.kind == "motion" else case.seed_file.parent / "motion.csv"


def run_cli(argv: list[str]) -> tuple[int, str]:
    """``hexapod ARGV`` in process: its exit status and stderr."""
    from hexapod.cli import main

    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        try:
            status = main(argv)
        except SystemExit as exit_:
            status = exit_.code if isinstance(exit_.code, int) else 1
    return status, stderr.getvalue()


def one_message(stderr: str) -> bool:
    """One ``hexapod: error:`` line, its problems (``  - ...``) and warnings: nothing else."""
    lines = stderr.strip().splitlines()
    return (sum(line.startswith("hexapod: error:") for line in lines) == 1
            and all(line.startswith(("hexapod: error:", "hexapod: warning:", "  - "))
                    for line in lines))


def expected_outputs(argv: list[str], status: int, stderr: str) -> set[str]:
    """What the output directory may hold after the command: its output when it succeeded
    (a failed simulation keeps the states up to the failure, by design), else nothing."""
    if "--out" not in argv:
        return set()
    name = Path(argv[argv.index("--out") + 1]).name
    if status == 0 or (argv[0] == "simulate" and "the states up to it are in" in stderr):
        # inverse writes its units beside its CSV (OUT.units.json)
        return {name, Path(name).stem + ".units.json"} if argv[0] == "inverse" else {name}
    return set()


def leftovers(out: Path, expected: set[str]) -> list[str]:
    """What the output directory holds beyond the expected outputs, temporary files included
    (in the output directory and in an output that is a directory)."""
    found = sorted(p.name for p in out.iterdir() if p.name not in expected)
    for name in sorted(expected):
        if (out / name).is_dir():
            found += [f"{name}/{p.name}" for p in (out / name).iterdir()
                      if p.name.startswith(".")]
    return found


def judge_cli(argv: list[str], path: Path, out: Path) -> Outcome:
    """Run ``hexapod ARGV``; judge its exit, its message and what it left in ``out``."""
    try:
        status, stderr = run_cli(argv)
    except Exception as error:  # escaped main() itself
        return Outcome("traceback", f"hexapod {' '.join(argv)}\n"
                       + "".join(traceback.format_exception(error)))
    command = f"hexapod {' '.join(argv)} -> exit {status}\n{stderr}"
    if "Traceback" in stderr or "internal error" in stderr:
        return Outcome("traceback", command)
    if status != 0 and not one_message(stderr):
        return Outcome("traceback", command + "\n(not one 'hexapod: error:' message)")
    extra = leftovers(out, expected_outputs(argv, status, stderr))
    if extra:
        return Outcome("partial", command, extra)
    if status == 0:
        return Outcome("accepted", command)
    return Outcome("rejected", command, unnamed=path.name not in stderr)


def fill(template: list[str], path: Path, model: Path | None, out: Path) -> list[str]:
    return [a.format(input=path, model=model or "", out=out) for a in template]


def check_cli(case: Case, path: Path, out: Path, rng: random.Random) -> Outcome:
    """The command line on the input, writing (if at all) into the empty directory ``out``."""
    template = cli_arguments(case, rng)
    outcome = judge_cli(fill(template, path, companion(case), out), path, out)
    outcome.command = template
    return outcome
