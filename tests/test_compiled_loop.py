"""The compiled time loop of DOPRI5 and DOP853 (hexapod.simulation.compiled_loop) against the
Python loop it replaces: the same steps and counters where the steps are decided alike, states
to the tolerance, constraint residuals at round-off; its handovers to Python (singular poses,
laws without a closed form); output times, ``every``, the limits, progress and interruptions
through its batches.

Most runs use CasADi's virtual machine (``loop="vm"``): the same Function as the C kernel, and
no compiler to wait for; one test compiles it and compares the two.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod._support.compiled import compiler
from hexapod.benchmarks import bricard, n_four_bar
from hexapod.scene.reader import read_scene
from hexapod.simulation.registry import get_integrator

from mechanisms import four_bar, random_tree

SCENES = Path(__file__).resolve().parents[1] / "data" / "scenes"
METHODS = ["dopri5-projection", "dop853-projection"]


def _cases():
    """name -> (model, duration, tolerance)."""
    return {
        "pendulum": (hx.assemble(read_scene(SCENES / "pendulum.toml")), 2.0, 1e-9),
        "seed002-closed-loop": (hx.assemble(read_scene(SCENES / "closed_pendulum_seed002.toml")),
                                1.0, 1e-9),
        "andrews": (hx.assemble(read_scene(SCENES / "andrews.toml")), 0.01, 1e-8),
        "spatial-chain": (hx.assemble(random_tree(3, 4, chain=True, driven=False)), 0.3, 1e-8),
        "bricard-redundant": (hx.assemble(bricard().scene), 0.5, 1e-9),
        "four-bar-3d-harmonic-law": (hx.assemble(read_scene(SCENES / "four_bar_3d.toml")), 0.5,
                                     1e-9),
    }


CASES = _cases()


def run(model, t_end, method, tol, loop, **kwargs):
    return hx.simulate(model, t_end, method=method, rtol=tol, atol=tol,
                       options={"loop": loop}, **kwargs)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("case", CASES)
def test_the_compiled_loop_takes_the_python_loops_steps(case, method):
    model, t_end, tol = CASES[case]
    python = run(model, t_end, method, tol, "python")
    compiled = run(model, t_end, method, tol, "vm")
    assert python.status == compiled.status == "finished"
    loop = compiled.options["loop"]
    assert loop["reason"] == "" and loop["kernels"] == ["vm"]
    # every step in the kernel (none handed over on these smooth motions)
    assert loop["steps"] == compiled.counters.steps and loop["handovers"] == 0
    assert python.options["loop"]["steps"] == 0
    # the same error tests decide the same steps: the counters agree. The error estimate is a
    # difference of nearly equal numbers, known to about eps / tol: the step sizes it sets
    # differ from one loop to the other by 1e-8 relative, and a decision may flip
    a, b = python.counters.as_dict(), compiled.counters.as_dict()
    assert abs(a["steps"] - b["steps"]) <= max(1, 0.02 * a["steps"])
    if a["steps"] == b["steps"]:
        assert a == b
        np.testing.assert_allclose(compiled.t, python.t, rtol=1e-6)
    scale = 1.0 + np.abs(python.q[-1]).max()
    assert np.abs(compiled.q[-1] - python.q[-1]).max() <= 10 * tol * scale
    assert np.abs(compiled.v[-1] - python.v[-1]).max() <= 100 * tol * (1 + np.abs(python.v).max())
    # projected at every step: the constraints at round-off, as in Python
    assert compiled.max_position_violation <= 1e-13
    assert compiled.max_velocity_violation <= max(1e-11, 10 * python.max_velocity_violation)
    if python.energy_drift is not None:
        assert compiled.energy_drift == pytest.approx(python.energy_drift, rel=0.5, abs=10 * tol)
    # what is saved at each state: accelerations, multipliers (by the policy where rows are
    # redundant), as the Python loop saves them
    np.testing.assert_allclose(compiled.v_dot[-1], python.v_dot[-1],
                               atol=1e3 * tol * (1 + np.abs(python.v_dot).max()))
    np.testing.assert_allclose(compiled.lam[-1], python.lam[-1],
                               atol=1e3 * tol * (1 + np.abs(python.lam).max()))


@pytest.mark.skipif(compiler() is None, reason="no C compiler")
def test_the_kernel_compiled_to_c_computes_what_the_virtual_machine_does(monkeypatch):
    """In mode "auto" the kernel is compiled once the run is foreseen to need more than
    COMPILE_AFTER seconds of the virtual machine (here at once); C and the virtual machine
    evaluate the same Function: the same steps, the states to round-off."""
    from hexapod.simulation import compiled_steps

    model, t_end, tol = CASES["pendulum"]
    vm = run(model, t_end, "dop853-projection", tol, "vm")
    monkeypatch.setattr(compiled_steps, "COMPILE_AFTER", 0.0)
    monkeypatch.setattr(compiled_steps, "COMPILE_PAYOFF", 0.0)
    auto = run(model, t_end, "dop853-projection", tol, "auto")
    assert auto.options["loop"]["kernels"] == ["vm", "c"]
    c = run(model, t_end, "dop853-projection", tol, "c")
    assert c.options["loop"]["kernels"] == ["c"]
    for result in (auto, c):
        assert result.counters == vm.counters
        np.testing.assert_allclose(result.q, vm.q, rtol=0, atol=1e-13)
        np.testing.assert_allclose(result.lam, vm.lam, rtol=0, atol=1e-10)


#: tolerances at which each method needs a crossing of the N-four-bar's flat pose (DOP853 at
#: 1e-10 and 1e-11 passes it with every row kept)
CROSSING_RTOL = {"dopri5-projection": 1e-10, "dop853-projection": 1e-12}


@pytest.mark.parametrize("method", METHODS)
def test_singular_poses_are_handed_over_and_crossed_in_python(method):
    """The N-four-bar lying flat (its Jacobian losing 10 ranks) at a tolerance where the
    method must cross it: the kernel hands the steps near the pose over, Python crosses it, the
    kernel resumes; the error against the reference stays that of the Python loop."""
    case = n_four_bar(10, t_end=3.0)
    model = hx.assemble(case.scene)
    results = {loop: run(model, 3.0, method, CROSSING_RTOL[method], loop)
               for loop in ("python", "vm")}
    errors = {}
    for loop, result in results.items():
        assert result.status == "finished", result.message
        assert result.counters.crossings >= 1
        positions = np.column_stack([result.q[:, model.bodies[model.body_index[b]].q][:, :2]
                                     for b in case.observed])
        errors[loop] = np.abs(positions - case.reference(result.t)).max()
        assert result.max_position_violation <= 1e-13
    loop = results["vm"].options["loop"]
    assert loop["handovers"] >= 1
    # the kernel resumes after each crossing: a good part of the steps are its (the crossings'
    # short steps, Python's, are most of them at 1e-12)
    assert 0.3 * results["vm"].counters.steps < loop["steps"] < results["vm"].counters.steps
    assert errors["vm"] <= max(1e-8, 3 * errors["python"])


#: fixed steps of rk4-baumgarte per case
RK4_STEPS = {"pendulum": 0.01, "seed002-closed-loop": 1e-3, "andrews": 1e-5,
             "spatial-chain": 1e-3, "bricard-redundant": 1e-2, "four-bar-3d-harmonic-law": 1e-3}


@pytest.mark.parametrize("case", CASES)
def test_rk4_baumgarte_in_the_compiled_loop_is_the_python_loop(case):
    """Fixed steps and no error test: the same arithmetic in the same order, so the same
    numbers; the multipliers saved are those of the unstabilised solve, as in Python."""
    model, t_end, _ = CASES[case]
    results = [hx.simulate(model, t_end, method="rk4-baumgarte", step=RK4_STEPS[case],
                           options={"loop": loop}) for loop in ("python", "vm")]
    python, compiled = results
    assert python.status == compiled.status == "finished"
    assert compiled.options["loop"]["steps"] == compiled.counters.steps
    assert compiled.counters == python.counters
    np.testing.assert_allclose(compiled.q, python.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(compiled.v_dot, python.v_dot, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(compiled.lam, python.lam, rtol=1e-9, atol=1e-9)
    assert compiled.max_position_violation == pytest.approx(python.max_position_violation,
                                                            rel=1e-6, abs=1e-15)


def test_rk4_baumgarte_drifting_too_far_fails_in_python_with_its_message():
    """A step too large for Baumgarte's stabilisation: the kernel hands the step where the
    drift check fails over, and Python fails it, as the Python loop does."""
    model, _, _ = CASES["pendulum"]
    results = [hx.simulate(model, 20.0, method="rk4-baumgarte", step=0.15,
                           options={"loop": loop}) for loop in ("python", "vm")]
    assert results[0].status == results[1].status == "failed"
    assert results[1].message == results[0].message
    assert "drifted" in results[0].message
    assert results[1].counters == results[0].counters


def test_laws_without_a_closed_form_keep_the_python_loop():
    scene = four_bar(2, 0.8, law=hx.Spline((0.0, 0.5, 1.0, 1.5), (0.8, 1.0, 1.5, 2.2)))
    result = run(hx.assemble(scene), 1.0, "dopri5-projection", 1e-8, "auto")
    assert result.status == "finished"
    assert result.options["loop"]["steps"] == 0
    assert "spline law has no closed form" in result.options["loop"]["reason"]


@pytest.mark.parametrize("law", [hx.Expression("0.8 + 0.5*t + 0.2*sin(3*t)"),
                                 hx.Polynomial([0.8, 2.0, -1.5])])
def test_laws_with_a_closed_form_are_compiled(law):
    model = hx.assemble(four_bar(2, 0.8, law=law))
    python = run(model, 0.8, "dop853-projection", 1e-9, "python")
    compiled = run(model, 0.8, "dop853-projection", 1e-9, "vm")
    assert compiled.options["loop"]["steps"] == compiled.counters.steps > 0
    np.testing.assert_allclose(compiled.q[-1], python.q[-1], atol=1e-8)
    np.testing.assert_allclose(compiled.lam[-1], python.lam[-1], rtol=1e-6)
    assert compiled.max_velocity_violation <= 1e-11


@pytest.mark.parametrize("method", [*METHODS, "rk4-baumgarte"])
def test_output_times_and_every_through_batches(method):
    model, _, tol = CASES["pendulum"]
    times = np.linspace(0.0, 2.0, 41)
    settings = {"step": 0.01} if method == "rk4-baumgarte" else {"rtol": tol, "atol": tol}

    def run(model, t_end, method, tol, loop, **kwargs):
        return hx.simulate(model, t_end, method=method, options={"loop": loop},
                           **settings, **kwargs)

    python = run(model, 2.0, method, tol, "python", t_eval=times)
    compiled = run(model, 2.0, method, tol, "vm", t_eval=times)
    np.testing.assert_array_equal(compiled.t, times)
    assert compiled.options["loop"]["steps"] == compiled.counters.steps
    np.testing.assert_allclose(compiled.q, python.q, atol=10 * tol)
    np.testing.assert_allclose(compiled.v_dot, python.v_dot, atol=1e3 * tol)
    every = {loop: run(model, 2.0, method, tol, loop, every=7) for loop in ("python", "vm")}
    assert every["vm"].t.size == every["python"].t.size
    np.testing.assert_allclose(every["vm"].t, every["python"].t, atol=1e-9)
    assert every["vm"].t[-1] == 2.0


@pytest.mark.parametrize("max_steps", [300, 1000])
def test_the_limits_stop_the_run_where_the_python_loop_stops(max_steps):
    """The step limit, and the weighing of the pace each time the steps tried double: the
    kernel's calls end where the Python loop weighs, so the run stops at the same step."""
    model, _, tol = CASES["pendulum"]
    results = [run(model, 20.0, "dopri5-projection", tol, loop, max_steps=max_steps)
               for loop in ("python", "vm")]
    for result in results:
        assert result.status == "failed" and f"after {result.counters.steps} steps" in (
            result.message)
    assert results[1].counters.steps == results[0].counters.steps <= max_steps
    assert results[0].t.size == results[1].t.size
    np.testing.assert_allclose(results[1].q[-1], results[0].q[-1], atol=1e-8)


def test_progress_the_cpu_budget_and_an_interruption_between_calls():
    model, _, tol = CASES["pendulum"]
    seen = []
    result = run(model, 20.0, "dopri5-projection", tol, "vm",
                 progress=lambda t, t_end: seen.append(t))
    assert result.status == "finished"
    assert seen == sorted(seen) and seen[-1] == 20.0
    assert 1 < len(seen) < result.counters.steps  # once per call, calls of many steps

    budget = run(model, 2000.0, "dopri5-projection", tol, "vm", cpu_budget=0.05)
    assert budget.status == "failed" and "CPU budget" in budget.message
    assert 0 < budget.t[-1] < 2000.0

    def interrupt(t, t_end):
        if t > 1.0:
            raise KeyboardInterrupt

    stopped = run(model, 20.0, "dop853-projection", tol, "vm", progress=interrupt)
    assert stopped.status == "interrupted"
    assert stopped.t.size == stopped.q.shape[0] == stopped.lam.shape[0] > 1
    assert stopped.t[-1] > 1.0 and np.all(np.diff(stopped.t) > 0)


def test_a_batch_ends_at_the_first_step_past_the_output_time():
    model, _, tol = CASES["pendulum"]
    integrator = get_integrator("dopri5")(model, 0.0, 2.0, rtol=tol, atol=tol, loop="vm")
    times = [0.0]
    while times[-1] < 0.5:
        batch = integrator.advance(t_stop=0.5)
        times += list(batch.t)
    assert times[-1] >= 0.5 > times[-2]
    assert integrator.t == batch.t[-1] and integrator.status == "running"
    np.testing.assert_array_equal(integrator.q, batch.q[-1])
    # its dense output is that of the last step, as the Python step would leave it
    q, v = integrator.dense_output()(0.5)
    python = get_integrator("dopri5")(model, 0.0, 2.0, rtol=tol, atol=tol, loop="python")
    while python.t < 0.5:
        python.step()
    np.testing.assert_allclose(q, python.dense_output()(0.5)[0], atol=1e-12)


def test_an_unknown_loop_is_refused():
    model, _, _ = CASES["pendulum"]
    with pytest.raises(ValueError, match="loop must be one of"):
        get_integrator("dopri5")(model, 0.0, 1.0, loop="fortran")


def test_a_subclass_that_may_step_otherwise_keeps_the_python_loop():
    from hexapod.simulation.integrators.embedded import DormandPrince5

    class Tweaked(DormandPrince5):
        name = "tweaked"

    model, t_end, tol = CASES["pendulum"]
    result = hx.simulate(model, t_end, method=Tweaked, rtol=tol, atol=tol)
    assert result.status == "finished" and result.options["loop"]["steps"] == 0
    assert "Tweaked is not a class" in result.options["loop"]["reason"]
