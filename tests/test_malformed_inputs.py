"""Bad input never crashes: malformed scene, URDF and motion files give one error naming the file,
never a traceback, and no command leaves a partial output.

The mutations are those of ``tests/fuzz/fuzz_inputs.py`` (which runs thousands of them); here
Hypothesis draws them, so that a failure is shrunk to a small input and replayed the same way on
every run (``derandomize``).
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import warnings
from pathlib import Path

import commands
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from script_loader import load_script

import hexapod as hx
from hexapod import cli
from hexapod._support import files as fileio
from hexapod.errors import HexapodError, InputFileError, ModelError
from hexapod.scene.motion import apply_motion, read_motion
from hexapod.scene.reader import read_scene
from hexapod.scene.urdf import read_urdf

fuzz = load_script("tests/fuzz/fuzz_inputs.py")  # the mutations and the TOML writer

ROOT = Path(__file__).resolve().parents[1]


FIXTURE = ROOT / "tests" / "data" / "pinocchio-fixtures" / "chain-3"
PENDULUM = ROOT / "data" / "scenes" / "pendulum.toml"

# Reproducible (derandomize), no example database written into the checkout, no deadline: a
# first CasADi call may take a while on a busy machine. 60 examples a kind of file (each up to
# a model assembled, 0.1 s): the default run's share; `python tests/fuzz/fuzz_inputs.py` runs
# 5000 of them.
FUZZ = settings(max_examples=60, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    """One directory for the examples of a test (Hypothesis reruns a test function many times,
    so a function-scoped tmp_path would be shared anyway)."""
    return tmp_path_factory.mktemp("malformed")


def reads_or_fails_cleanly(case, path: Path) -> None:
    """Read, validate, assemble and find a consistent state: it works, or it raises a
    HexapodError whose message names the file. Any other exception fails the test."""
    path.write_bytes(case.data)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fuzz.read_and_assemble(case, path)
    except HexapodError as error:
        assert path.name in str(error), str(error)


# ------------------------------------------------------------------ mutated files

def modes(*weighted: tuple[str, int]):
    """The kind of mutation, drawn by Hypothesis (which shrinks towards the first)."""
    return st.sampled_from([mode for mode, weight in weighted for _ in range(weight)])


@FUZZ
@given(seed_file=st.sampled_from(fuzz.SCENES), rng=st.randoms(use_true_random=False),
       mode=modes(("document", 3), ("bytes", 1)))
def test_mutated_scene_files(seed_file, rng, mode, workdir):
    mutations, data = fuzz.mutate_toml(rng, seed_file.read_bytes(), mode)
    reads_or_fails_cleanly(fuzz.Case("scene", seed_file, mutations, data),
                           workdir / "scene.toml")


@FUZZ
@given(seed_file=st.sampled_from(fuzz.URDFS), rng=st.randoms(use_true_random=False),
       mode=modes(("tree", 3), ("bytes", 1)))
def test_mutated_urdf_files(seed_file, rng, mode, workdir):
    mutations, data = fuzz.mutate_urdf(rng, seed_file.read_bytes(), mode)
    reads_or_fails_cleanly(fuzz.Case("urdf", seed_file, mutations, data), workdir / "model.urdf")


@FUZZ
@given(seed_file=st.sampled_from(fuzz.MOTIONS), rng=st.randoms(use_true_random=False),
       mode=modes(("table", 3), ("bytes", 1)))
def test_mutated_motion_files(seed_file, rng, mode, workdir):
    mutations, data = fuzz.mutate_motion(rng, seed_file.read_bytes(), mode)
    reads_or_fails_cleanly(fuzz.Case("motion", seed_file, mutations, data),
                           workdir / "motion.csv")


@settings(FUZZ, max_examples=60)
@given(kind=st.sampled_from(tuple(fuzz.KINDS)),
       data=st.one_of(st.binary(max_size=300), st.text(max_size=300).map(str.encode)))
def test_random_bytes_and_text(kind, data, workdir):
    seed_file = fuzz.KINDS[kind][0][0]
    reads_or_fails_cleanly(fuzz.Case(kind, seed_file, ["random"], data),
                           workdir / f"random{fuzz.KINDS[kind][2]}")


# ------------------------------------------------------------------ what the fuzzer found


def _error(read, path: Path, text: str | bytes) -> str:
    """The message of the HexapodError raised by reading ``text`` as ``path``."""
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(HexapodError) as info:
        read(path)
    message = str(info.value)
    assert path.name in message
    return message


@pytest.mark.parametrize("text, message", [
    ("x = " + "[" * 2000 + "]" * 2000, "nested too deeply"),  # was a RecursionError
    ("x = " + "9" * 5000, "4300 digits"),  # was a ValueError of int()
    (b"[scene]\nname = \"\xff\"\n", "byte 0xff on line 2"),
    ("", None),  # an empty file is an empty scene: nothing wrong with it
], ids=["deep", "long-integer", "not-utf8", "empty"])
def test_scene_parser_limits(tmp_path, text, message):
    path = tmp_path / "scene.toml"
    if message is None:
        path.write_text(text)
        assert read_scene(path).bodies == {}
    else:
        assert message in _error(read_scene, path, text)


@pytest.mark.parametrize("text", fuzz.BROKEN_XML, ids=["billion-laughs", "external", "undefined"])
def test_xml_entity_tricks(tmp_path, text):
    assert "not well-formed XML" in _error(read_urdf, tmp_path / "trick.urdf", text)


def test_scene_messages_stay_on_one_line_per_problem(tmp_path):
    text = ('[[body]]\nname = "a\\nb"\nmass = [' + ", ".join(["1.0"] * 3000) + ']\n'
            'inertia = [1.0, 1.0, 1.0]\n"odd\\nkey" = 1\n')
    message = _error(read_scene, tmp_path / "long.toml", text)
    lines = message.splitlines()
    assert len(lines) == 3 and all(len(line) < 300 for line in lines), message
    assert "must be a number, got [1.0, 1.0" in message and "..." in message


def test_a_byte_order_mark_is_not_an_error(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + PENDULUM.read_bytes())
    assert read_scene(path).name == read_scene(PENDULUM).name


def test_a_list_with_a_wrong_entry_is_reported_as_a_list(tmp_path):
    text = PENDULUM.read_text().replace("position = [0.5, 0.0, 0.0]",
                                        'position = [0.5, "0", 0.0]')
    assert text != PENDULUM.read_text()
    message = _error(read_scene, tmp_path / "p.toml", text)
    assert "position): must be a list of 3 numbers, got [0.5, '0', 0.0]" in message


URDF = FIXTURE.joinpath("model.urdf").read_text()


@pytest.mark.parametrize("change, message", [
    (('<mass value="0.7680249867939197"/>', '<mass value="-2"/>'),
     '<link name="l0"> (PATH): <mass> value="-2" must not be negative'),
    (('<child link="l1"/>', '<child link="l0"/>'),
     '<joint name="j1"> (PATH): joins link "l0" to itself'),
    (('ixx="0.022563561519912536"', 'ixx="0x10"'),
     '<link name="l0"> (PATH): <inertia> ixx="0x10" must be a finite number'),
    (('izz="0.06359831753429228"', 'izz="1"'),
     "body 'l0' (spatial) (PATH, <link name=\"l0\">.inertia): is not physical"),
    (('<axis xyz="-1.5596821710456612 0.40679667184628404 -0.6906239781016781"/>',
      '<axis xyz="1e308 1e308 1e308"/>'), None),  # finite: normalised without overflow
], ids=["negative-mass", "self-joint", "hex-number", "triangle-inequality", "huge-axis"])
def test_urdf_problems_name_the_element(tmp_path, change, message):
    path = tmp_path / "bad.urdf"
    text = URDF.replace(*change)
    assert text != URDF
    if message is None:
        path.write_text(text)
        axis = read_urdf(path).joints["j0"].axis
        assert np.allclose(axis, np.ones(3) / np.sqrt(3))
    else:
        assert message.replace("PATH", str(path)) in _error(read_urdf, path, text)


def test_motion_rates_without_a_spline_are_an_error_not_a_crash(tmp_path):
    """qd given without qdd, at times too close together for a spline through the rates: was
    a ValueError from the spline."""
    path = tmp_path / "motion.csv"
    path.write_text("t,j0,j1,j2,qd:j0,qd:j1,qd:j2\n" + "".join(
        f"{t},0,0,0,{k},0,0\n" for k, t in enumerate(("0", "1e-320", "2e-320", "1"))))
    with pytest.raises(ModelError) as info:
        apply_motion(read_urdf(FIXTURE / "model.urdf"), read_motion(path))
    assert "motion column 'j0'" in str(info.value) and "give 'qdd:j0'" in str(info.value)


def test_an_inertia_too_small_for_floating_point_is_a_problem_not_a_crash(tmp_path):
    """Positive in the file, zero in SI: was a LinAlgError inverting the mass matrix."""
    text = ('[scene]\nlength_unit = "um"\n[[body]]\nname = "speck"\nmass = 1.0\n'
            'inertia = [1e-320, 1e-320, 1e-320]\n')
    message = _error(read_scene, tmp_path / "speck.toml", text)
    assert "body 'speck' (spatial)" in message and "too small to compute with" in message


def test_assembly_errors_name_the_file(tmp_path):
    """A loop that cannot close is found by the assembly, after reading: its message names the
    file too."""
    text = (ROOT / "data" / "scenes" / "andrews.toml").read_text()
    path = tmp_path / "torn.toml"
    path.write_text(text.replace('child = "rod4"', 'child = "rod2"', 1))
    model = hx.assemble(read_scene(path))
    with pytest.raises(hx.AssemblyError) as info:
        data = model.create_data()
        hx.consistent_state(model, data)
    assert str(path) in str(info.value) and "cannot assemble" in str(info.value)


# ------------------------------------------------------------------ the command line


def assert_clean_failure(result: subprocess.CompletedProcess, name: str) -> None:
    """Non-zero exit, nothing on stdout, one message naming the file: a head line and at most
    one line per problem, and no traceback."""
    assert result.returncode not in (0, 3), result.stderr
    assert "Traceback" not in result.stderr and "internal error" not in result.stderr
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert lines[0].startswith("hexapod: error:") and name in lines[0], result.stderr
    assert all(line.startswith("  - ") for line in lines[1:]), result.stderr


def test_command_line_on_malformed_files(tmp_path):
    (tmp_path / "bad.toml").write_text("[[body]]\nname = \"b\"\nmass = nan\n")
    (tmp_path / "bad.urdf").write_text(URDF.replace('<child link="l1"/>', '<child link="no"/>'))
    (tmp_path / "bad.csv").write_text("t,j0,j1,j2\n0,0,0,0\n1,nan,0,0\n2,0,0,0\n3,0,0,0\n")
    for args, name in ((("validate", "bad.toml"), "bad.toml"),
                       (("info", "bad.urdf"), "bad.urdf"),
                       (("inverse", str(FIXTURE / "model.urdf"), "--motion", "bad.csv",
                         "--out", "X.csv"), "bad.csv")):
        assert_clean_failure(commands.in_process(*args, cwd=tmp_path), name)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv", "bad.toml", "bad.urdf"]


# ------------------------------------------------------------------ no partial output


def run_main(argv: list[str], capsys) -> tuple[int, str]:
    status = cli.main(argv)
    return status, capsys.readouterr().err


def names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def _fail_on_second_file(monkeypatch, error: BaseException) -> None:
    """Make the directory writer fail once it has written one file of the directory."""
    sync = fileio._sync
    written = []

    def failing(stream):
        written.append(stream.name)
        if len(written) == 2:
            raise error
        sync(stream)

    monkeypatch.setattr(fileio, "_sync", failing)


SIMULATE = ["simulate", str(PENDULUM), "--method", "rk4-baumgarte", "--t-end", "0.01",
            "--step", "0.001"]


@pytest.mark.parametrize("error, status", [(KeyboardInterrupt(), 130),
                                           (InputFileError("disk full"), 1)],
                         ids=["interrupted", "failed"])
def test_a_directory_interrupted_while_written_is_not_left(tmp_path, capsys, monkeypatch,
                                                             error, status):
    _fail_on_second_file(monkeypatch, error)
    code, stderr = run_main(SIMULATE + ["--out", str(tmp_path / "run")], capsys)
    assert code == status and stderr.startswith("hexapod: ")
    assert names(tmp_path) == []  # neither the directory nor its staging copy


def _fail_on_second_rename(monkeypatch, error: BaseException) -> None:
    """Make the directory writer fail between moving the earlier output away and moving the
    new one in (the two-rename swap of systems that cannot exchange two names at once)."""
    monkeypatch.setattr(fileio, "_exchange", lambda first, second: False)
    replace = os.replace
    calls = []

    def failing(source, target):
        calls.append(target)
        if len(calls) == 2:
            raise error
        replace(source, target)

    monkeypatch.setattr(fileio.os, "replace", failing)


@pytest.mark.parametrize("fail", [_fail_on_second_file, _fail_on_second_rename],
                         ids=["while-writing", "while-renaming"])
def test_an_earlier_output_survives_an_interrupted_rewrite(tmp_path, capsys, monkeypatch,
                                                           fail):
    out = tmp_path / "run"
    assert run_main(SIMULATE + ["--out", str(out)], capsys)[0] == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    fail(monkeypatch, KeyboardInterrupt())
    assert run_main(SIMULATE + ["--t-end", "0.02", "--out", str(out)], capsys)[0] == 130
    assert names(tmp_path) == ["run"]
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_a_file_interrupted_while_written_is_not_left(tmp_path, capsys, monkeypatch):
    def interrupted(stream):
        stream.write("half a line")
        raise KeyboardInterrupt

    monkeypatch.setattr(fileio, "_sync", interrupted)
    code, stderr = run_main(["inverse", str(FIXTURE / "model.urdf"), "--motion",
                             str(FIXTURE / "motion.csv"), "--out", str(tmp_path / "X.csv")],
                            capsys)
    assert (code, stderr.strip()) == (130, "hexapod: interrupted")
    assert names(tmp_path) == []


def test_an_error_after_reading_writes_nothing(tmp_path, capsys, monkeypatch):
    def failing(*args, **kwargs):
        raise hx.SingularSystemError("no solution")

    monkeypatch.setattr("hexapod.algorithms.inverse.inverse_dynamics", failing)
    code, _ = run_main(["inverse", str(FIXTURE / "model.urdf"), "--motion",
                        str(FIXTURE / "motion.csv"), "--out", str(tmp_path / "X.csv")], capsys)
    assert code == 1 and names(tmp_path) == []


def _time_reached(progress: str) -> float:
    """The time (s) the last progress line of ``hexapod simulate`` gives, 0 before the first."""
    times = re.findall(r"t = ([-+.0-9eE]+) s", progress)
    return float(times[-1]) if times else 0.0


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_killed_simulation_writes_what_it_computed(tmp_path, signum):
    """A long run stopped by Ctrl-C or kill: the states computed so far are written, marked
    interrupted in stats.json, and the status is the signal's (130, 143)."""
    # a shell that starts a job in the background (nohup ... &) makes it ignore SIGINT, and
    # Python then never turns SIGINT into KeyboardInterrupt: give the run the default action
    with commands.Running("-m", "hexapod", "simulate", str(PENDULUM), "--method",
                          "rk4-baumgarte", "--step", "1e-4", "--t-end", "50", "--every", "100",
                          "--out", "run", cwd=tmp_path, default_sigint=True,
                          HEXAPOD_PROGRESS="1") as process:
        # well into the time loop, as its progress line says: states saved past t = 0
        process.wait_until(lambda err: _time_reached(err) >= 0.05, "at t = 0.05 s")
        process.send_signal(signum)
        status, _, stderr = process.finish()
    assert "Traceback" not in stderr
    assert status == 128 + signum, stderr
    stats = json.loads((tmp_path / "run" / "stats.json").read_text())
    assert stats["status"] == "interrupted" and 0 < stats["t_reached"] < 50, stats
    assert "interrupted" in stderr.strip().splitlines()[-1]
    assert names(tmp_path) == ["run"]


def test_the_command_line_writes_only_through_the_atomic_helpers():
    """Outputs go through hexapod._support.files (a temporary file or directory renamed into place);
    nothing else in the package opens a file for writing."""
    writes = re.compile(r"\.(write_text|write_bytes|tofile)\(|savetxt\(|\bopen\([^)]*['\"][wax]")
    offenders = [f"{path.relative_to(ROOT)}: {match.group(0)}"
                 for path in sorted((ROOT / "hexapod").rglob("*.py")) if path.name != "files.py"
                 for match in writes.finditer(path.read_text())]
    assert offenders == []
