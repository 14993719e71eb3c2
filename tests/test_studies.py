"""The work-precision study: its references, its error measures and `hexapod bench`."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from hexapod.benchmarks.work_precision import (
    Run,
    andrews_angles,
    andrews_check,
    build_problems,
    cpu_to_reach,
    run_method,
)
from hexapod.cli import main
from hexapod.scene.builtin import load_scene
from hexapod.simulation.loop import simulate

DATA = Path(__file__).resolve().parents[1] / "data"


def test_andrews_forces_at_joint_e_equal_the_published_multipliers():
    # the published multipliers are correct to about 1e-6 (data/benchmarks/andrews.json); at
    # t = 0 the state is the published one and the agreement is to round-off
    _, numbers = andrews_check(DATA, rtol=1e-10)
    assert numbers["forces_t0"] < 1e-12
    assert numbers["forces_t0.03"] < 1e-6
    # our positions at 0.03 s against the published ones, correct to about 1e-10
    assert numbers["positions"] < 1e-9


def test_andrews_angles_of_the_initial_pose_are_the_published_ones():
    (problem,) = build_problems(["andrews"], DATA)
    benchmark = json.loads((DATA / "benchmarks" / "andrews.json").read_text())
    angles = andrews_angles(problem.model, problem.model.q0)[0]
    assert np.allclose(angles, benchmark["initial"]["y"][:7], rtol=0, atol=1e-14)


def test_dop853_reaches_1e9_on_andrews():
    (problem,) = build_problems(["andrews"], DATA)
    result = simulate(problem.model, problem.t_end, method="dop853-projection", rtol=1e-9,
                      atol=1e-9, every=10**9)
    assert problem.error(result) < 1e-9


def test_the_engine_follows_the_recursive_model_of_the_falling_leg():
    # two formulations (absolute coordinates with multipliers; joint coordinates, recursive)
    # of the same free leg: at tight tolerance they agree far below the study's targets
    (problem,) = build_problems(["front-leg"], DATA, quick=True, leg=load_scene("front-leg"))
    result = simulate(problem.model, problem.t_end, method="dop853-projection", rtol=1e-11,
                      atol=1e-11 * problem.scale)
    assert result.success
    assert problem.error(result) < 1e-9
    # a coarse run is measurably worse: the measure can fail
    coarse = simulate(problem.model, problem.t_end, method="rk4-baumgarte",
                      step=problem.t_end / 10)
    assert problem.error(coarse) > 1e-8


def test_seed002_error_shrinks_with_the_tolerance():
    (problem,) = build_problems(["seed002"], DATA, quick=True)
    runs = run_method(problem, "dop853-projection", quick=True, budget=2.0)
    errors = [r.error for r in runs]
    assert errors[0] > 1e-5 and min(errors) < 1e-9


def _run(cpu, error):
    return Run("p", "m", "", "finished", cpu, 1, 1, error, 0.0, 0.0, None)


def test_cpu_to_reach_interpolates_log_log():
    # error = cpu^-4 exactly: the time to reach 1e-6 is 10^(6/4)
    runs = [_run(c, c**-4.0) for c in (1.0, 10.0, 100.0)]
    assert cpu_to_reach(runs, 1e-6) == pytest.approx(10**1.5, rel=1e-12)
    assert cpu_to_reach(runs, 1e-9) is None  # never reached
    assert cpu_to_reach(runs, 10.0) == 1.0  # reached by the cheapest run
    assert cpu_to_reach([_run(1.0, np.inf)], 1e-3) is None  # failed runs count for nothing


def test_bench_writes_its_table_and_figures(tmp_path, capsys):
    out = tmp_path / "wp"
    code = main(["bench", "--quick", "--problems", "seed002", "--methods", "dop853-projection",
                 "--budget", "0.2", "--data", str(DATA), "--out", str(out)])
    assert code == 0
    names = {p.name for p in out.iterdir()}
    assert names == {"work_precision.md", "runs.csv", "units.json", "work_precision.png",
                     "drift_seed002.png"}
    assert "| seed002 | dop853-projection |" in (out / "work_precision.md").read_text()


def test_bench_outside_a_checkout_is_a_clear_error(tmp_path, capsys):
    assert main(["bench", "--data", str(tmp_path), "--out", str(tmp_path / "x")]) == 1
    assert "not the project's data directory" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
