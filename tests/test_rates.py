"""The compiled right-hand side equals the exact, rank-deciding forward dynamics, and refuses
the states where its fixed row set no longer spans the constraints."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from robots import builtin_model

import hexapod as hx
from hexapod._support.compiled import compiler_flags
from hexapod.scene.reader import read_scene
from hexapod.simulation.kernels import CompiledRates, compiled_rates, weighted_squares

from mechanisms import four_bar, random_tree, solve_state

SCENES = Path(__file__).resolve().parents[1] / "data" / "scenes"


def _random_velocities(model, q, t, seed):
    guess = np.random.default_rng(seed).normal(size=model.n_v)
    data = model.create_data()
    return hx.solve_velocities(model, data, t, q, guess)


@pytest.mark.parametrize("case", ["andrews", "front_leg", "four-bar-3d", "driven-tree"])
def test_compiled_rates_equal_the_exact_solve(case):
    if case == "four-bar-3d":  # three redundant rows: the compiled solve drops them
        scene = four_bar(3, 0.7, driven=False, gravity=[0, -9.81, 0])
    elif case == "driven-tree":  # time laws enter through w, wd, wdd
        scene = random_tree(3, 4)
    else:
        scene = read_scene(SCENES / f"{case}.toml")
    model, q, _, _, data = solve_state(scene, 0.2)
    for seed in range(3):
        v = _random_velocities(model, q, 0.2, seed)  # away from rest: Coriolis terms matter
        exact = hx.forward_dynamics(model, data, 0.2, q, v)
        rates = compiled_rates(model, data.independent_rows)
        q_dot, v_dot, lam = rates.solve(0.2, q, v)
        if rates.complete:  # no redundant row: the multipliers are unique
            assert np.abs(lam - data.lam).max() <= 1e-9 * np.abs(data.lam).max()
        else:  # the policy's multipliers come from the exact solve
            assert case == "four-bar-3d"
        # same equations, two factorisations: agreement to round-off times the conditioning
        assert np.abs(v_dot - exact).max() <= 1e-9 * np.abs(exact).max()
        assert np.allclose(q_dot, model.call("qdot", q=q, v=v), rtol=0, atol=1e-14)
    assert compiled_rates(model, data.independent_rows).function is rates.function  # once


@pytest.mark.parametrize("case", ["four-bar-3d", "driven-tree"])
def test_a_steps_stages_in_one_call_are_those_taken_one_by_one(case):
    """DOP853's eleven later stages in one call of the kernel (the tableau applied inside
    the Function) are the stages one by one, from the same sums in the same order: equal to
    round-off (they were bit for bit on both cases), with redundant rows left out
    (four-bar-3d) and time laws read at each stage's time (driven-tree); the stages'
    combinations the call forms (the propagated solution's and the error estimate's) are
    those of the stages one by one, and so are the error test's sums of squares. A stage
    whose solve would be refused refuses the call."""
    from hexapod.simulation.integrators import DormandPrince853

    scene = (four_bar(3, 0.7, driven=False, gravity=[0, -9.81, 0]) if case == "four-bar-3d"
             else random_tree(3, 4))
    model, q, _, _, data = solve_state(scene, 0.2)
    v = _random_velocities(model, q, 0.2, 0)
    method = DormandPrince853(model, 0.2, 1.0, q, v)
    y0 = np.concatenate([method.q, method.v])
    f0 = np.concatenate([model.call("qdot", q=method.q, v=method.v), method.v_dot])
    h = 1e-2
    tolerances = (method.atol_vector, method.rtol)
    K, combined, sums = method._compiled.stages(method.A, method.c, 0.2, h, y0, f0,
                                                weights=method._combinations,
                                                tolerances=tolerances)
    stages = [f0]
    for i in range(1, len(method.c)):
        y = y0 + h * sum(a * k for a, k in zip(method.A[i, :i], stages, strict=True))
        stages.append(method._derivative(0.2 + method.c[i] * h, y[:model.n_q], y[model.n_q:]))
    one_by_one = np.array(stages[1:])
    assert K.shape == one_by_one.shape == (len(method.c) - 1, y0.size)
    assert np.abs(K - one_by_one).max() <= 1e-14 * np.abs(one_by_one).max()
    expected = method._combinations @ np.array(stages)
    assert combined.shape == expected.shape == (3, y0.size)
    assert np.abs(combined - expected).max() <= 1e-14 * np.abs(one_by_one).max()
    # the error test's sums, formed in the call as the step one by one forms them from its
    # combinations (compared on the call's own: the error's are differences of stages, whose
    # round-off they magnify)
    y1 = y0 + h * combined[0]
    by_numpy = [weighted_squares(e, y0, y1, *tolerances) for e in combined[1:]]
    assert np.allclose(sums, by_numpy, rtol=1e-13, atol=0.0) and min(by_numpy) > 0
    bad = y0.copy()
    bad[3] = np.nan  # an Euler parameter: every term of the first body depends on it
    assert method._compiled.stages(method.A, method.c, 0.2, h, bad, f0) is None


@pytest.mark.parametrize("case", ["four-bar-3d", "driven-tree"])
def test_an_embedded_pairs_start_takes_the_exact_solves_rates_from_the_kernels(case):
    """DOP853's start solves its accelerations by the compiled kernels (built from the start
    projection's rank decision) instead of the exact saddle-point solve: they are the exact
    solve's to round-off, and so are its multipliers (by the redundancy policy where rows are
    redundant: four-bar-3d), and the kernels keep the exact decision's rows."""
    from hexapod.simulation.integrators import DormandPrince853

    scene = (four_bar(3, 0.7, driven=False, gravity=[0, -9.81, 0]) if case == "four-bar-3d"
             else random_tree(3, 4))
    model, q, _, _, data = solve_state(scene, 0.2)
    v = _random_velocities(model, q, 0.2, 0)
    method = DormandPrince853(model, 0.2, 1.0, q, v)
    v_dot = hx.forward_dynamics(model, data, 0.2, method.q, method.v)
    assert np.abs(method.v_dot - v_dot).max() <= 1e-12 * max(1.0, np.abs(v_dot).max())
    assert np.abs(method.lam - data.lam).max() <= 1e-10 * max(1.0, np.abs(data.lam).max())
    assert np.array_equal(np.sort(method._compiled.rows), np.sort(data.independent_rows))


def test_baumgarte_terms_match_the_exact_solve():
    model, q, v, _, data = solve_state(four_bar(2, 0.7, driven=False, gravity=[0, -9.81]))
    drifted_q = q + 1e-3 * np.random.default_rng(1).normal(size=q.size)
    drifted_v = v + 1e-2
    exact = hx.forward_dynamics(model, data, 0.0, drifted_q, drifted_v, baumgarte=(7.0, 7.0))
    _, v_dot = compiled_rates(model, data.independent_rows)(0.0, drifted_q, drifted_v, 7.0)
    assert np.abs(v_dot - exact).max() <= 1e-9 * np.abs(exact).max()


def test_a_row_set_that_no_longer_spans_the_constraints_is_refused():
    # the planar four-bar solved with one of its independent rows left out: the residual of
    # the omitted row exposes it, and the caller falls back on the exact solve
    model, q, v, _, data = solve_state(four_bar(2, 0.7, driven=False, gravity=[0, -9.81]))
    rows = data.independent_rows
    assert CompiledRates(model, rows)(0.0, q, v) is not None
    assert CompiledRates(model, rows[:-1])(0.0, q, v) is None


def test_fast_function_equals_the_casadi_call():
    import casadi as ca

    from hexapod._support.fastcall import FastFunction

    x = ca.SX.sym("x", 3)
    y = ca.SX.sym("y", 2, 2)
    sparse_matrix = ca.vertcat(ca.horzcat(x[0], 0), ca.horzcat(x[1] * x[2], 0),
                               ca.horzcat(0, y[0, 1]))  # structural zeros, 3 x 2
    function = ca.Function("f", [x, y], [sparse_matrix, ca.sin(x) + y[1, 0]])
    fast = FastFunction(function)
    rng = np.random.default_rng(0)
    for _ in range(3):  # the buffers are reused: each call sees its own arguments
        X, Y = rng.normal(size=3), rng.normal(size=(2, 2))
        A, b = fast(X, Y)
        A_ref, b_ref = (o.full() for o in function(X, Y))
        assert A.shape == (3, 2) and np.array_equal(A, A_ref)
        assert b.shape == (3,) and np.array_equal(b, b_ref.reshape(-1))


@pytest.mark.parametrize("kind", ["FastFunction", "ScatteredFunction"])
def test_a_failed_fast_evaluation_raises_instead_of_returning_the_last_results(kind):
    # a linear solve of a singular matrix fails inside CasADi; through the buffers the outputs
    # were then left as the previous call wrote them, and a projection near a singular pose
    # silently returned the state before the step (the N-four-bar stood still, its steps
    # accepted, until the run's budget ran out)
    import casadi as ca

    from hexapod._support import fastcall

    A, b = ca.MX.sym("A", 2, 2), ca.MX.sym("b", 2)
    fast = getattr(fastcall, kind)(ca.Function("solve", [A, b], [ca.solve(A, b, "qr")]))
    (x,) = fast(np.array([[2.0, 0.0], [0.0, 4.0]]), np.array([2.0, 2.0]))
    assert np.allclose(x, [1.0, 0.5])
    with pytest.raises(RuntimeError, match="solve"):
        fast(np.zeros((2, 2)), np.array([1.0, 3.0]))
    with pytest.raises(RuntimeError):
        ca.Function("solve", [A, b], [ca.solve(A, b, "qr")])(np.zeros((2, 2)), [1.0, 3.0])


@pytest.mark.parametrize("case", ["front_leg", "four-bar-3d", "driven-tree"])
def test_compiled_projection_equals_the_exact_one(case):
    from hexapod.simulation.kernels import compiled_projection

    if case == "four-bar-3d":
        scene = four_bar(3, 0.7, driven=False)
    elif case == "driven-tree":
        scene = random_tree(3, 4)
    else:
        scene = read_scene(SCENES / f"{case}.toml")
    model, q, v, _, data = solve_state(scene, 0.2)
    rng = np.random.default_rng(5)
    # the end of an integration step: off the constraints by about a tolerance
    drifted_q = model.integrate(q, 1e-7 * rng.normal(size=model.n_v))
    drifted_v = v + 1e-6 * rng.normal(size=model.n_v)
    projected = compiled_projection(model, data.independent_rows)(0.2, drifted_q, drifted_v)
    assert projected is not None
    kinematics = model.create_data()  # ``data`` keeps the dynamics at the state
    exact_q = hx.assemble_positions(model, kinematics, 0.2, drifted_q)
    exact_v = hx.solve_velocities(model, kinematics, 0.2, exact_q, drifted_v)
    w, wd, _ = model.law_values(0.2)
    assert np.abs(model.call("phi", q=projected[0], w=w) / model.row_scale).max() < 1e-12
    rate = model.call("Phi_v", q=projected[0], w=w) @ projected[1] - model.call(
        "nu", q=projected[0], w=w, wd=wd)
    assert np.abs(rate).max() < 1e-12 * max(1.0, np.abs(exact_v).max())
    if case == "four-bar-3d":
        # the drift makes the redundant rows independent to the exact projection's rank
        # decision, not to the compiled one's: two points of the constraints within the drift
        assert np.abs(projected[0] - exact_q).max() < 1e-6
    else:
        # both take least-M-norm Newton steps from the same start: the same point
        assert np.abs(projected[0] - exact_q).max() < 1e-13
        assert np.abs(projected[1] - exact_v).max() < 1e-12 * max(1.0, np.abs(exact_v).max())
    # far from the constraints two Newton steps are not enough: refused, not returned
    far = model.integrate(q, 0.3 * rng.normal(size=model.n_v))
    assert compiled_projection(model, data.independent_rows)(0.2, far, v) is None


def test_kernels_compiled_to_c_give_the_interpreters_numbers_and_are_kept(tmp_path,
                                                                         monkeypatch):
    """With compiled execution the integrators' kernels are C code from the cache: a run gives
    the interpreter's states (the same operations: to round-off), and a later model of the same
    scene loads the libraries instead of compiling them again (the laws are inputs: the front
    leg's tabulated twin shares them)."""
    from hexapod._support import cache, compiled

    scene = hx.load_scene("front-leg")
    options = dict(method="rk4", step=2e-3, t0=0.1)
    interpreted = hx.simulate(hx.assemble(scene), 0.12, **options)
    with hx.executing(compiled=True, cache=tmp_path):
        first = hx.simulate(hx.assemble(scene), 0.12, **options)
        kept = {entry.what for entry in cache.entries(describe=True)}
        flags = " ".join(compiler_flags())
        assert {f"forward rates, compiled {flags}", f"forward project, compiled {flags}"} <= kept

        def no_compiler(*args):
            raise AssertionError(f"a kernel was compiled again: {args[0].name()}")

        monkeypatch.setattr(compiled, "_compile", no_compiler)
        again = hx.simulate(hx.assemble(scene), 0.12, **options)
    assert np.abs(first.q - interpreted.q).max() <= 1e-12
    assert np.array_equal(again.q, first.q)


def test_kernels_compiled_with_pivots_solve_by_lu_to_the_exact_numbers():
    """Compiled to C with a reference state, the kernels factorise by an LU with pivots chosen
    there, written out (here the saddle-point matrix of a four-bar, whose rows are fewer than
    its velocities; the front leg's square Jacobian in the test above, through a simulation):
    the exact solve's accelerations, and the projection's state, to round-off times the
    conditioning."""
    from hexapod.simulation.kernels import compiled_projection, pivots_near

    scene = four_bar(3, 0.7, driven=False, gravity=[0, -9.81, 0])
    model, q, _, _, data = solve_state(scene, 0.2)
    v = _random_velocities(model, q, 0.2, 0)
    exact = hx.forward_dynamics(model, data, 0.2, q, v)
    rows = data.independent_rows
    reference = (q, model.law_values(0.2)[0])
    with hx.executing(compiled=True):
        rates = compiled_rates(model, rows, reference)
        projection = compiled_projection(model, rows, reference)
    assert pivots_near(model, rows, reference).n == model.n_v + rows.size  # [[I, W^T], [W, 0]]
    _, v_dot, _ = rates.solve(0.2, q, v)
    assert np.abs(v_dot - exact).max() <= 1e-9 * np.abs(exact).max()
    rng = np.random.default_rng(1)
    drifted = model.integrate(q, 1e-6 * rng.normal(size=model.n_v))
    drifted_v = v + 1e-5 * rng.normal(size=model.n_v)
    state = projection(0.2, drifted, drifted_v)
    assert state is not None
    assert np.abs(model.call("phi", q=state[0], w=reference[1]) / model.row_scale).max() <= 1e-12
    # its factors kept from the drifted positions (a chord method, the velocities corrected by
    # the residual where the positions end) against the interpreted kernel on the same rows
    # (the same chord; the velocities projected exactly at the positions found; the exact
    # projection decides the rank again, and the drift makes this four-bar's redundant rows
    # independent to it): the same positions to round-off, velocities on the constraints
    # projected along the rows' directions at the drifted positions rather than at the
    # projected ones, apart by the product of the two corrections (1e-6 and 1e-5 here) times
    # the rows' conditioning: 5e-9 of the speeds
    newton_q, newton_v = compiled_projection(model, rows)(0.2, drifted, drifted_v)
    assert np.abs(state[0] - newton_q).max() <= 1e-13
    rate = model.call("Phi_v", q=state[0], w=reference[1]) @ state[1] - model.call(
        "nu", q=state[0], w=reference[1], wd=model.law_values(0.2)[1])
    assert np.abs(rate).max() <= 1e-12 * np.abs(newton_v).max()
    assert 0 < np.abs(state[1] - newton_v).max() <= 1e-7 * np.abs(newton_v).max()


def test_a_states_pivots_are_chosen_once_for_its_kernels_and_kept_where_they_serve():
    """The rates' and the projection's kernels of one state (an integrator's start) share one
    choice of pivots; at other states the pivots first chosen for the same rows are kept
    where they serve (:meth:`StaticLU.serves`: the same kernels, compiled once, where a walk
    made and compiled new ones at contact changes stride after stride); a model keeps its
    last eight states' decisions. Pivots that no longer serve are chosen again."""
    from hexapod.simulation import kernels

    scene = four_bar(3, 0.7, driven=False, gravity=[0, -9.81, 0])
    model, q, _, _, data = solve_state(scene, 0.2)
    rows, w = data.independent_rows, model.law_values(0.2)[0]
    first = kernels.pivots_near(model, rows, (q, w))
    assert kernels.pivots_near(model, rows, (q.copy(), w.copy())) is first
    moved = [model.integrate(q, 1e-3 * k * np.ones(model.n_v)) for k in range(1, 9)]
    assert all(kernels.pivots_near(model, rows, (x, w)) is first for x in moved)
    assert kernels.RECENT_PIVOTS == 8
    # where the first pivots do not serve, the state's own are chosen (and kept for it)
    serves = first.serves
    first.serves = lambda values, bound=10.0: False
    try:
        other = kernels.pivots_near(model, rows, (model.integrate(q, 0.01 * np.ones(model.n_v)),
                                                  w))
    finally:
        first.serves = serves
    assert other is not first and kernels.pivots_near(model, rows, (moved[0], w)) is first


def test_pivots_that_a_matrix_has_outgrown_do_not_serve_it():
    """:meth:`StaticLU.serves`: the pivots of one matrix serve another of its pattern while
    their factors' growth stays within ten times partial pivoting's; a pivot gone to nearly
    zero (growth 1e12) does not, nor an exactly zero one."""
    from hexapod.algorithms.static_lu import StaticLU

    rows, columns = np.array([0, 0, 1, 1]), np.array([0, 1, 0, 1])
    lu = StaticLU.pivoted(rows, columns, 2, [2.0, 1.0, 1.0, 1.0])  # pivot on the 2
    assert lu.serves([3.0, 1.0, 1.0, 2.0])
    assert not lu.serves([1e-12, 1.0, 1.0, 1.0])
    assert not lu.serves([0.0, 1.0, 1.0, 1.0])


def test_kernels_refuse_what_gives_nan_though_their_residual_maxima_skip_it():
    """CasADi's maxima skip NaN (C's fmax: all NaN gives -inf), so a residual test alone let a
    projection through a singular matrix return NaN positions (a compiled walking run, at the
    end of a step on a lift-off whose rows the kernel still kept). The outputs say it."""
    from hexapod.simulation.kernels import compiled_projection

    model, q, _, _, data = solve_state(four_bar(3, 0.7, driven=False, gravity=[0, -9.81, 0]),
                                       0.2)
    v = np.zeros(model.n_v)
    projection = compiled_projection(model, data.independent_rows)
    bad = q.copy()
    bad[3] = np.nan  # an Euler parameter: every term of the first body depends on it
    assert projection._fast(bad, v)[2][0] == -np.inf  # the maximum said all is well
    assert projection(0.2, bad, v) is None
    assert compiled_rates(model, data.independent_rows).solve(0.2, bad, v) is None


def test_the_kernels_ground_policy_multipliers_are_the_exact_solves():
    """A walking simulation saves its states' multipliers through the kernel's ground-force
    policy (the redundant feet's rows left out, the multipliers that change no force solved
    with the kept rows' factorisation, the policy's choice the exact solve's own function).
    At states of a run across the tripods' switch at 0.25 s (a load ramp, feet that carry
    nothing, a new contact set), they are the exact solve's, with its own rank decision, to
    1e-10 of the largest multiplier: the two decisions alone give 2e-12 (measured), and
    ``1e-10`` is what the inverse dynamics' paths must meet against the exact one. A decision
    whose rows left out have left the span of the kept ones is refused. The run's own saved
    multipliers are the exact solve's on its twin to the same bound: at 0.2 s, a touch-down
    the step ends on, the old contact set's kernels gave 2e-8, and the exact solve serves."""
    from hexapod.algorithms.dynamics import forward_dynamics
    from hexapod.model.tabulation import TOLERANCE_PER_RTOL, tabulated_model
    from hexapod.simulation.kernels import policy_multipliers

    model = builtin_model("hexapod")
    times = np.array([0.02, 0.2, 0.245, 0.25, 0.252, 0.258])
    run = hx.simulate(model, 0.26, t_eval=times)
    assert run.success, run.message
    kernels, compared = {}, 0
    for t, q, v in zip(run.t, run.q, run.v, strict=True):
        data = model.create_data()
        forward_dynamics(model, data, t, q, v)
        key = (tuple(np.sort(data.independent_rows)), tuple(np.sort(data.redundant_rows)))
        if key not in kernels:
            kernels[key] = compiled_rates(model, data.independent_rows,
                                          left_out=data.redundant_rows)
        solution = kernels[key].dynamics(t, q, v)
        assert solution is not None, t
        _, lam = solution
        assert np.abs(lam - data.lam).max() <= 1e-10 * np.abs(data.lam).max(), t
        compared += 1
    assert compared == times.size and len(kernels) >= 2  # both tripods' contact sets
    # the run saved these states' multipliers (output times: the dense output's states made
    # consistent) by the kernels too, on its twin with the gait laws tabulated
    twin, _ = tabulated_model(model, 0.0, 0.26, TOLERANCE_PER_RTOL * hx.simulation.DEFAULT_RTOL)
    for t, q, v, lam in zip(run.t, run.q, run.v, run.lam, strict=True):
        data = twin.create_data()
        forward_dynamics(twin, data, t, q, v)
        assert np.abs(lam - data.lam).max() <= 1e-10 * np.abs(data.lam).max(), t
    # the first tripod's decision after the switch: its rows left out now have a force of
    # their own (or none at all), and the kernel says so
    (first, *_), t, q, v = list(kernels), run.t[-1], run.q[-1], run.v[-1]
    stale = policy_multipliers(model, np.array(first[0]), np.array(first[1]))
    assert stale(t, q, v) is None


def test_steps_ending_on_a_touch_down_or_lift_off_are_taken_by_the_kernels(monkeypatch):
    """A step cut to end on a break of the laws integrates the regime before it: its last
    stages read the laws just before the break (at a lift-off itself the foot's gate is 0
    already, its rows vanish and the old contact set's kernels refused those stages), and the
    state it ends on, in the new regime, is projected, solved and saved by the new set's
    kernels. From the start across a touch-down (0.2 s) and the tripods' switch (0.25 s,
    a lift-off), no state needs the exact solve, and none the exact projection but the
    start's (before, ten a stride, each a rank decision; the start's accelerations come from
    the kernels, built from its projection's decision); the saved multipliers at both breaks
    are the exact solve's (the test above)."""
    import hexapod.simulation.integrators.base as base

    exact = []
    dynamics, positions = base.forward_dynamics, base.assemble_positions
    monkeypatch.setattr(base, "forward_dynamics",
                        lambda *a, **k: exact.append(("dynamics", a[2])) or dynamics(*a, **k))
    monkeypatch.setattr(base, "assemble_positions",
                        lambda *a, **k: exact.append(("positions", a[2])) or positions(*a, **k))
    run = hx.simulate(builtin_model("hexapod"), 0.26)
    assert run.success, run.message
    assert {0.2, 0.25} <= set(run.t.tolist())  # steps ended on both breaks
    assert exact == [("positions", 0.0)], exact  # the start's projection


def test_a_step_ends_accelerations_and_its_saved_multipliers_come_from_one_call():
    """With feet on the ground and redundant rows left out, a step's end takes its
    accelerations from the ground-force policy's kernel, and the multipliers saved there
    come from that same call: one kernel call a saved step instead of two (the rates
    kernel's, then the policy's), the same numbers as the two apart (bit for bit)."""
    from hexapod.simulation.kernels import policy_multipliers

    model = builtin_model("hexapod")
    integrator = hx.simulation.get_integrator("dopri5-projection")(model, 0.0, 0.1)
    for _ in range(2):
        integrator.step()
    t, q, v = integrator.t, integrator.q, integrator.v
    kernel = integrator._compiled
    policy = kernel.policy
    assert policy is not None and policy.holds(t, q, v)
    evaluate, calls = policy._fast, []
    policy._fast = lambda *a: calls.append(1) or evaluate(*a)
    lam = integrator.lam
    assert not calls  # the step end's call served
    assert np.array_equal(integrator.v_dot, kernel.solve(t, q, v)[1])
    apart = policy_multipliers(model, kernel.rows, kernel.left_out)(t, q.copy(), v.copy())
    assert np.array_equal(lam, apart[1]) and np.array_equal(integrator.v_dot, apart[0])


def test_runs_from_other_states_take_the_same_pivots():
    """A model's first pivots for a row set are those of its reference positions ``q0`` where
    they serve the run's state, not the state's own: two fresh models started at different
    states take the same pivots (the same kernels' code, found again in the cache), where
    each state's own pivots differ (checked too)."""
    from hexapod.algorithms.step import kept_pivots
    from hexapod.simulation import kernels

    scene = random_tree(3, 8, chain=True, driven=False)
    model, q, _, _, data = solve_state(scene)
    rows, w = data.independent_rows, model.law_values(0.0)[0]
    other_model = hx.assemble(scene)
    rng = np.random.default_rng(5)
    moved = other_model.integrate(q, 0.3 * rng.standard_normal(model.n_v))
    own = [kept_pivots(model, rows.tolist(), x, w) for x in (q, moved)]
    assert not (np.array_equal(own[0].row_order, own[1].row_order)
                and np.array_equal(own[0].column_order, own[1].column_order))
    first = kernels.pivots_near(model, rows, (q, w))
    second = kernels.pivots_near(other_model, rows, (moved, w))
    assert np.array_equal(first.row_order, second.row_order)
    assert np.array_equal(first.column_order, second.column_order)
