"""``hexapod simulate``: its files, their numbers against independent checks, its failures (run
in this process; its help and usage errors in a process of its own)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from commands import hexapod as run_cli
from commands import in_process

import hexapod as hx
from hexapod.algorithms.balance import body_balance
from hexapod.benchmarks import ClosedLoopPendulum
from hexapod.scene.reader import read_scene
from hexapod.scene.writer import scene_text
from hexapod.simulation.registry import INTEGRATORS

ROOT = Path(__file__).resolve().parents[1]
SEED002 = ROOT / "data" / "scenes" / "closed_pendulum_seed002.toml"
FILES = {"results.csv", "results.npz", "units.json", "stats.json"}
STATISTICS = {"scene", "method", "options", "status", "message", "reason", "t_start", "t_end",
              "t_reached", "saved",
              "steps", "rejected", "rhs", "jacobians", "factorisations", "newton", "crossings",
              "wall_time_s", "cpu_time_s", "max_position_violation", "max_velocity_violation_per_s",
              "energy_conserved", "energy_drift"}
UNREACHABLE = """\
# A particle on a 1 m rod whose x is driven at 2 m/s: out of reach from t = 0.5 s.
[scene]
name = "unreachable"
dimension = 2

[[body]]
name = "p"
type = "particle"
mass = 1.0
position = [0.0, -1.0]

[[joint]]
name = "rod"
type = "distance"
parent = "ground"
child = "p"
parent_frame = [0.0, 0.0]

[[driver]]
name = "push"
body = "p"
coordinate = "x"
law = { type = "polynomial", coefficients = [0.0, 2.0] }
"""


def read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    lines = path.read_text().splitlines()
    return lines[0].split(","), np.array([[float(x) for x in line.split(",")]
                                         for line in lines[1:]])


def strict_json(text: str):
    def reject(constant):
        raise ValueError(f"non-standard JSON constant {constant}")
    return json.loads(text, parse_constant=reject)


@pytest.fixture(scope="module")
def seed002_run(tmp_path_factory):
    """The closed pendulum of Richard, Anderson and Andrews over 1 s with the joint wrenches, from
    an empty directory."""
    cwd = tmp_path_factory.mktemp("simulate")
    result = in_process("simulate", str(SEED002), "--t-end", "1", "--rtol", "1e-9", "--atol",
                     "1e-11", "--forces", "--out", "run", cwd=cwd)
    return cwd, result


def test_simulate_writes_its_files_and_says_what_it_did(seed002_run):
    cwd, result = seed002_run
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert {p.name for p in (cwd / "run").iterdir()} == FILES
    assert [p.name for p in cwd.iterdir()] == ["run"]  # no temporary directory left behind
    assert "wrote run/" in result.stdout and "dop853-projection over 1 s" in result.stdout
    stats = strict_json((cwd / "run" / "stats.json").read_text())
    assert set(stats) == STATISTICS
    assert stats["status"] == "finished" and stats["t_end"] == 1.0
    assert stats["steps"] > 0 and stats["rhs"] >= 6 * stats["steps"]
    assert stats["max_position_violation"] < 1e-14 and stats["energy_drift"] < 1e-6


def test_simulate_csv_follows_the_lagrange_equation_and_matches_the_npz(seed002_run):
    """The documented columns; positions against the one-degree-of-freedom equation of Richard,
    Anderson and Andrews; the binary file holds the same numbers."""
    cwd, _ = seed002_run
    header, table = read_csv(cwd / "run" / "results.csv")
    model = hx.assemble(read_scene(SEED002))
    assert header[:5] == ["t", "q:m1.x", "q:m1.y", "q:m2.x", "q:m2.y"]
    assert header[5:9] == ["v:m1.vx", "v:m1.vy", "v:m2.vx", "v:m2.vy"]
    assert header[13:16] == ["lambda:rod1/length", "lambda:rod2/length",
                             "lambda:coupler/length"]
    assert header[16:23] == ["Fx:rod1", "Fy:rod1", "Fz:rod1", "Tx:rod1", "Ty:rod1", "Tz:rod1",
                             "Fx:rod2"]
    assert len(header) == 1 + 2 * model.n_q + model.n_v + model.n_c + 6 * len(model.joints)
    t = table[:, 0]
    p1, p2, _ = ClosedLoopPendulum().solve(1.0)(t)
    assert np.abs(table[:, 1:3] - p1).max() < 1e-6 and np.abs(table[:, 3:5] - p2).max() < 1e-6
    with np.load(cwd / "run" / "results.npz") as saved:
        assert np.array_equal(saved["t"], t) and np.array_equal(saved["q"], table[:, 1:5])
        assert np.array_equal(saved["lam"], table[:, 13:16])
        assert list(saved["rows"]) == ["rod1/length", "rod2/length", "coupler/length"]
        assert strict_json(str(saved["statistics"]))["method"] == "dop853-projection"


def test_simulate_forces_balance_every_body(seed002_run):
    """Each particle's equation of motion closes under the written joint wrenches and gravity
    (an independent check of the liaison-force columns and their convention)."""
    cwd, _ = seed002_run
    model = hx.assemble(read_scene(SEED002))
    with np.load(cwd / "run" / "results.npz") as saved:
        balance = body_balance(model, saved["t"], saved["q"], saved["v"], saved["v_dot"],
                               saved["force"], saved["torque"])
    assert balance.relative().max() < 1e-10


def test_scene_asking_for_forces_gets_them(tmp_path):
    scene = tmp_path / "scene.toml"
    text = SEED002.read_text().replace('length_unit = "dm"', 'length_unit = "dm"\n'
                                       "report_forces = true")
    scene.write_text(text)
    assert read_scene(scene).report_forces
    (tmp_path / "again.toml").write_text(scene_text(read_scene(scene)))  # kept by the writer
    assert read_scene(tmp_path / "again.toml").report_forces
    assert not read_scene(SEED002).report_forces
    result = in_process("simulate", str(scene), "--t-end", "0.05", "--out", "run", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    header, _ = read_csv(tmp_path / "run" / "results.csv")
    assert "Fx:coupler" in header


@pytest.mark.parametrize("method", INTEGRATORS)
def test_every_method_runs_from_the_command_line(tmp_path, method):
    result = in_process("simulate", str(SEED002), "--method", method, "--t-end", "0.1", "--step",
                     "1e-3", "--every", "10", "--out", "run", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    stats = strict_json((tmp_path / "run" / "stats.json").read_text())
    assert stats["method"] == method and stats["status"] == "finished"
    if not INTEGRATORS[method].adaptive:  # 100 steps, saved at 0, 10, ..., 100
        assert stats["steps"] == 100 and stats["saved"] == 11


def test_help_lists_every_method_with_its_order_and_index(tmp_path):
    result = run_cli("simulate", "--help", cwd=tmp_path)
    text = " ".join(result.stdout.split())
    for name, cls in INTEGRATORS.items():
        assert f"{name}: order {cls.order}, index {cls.index}" in text


def test_a_failed_run_writes_the_states_up_to_it_and_says_why(tmp_path):
    (tmp_path / "unreachable.toml").write_text(UNREACHABLE)
    result = in_process("simulate", "unreachable.toml", "--out", "run", cwd=tmp_path)
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    errors = result.stderr.strip().splitlines()
    assert len(errors) == 1 and errors[0].startswith("hexapod: error: dop853-projection failed")
    stats = strict_json((tmp_path / "run" / "stats.json").read_text())
    # the reach is exhausted at 0.5 s; a step may end past it by the assembly tolerance
    assert stats["status"] == "failed" and 0.49 < stats["t_reached"] <= 0.5 + 1e-9
    _, table = read_csv(tmp_path / "run" / "results.csv")
    assert table[-1, 0] == stats["t_reached"] and np.all(np.isfinite(table))


def test_bad_options_and_occupied_output_are_one_clear_error(tmp_path):
    result = run_cli("simulate", str(SEED002), "--method", "euler", cwd=tmp_path)
    assert result.returncode == 2 and "invalid choice: 'euler'" in result.stderr
    result = run_cli("simulate", str(SEED002), "--rtol", "-1", cwd=tmp_path)
    assert result.returncode == 2 and "must be positive" in result.stderr
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "notes.txt").write_text("keep me")
    result = in_process("simulate", str(SEED002), "--t-end", "0.01", "--out", "busy",
                        cwd=tmp_path)
    assert result.returncode == 1 and "holds other files (notes.txt)" in result.stderr
    assert [p.name for p in (tmp_path / "busy").iterdir()] == ["notes.txt"]


def test_help_names_the_short_names_and_the_output_options(tmp_path):
    from hexapod.simulation.methods import ALIASES

    result = run_cli("simulate", "--help", cwd=tmp_path)
    text = " ".join(result.stdout.split())
    for alias, name in ALIASES.items():
        assert f"(short name {alias})" in text and name in text
    for option in ("--t-eval", "--dt-out", "--atol-position", "--atol-angle", "--atol-velocity",
                   "--atol-angular-velocity"):
        assert option in text


def test_short_name_runs_and_is_recorded_by_its_full_name(tmp_path):
    result = in_process("simulate", str(SEED002), "--method", "radau", "--t-end", "0.05",
                     "--dt-out", "0.01", "--out", "run", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "radau5-ggl over 0.05 s" in result.stdout
    stats = strict_json((tmp_path / "run" / "stats.json").read_text())
    assert stats["method"] == "radau5-ggl" and stats["saved"] == 6
    _, table = read_csv(tmp_path / "run" / "results.csv")
    assert np.allclose(table[:, 0], np.linspace(0.0, 0.05, 6), rtol=0, atol=1e-15)
