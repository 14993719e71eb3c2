"""Fuzz the input readers and the command line with malformed files: no traceback, ever.

    python tests/fuzz/fuzz_inputs.py                          # 5000 inputs, seed 0 (a few minutes)
    python tests/fuzz/fuzz_inputs.py --count 200 --seed 7     # a quick look
    python tests/fuzz/fuzz_inputs.py --replay fuzz-failures/0042-scene-cli  # one saved failure

Protocol
--------
Each input is made from a valid file of the repository -- a scene (``data/scenes/*.toml``), a URDF
or a motion CSV (``tests/data/pinocchio-fixtures/*/``) -- by one to three random mutations: on the
parsed document (delete a key or an element, replace a value by NaN, infinity, -1, 0, 1e308, a
string, a list or a table, rename a reference to an unknown name, make a joint join a body to
itself, duplicate an element, change a type, a unit or an inertia), or on the bytes (truncate,
flip, insert or delete bytes, break tags, nest arrays deeply, add a BOM); a few inputs are random
text or random bytes. The mutations are those of ``tests/test_malformed_inputs.py``, where
Hypothesis draws them; here ``random.Random(seed)`` does, so a run is reproducible.

Every input goes through its reader and, when it reads, through ``hexapod.assemble`` and
``hexapod.consistent_state`` (a motion drives the URDF it was made for). Every fourth input also
goes through the command line, in process (``hexapod.cli.main``, stdout and stderr captured):
``validate`` or ``info`` for a scene, ``info`` for a URDF, ``inverse --out`` for a motion (and
for a URDF with its motion), each writing into an empty directory of its own.

Each run is counted as

* **accepted**: read (and assembled) without error, or the command succeeded;
* **rejected**: a :class:`hexapod.HexapodError` whose message names the file; on the command
  line, a non-zero exit with a message starting ``hexapod: error:``;
* **traceback**: any other exception (``KeyError``, ``ValueError``, ``RecursionError``, ...), a
  ``HexapodError`` that does not name the file, or a command that ended in ``hexapod: internal
  error`` or printed a traceback;
* **partial file**: after the command, the output directory holds a file it should not (an
  output after a failure, or a temporary file after anything).

The column **unnamed** counts the command-line rejections whose message does not name the input:
errors of the computation after the files were read and assembled (the forward dynamics of
``info``, a diverging ``simulate``), which name what failed but not the file. They are not
failures (the readers' own errors always name the file: the library path checks it).

Then come the hostile command lines and the fault trials of ``tests/fuzz/fuzz_hostile.py`` (devices
and inputs as outputs, non-finite and absurd numbers, huge requests, broken meshes; signals at
random moments of ``simulate``, ``report`` and ``inverse``), each a subprocess with a 30 s limit.

Progress goes to stderr, a summary table to stdout; the exit status is 1 when any traceback or
partial file was seen, else 0. Every failing input is saved in ``--failures DIR`` (default
``fuzz-failures``) as ``NNNN-KIND/`` with the input, the file it needs (the URDF of a motion) and
``failure.txt`` (the mutations, the command, the traceback); ``--replay`` runs one again.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

# ``X as X``: names this script does not use, re-exported for the tests (tests/fuzzer.py loads
# this script as the module they share)
import fuzz_hostile
from fuzz_mutations import BROKEN_XML as BROKEN_XML
from fuzz_mutations import mutate_motion as mutate_motion
from fuzz_mutations import mutate_urdf as mutate_urdf
from fuzz_targets import (
    KINDS,
    ROOT,
    Case,
    Outcome,
    check_cli,
    check_library,
    companion,
    fill,
    judge_cli,
    make_case,
    quiet,
)
from fuzz_targets import MOTIONS as MOTIONS
from fuzz_targets import SCENES as SCENES
from fuzz_targets import URDFS as URDFS
from fuzz_targets import read_and_assemble as read_and_assemble
from fuzz_toml import mutate_toml as mutate_toml
from fuzz_toml import toml_text as toml_text

# ------------------------------------------------------------------ the run


@dataclass
class Tally:
    counts: Counter = field(default_factory=Counter)
    failures: int = 0

    def add(self, kind: str, path: str, outcome: Outcome) -> None:
        self.counts[(kind, path, outcome.status)] += 1
        self.counts[(kind, path, "unnamed")] += outcome.unnamed

    def table(self) -> str:
        statuses = ("accepted", "rejected", "traceback", "partial")
        rows = [("input", "path", "runs", *statuses, "unnamed")]
        for kind in KINDS:
            for path in ("library", "cli"):
                counts = [self.counts[(kind, path, s)] for s in statuses + ("unnamed",)]
                rows.append((kind, path, str(sum(counts[:-1])), *map(str, counts)))
        totals = [sum(v for (_, _, s), v in self.counts.items() if s == status)
                  for status in statuses + ("unnamed",)]
        rows.append(("all", "", str(sum(totals[:-1])), *map(str, totals)))
        widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
        lines = ["  ".join(c.ljust(w) if i < 2 else c.rjust(w)
                           for i, (c, w) in enumerate(zip(r, widths, strict=True)))
                 for r in rows]
        return "\n".join(lines[:1] + ["-" * len(lines[0])] + lines[1:-1]
                         + ["-" * len(lines[0])] + lines[-1:])


def save_failure(folder: Path, number: int, case: Case, path: Path, outcome: Outcome,
                 how: str) -> Path:
    """Keep a failing input, with what it needs and what happened, for --replay."""
    target = folder / f"{number:04d}-{case.kind}-{how}"
    target.mkdir(parents=True, exist_ok=True)
    (target / path.name).write_bytes(case.data)
    other = companion(case)
    if other is not None:
        shutil.copy(other, target / other.name)
    command = json.dumps(outcome.command) if outcome.command else ""
    (target / "failure.txt").write_text(
        f"kind: {case.kind}\ninput: {path.name}\ncompanion: {other.name if other else ''}\n"
        f"command: {command}\nmade from: {case.seed_file.relative_to(ROOT)}\nmutations:\n"
        + "".join(f"  - {m}\n" for m in case.mutations)
        + f"path: {how}\nstatus: {outcome.status}\nleftovers: {outcome.leftovers}\n\n"
        + outcome.detail + "\n", encoding="utf-8")
    return target


def run(count: int, seed: int, cli_share: float, failures: Path, progress) -> Tally:
    rng = random.Random(seed)
    tally = Tally()
    with tempfile.TemporaryDirectory(prefix="hexapod-fuzz-") as work:
        work = Path(work)
        for number in range(count):
            case = make_case(rng)
            folder = work / f"{number:05d}"
            folder.mkdir()
            path = folder / f"input{case.suffix}"
            path.write_bytes(case.data)
            runs = [("library", check_library(case, path))]
            if rng.random() < cli_share:
                out = folder / "out"
                out.mkdir()
                with quiet():
                    runs.append(("cli", check_cli(case, path, out, rng)))
            for how, outcome in runs:
                tally.add(case.kind, how, outcome)
                if outcome.status in ("traceback", "partial"):
                    tally.failures += 1
                    saved = save_failure(failures, number, case, path, outcome, how)
                    progress(f"\n{outcome.status}: {saved}\n")
            shutil.rmtree(folder)
            if (number + 1) % 50 == 0 or number + 1 == count:
                progress(f"\r{number + 1}/{count} inputs, {tally.failures} failures")
    progress("\n")
    return tally


def replay(folder: Path) -> int:
    """Run one saved failure again (through the command line too when it failed there)."""
    info = dict(line.split(":", 1) for line in
                (folder / "failure.txt").read_text(encoding="utf-8").splitlines()[:4])
    info = {key: value.strip() for key, value in info.items()}
    path = folder / info["input"]
    model = folder / info["companion"] if info["companion"] else None
    case = Case(info["kind"], path, [], path.read_bytes())  # its model.urdf is beside it
    outcome = check_library(case, path)
    print(f"library: {outcome.status}\n{outcome.detail}")
    failed = outcome.status not in ("accepted", "rejected")
    if info["command"]:
        with tempfile.TemporaryDirectory() as out:
            argv = fill(json.loads(info["command"]), path, model, Path(out))
            outcome = judge_cli(argv, path, Path(out))
        print(f"command line: {outcome.status} {outcome.leftovers}\n{outcome.detail}")
        failed |= outcome.status not in ("accepted", "rejected")
    return 1 if failed else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--count", type=int, default=5000, help="inputs to make (default 5000)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--cli-share", type=float, default=0.25,
                        help="share of the inputs also run through the command line "
                        "(default 0.25)")
    parser.add_argument("--failures", type=Path, default=Path("fuzz-failures"),
                        help="where failing inputs are saved (default fuzz-failures)")
    parser.add_argument("--replay", type=Path, metavar="DIR", help="run one saved failure")
    parser.add_argument("--trials", type=int, default=60,
                        help="fault trials after the hostile command lines (default 60; see "
                        "tests/fuzz/fuzz_hostile.py)")
    args = parser.parse_args(argv)
    if args.replay:
        return replay(args.replay)
    started = time.perf_counter()

    def progress(text: str) -> None:
        print(text, end="", file=sys.stderr, flush=True)

    tally = run(args.count, args.seed, args.cli_share, args.failures, progress)
    elapsed = time.perf_counter() - started
    print(f"hexapod input fuzzing: {args.count} inputs, seed {args.seed}, "
          f"{elapsed:.0f} s\n")
    print(tally.table())
    partial = sum(v for (_, _, s), v in tally.counts.items() if s == "partial")
    tracebacks = sum(v for (_, _, s), v in tally.counts.items() if s == "traceback")
    print(f"\ntracebacks: {tracebacks}, partial files: {partial}"
          + (f" (inputs saved in {args.failures}/)" if tally.failures else ""))
    print()
    hostile = fuzz_hostile.main(["--trials", str(args.trials), "--seed", str(args.seed)])
    return 1 if tally.failures or hostile else 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))  # scratch_cache
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    sys.exit(main())
