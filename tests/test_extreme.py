"""The extreme-case suite, reduced: the default method through every case against its
independent reference, the redundancy policy along Bricard's run, the outcome of methods that
must break, and the report of ``hexapod check``."""

from __future__ import annotations

import json
from functools import partial

import numpy as np
import pytest

import hexapod as hx
from hexapod.benchmarks import four_bar_dead_points, n_four_bar
from hexapod.benchmarks.check import (
    ACCURACY,
    build_suite,
    recommend,
    report_files,
    run_case,
    run_suite,
    scene_case,
)
from hexapod.cli import main
from hexapod.simulation.registry import DEFAULT_METHOD

CASES = {case.name: case for case in build_suite(quick=True)}


@pytest.mark.parametrize("name", list(CASES))
def test_default_method_runs_every_case_to_the_end_accurately(name):
    """Stiff, singular, redundant, light, long and coarse: the default method finishes and
    stays within ACCURACY of the independent reference (and the energy, relative to the largest
    kinetic energy), constraints held to round-off."""
    run = run_case(CASES[name], DEFAULT_METHOD, budget=120.0)
    assert run.status == "finished", run.reason
    assert run.error is not None and run.error < ACCURACY
    assert run.position_drift < 1e-9
    if run.energy_error is not None:
        assert run.energy_error < ACCURACY


def test_n_four_bar_stays_on_its_branch_through_the_singular_pose():
    """All cranks pass horizontal together (the pose where the DOF jumps from 1 to 11): the
    run follows the one-DOF reference of the parallelogram chain and keeps its energy."""
    case = CASES["n-four-bar-10"]
    result = hx.simulate(case.model, case.t_end, rtol=1e-8, atol=1e-10)
    assert result.success
    assert case.error(result) < 1e-6
    assert result.energy_drift < 1e-6


@pytest.mark.slow  # a tolerance study over 20 s; ten windows are crossed by default (above)
@pytest.mark.parametrize("method, tolerances", [("dopri5-projection", (1e-8, 1e-9)),
                                                 ("dop853-projection", (1e-9,))])
def test_forty_windows_cross_all_their_flat_poses_more_accurately_at_tighter_tolerances(
        method, tolerances):
    """IFToMM A02 as the benchmark library has it: 40 windows, whose 40 singular values
    collapse at once, twenty times in 20 s, spread over a factor 26 by the windows' places in
    the chain. Each pose used to cost energy that did not fall with the tolerance: one
    crossing in twenty lost 1e-2 J of 620 J when crossings went on with growing steps, and
    with steps as long as the motion's around the pose, each still lost about 5e-8 J (DOP853
    ended 1.2e-8 off at rtol 1e-10, no better than at 1e-9). Crossings now begin at the first
    rejection near the pose, step over it (never ending at it), take steps short enough for
    the forces they leave out (Integrator._crossing_step_limit) and end as soon as the state
    is as far past it: the error against the exact motion falls with the tolerance (DOPRI5:
    1.3e-7, 8.3e-9, 5.2e-10 at rtol 1e-8, 1e-9, 1e-10; DOP853 at 1e-9: 1.3e-9; another branch
    is an error of order 1). The whole table:
    ``python3 scripts/studies/singular_crossings.py --rtol 1e-4 1e-6 1e-8 1e-9 1e-10 --cases
    n-four-bar-40``."""
    case = n_four_bar(40, t_end=20.0)
    model = hx.assemble(case.scene)
    errors = {}
    for rtol in tolerances:
        result = hx.simulate(model, case.t_end, method=method, rtol=rtol, atol=rtol / 100)
        assert result.success, result.message
        assert result.counters.crossings >= 5
        errors[rtol] = case.error(model, result.t, result.q)
    assert errors.get(1e-8, 0.0) < 1e-6
    assert errors[1e-9] < min(3e-8, errors.get(1e-8, np.inf) / 5)
    if method == "dop853-projection":  # 7.5e-9 before the crossings' steps were limited
        assert errors[1e-9] < 5e-9


@pytest.mark.parametrize("build, t_end, tol", [
    (n_four_bar, 1.0, 1e-8),                                # flat at t = 0.720 s
    (partial(four_bar_dead_points, driven=True), 1.0, 1e-8),  # change points at 0.25, 0.75 s
])
def test_tight_tolerances_cross_singular_poses(build, t_end, tol):
    """At rtol 1e-10 the accelerations in the nearly dependent directions are solved less
    accurately than the error test asks (their error grows as 1/sigma^2): without crossing,
    the step fell to 7e-15 s at the N-four-bar's flat pose. The step crosses with those rows
    left out and projects back onto all of them: the run ends on the reference's branch."""
    case = build()
    model = hx.assemble(case.scene)
    result = hx.simulate(model, t_end, rtol=1e-10, atol=1e-12)
    assert result.success, result.message
    assert result.counters.crossings >= 1
    assert case.error(model, result.t, result.q) < tol
    if case.energy_conserved:
        assert result.energy_drift < 1e-6


def test_a_fixed_step_that_leaves_the_branch_at_a_change_point_fails_and_says_where():
    """RK4 at the check's step (2e-3 s) reaches the free anti-parallelogram's change point at
    0.822 s, where one step changes the velocities 4.4 times as much as the accelerations at its
    ends explain, and went on along the other branch to finish 0.54 off, reported finished.
    Now the run stops there and names the pose and the methods that cross it; before the pose
    every step stays within the bound (ratio 1.00 on this motion), and the state it reached is
    still the reference's."""
    case = four_bar_dead_points()
    model = hx.assemble(case.scene)
    result = hx.simulate(model, case.t_end, method="rk4", step=case.t_end / 1000)
    assert result.status == "failed"
    assert "left the motion's branch" in result.message
    assert "singular configuration" in result.message and "dopri5" in result.message
    assert 0.8 < result.t[-1] < 0.83
    assert case.error(model, result.t, result.q) < 1e-2


def test_bricard_names_its_redundant_row_and_keeps_unique_constraint_forces():
    """Grubler counts 0 DOF, the mechanism has 1: one row is redundant all along. The
    constraint forces -Phi_v^T lambda are unique (they balance M v_dot - Q); the multipliers
    follow the policy, which is the same at every saved state: the redundant row is named."""
    case = CASES["bricard"]
    model = case.model
    result = hx.simulate(model, 0.5, rtol=1e-8, atol=1e-10)
    assert result.success
    data = model.create_data()
    for k in range(0, result.t.size, max(1, result.t.size // 5)):
        q, v = result.q[k], result.v[k]
        v_dot = hx.forward_dynamics(model, data, float(result.t[k]), q, v)
        assert [model.rows[i].name for i in data.redundant_rows]
        balance = model.mass @ v_dot + data.Phi_v.T @ data.lam - data.Q
        assert np.abs(balance).max() < 1e-9 * max(1.0, np.abs(data.Q).max())
        assert np.allclose(data.lam, result.lam[k], rtol=1e-6, atol=1e-9)


def test_stiff_spring_breaks_the_explicit_fixed_step_and_not_the_implicit_methods():
    """1e9 N/m on 1 kg at h = 2e-5 s: the implicit, adaptive methods follow the oscillator;
    the fixed-step ones at that step are not accurate (RK4 loses phase, the index-3 methods
    damp or distort it). Over 25 periods of the 0.2 ms oscillation (the suite's case runs
    100): RK4's phase error grows with the periods, 0.66 of the amplitude over 100 and 0.20
    over 25, still 200 times ACCURACY; Radau and IDA stay near 3e-5 (9e-5 over 100), and Radau's
    run takes 2.4 s instead of 9.6."""
    from hexapod.benchmarks import stiff_slider
    from hexapod.benchmarks.check import _from_mechanism

    case = _from_mechanism(stiff_slider(1e9, t_end=0.005), 250)  # h = 2e-5 s, as the suite's
    suite = CASES[case.name]  # its fixed step: a thousandth of its 20 ms
    assert case.step == pytest.approx(suite.t_end / 1000, rel=1e-12) and suite.step is None
    runs = run_suite([case], ["rk4-baumgarte", "radau5-ggl", "idas-bdf"], budget=60.0)
    outcome = {r.method: r for r in runs}
    assert outcome["radau5-ggl"].accurate and outcome["idas-bdf"].accurate
    assert not outcome["rk4-baumgarte"].accurate
    assert recommend(runs).split()[0] in ("radau5-ggl", "idas-bdf")


def test_report_has_table_recommendation_and_figures(tmp_path):
    case = CASES["stretched-leg"]
    runs = run_suite([case], [DEFAULT_METHOD, "rk4-baumgarte"], budget=30.0)
    data = case.model.create_data()
    q, v = hx.consistent_state(case.model, data)
    from hexapod.simulation.diagnostics import diagnose

    diagnosis = diagnose(case.model, case.model.create_data(), 0.0, q, v)
    files = report_files([case], runs, {case.name: diagnosis}, [], "hexapod check")
    text = files["check.md"].decode()
    assert "## What to use" in text and "stretched-leg" in text
    assert text.count("| stretched-leg |") >= 3
    for figure in ("outcomes.png", "condition.png"):
        assert files[figure].startswith(b"\x89PNG")
    assert files["runs.csv"].decode().splitlines()[0].startswith("case,category,method")


def test_check_command_on_a_scene_writes_its_report(tmp_path, capsys):
    out = tmp_path / "check"
    code = main(["check", "data/scenes/pendulum.toml", "--t-end", "0.5", "--methods",
                 DEFAULT_METHOD, "rattle", "--out", str(out)])
    assert code == 0
    assert sorted(p.name for p in out.iterdir()) == [
        "check.md", "condition.png", "diagnostics.json", "outcomes.png", "runs.csv",
        "units.json"]
    units = json.loads((out / "units.json").read_text())  # the columns of runs.csv, in order
    header = (out / "runs.csv").read_text().splitlines()[0].split(",")
    assert list(units) == ["runs.csv"] and list(units["runs.csv"]) == header
    assert units["runs.csv"]["cpu_time"] == {"unit": "s", "quantity": "CPU time of the time loop"}
    printed = capsys.readouterr().out
    assert "largest stable step" in printed and "What to use" in printed


def test_a_scene_case_without_reference_is_judged_by_drift_and_energy():
    from hexapod.scene.reader import read_scene

    model = hx.assemble(read_scene("data/scenes/pendulum.toml"))
    good = run_case(scene_case("pendulum", model, 1.0), DEFAULT_METHOD)
    assert good.accurate and good.error is None and good.energy_error < ACCURACY
    coarse = scene_case("pendulum", model, 1.0)
    coarse.step = 0.25  # RATTLE at a quarter second: bounded, but far from the energy
    bad = run_case(coarse, "rattle")
    assert bad.status == "finished" and not bad.accurate


def test_where_no_run_is_accurate_the_adaptive_ones_retry_tighter():
    """Ten periods of a pendulum released 5 degrees from the top: at the suite's rtol 1e-6 the
    error grows past ACCURACY near the unstable top (measured 4.7e-3 with DOP853; 3.6e-4 from 8
    degrees); the retry at 1e-9 is accurate and the recommendation says at which setting."""
    import hexapod.benchmarks as m
    from hexapod.benchmarks.check import RETRY_TIGHTER, _from_mechanism

    case = _from_mechanism(m.large_step_pendulum(3.05), 100)
    runs = run_suite([case], ["dop853-projection"], budget=60.0)
    first, retry = runs
    assert not first.accurate and first.tighter == 1.0
    assert retry.tighter == RETRY_TIGHTER and retry.accurate
    assert recommend(runs).startswith(f"dop853-projection at {retry.setting}")
