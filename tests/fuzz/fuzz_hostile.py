"""Hostile command lines and interrupted runs: the cases of the hardening issue, each with the
status and the words its one error line must have.

    python tests/fuzz/fuzz_hostile.py                  # every case, then 60 fault trials
    python tests/fuzz/fuzz_hostile.py --trials 200 --seed 3

Each case makes its inputs in a folder of its own and runs ``python -m hexapod ...`` there as a
subprocess, with a time limit of 30 s (a case that needs longer is a **hang**), and is judged:

* **ok**: the expected status, one ``hexapod: error:`` line naming what the case names (the
  option, the key, the file), nothing written but what a successful command writes;
* **traceback**: a traceback or an ``internal error``;
* **partial**: a file left that should not be (a temporary file, an output after a failure),
  or a file that was there changed or replaced (a device node, an input);
* **wrong**: another status or message.

The fault trials run ``simulate``, ``report`` and ``inverse`` writing over an earlier output and
send SIGINT, SIGTERM or SIGKILL after a random delay: the status must be 0 or the signal's
(130, 143, -9), with no traceback, and the output the earlier one or a complete new one.
``tests/test_hostile_inputs.py`` runs the same cases (``CASES``) in the test suite.
"""

from __future__ import annotations

import argparse
import atexit
import json
import math
import os
import random
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
import zipfile
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CHAIN = ROOT / "tests" / "data" / "pinocchio-fixtures" / "chain-3"
PENDULUM = ROOT / "data" / "scenes" / "pendulum.toml"
TIME_LIMIT = 30.0


@dataclass(frozen=True)
class Hostile:
    """One hostile command: ``make(folder)`` writes its inputs and returns the arguments."""

    name: str
    make: object
    status: tuple[int, ...]
    says: tuple[str, ...]  # words the error line must hold
    writes: tuple[str, ...] = ()  # outputs a failed run writes (marked failed in stats.json)
    env: tuple[tuple[str, str], ...] = ()  # environment variables of the run

    def argv(self, folder: Path) -> list[str]:
        return [str(a) for a in self.make(folder)]


def _copy(folder: Path, source: Path, name: str | None = None) -> Path:
    target = folder / (name or source.name)
    target.write_bytes(source.read_bytes())
    return target


def _chain_inverse(folder: Path, out) -> list:
    model, motion = _copy(folder, CHAIN / "model.urdf"), _copy(folder, CHAIN / "motion.csv")
    return ["inverse", model, "--motion", motion, "--out", out(folder, model, motion)]


def _device(folder: Path) -> Path:
    """A device node of our own where this process may make one, else a named pipe."""
    path = folder / "node"
    try:
        os.mknod(path, stat.S_IFCHR | 0o600, os.makedev(1, 3))
    except OSError:
        os.mkfifo(path)
    return path


def _pipe(folder: Path, name: str) -> Path:
    """A named pipe that nobody writes to: reading it would wait for ever."""
    path = folder / name
    os.mkfifo(path)
    return path


def _report_csv(folder: Path, rows: int = 2, cell: str = "0") -> Path:
    """A report folder whose ``inverse.csv`` has ``rows`` rows, the second value ``cell``."""
    run = folder / "report"
    run.mkdir()
    with open(run / "inverse.csv", "w") as stream:
        stream.write("t,x\n" + f"0,{cell}\n" + "".join(f"{k},0\n" for k in range(1, rows)))
    return run


def _scene(folder: Path, text: str, name: str = "scene.toml") -> Path:
    path = folder / name
    path.write_text(text)
    return path


PENDULUM_TEXT = PENDULUM.read_text()
SPLINE_SCENE = PENDULUM_TEXT + """
[[driver]]
name = "swing"
kind = "joint"
joint = "hinge"
law = { type = "spline", times = [0.0, 1e-300, 2e-300], values = [0.0, 0.1, 0.2] }
"""


_DOC = (ROOT / "docs" / "scene-format.md").read_text()
#: the documentation's stool: a body on four contacts, two of them stepping (period 2 s)
STOOL_TEXT = _DOC[_DOC.index("# A stool on four feet"):_DOC.index("```", _DOC.index(
    "# A stool on four feet"))]


def _driven(expression: str) -> str:
    """The pendulum driven by the law ``expression`` of t."""
    return PENDULUM_TEXT + ('\n[[driver]]\nname = "swing"\njoint = "pivot"\nlaw = { type = '
                            f'"expression", expression = "{expression}" }}\n')


def _many_feet(count: int) -> str:
    """The stool on ``count`` feet in a circle, all on the ground."""
    feet = []
    for k in range(count):
        x, y = 0.2 * math.cos(2 * math.pi * k / count), 0.2 * math.sin(2 * math.pi * k / count)
        feet.append(f'[[joint]]\nname = "f{k}"\ntype = "contact"\nparent = "ground"\n'
                    f'child = "seat"\nchild_frame = [{x}, {y}, -0.4]\nduty = 1.0\n'
                    f"foothold = [{x}, {y}, 0.0]\n")
    return STOOL_TEXT[:STOOL_TEXT.index("[[joint]]")] + "".join(feet)


def _wide_motion(folder: Path, columns: int = 100_000) -> Path:
    path = folder / "wide.csv"
    names = ["t"] + [f"j{k}" for k in range(columns)]
    path.write_text(",".join(names) + "\n" + ",".join(["0"] * len(names)) + "\n"
                    + ",".join(["1"] * len(names)) + "\n")
    return path


def _huge_npz(folder: Path) -> Path:
    """A results folder whose npz declares arrays of 1e12 numbers in a few bytes."""
    run = folder / "run"
    run.mkdir()
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (1000000, 1000000), }"
    header = header + " " * (63 - len(header) % 64) + "\n"
    array = b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode()
    with zipfile.ZipFile(run / "results.npz", "w") as archive:
        for name in ("t", "q", "v"):
            archive.writestr(f"{name}.npy", array)
    (run / "stats.json").write_text(json.dumps({"scene": str(PENDULUM)}))
    return run


_SMALL_RUN: list[Path] = []  # the one simulation of this process, made at the first need


def _small_run(folder: Path) -> Path:
    """The output of a short simulation of the pendulum, to export, copied into ``folder``.

    Three cases export one; the simulation (a process of its own, a second and a half) is run
    once per process and its folder copied, as it would be written: it names no path of its
    own, and the cases judge the export, not the run that made its input."""
    if not _SMALL_RUN:
        made = Path(tempfile.mkdtemp(prefix="hexapod-hostile-run-"))
        atexit.register(shutil.rmtree, made, ignore_errors=True)
        subprocess.run([sys.executable, "-m", "hexapod", "simulate", str(PENDULUM), "--t-end",
                        "0.01", "--out", str(made / "run")], capture_output=True, check=True,
                       env={**os.environ, "OPENBLAS_NUM_THREADS": "1"}, timeout=TIME_LIMIT)
        _SMALL_RUN.append(made / "run")
    return Path(shutil.copytree(_SMALL_RUN[0], folder / "run"))


def _huge_mesh(folder: Path) -> Path:
    path = folder / "huge.stl"
    with open(path, "wb") as stream:
        stream.truncate(4 * 2**30)  # a sparse file: 4 GiB to read, nothing on the disk
    return path


CASES = (
    # writes that destroy
    Hostile("inverse --out a device", lambda f: _chain_inverse(f, lambda f, m, q: _device(f)),
            (1,), ("--out", "not a regular file")),
    Hostile("scenes --write a device", lambda f: ["scenes", "pendulum", "--write", _device(f)],
            (1,), ("--write",)),
    Hostile("inverse --out the motion", lambda f: _chain_inverse(f, lambda f, m, q: q),
            (1,), ("--out", "input")),
    Hostile("inverse --out the URDF", lambda f: _chain_inverse(f, lambda f, m, q: m),
            (1,), ("--out", "input")),
    Hostile("inverse --out a name too long",
            lambda f: _chain_inverse(f, lambda f, m, q: f / ("x" * 400)), (1,), ("--out",)),
    Hostile("simulate --out a file", lambda f: ["simulate", PENDULUM, "--out",
                                                _scene(f, "x", "taken")], (1,), ("--out",)),
    # non-finite and absurd numbers
    Hostile("simulate --start nan", lambda f: ["simulate", PENDULUM, "--start", "nan"],
            (2,), ("--start",)),
    Hostile("simulate --start inf", lambda f: ["simulate", PENDULUM, "--start", "inf"],
            (2,), ("--start",)),
    Hostile("simulate --start 1e17", lambda f: ["simulate", PENDULUM, "--start", "1e17"],
            (2,), ("--start",)),
    Hostile("report --start nan", lambda f: ["report", "--start", "nan"], (2,), ("--start",)),
    Hostile("dynamics --t nan", lambda f: ["dynamics", "--t", "nan"], (2,), ("--t",)),
    Hostile("spline knots 1e-300 apart", lambda f: ["validate", _scene(f, SPLINE_SCENE)],
            (1,), ("scene.toml",)),
    Hostile("gravity 1e308", lambda f: ["simulate", _scene(f, PENDULUM_TEXT.replace(
        'length_unit = "m"', 'length_unit = "m"\ngravity = [0.0, 0.0, -1e308]'))], (1,),
            ("gravity",)),
    Hostile("generalized-alpha --t-end 1e308", lambda f: [
        "simulate", PENDULUM, "--method", "generalized-alpha", "--t-end", "1e308"], (1, 2),
            ("--t-end",)),
    Hostile("simulate --t-end 1e9", lambda f: ["simulate", PENDULUM, "--t-end", "1e9",
                                                "--out", f / "run"], (1,), ("--t-end",),
            writes=("run",)),
    # memory and time
    Hostile("report --samples 1e9", lambda f: ["report", "--samples", "1000000000"], (1, 2),
            ("--samples",)),
    Hostile("report --samples 1e7", lambda f: ["report", "--samples", "10000000"], (1, 2),
            ("--samples",)),
    Hostile("a motion of 100,000 columns", lambda f: [
        "inverse", _copy(f, CHAIN / "model.urdf"), "--motion", _wide_motion(f), "--out",
        f / "out.csv"], (1,), ("wide.csv",)),
    Hostile("a results.npz declaring 1e12 numbers", lambda f: [
        "export", _huge_npz(f), "--vtk", f / "vtk"], (1,), ("results.npz",)),
    Hostile("a mesh of 4 GiB", lambda f: [
        "export", _small_run(f), "--vtk", f / "vtk", "--mesh", f"rod={_huge_mesh(f)}"], (1,),
            ("huge.stl",)),
    # inputs that never end: refused by kind before they are opened
    Hostile("a scene that is a pipe", lambda f: ["simulate", _pipe(f, "scene.toml")], (1,),
            ("scene.toml", "named pipe")),
    Hostile("a scene without suffix that is a pipe", lambda f: ["validate", _pipe(f, "s")],
            (1,), ("named pipe",)),
    Hostile("a URDF that is a pipe", lambda f: [
        "inverse", _pipe(f, "model.urdf"), "--motion", _copy(f, CHAIN / "motion.csv"), "--out",
        f / "out.csv"], (1,), ("model.urdf", "named pipe")),
    Hostile("a motion that is a pipe", lambda f: [
        "inverse", _copy(f, CHAIN / "model.urdf"), "--motion", _pipe(f, "motion.csv"), "--out",
        f / "out.csv"], (1,), ("motion.csv", "named pipe")),
    Hostile("a study that is a pipe", lambda f: ["sweep", _pipe(f, "study.toml"), "--out",
                                                f / "study"], (1,), ("study.toml", "named pipe")),
    Hostile("a study's scene that is a pipe", lambda f: ["sweep", _scene(
        f, f'[study]\nname = "s"\nscene = "{_pipe(f, "base.toml")}"\n[vary.duty]\n'
        'values = [0.6]\n[job]\nkind = "inverse"\n', "study.toml"), "--out", f / "study"],
            (1,), ("base.toml", "named pipe")),
    Hostile("--t-eval @ a pipe", lambda f: ["simulate", PENDULUM, "--t-eval",
                                            f"@{_pipe(f, 'times.txt')}"], (2,),
            ("--t-eval", "named pipe")),
    Hostile("a report's CSV that is a pipe", lambda f: [
        "export", _pipe((f / "r").mkdir() or f / "r", "inverse.csv").parent, "--vtk", f / "v"],
            (1,), ("inverse.csv", "named pipe")),
    Hostile("a results.npz that is a pipe", lambda f: [
        "export", _pipe((f / "r").mkdir() or f / "r", "results.npz").parent, "--vtk", f / "v"],
            (1,), ("results.npz", "named pipe")),
    Hostile("a mesh that is a pipe", lambda f: [
        "export", _small_run(f), "--vtk", f / "vtk", "--mesh", f"rod={_pipe(f, 'rod.stl')}"],
            (1,), ("rod.stl", "named pipe")),
    # counts and sizes bounded
    Hostile("a report of 30,000 rows to export", lambda f: [
        "export", _report_csv(f, 30_000), "--vtk", f / "v"], (1,),
            ("30,000 saved instants", "--max-instants")),
    Hostile("a CSV field over 131,072 characters", lambda f: [
        "export", _report_csv(f, 2, "x" * 200_000), "--vtk", f / "v"], (1,),
            ("inverse.csv", "line 2")),
    Hostile("a scene larger than the memory limit", lambda f: [
        "validate", _scene(f, PENDULUM_TEXT + "#" * 400_000)], (1,),
            ("scene.toml", "HEXAPOD_MAX_MEMORY"), env=(("HEXAPOD_MAX_MEMORY", "1M"),)),
    Hostile("a motion weighed before it is read", lambda f: [
        "inverse", _copy(f, CHAIN / "model.urdf"), "--motion", _scene(
            f, "t,j0,j1,j2\n" + "".join(f"{k},0.1,0.2,0.3\n" for k in range(200_000)),
            "motion.csv"), "--out", f / "out.csv"], (1,), ("reading the motion file", "motion.csv"),
            env=(("HEXAPOD_MAX_MEMORY", "50M"),)),
    Hostile("a friction pyramid of 1e9 faces in the scene", lambda f: [
        "report", _scene(f, STOOL_TEXT.replace("faces = 0 ", "faces = 1000000000 ")), "--out",
        f / "r"], (1,), ("scene.toml", "faces", "1000")),
    Hostile("a contact of period 1e-12 s", lambda f: [
        "report", _scene(f, STOOL_TEXT.replace("period = 2.0  ", "period = 1e-12")), "--out",
        f / "r"], (1,), ("scene.toml", "period", "back_left")),
    Hostile("a contact of period 2e-6 s over 100 s", lambda f: [
        "report", _scene(f, STOOL_TEXT.replace("period = 2.0  ", "period = 2e-6")), "--out",
        f / "r", "--duration", "100", "--samples", "3"], (1,),
            ("back_left", "HEXAPOD_MAX_STEPS")),
    Hostile("validate a scene of more bodies than the limit", lambda f: [
        "validate", _scene(f, '[scene]\nname = "many"\n' + "".join(
            f'[[body]]\nname = "b{k}"\nmass = 1.0\ninertia = [1.0, 1.0, 1.0]\n'
            for k in range(3)))], (1,), ("3 bodies", "HEXAPOD_MAX_BODIES"),
            env=(("HEXAPOD_MAX_BODIES", "2"),)),
    Hostile("1000 contacts on one body", lambda f: [
        "report", _scene(f, _many_feet(1000)), "--out", f / "r"], (1,),
            ("1000 foot contacts", "HEXAPOD_MAX_CONTACTS")),
    Hostile("validate 1000 contacts on one body", lambda f: [
        "validate", _scene(f, _many_feet(1000))], (1,),
            ("1000 foot contacts", "HEXAPOD_MAX_CONTACTS")),
    # laws that blow up end the run as failed, naming the law and the time
    Hostile("a driver law 1/(t-0.1)", lambda f: [
        "simulate", _scene(f, _driven("1/(t-0.1)")), "--t-end", "0.3", "--out", f / "run"],
            (1,), ("driver 'swing'", "t = 0.09"), writes=("run",)),
    Hostile("a driver law 1/0", lambda f: ["report", _scene(f, _driven("1/0")), "--out",
                                          f / "r"], (1,), ("driver 'swing'", "division by zero")),
    # errors that escape
    Hostile("an unreadable .vtu mesh", lambda f: [
        "export", _small_run(f), "--vtk", f / "vtk", "--mesh",
        f"rod={_scene(f, 'not a mesh', 'broken.vtu')}"], (1,), ("broken.vtu",)),
)


# ------------------------------------------------------------------ running and judging


def run_case(case: Hostile, folder: Path) -> tuple[str, str]:
    """(verdict, detail) of one case run in ``folder``."""
    argv = case.argv(folder)
    before = _listing(folder)
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", **dict(case.env)}
    started = time.perf_counter()
    try:
        done = subprocess.run([sys.executable, "-m", "hexapod", *argv], cwd=folder, env=env,
                              capture_output=True, text=True, timeout=TIME_LIMIT)
    except subprocess.TimeoutExpired:
        return "hang", f"over {TIME_LIMIT:g} s"
    elapsed = time.perf_counter() - started
    err = done.stderr
    if "Traceback" in err or "internal error" in err:
        return "traceback", err[-2000:]
    after = _listing(folder)
    changed = {name for name in before if after.get(name) != before[name]}
    added = {name for name in set(after) - set(before)
             if name.split("/")[0] not in case.writes}
    if changed or added:
        return "partial", f"changed {sorted(changed)}, added {sorted(added)}"
    # one error message (its first line "hexapod: error:" or, from the argument parser,
    # "hexapod COMMAND: error:"; a scene's problems follow it, one per line)
    errors = [k for k, line in enumerate(err.splitlines())
              if line.startswith("hexapod") and ": error:" in line]
    message = "\n".join(err.splitlines()[errors[0]:]) if len(errors) == 1 else ""
    if done.returncode not in case.status or not message or not all(
            word in message for word in case.says):
        return "wrong", f"status {done.returncode}: {err.strip()[-800:]}"
    return "ok", f"{elapsed:.1f} s: {message.splitlines()[0][:160]}"


def _listing(folder: Path) -> dict:
    """Every entry under ``folder``: its kind, inode and content digest (files)."""
    found = {}
    for path in sorted(folder.rglob("*")):
        info = os.lstat(path)
        content = (path.read_bytes() if stat.S_ISREG(info.st_mode) and info.st_size < 2**24
                   else info.st_size)
        found[str(path.relative_to(folder))] = (stat.S_IFMT(info.st_mode), info.st_ino,
                                                hash(content) if isinstance(content, bytes)
                                                else content)
    return found


FAULT_COMMANDS = {
    "inverse": lambda out: ["inverse", CHAIN / "model.urdf", "--motion", CHAIN / "motion.csv",
                            "--out", out / "out.csv"],
    "report": lambda out: ["report", "front-leg", "--samples", "41", "--out", out / "out"],
    "simulate": lambda out: ["simulate", "front-leg", "--t-end", "0.3", "--out", out / "out"],
}
SIGNALS = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGKILL: -signal.SIGKILL}


def fault_trial(kind: str, number: int, delay: float, folder: Path) -> tuple[str, str]:
    """Run ``kind`` once to completion, then again with a signal after ``delay``."""
    argv = [str(a) for a in FAULT_COMMANDS[kind](folder)]
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    command = [sys.executable, "-m", "hexapod", *argv]
    first = subprocess.run(command, cwd=folder, env=env, capture_output=True, text=True,
                           timeout=300)
    if first.returncode != 0:
        return "wrong", first.stderr[-800:]
    out = Path(argv[-1])
    earlier = contents(out)
    child = subprocess.Popen(command, cwd=folder, env=env, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    time.sleep(delay)
    child.send_signal(number)
    try:
        _, err = child.communicate(timeout=TIME_LIMIT)
    except subprocess.TimeoutExpired:
        child.kill()
        return "hang", f"after {signal.Signals(number).name} at {delay:.2f} s"
    if "Traceback" in err or "internal error" in err:
        return "traceback", err[-2000:]
    if child.returncode not in (0, SIGNALS[number]):
        return "wrong", f"status {child.returncode}: {err[-400:]}"
    now = contents(out)
    if now != earlier and not complete(kind, out):
        return "partial", f"{out} incomplete after {signal.Signals(number).name} at {delay:.2f}"
    return "ok", f"status {child.returncode}"


def contents(out: Path) -> dict:
    if out.is_dir():
        return {p.name: p.read_bytes() for p in out.iterdir()}
    return {out.name: out.read_bytes()} if out.exists() else {}


def complete(kind: str, out: Path) -> bool:
    if kind == "inverse":
        return out.read_text().endswith("\n")
    if kind == "report":
        return (out / "summary.md").is_file() and (out / "inverse.csv").is_file()
    stats = json.loads((out / "stats.json").read_text())
    return stats.get("status") in ("finished", "interrupted")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--trials", type=int, default=60, help="fault trials (default 60)")
    parser.add_argument("--seed", type=int, default=0, help="random seed of the trials")
    args = parser.parse_args(argv)
    tally: Counter = Counter()
    failures = []
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="hexapod-hostile-") as work:
        for k, case in enumerate(CASES):
            folder = Path(work) / f"case{k:02d}"
            folder.mkdir()
            verdict, detail = run_case(case, folder)
            tally[("cases", verdict)] += 1
            print(f"{verdict:9s} {case.name}: {detail.splitlines()[0] if detail else ''}",
                  file=sys.stderr, flush=True)
            if verdict != "ok":
                failures.append((case.name, detail))
        rng = random.Random(args.seed)
        for k in range(args.trials):
            kind = rng.choice(sorted(FAULT_COMMANDS))
            number = rng.choice(list(SIGNALS))
            delay = rng.uniform(0.05, 4.0)
            folder = Path(work) / f"trial{k:03d}"
            folder.mkdir()
            verdict, detail = fault_trial(kind, number, delay, folder)
            tally[("faults", verdict)] += 1
            print(f"\r{k + 1}/{args.trials} fault trials", end="", file=sys.stderr, flush=True)
            if verdict != "ok":
                failures.append((f"{kind} {signal.Signals(number).name} at {delay:.2f} s",
                                 detail))
        print(file=sys.stderr)
    verdicts = ("ok", "traceback", "partial", "hang", "wrong")
    print(f"hostile inputs: {len(CASES)} cases, {args.trials} fault trials (seed {args.seed}), "
          f"{time.perf_counter() - started:.0f} s\n")
    print(f"{'':8s}" + "".join(f"{v:>11s}" for v in verdicts))
    for group in ("cases", "faults"):
        print(f"{group:8s}" + "".join(f"{tally[(group, v)]:>11d}" for v in verdicts))
    for name, detail in failures:
        print(f"\n{name}:\n{detail}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT / "scripts"))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    sys.exit(main())
