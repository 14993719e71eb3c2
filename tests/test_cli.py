"""The ``hexapod`` command: run as ``python -m hexapod.cli`` in a subprocess where the test is
about the process (its help, usage errors and version, its imports, its environment, the console
script), by its entry function in this process where it is about what a command does."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import commands
import pytest

import hexapod
from hexapod.scene.builtin import DEFAULT_SCENE, builtin_scenes
from hexapod.scene.reader import read_scene

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "data" / "scenes"
MALFORMED = Path(__file__).resolve().parent / "data" / "malformed_scene.toml"

SUBCOMMANDS = ("dynamics", "info", "inverse", "report", "sensitivity", "optimize", "simulate",
               "sweep", "check", "export", "bench", "validate", "scenes", "cache")
#: What ``--help`` must not load (NumPy: the command line limits the BLAS threads before it).
HEAVY = ("numpy", "casadi", "scipy")
REPORT_KEYS = {"scene", "t", "dimension", "counts", "dof", "dof_with_drivers", "redundant_rows",
               "state", "joints", "driver_efforts", "accelerations", "multipliers"}
STATE_KEYS = {"t", "max_abs_phi", "condition_number", "sigma_min", "characteristic_length_m"}


def hexapod_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    """Run ``python -m hexapod.cli ARGS`` from ``cwd`` (so no file there shadows a scene name)."""
    return commands.python("-m", "hexapod.cli", *args, cwd=cwd)


def hexapod_here(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    """Run ``hexapod ARGS`` from ``cwd`` in this process (see ``commands.in_process``)."""
    return commands.in_process(*args, cwd=cwd)


def assert_no_traceback(result: subprocess.CompletedProcess) -> None:
    assert "Traceback" not in result.stdout + result.stderr, result.stderr


def assert_one_error_line(result: subprocess.CompletedProcess) -> str:
    """A failure: non-zero exit, nothing on stdout, one ``hexapod: error:`` line on stderr."""
    assert result.returncode != 0
    assert_no_traceback(result)
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("hexapod: error: "), result.stderr
    return lines[0]


def strict_json(text: str):
    """Parse JSON as the standard defines it (no NaN or Infinity)."""
    def reject(constant):
        raise ValueError(f"non-standard JSON constant {constant}")
    return json.loads(text, parse_constant=reject)


# ------------------------------------------------------------------ help

def test_help_lists_the_subcommands(tmp_path):
    result = hexapod_cli("--help", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("usage: hexapod")
    for name in SUBCOMMANDS:
        assert name in result.stdout


@pytest.mark.parametrize("name", SUBCOMMANDS)
def test_subcommand_help(tmp_path, name):
    result = hexapod_cli(name, "--help", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"usage: hexapod {name}")
    assert result.stderr == ""


def test_no_subcommand_is_a_usage_error(tmp_path):
    result = hexapod_cli(cwd=tmp_path)
    assert result.returncode == 2
    assert "usage: hexapod" in result.stderr
    assert_no_traceback(result)


def test_unknown_subcommand_is_a_usage_error(tmp_path):
    result = hexapod_cli("fly", cwd=tmp_path)
    assert result.returncode == 2
    assert "invalid choice" in result.stderr
    assert_no_traceback(result)


def test_version(tmp_path):
    result = hexapod_cli("--version", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout == f"hexapod {hexapod.__version__}\n" == "hexapod 0.2.0\n"


def imported(*args: str, cwd: Path) -> set[str]:
    """The top-level packages ``python -X importtime ARGS`` imports (every import is listed)."""
    result = commands.python("-X", "importtime", *args, cwd=cwd)
    assert result.returncode == 0, result.stderr
    return {line.rpartition("|")[2].strip().split(".")[0] for line in result.stderr.splitlines()
            if line.startswith("import time:")}


@pytest.mark.parametrize("args", [("--help",), ("--version",), ("scenes",)]
                         + [(name, "--help") for name in SUBCOMMANDS], ids=" ".join)
def test_help_loads_no_heavy_library(tmp_path, args):
    loaded = imported("-m", "hexapod", *args, cwd=tmp_path)
    assert "hexapod" in loaded
    heavy = loaded & {*HEAVY, "distributed"}
    assert not heavy, f"hexapod {' '.join(args)} imports {heavy}"


def test_the_import_check_sees_a_heavy_import(tmp_path):
    """The check above can fail: the integrator registry loads CasADi, SciPy and NumPy."""
    loaded = imported("-c", "import hexapod.simulation.registry", cwd=tmp_path)
    assert set(HEAVY) <= loaded


def test_the_command_line_sets_one_blas_thread_before_numpy(tmp_path):
    code = ("import os, sys\n"
            "from hexapod.cli import main\n"
            "assert 'numpy' not in sys.modules\n"
            "assert main(['validate', sys.argv[1]]) == 0 and 'numpy' in sys.modules\n"
            "print(os.environ['OPENBLAS_NUM_THREADS'])\n")
    for given, expected in ((None, "1"), ("3", "3")):
        result = commands.python("-c", code, str(SCENES / "pendulum.toml"), cwd=tmp_path,
                                 OPENBLAS_NUM_THREADS=given)
        assert result.returncode == 0, result.stderr
        assert result.stdout.splitlines()[-1] == expected


def test_console_script_if_installed(tmp_path):
    script = Path(sys.executable).with_name("hexapod")
    if not script.exists():
        pytest.skip("no hexapod console script next to the interpreter")
    result = commands.run([str(script), "--help"], cwd=tmp_path)
    assert result.returncode == 0 and "dynamics" in result.stdout


# ------------------------------------------------------------------ scenes

def test_scenes_lists_each_scene_with_what_it_is(tmp_path):
    result = hexapod_here("scenes", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    scenes = builtin_scenes()
    assert [line.split(":")[0].removesuffix(" (default)") for line in lines] == sorted(scenes)
    assert f"{DEFAULT_SCENE} (default): " in result.stdout
    for line, name in zip(lines, sorted(scenes), strict=True):
        described = line.partition(": ")[2]
        assert described and described != scenes[name].value, line  # not module:function
        assert "``" not in described and "Built-in" not in described, line
    standing = next(line for line in lines if line.startswith("hexapod-standing:"))
    assert standing == ("hexapod-standing: The robot standing still on its feet, every joint "
                        "held: redundant constraints.")


def test_scene_summary_reads_the_docstring_without_running_the_module(tmp_path, monkeypatch):
    from importlib.metadata import EntryPoint

    from hexapod.cli.scenes import builder_summary

    package = tmp_path / "fake_legs"
    package.mkdir()
    (package / "__init__.py").write_text("raise RuntimeError('imported')\n")
    (package / "build.py").write_text(
        "raise RuntimeError('imported')\n\n\n"
        "def quiet():\n    return None\n\n\n"
        "def walker():\n"
        '    """Built-in ``walker``: a leg with :func:`~x.law`, ``L1``.\n\n    More."""\n')
    monkeypatch.syspath_prepend(str(tmp_path))

    def summary(value: str, name: str = "walker") -> str:
        return builder_summary(name, EntryPoint(name, value, "hexapod.scenes"))

    assert summary("fake_legs.build:walker") == "A leg with x.law, L1."
    assert summary("fake_legs.build:walker", "other") == \
        "Built-in walker: a leg with x.law, L1."
    # no docstring, no such function, no such module: the builder's name
    for value in ("fake_legs.build:quiet", "fake_legs.build:missing", "no_such_pkg.m:f",
                  "fake_legs.nothing:f"):
        assert summary(value) == value
    assert "fake_legs" not in sys.modules


def test_scenes_name_prints_the_toml_and_writes_nothing(tmp_path):
    import tomllib

    printed = hexapod_here("scenes", DEFAULT_SCENE, cwd=tmp_path)
    assert printed.returncode == 0, printed.stderr
    assert list(tmp_path.iterdir()) == []
    assert tomllib.loads(printed.stdout)["scene"]["name"] == DEFAULT_SCENE
    written = hexapod_here("scenes", DEFAULT_SCENE, "--write", "copy.toml", cwd=tmp_path)
    assert written.returncode == 0 and written.stdout == "wrote copy.toml\n", written.stderr
    text = (tmp_path / "copy.toml").read_text()
    assert printed.stdout.splitlines()[0] == f"# Built-in scene '{DEFAULT_SCENE}', written by " \
        f"'hexapod scenes {DEFAULT_SCENE}'."
    assert printed.stdout.splitlines()[1:] == text.splitlines()[1:]


# ------------------------------------------------------------------ dynamics


@pytest.fixture(scope="module")
def default_joints() -> list[str]:
    scene = builtin_scenes()[DEFAULT_SCENE].load()()
    return list(scene.joints)


def test_dynamics_runs_the_default_scene(tmp_path, default_joints):
    result = hexapod_here("dynamics", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert_no_traceback(result)
    out = result.stdout
    assert f"scene '{DEFAULT_SCENE}'" in out
    assert ("joint wrenches: exerted by the parent on the child, about the joint origin, "
            "in the child's joint frame") in out
    lines = out.splitlines()
    (header,) = [line for line in lines if line.split()[:2] == ["joint", "type"]]
    assert header.split()[2:] == ["tau", "Fx", "Fy", "Fz", "|F|", "Tx", "Ty", "Tz"]
    table = lines[lines.index(header) + 1:]
    assert [row.split()[0] for row in table] == default_joints
    for row in table:
        numbers = [float(x) for x in row.split()[2:] if x != "-"]
        assert len(numbers) >= 7


def test_dynamics_json(tmp_path, default_joints):
    result = hexapod_here("dynamics", "--json", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    report = strict_json(result.stdout)
    assert set(report) == REPORT_KEYS and set(report["state"]) == STATE_KEYS
    assert report["scene"] == DEFAULT_SCENE and report["t"] == 0.0
    assert list(report["joints"]) == default_joints
    for wrench in report["joints"].values():
        assert {"Fx", "Fy", "Fz", "Tx", "Ty", "Tz"} <= set(wrench)
    assert report["counts"]["joints"] == len(default_joints)


#: example scenes with unilateral contacts: their forces are a contact scheme's, over time
CONTACT_SCENES = tuple(path.name for path in SCENES.glob("*.toml")
                       if 'type = "ground-contact"' in path.read_text())


@pytest.mark.parametrize("path", sorted(SCENES.glob("*.toml")), ids=lambda p: p.name)
def test_dynamics_json_on_the_example_files(tmp_path, path):
    result = hexapod_here("dynamics", str(path), "--json", "--t", "0.25", cwd=tmp_path)
    if path.name in CONTACT_SCENES:  # not an analysis at an instant: refused, and said why
        assert result.returncode == 1 and result.stdout == ""
        assert "unilateral contacts" in result.stderr and "moreau-jean" in result.stderr
        assert_no_traceback(result)
        return
    assert result.returncode == 0, result.stderr
    report = strict_json(result.stdout)
    assert set(report) == REPORT_KEYS
    assert report["t"] == 0.25
    assert list(report["joints"]) == list(read_scene(path).joints)
    if path.name == "four_bar_3d.toml":
        assert len(report["redundant_rows"]) == 3


def test_dynamics_json_is_standard_for_a_scene_without_constraints(tmp_path):
    """A free body has no constraint rows: its report must still be standard JSON."""
    scene = tmp_path / "free.toml"
    scene.write_text("[[body]]\nname = 'block'\nmass = 0.2\ninertia = [2e-5, 2e-5, 3e-5]\n")
    result = hexapod_here("dynamics", str(scene), "--json", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    strict_json(result.stdout)


# ------------------------------------------------------------------ validate

@pytest.mark.parametrize("path", sorted(SCENES.glob("*.toml")), ids=lambda p: p.name)
def test_validate_good_file(tmp_path, path):
    result = hexapod_here("validate", str(path), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "is valid" in result.stdout
    assert result.stderr == ""


def test_validate_malformed_file_prints_every_problem(tmp_path):
    with pytest.raises(hexapod.ModelError) as info:
        read_scene(MALFORMED)
    problems = info.value.problems
    assert len(problems) > 20
    result = hexapod_here("validate", str(MALFORMED), cwd=tmp_path)
    assert result.returncode != 0
    assert_no_traceback(result)
    assert result.stdout == ""
    assert result.stderr.startswith("hexapod: error: ")
    for problem in problems:
        assert str(problem) in result.stderr
    assert f"{len(problems)} problems" in result.stderr


def test_dynamics_on_the_malformed_file(tmp_path):
    result = hexapod_here("dynamics", str(MALFORMED), cwd=tmp_path)
    assert result.returncode != 0
    assert_no_traceback(result)
    assert "problems" in result.stderr


# ------------------------------------------------------------------ input errors

@pytest.mark.parametrize("command", ["validate", "dynamics"])
def test_missing_file(tmp_path, command):
    line = assert_one_error_line(hexapod_here(command, "no_such_scene.toml", cwd=tmp_path))
    assert "no_such_scene.toml: no such file" in line


@pytest.mark.parametrize("command", ["validate", "dynamics"])
def test_unknown_builtin_scene(tmp_path, command):
    line = assert_one_error_line(hexapod_here(command, "no-such-robot", cwd=tmp_path))
    assert "no-such-robot" in line and "built-in" in line and DEFAULT_SCENE in line


@pytest.mark.parametrize("command", ["validate", "dynamics"])
def test_toml_syntax_error(tmp_path, command):
    path = tmp_path / "broken.toml"
    path.write_text("[scene]\nname = 'broken'\n\n[[body]\nname = 'b'\n")
    line = assert_one_error_line(hexapod_here(command, str(path), cwd=tmp_path))
    assert str(path) in line and "not valid TOML" in line and "line 4" in line


def test_directory_instead_of_file(tmp_path):
    line = assert_one_error_line(hexapod_here("validate", str(tmp_path), cwd=tmp_path))
    assert "is a directory" in line


def test_scene_that_cannot_be_assembled(tmp_path):
    """Two welds hold one body at two places: valid as a description, but no configuration
    satisfies both."""
    path = tmp_path / "apart.toml"
    path.write_text("[[body]]\nname = 'a'\nmass = 1.0\ninertia = [1, 1, 1]\n"
                    "[[joint]]\nname = 'weld'\ntype = 'fixed'\nparent = 'ground'\nchild = 'a'\n"
                    "[[joint]]\nname = 'weld2'\ntype = 'fixed'\nparent = 'ground'\n"
                    "child = 'a'\nparent_frame = [0.0, 0.0, 1.0]\nchild_frame = [0.0, 0.0, 0.0]\n")
    assert hexapod_here("validate", str(path), cwd=tmp_path).returncode == 0
    line = assert_one_error_line(hexapod_here("dynamics", str(path), cwd=tmp_path))
    assert "cannot assemble" in line and "weld2/z" in line


def test_bad_time_option(tmp_path):
    result = hexapod_cli("dynamics", "--t", "soon", cwd=tmp_path)
    assert result.returncode == 2
    assert "--t" in result.stderr
    assert_no_traceback(result)


# ------------------------------------------------------------------ info

def test_info_on_a_redundant_mechanism_names_the_redundant_rows(tmp_path):
    result = hexapod_here("info", str(SCENES / "four_bar_3d.toml"), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "redundant rows: D/z, D/ax1, D/ax2" in result.stdout
    assert "-2 counted (Grubler-Kutzbach), 1 numerical" in result.stdout
    assert "loop closed by D" in result.stdout and "condition number" in result.stdout


def test_info_json_and_graph(tmp_path):
    result = hexapod_here("info", str(SCENES / "closed_pendulum_seed002.toml"), "--json",
                         "--graph", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    info = strict_json(result.stdout)
    assert {"bodies", "joints", "drivers", "forces", "model", "topology", "mobility",
            "initial_pose", "vector_network"} <= set(info)
    assert info["topology"]["independent_loops"] == 1
    assert info["mobility"]["numerical"] == info["mobility"]["counted"] == 1
    net = info["vector_network"]
    assert (len(net["vertices"]), len(net["edges"]), len(net["cutset"]),
            len(net["circuit"])) == (5, 9, 4, 5)
    assert net["orthogonal"] is True
    assert [b["coordinates"] for b in info["bodies"]] == [["m1.x", "m1.y"], ["m2.x", "m2.y"]]


def test_info_graph_prints_the_matrices(tmp_path):
    result = hexapod_here("info", str(SCENES / "seed002_figure2.toml"), "--graph", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "6 vertices, 8 edges, 5 cutsets, 3 circuits" in result.stdout
    for title in ("incidence matrix", "cutset matrix [U A]", "circuit matrix [B U]"):
        assert title in result.stdout


def test_info_on_a_malformed_file_is_one_clear_error(tmp_path):
    result = hexapod_here("info", str(MALFORMED), cwd=tmp_path)
    assert result.returncode != 0
    assert_no_traceback(result)
    assert result.stdout == ""
    assert result.stderr.startswith("hexapod: error: scene file")


def test_validate_counts_in_words(capsys):
    """One body, one joint: no "1 bodies"."""
    from hexapod.cli import main as cli_main

    assert cli_main(["validate", str(SCENES / "pendulum.toml")]) == 0
    assert "(1 body, 1 joint, 0 drivers, 0 force elements)" in capsys.readouterr().out


def test_progress_is_drawn_when_stderr_is_a_terminal(tmp_path, monkeypatch, capsys):
    """The progress lines (drawn only on a terminal, so no other test sees them) work."""
    from hexapod.cli import main as cli_main

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert cli_main(["report", "--out", str(tmp_path / "report"), "--samples", "11"]) == 0
    # the default scene is guided: its guides' kinematics, then its efforts, 11 samples each
    assert "inverse dynamics: 22/22 samples" in capsys.readouterr().err


def test_progress_is_drawn_where_hexapod_progress_asks(tmp_path, monkeypatch, capsys):
    """HEXAPOD_PROGRESS=1 draws the progress lines off a terminal too (into a log, for a program
    that watches the run: the signal tests wait for them); 0, they are not drawn."""
    from hexapod.cli import main as cli_main

    args = ["simulate", str(SCENES / "pendulum.toml"), "--t-end", "0.01", "--out",
            str(tmp_path / "run")]
    for setting, drawn in (("1", True), ("0", False)):
        monkeypatch.setenv("HEXAPOD_PROGRESS", setting)
        assert cli_main(args) == 0
        assert ("100 %  t = 0.01 s" in capsys.readouterr().err) == drawn


def test_a_signal_while_the_handlers_are_installed_ends_the_command_cleanly(monkeypatch,
                                                                           capsys):
    """A signal right after the command starts, between the installation of the SIGINT and
    the SIGTERM handlers (a race seen once in four full runs of the suite: a traceback and
    status -2), is remembered until the command can handle it: status 130 and one line. The
    signal is delivered as the interpreter does, by calling the handler just installed (a
    real signal is taken by any thread of a test worker, at a time of its own)."""
    import signal

    from hexapod.cli.entry import main

    install = signal.signal
    sent = []

    def racing(number, handler):
        previous = install(number, handler)
        if not sent:  # the first handler is in, the second not yet: the signal comes now
            sent.append(number)
            handler(signal.SIGINT, None)
        return previous

    monkeypatch.setattr(signal, "signal", racing)
    try:
        status = main(["--version"])
    except KeyboardInterrupt:
        pytest.fail("the signal escaped the command as a KeyboardInterrupt")
    finally:
        monkeypatch.setattr(signal, "signal", install)
    assert sent and status == 130
    assert capsys.readouterr().err.strip().count("\n") == 0


def test_an_interruption_an_import_wraps_in_another_error_ends_the_command_cleanly(
        monkeypatch, capsys):
    """SIGINT while Python creates a class during the command's imports reaches it as a
    RuntimeError ("Error calling __set_name__ ...") caused by the KeyboardInterrupt (seen once
    in a clean clone's run of the signal tests: a traceback and status 1): status 130 and one
    line, no traceback. Any other error of the imports is not taken for one."""
    from hexapod.cli import entry

    def wrapped():
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as interruption:
            raise RuntimeError("Error calling __set_name__ on 'cached_property' instance "
                               "'broadcast_address' in '_BaseNetwork'") from interruption

    monkeypatch.setattr(entry, "_load", wrapped)
    assert entry.main(["--version"]) == 130
    err = capsys.readouterr().err
    assert err.strip() == "hexapod: interrupted" and "Traceback" not in err

    def broken():
        raise RuntimeError("a bug")

    monkeypatch.setattr(entry, "_load", broken)
    with pytest.raises(RuntimeError, match="a bug"):
        entry.main(["--version"])


def test_an_interruption_in_a_finalizer_prints_no_traceback(monkeypatch):
    """A signal whose handler raises inside a callback or a finalizer (seen in importlib's
    module-lock callback during the imports: "Exception ignored in ... Traceback" on stderr,
    the command otherwise ending as interrupted) does not reach the unraisable-exception hook
    while the command's handlers are in; other exceptions there do, and the hook is put back
    after."""
    import gc
    import sys

    from hexapod._support import signals

    class Raising:
        def __init__(self, error):
            self.error = error

        def __del__(self):
            raise self.error

    seen = []
    monkeypatch.setattr(sys, "unraisablehook", seen.append)
    restore = signals.handle_signals()
    try:
        Raising(KeyboardInterrupt())
        gc.collect()
        assert seen == []
        Raising(ValueError("a finalizer's own bug"))
        gc.collect()
        assert [type(u.exc_value) for u in seen] == [ValueError]
    finally:
        restore()
    assert sys.unraisablehook == seen.append
