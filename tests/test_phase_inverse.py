"""The compiled closed-loop inverse dynamics (the phase path) gives the exact saddle path's numbers:
on four-bars (planar, and spatial with three redundant rows), the standing hexapod (twelve
redundant drivers), the walking hexapod across a touch-down (a change of contact set, feet that
carry nothing at that instant) and with the friction policy; and where its own result cannot be
trusted (Newton's method cannot follow samples far apart, the rows it was built for no longer
hold) it redoes the sample exactly and still agrees."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from robots import builtin_model, walking_robot

import hexapod as hx
from hexapod._support.compiled import compiler
from hexapod.algorithms import phase_inverse, phase_plan, prescribed
from hexapod.algorithms.inverse import inverse_dynamics

from mechanisms import four_bar

QUANTITIES = ("force", "torque", "effort", "ground_force", "q", "v", "v_dot")
#: across a touch-down of the walking robot (at t = 0.2 s, sampled)
TOUCH_DOWN = (0.194, 0.206, 7)


def scene_model(name: str, policy: str | None = None, mu: float | None = None):
    """A built-in scene's model, the walking robot's with another ground-force policy when
    given (shared with the other modules' tests: tests/robots.py)."""
    if policy is None:
        return builtin_model(name)
    assert name == "hexapod"
    return walking_robot(policy=policy, mu=mu)


@cache
def saddle(name: str, start: float, stop: float, count: int):
    """The exact saddle path's result on a built-in scene (computed once per module)."""
    return inverse_dynamics(scene_model(name), np.linspace(start, stop, count),
                            method="saddle")


def four_bar_model(dimension: int):
    law = hx.scene.Harmonic(offset=1.05, sin=[0.6], frequency=0.8)
    return hx.assemble(four_bar(dimension, 1.05, law=law))


def phase(model, times, frame="joint"):
    """The phase path's fields and the number of samples it solved exactly."""
    w, wd, wdd = (x.reshape(model.n_w, times.size) for x in model.law_values(times))
    return phase_inverse.phase_inverse(model, model.create_data(), times, w, wd, wdd, frame)


def assert_agree(fields, exact, rel=1e-9):
    """Every quantity within ``rel`` of its largest magnitude (positions, velocities and
    accelerations: of one, in SI, when they are smaller: the standing robot's are round-off)."""
    names = {"ground_force": "ground"}
    for key in QUANTITIES:
        mine, theirs = fields[names.get(key, key)], getattr(exact, key)
        if theirs.size == 0:
            continue
        floor = 1.0 if key in ("q", "v", "v_dot") else 1e-12
        scale = max(np.nanmax(np.abs(theirs)), floor)
        assert np.array_equal(np.isnan(mine), np.isnan(theirs)), key
        assert np.nanmax(np.abs(mine - theirs)) <= rel * scale, key
    assert fields["max_violation"] < 1e-12


@pytest.mark.parametrize("dimension", [2, 3])
def test_four_bars_agree_with_the_saddle_path(dimension):
    model = four_bar_model(dimension)
    times = np.linspace(0.0, 1.2, 25)
    for frame in ("joint", "world"):
        exact = inverse_dynamics(model, times, method="saddle", frame=frame)
        fields = phase(model, times, frame)
        assert_agree(fields, exact)
        # every sample compiled, the first from the positions Newton's method found there
        assert fields["exact_samples"] == 0
    # the spatial four-bar's loop closure is named redundant, as by the saddle path
    assert fields["redundant_rows"] == exact.redundant_rows
    assert len(exact.redundant_rows) == (3 if dimension == 3 else 0)
    result = inverse_dynamics(model, times, method="phase")
    assert result.method == "phase" and result.redundant_rows == exact.redundant_rows


def test_the_first_sample_s_newton_stops_early_and_the_plan_takes_it_to_round_off(monkeypatch):
    """The first sample's positions are found to FIRST_TOL only (the scene's guess at t = 1e-10
    s is off by its motion over that time: within it, no exact Newton step), the plan's own
    Newton steps take them to round-off, and the sample agrees with the saddle path's."""
    from hexapod.algorithms.kinematics import assemble_positions

    model = four_bar_model(3)
    times = np.linspace(1e-10, 1.2, 25)
    found = []

    def kept(*args, **kwargs):
        found.append(assemble_positions(*args, **kwargs))
        return found[-1]

    monkeypatch.setattr(phase_inverse, "assemble_positions", kept)
    fields = phase(model, times)
    assert_agree(fields, inverse_dynamics(model, times, method="saddle"))
    assert fields["exact_samples"] == 0
    w = model.law_values(times[0])[0]
    off = np.abs(model.call("phi", q=found[0], w=w) / model.row_scale).max()
    assert 1e-12 < off <= phase_inverse.FIRST_TOL


def test_a_run_goes_in_blocks_that_carry_the_state_from_one_to_the_next(monkeypatch):
    """The samples are evaluated in blocks (phase_plan.blocks: BLOCK samples, then the binary
    digits of the rest), each starting from the last state of the block before: small blocks
    give the saddle path's numbers as one block does."""
    for n in range(1, 300):
        sizes = phase_plan.blocks(n)
        assert sum(sizes) == n and sizes == sorted(sizes, reverse=True)
        assert set(sizes) <= {phase_plan.BLOCK >> k for k in range(7)}
    model = four_bar_model(3)
    times = np.linspace(0.0, 1.2, 25)
    exact = inverse_dynamics(model, times, method="saddle")
    monkeypatch.setattr(phase_plan, "BLOCK", 4)  # 24 compiled samples: six blocks of 4
    fields = phase(model, times)
    assert_agree(fields, exact)
    assert fields["exact_samples"] == 0


def test_the_standing_hexapod_agrees_with_the_saddle_path():
    """Six feet pinned, every joint held: twelve redundant drivers, forces by the least-wrench
    policy."""
    model = scene_model("hexapod-standing")
    times = np.linspace(0.0, 0.1, 4)
    exact = inverse_dynamics(model, times, method="saddle")
    fields = phase(model, times)
    assert_agree(fields, exact)
    assert fields["exact_samples"] == 0
    assert set(fields["redundant_rows"]) == set(exact.redundant_rows)
    assert len(exact.redundant_rows) == 12


def _no_split(*args, **kwargs):
    raise AssertionError("a rank decision at a new contact set")


def test_the_walking_hexapod_agrees_across_a_touch_down(monkeypatch):
    """Three feet down, then six: a new contact set, whose new feet carry nothing at the
    touch-down itself (their multipliers held at zero) and whose feet down before keep the
    rows they had (no rank decision: the split is made to fail); the ground forces by the
    least-wrench policy with the feet's load-sharing weights."""
    model, exact = scene_model("hexapod"), saddle("hexapod", *TOUCH_DOWN)
    monkeypatch.setattr(phase_inverse, "split_rows", _no_split)
    fields = phase(model, exact.times)
    assert_agree(fields, exact)
    assert fields["exact_samples"] == 0
    stance = exact.ground_status != "swing"
    assert stance.sum(axis=1)[0] == 3 and stance.sum(axis=1)[-1] == 6


def test_the_guides_kinematics_leave_every_foot_row_out_without_deciding_again(monkeypatch):
    """The guides' kinematics (a motion run) across the touch-down: their drivers fix every
    velocity, so the new contact set's plan keeps no foot's row, as the plan before, without a
    rank decision (none is taken: the split is made to fail), and the motion is the exact
    path's."""
    from hexapod.algorithms.prescribed import prescribed_motion

    kinematics = scene_model("hexapod").guidance.kinematics
    times = np.linspace(*TOUCH_DOWN)
    exact = prescribed_motion(kinematics, times)  # fewer samples than the phase path's: exact
    w, wd, wdd = (x.reshape(kinematics.n_w, times.size) for x in kinematics.law_values(times))
    monkeypatch.setattr(phase_inverse, "split_rows", _no_split)
    fields = phase_inverse.phase_inverse(kinematics, kinematics.create_data(), times, w, wd,
                                         wdd, "joint", motion=True)
    assert fields["exact_samples"] == 0
    for key, theirs in zip(("q", "v", "v_dot"), exact, strict=True):
        assert np.max(np.abs(fields[key] - theirs)) <= 1e-10 * max(np.max(np.abs(theirs)), 1)
    stance = np.array([c.in_stance(times) for c in kinematics.contacts])
    assert stance[:, 0].sum() == 3 and stance[:, -1].sum() == 6


def test_a_known_motion_whose_first_accelerations_break_the_constraints_is_refused():
    """A guided model's twin takes its guides' motion as it is; at the first sample the
    accelerations are checked against the constraints first: the guides' own are taken (every
    sample by the plan), a motion pushed off them there goes to the exact path, which names
    the body the dynamics moves away from it."""
    from hexapod.algorithms.guided import followed_guides, guided_twin

    model = scene_model("hexapod")
    times = np.linspace(0.1, 0.104, 3)
    q, v, v_dot, joints = followed_guides(model, times)
    twin = guided_twin(model, times, q, v, v_dot, joints)
    w, wd, wdd = (x.reshape(twin.n_w, times.size) for x in twin.law_values(times))
    fields = phase_inverse.phase_inverse(twin, twin.create_data(), times, w, wd, wdd, "joint",
                                         known=(q, v, v_dot))
    assert fields["exact_samples"] == 0
    pushed = v_dot.copy()
    pushed[0, 2] += 1e-3  # the trunk's vertical acceleration, m/s^2
    with pytest.raises(hx.HexapodError, match="does not follow the known motion"):
        phase_inverse.phase_inverse(twin, twin.create_data(), times, w, wd, wdd, "joint",
                                    known=(q, v, pushed))


def test_samples_evaluated_apart_give_the_numbers_of_the_chain(monkeypatch):
    """A plan that has evaluated enough samples (phase_plan.EXPAND_AFTER), interpreted, runs
    its step expanded into one SX Function: along a chain of every sample (no CHAIN_SPACING),
    the same operations as the graph it expands, so the same numbers to round-off. And it
    evaluates its samples apart, ACROSS at a time by the MX virtual machine: here a chain of
    every other sample (2 ms apart, within CHAIN_SPACING) starts the others. Each converges
    to round-off from its own start, so the numbers are the sequential run's to round-off."""
    model, exact = scene_model("hexapod"), saddle("hexapod", *TOUCH_DOWN)
    monkeypatch.setattr(phase_plan, "EXPAND_AFTER", 10**9)
    graph = phase(model, exact.times)
    monkeypatch.setattr(phase_plan, "EXPAND_AFTER", 0)
    with monkeypatch.context() as patched:
        patched.setattr(phase_plan, "CHAIN_SPACING", 0.0)  # the chain is the run
        expanded = phase(model, exact.times)
    assert any(key[2] for plan in _plans(model) for key in plan.__dict__.get("_mapped", {})
               if key[0] != "across")
    for key in ("force", "torque", "q", "v", "v_dot", "ground"):
        scale = max(np.nanmax(np.abs(graph[key])), 1.0)
        assert np.nanmax(np.abs(expanded[key] - graph[key])) <= 1e-14 * scale, key
    apart = phase(model, exact.times)
    assert any(key[0] == "across" for plan in _plans(model)
               for key in plan.__dict__.get("_mapped", {}))
    assert apart["exact_samples"] == graph["exact_samples"]
    for key in ("force", "torque", "q", "v", "v_dot", "ground"):
        scale = max(np.nanmax(np.abs(graph[key])), 1.0)
        assert np.nanmax(np.abs(apart[key] - graph[key])) <= 1e-12 * scale, key
    assert_agree(apart, exact)


def test_a_guided_robot_s_samples_evaluated_apart_agree_with_its_sequential_run(monkeypatch):
    """The guided walking robot by the phase path, its plans evaluating samples apart from
    the first: its guides' kinematics from a chain every 4 ms (samples 1 ms apart: each at
    most 2 ms from it), its twin's dynamics each sample alone from the known motion; the same
    numbers as its run sample after sample (which agrees with the saddle path: above), across
    a touch-down, to round-off."""
    times = np.linspace(0.19, 0.21, 21)
    monkeypatch.setattr(prescribed, "PHASE_FROM_SAMPLES", 0)  # the guides' too
    monkeypatch.setattr(phase_plan, "EXPAND_AFTER", 10**9)
    sequential = inverse_dynamics(builtin_model("hexapod"), times, method="phase")
    apart = []
    evaluate = phase_plan.PhasePlan._apart

    def watched(plan, data, states, mapped, outputs, newton, known):
        apart.append((plan.motion, known, states.shape[0]))
        return evaluate(plan, data, states, mapped, outputs, newton, known)

    monkeypatch.setattr(phase_plan.PhasePlan, "_apart", watched)
    monkeypatch.setattr(phase_plan, "EXPAND_AFTER", 0)
    result = inverse_dynamics(builtin_model("hexapod"), times, method="phase")
    for key in QUANTITIES:
        mine, theirs = getattr(result, key), getattr(sequential, key)
        scale = max(np.nanmax(np.abs(theirs)), 1.0)
        assert np.array_equal(np.isnan(mine), np.isnan(theirs)), key
        assert np.nanmax(np.abs(mine - theirs)) <= 1e-12 * scale, key
    assert {(motion, known) for motion, known, _ in apart} == {(True, False), (False, True)}
    assert sum(n for motion, _, n in apart if not motion) == times.size  # the twin: all
    assert sum(n for motion, _, n in apart if motion) > 0  # on the guides' own grid


def test_guided_coordinates_evaluated_apart_are_those_of_the_samples_one_by_one(monkeypatch):
    """Interpreted, past EXPAND_AFTER samples, a guided model's joint coordinates, rates and
    accelerations come ACROSS samples at a time from the MX virtual machine: the operations
    of the SX Function, in its order, so the same numbers bit for bit (37 samples: the last
    group filled up)."""
    from hexapod.algorithms.guided import guided_coordinates, guides_motion

    model = builtin_model("hexapod")
    q, v, v_dot = guides_motion(model, np.linspace(0.0, 0.5, 37))
    monkeypatch.setattr(phase_plan, "EXPAND_AFTER", 10**9)
    one_by_one = guided_coordinates(model, q, v, v_dot)
    monkeypatch.setattr(phase_plan, "EXPAND_AFTER", 0)
    apart = guided_coordinates(model, q, v, v_dot)
    assert ("guided coordinates across",) in model._built
    for mine, theirs in zip(apart, one_by_one, strict=True):
        assert mine.shape == theirs.shape == (len(model.guidance.laws), 37)
        assert np.array_equal(mine, theirs)


def test_plans_take_the_same_pivots_whatever_the_samples(monkeypatch):
    """A plan's pivots are chosen at the model's reference positions where they serve, not at
    the decision's own (which move with the samples a run is given): two fresh models of the
    walking robot, run on different samples across a touch-down, build the same plans (rows
    and pivots), so that compiled, the second run finds the first one's code. A decision's
    own pivots differed with the positions it was taken at (5 to 8 pivot orders at 8 positions
    of a contact phase, one-off script)."""
    monkeypatch.setattr(prescribed, "PHASE_FROM_SAMPLES", 0)  # the guides' too

    def pivots(times) -> dict:
        model = hx.assemble(hx.load_scene("hexapod"))
        inverse_dynamics(model, times, method="phase")
        found = {}
        for owner in (model, model.guidance.kinematics):
            for plan in _plans(owner):
                found[(plan.motion, plan.kept.tobytes(), plan.left_out.tobytes())] = (
                    plan.lu.row_order.tobytes(), plan.lu.column_order.tobytes())
        return found

    first, second = pivots(np.linspace(0.19, 0.21, 11)), pivots(np.linspace(0.185, 0.215, 23))
    common = first.keys() & second.keys()
    assert {motion for motion, _, _ in common} == {False, True}  # the guides' and the twin's
    assert all(first[key] == second[key] for key in common)


def _plans(model) -> list:
    """The phase plans a model has built."""
    return [v for v in model._built.values() if isinstance(v, phase_plan.PhasePlan)]


def test_a_change_of_rank_is_redone_exactly(monkeypatch):
    """Told that the contact set does not change, the driver keeps the three-feet decision past
    the touch-down: the new feet's rows, neither kept nor left out, show in the checks, the
    sample is redone exactly, the exact decision taken over, and the numbers still agree."""
    model, exact = scene_model("hexapod"), saddle("hexapod", *TOUCH_DOWN)
    first = tuple(bool(x) for x in exact.ground_status[0] != "swing")
    monkeypatch.setattr(phase_inverse._Feet, "contact_set", lambda self, k: first)
    fields = phase(model, exact.times)
    assert_agree(fields, exact)
    assert fields["exact_samples"] >= 1


@pytest.mark.parametrize("count", [41, 9])
def test_samples_too_far_apart_for_newton_take_more_steps(count):
    """A four-bar sampled coarsely: the predicted positions are too far off for the first
    Newton steps, the samples from there on take more (the most for samples 0.15 s apart), none
    is evaluated exactly, and the numbers agree."""
    model = four_bar_model(3)
    times = np.linspace(0.0, 1.2, count)
    exact = inverse_dynamics(model, times, method="saddle")
    fields = phase(model, times)
    assert_agree(fields, exact)
    assert fields["exact_samples"] == 0
    steps = phase_plan.NEWTON_STEPS
    assert fields["newton_steps"] == {41: steps[1], 9: steps[-1]}[count]


def test_samples_too_far_apart_for_the_most_newton_steps_are_redone_exactly():
    """Samples 0.2 s apart: not even the most Newton steps converge, those samples are redone
    exactly, and the numbers agree."""
    model = four_bar_model(3)
    times = np.linspace(0.0, 1.2, 7)
    exact = inverse_dynamics(model, times, method="saddle")
    fields = phase(model, times)
    assert_agree(fields, exact)
    assert 0 < fields["exact_samples"] < times.size
    assert fields["newton_steps"] == phase_plan.NEWTON_STEPS[-1]


def test_friction_keeps_the_exact_qp_where_a_cone_binds():
    """The least-effort forces leave the friction pyramids (mu = 2) before t = 0.07 s, not
    after: the first samples get the exact per-sample QP, the others the compiled least-effort
    forces, and all agree with the saddle path."""
    model = scene_model("hexapod", "friction", 2.0)
    times = np.linspace(0.05, 0.09, 9)
    exact = inverse_dynamics(model, times, method="saddle")
    fields = phase(model, times)
    assert_agree(fields, exact)
    assert 0 < fields["exact_samples"] < times.size


def test_compiled_and_interpreted_phase_paths_agree():
    """The phase path compiled to C gives the interpreter's numbers (the planar four-bar:
    small Functions, quick to compile)."""
    model = four_bar_model(2)
    times = np.linspace(0.0, 1.2, 9)
    interpreted = inverse_dynamics(model, times, method="phase")
    with hx.executing(compiled=True):
        compiled = inverse_dynamics(model, times, method="phase")
    for key in ("force", "torque", "effort", "q", "v_dot"):
        a, b = getattr(interpreted, key), getattr(compiled, key)
        assert np.nanmax(np.abs(a - b)) <= 1e-12 * np.nanmax(np.abs(a)), key


def test_a_later_model_loads_the_phase_libraries_an_earlier_one_compiled(tmp_path):
    """With a cache, the phase path's libraries are kept by the hash of each Function's graph:
    the same mechanism assembled again (as a later process would) and run compiled loads them
    instead of compiling, and gives the same numbers."""
    from hexapod._support import cache

    times = np.linspace(0.0, 1.2, 9)
    with hx.executing(compiled=True, cache=tmp_path / "cache"):
        compiled = inverse_dynamics(four_bar_model(2), times, method="phase")
        kept = {e.key for e in cache.entries()}
        again = inverse_dynamics(four_bar_model(2), times, method="phase")
        assert {e.key for e in cache.entries()} == kept  # nothing compiled again
    if compiler() is not None:
        assert kept
    for key in ("force", "torque", "q", "v_dot"):
        assert np.array_equal(getattr(compiled, key), getattr(again, key)), key
