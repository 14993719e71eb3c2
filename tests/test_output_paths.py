"""Outputs that harm nothing: checked before any work, never replacing anything but a regular
file or a directory the command wrote, never an input, swapped in recoverably; and a process
that ends on a signal with the conventional status, leaving the earlier output or a complete
new one."""

from __future__ import annotations

import json
import os
import re
import signal
import stat
import subprocess
import sys
from pathlib import Path

import commands
import pytest
from script_loader import load_script

from hexapod._support import files as fileio
from hexapod.cli import main
from hexapod.errors import InputFileError

ROOT = Path(__file__).resolve().parents[1]
hostile = load_script("tests/fuzz/fuzz_hostile.py")
FIXTURE = ROOT / "tests" / "data" / "pinocchio-fixtures" / "chain-3"
PENDULUM = ROOT / "data" / "scenes" / "pendulum.toml"


def run(argv, capsys) -> tuple[int, str]:
    status = main(argv)
    err = capsys.readouterr().err
    return status, err


def one_error(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("hexapod: error: "), err
    assert "Traceback" not in err
    return lines[0]


def inverse(out: Path, motion: Path = FIXTURE / "motion.csv") -> list[str]:
    return ["inverse", str(FIXTURE / "model.urdf"), "--motion", str(motion), "--out", str(out)]


def special_files(folder: Path) -> dict[str, Path]:
    """A named pipe, a symbolic link and a directory; a character device too where this process
    may make one (a device of our own, in the test's folder)."""
    made = {"pipe": folder / "pipe", "link": folder / "link", "folder": folder / "folder"}
    os.mkfifo(made["pipe"])
    (folder / "target.csv").write_text("kept\n")
    made["link"].symlink_to(folder / "target.csv")
    made["folder"].mkdir()
    try:
        os.mknod(folder / "device", stat.S_IFCHR | 0o600, os.makedev(1, 3))
        made["device"] = folder / "device"
    except (PermissionError, OSError):
        pass
    return made


# ------------------------------------------------------------------ file outputs


def test_a_file_output_replaces_only_a_regular_file(tmp_path, capsys):
    for kind, path in special_files(tmp_path).items():
        before = os.lstat(path)
        status, err = run(inverse(path), capsys)
        line = one_error(err)
        assert status == 1 and f"--out {path}" in line, kind
        after = os.lstat(path)
        assert (after.st_mode, after.st_ino) == (before.st_mode, before.st_ino), kind
    assert (tmp_path / "target.csv").read_text() == "kept\n"


def test_scenes_write_refuses_a_special_file(tmp_path, capsys):
    pipe = special_files(tmp_path)["pipe"]
    status, err = run(["scenes", "pendulum", "--write", str(pipe)], capsys)
    assert status == 1 and "--write" in one_error(err) and "named pipe" in err
    assert stat.S_ISFIFO(os.lstat(pipe).st_mode)


def test_a_file_output_that_is_an_input_is_refused_before_work(tmp_path, capsys):
    motion = tmp_path / "motion.csv"
    motion.write_bytes((FIXTURE / "motion.csv").read_bytes())
    model = tmp_path / "model.urdf"
    model.write_bytes((FIXTURE / "model.urdf").read_bytes())
    (tmp_path / "same.csv").hardlink_to(motion)
    for out in (motion, model, tmp_path / "same.csv", tmp_path / "." / "motion.csv"):
        status, err = run(["inverse", str(model), "--motion", str(motion), "--out", str(out)],
                          capsys)
        assert status == 1 and "is the input" in one_error(err)
    assert motion.read_bytes() == (FIXTURE / "motion.csv").read_bytes()
    assert model.read_bytes() == (FIXTURE / "model.urdf").read_bytes()
    scene = tmp_path / "pendulum.toml"
    scene.write_bytes(PENDULUM.read_bytes())
    status, err = run(["scenes", str(scene), "--write", str(scene)], capsys)
    assert status == 1 and "is the input" in one_error(err)


def test_an_impossible_output_path_is_one_clear_error(tmp_path, capsys):
    cases = {tmp_path / ("x" * 300 + ".csv"): "too long",
             tmp_path / "missing" / "out.csv": "no folder",
             Path("/".join(["deep"] * 2000)) / "out.csv": "cannot use the path"}
    for out, said in cases.items():
        status, err = run(inverse(out), capsys)
        assert status == 1 and said in one_error(err), err


def test_a_temporary_file_of_a_killed_writer_is_removed_by_the_next(tmp_path):
    out = tmp_path / "out.csv"
    dead = _dead_pid()
    leftover = tmp_path / f".out.csv.{dead}.abcd.tmp"
    leftover.write_text("half")
    live = tmp_path / f".out.csv.{os.getppid()}.abcd.tmp"  # a live process's: kept
    live.write_text("busy")
    fileio.write_atomically(out, "whole\n")
    assert out.read_text() == "whole\n"
    assert not leftover.exists() and live.exists()


def _dead_pid() -> int:
    """The id of a process that has ended."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


# ------------------------------------------------------------------ directory outputs


SIMULATE = ["simulate", str(PENDULUM), "--t-end", "0.05"]


def test_a_directory_output_replaces_only_a_directory_the_command_wrote(tmp_path, capsys):
    made = special_files(tmp_path)
    for kind in ("pipe", "link"):
        status, err = run(SIMULATE + ["--out", str(made[kind])], capsys)
        assert status == 1 and "not a directory" in one_error(err), kind
    (made["folder"] / "notes.txt").write_text("mine")
    status, err = run(SIMULATE + ["--out", str(made["folder"])], capsys)
    assert status == 1 and "notes.txt" in one_error(err)
    assert (made["folder"] / "notes.txt").read_text() == "mine"


def test_a_directory_output_that_holds_an_input_is_refused(tmp_path, capsys):
    scene = tmp_path / "run" / "pendulum.toml"
    scene.parent.mkdir()
    scene.write_bytes(PENDULUM.read_bytes())
    status, err = run(["simulate", str(scene), "--t-end", "0.05", "--out", str(scene.parent)],
                      capsys)
    assert status == 1 and "holds the input" in one_error(err)
    assert scene.read_bytes() == PENDULUM.read_bytes()


def test_the_default_output_is_said_in_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status = main(["simulate", str(PENDULUM), "--t-end", "0.02"])
    err = capsys.readouterr().err
    said = [line for line in err.splitlines() if "no --out given" in line]
    assert status == 0 and len(said) == 1 and "pendulum-simulation" in said[0]
    assert (tmp_path / "pendulum-simulation" / "results.csv").is_file()


CRASH_BETWEEN_RENAMES = """
import os, sys
from hexapod._support import files
files._exchange = lambda first, second: False   # the two-rename swap
replace = os.replace
calls = []
def crashing(source, target):
    calls.append(target)
    if len(calls) == 2:          # the earlier output moved aside, the new one not yet in
        os._exit(9)
    replace(source, target)
files.os.replace = crashing
from hexapod.cli import main
sys.exit(main(sys.argv[1:]))
"""


def test_a_crash_between_the_two_renames_is_recovered_by_the_next_run(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(SIMULATE + ["--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    crashed = commands.python("-c", CRASH_BETWEEN_RENAMES, *SIMULATE, "--t-end", "0.03",
                              "--out", str(out), cwd=tmp_path)
    assert crashed.returncode == 9
    assert not out.exists() and (tmp_path / ".run.old").is_dir()  # the state a crash leaves
    fileio.recover_directory(out)  # what the next writer of the output does first
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    capsys.readouterr()


def test_a_run_after_the_crash_writes_its_output_and_leaves_nothing_else(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(SIMULATE + ["--out", str(out)]) == 0
    crashed = commands.python("-c", CRASH_BETWEEN_RENAMES, *SIMULATE, "--out", str(out),
                              cwd=tmp_path)
    assert crashed.returncode == 9
    assert main(SIMULATE + ["--t-end", "0.03", "--out", str(out)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    stats = json.loads((out / "stats.json").read_text())
    assert stats["t_end"] == pytest.approx(0.03)
    capsys.readouterr()


def test_the_swap_is_one_exchange_where_the_system_offers_it(tmp_path):
    first, second = tmp_path / "a", tmp_path / "b"
    first.mkdir()
    second.mkdir()
    (first / "one").write_text("1")
    (second / "two").write_text("2")
    if not fileio._exchange(first, second):
        pytest.skip("this system cannot exchange two names (the two-rename swap is tested)")
    assert (first / "two").exists() and (second / "one").exists()


def test_a_directory_with_a_file_of_someone_else_is_left_alone(tmp_path):
    out = tmp_path / "out"
    fileio.write_directory_atomically(out, {"a.csv": b"1"})
    (out / "mine.txt").write_text("x")
    with pytest.raises(InputFileError, match="holds other files"):
        fileio.write_directory_atomically(out, {"a.csv": b"3"})
    assert (out / "a.csv").read_bytes() == b"1" and (out / "mine.txt").read_text() == "x"


# ------------------------------------------------------------------ signals


def _command(kind: str, out: Path) -> list[str]:
    if kind == "inverse":
        return inverse(out)
    if kind == "report":
        return ["report", "front-leg", "--samples", "41", "--out", str(out)]
    return ["simulate", "front-leg", "--t-end", "0.3", "--out", str(out)]


def _reach(child: commands.Running, kind: str, moment: str) -> None:
    """Wait until the run is at ``moment``: ``imports`` (it catches SIGTERM: the handlers are
    the first thing the command installs, its imports come next), ``computation`` (its first
    progress line), ``writing`` (its last: all samples or 100 %, then the figures and files)."""
    if moment == "imports":
        child.wait_for_handler(signal.SIGTERM)
    elif moment == "computation":
        child.wait_for("inverse dynamics: " if kind != "simulate" else "%  t = ")
    elif kind == "simulate":
        child.wait_for("100 %")
    else:
        child.wait_until(lambda err: re.search(r"(\d+)/\1 samples", err) is not None,
                         "at its last sample")


@pytest.mark.parametrize("kind", ["inverse", "report", "simulate"])
def test_signals_leave_the_earlier_output_or_a_complete_new_one(tmp_path, kind):
    """SIGINT, SIGTERM and SIGKILL at several moments of a run (during the imports, the
    computation and the writing, each awaited as the run announces it): the status is the
    conventional one, no traceback, and the output is the earlier one or a complete new one,
    with no leftovers after the next run."""
    out = tmp_path / ("out.csv" if kind == "inverse" else "out")
    first = commands.in_process(*_command(kind, out), cwd=tmp_path)  # the earlier output
    assert first.returncode == 0, first.stderr
    earlier = hostile.contents(out)
    seen = set()
    for moment, number in (("imports", signal.SIGTERM), ("imports", signal.SIGINT),
                           ("computation", signal.SIGINT), ("computation", signal.SIGTERM),
                           ("writing", signal.SIGINT), ("computation", signal.SIGKILL)):
        with commands.Running("-m", "hexapod", *_command(kind, out), cwd=tmp_path,
                              HEXAPOD_PROGRESS="1") as child:
            _reach(child, kind, moment)
            child.send_signal(number)
            status, _, err = child.finish()
        expected = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGKILL: -9}[number]
        assert status in (expected, 0), (moment, number, status, err)
        assert "Traceback" not in err, err
        now = hostile.contents(out)
        assert now == earlier or hostile.complete(kind, out), (moment, number)
        if status == 0:
            earlier = now
        seen.add(status)
    assert 0 not in seen or len(seen) > 1, "no run was interrupted"
    assert main(_command(kind, out)) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name] + (
        [out.name.replace(".csv", ".units.json")] if kind == "inverse" else [])
