"""Laws evaluated together, and costly laws tabulated for a forward simulation
(``hexapod/scene/laws/table.py``, ``hexapod/model/tabulation.py``).

References are the laws' own exact values: a table is exact at its times, reads the same numbers
one column at a time or all together, repeats with its period, and between its times agrees with
the law it replaces to the tolerance it reports (checked here at times it never saw, with a
margin of 10 over the midpoints it measured, where a quintic Hermite interpolant's error is near
its largest). A simulation with the table agrees with one with the exact laws to far below its
tolerance, because the table's error is a hundredth of it.
"""

import numpy as np
import pytest
from robots import builtin_model

import hexapod as hx
from hexapod.model.law_values import law_breaks
from hexapod.model.tabulation import tabulated_model
from hexapod.scene import Harmonic, JointController
from hexapod.scene.laws.base import Rate
from hexapod.scene.laws.table import LawTable

PERIOD = 0.5


def test_a_table_is_exact_at_its_times_and_reads_the_same_in_one_call_or_column_by_column():
    times = np.linspace(0.0, 1.0, 11)
    table = np.random.default_rng(0).normal(size=(3, 4, times.size))
    laws = LawTable(times, table).laws()
    assert np.abs(laws[0].table.evaluate(times) - table).max() < 1e-14
    t = np.array([0.03, 0.5, 0.77])
    together = type(laws[0]).evaluate_batch(laws[1:3], t)
    for k, law in enumerate(laws[1:3]):
        assert np.array_equal(together[:, k], np.array(law.evaluate(t)))
    with pytest.raises(ValueError, match="shape"):
        LawTable(times, table[:, :, :-1])


def test_a_periodic_table_repeats():
    law = Harmonic(offset=0.1, cos=(0.3, 0.05), sin=(0.2,), frequency=1 / PERIOD)
    times = np.linspace(0.1, 0.1 + PERIOD, 257)
    table = LawTable(times, np.array(law.evaluate(times))[:, None, :], period=PERIOD)
    t = np.array([0.1, 0.37, 2.0, 7.77])
    read = table.evaluate(t)[:, 0]
    assert np.allclose(read, table.evaluate(0.1 + np.mod(t - 0.1, PERIOD))[:, 0], rtol=0,
                       atol=1e-12)
    # and agrees with the law itself (h^6 for values, h^4 for accelerations)
    exact = np.array(law.evaluate(t))
    scale = np.abs(exact).max(axis=1, keepdims=True)
    assert (np.abs(read - exact) / scale).max() < 1e-7


def test_gates_footholds_and_gait_laws_evaluated_together_are_those_evaluated_alone():
    model = builtin_model("hexapod")
    t = np.linspace(0.0, 1.3, 53)
    kinds = {"stance-gate", "foothold", "gait-coupled"}
    chosen = [i for i, law in enumerate(model.laws) if law.kind in kinds]
    assert len(chosen) == 42
    w, wd, wdd = model.law_values(t)
    for i in chosen:
        alone = model.laws[i].evaluate(t)
        assert np.array_equal(w[i], alone[0]) and np.array_equal(wd[i], alone[1])
        assert np.array_equal(wdd[i], alone[2])
    single = model.law_values(0.26)
    assert np.array_equal(single[0][chosen], [model.laws[i].evaluate(0.26)[0] for i in chosen])


def test_tabulation_meets_its_tolerance_between_the_times_it_checked():
    model = hx.assemble(hx.load_scene("front-leg"))
    costly = [i for i, law in enumerate(model.laws) if law.costly]
    assert len(costly) == 3  # the three joints that follow the foot's guides
    twin, record = tabulated_model(model, 0.0, 1.2, 1e-8)
    assert record["tabulated"] == 3 and record["period_s"] == pytest.approx(PERIOD)
    assert max(record["error"].values()) <= 1e-8
    assert twin.digest != model.digest and twin.n_w == model.n_w
    t = np.random.default_rng(1).uniform(0.0, 1.2, 400)  # over two periods and more
    exact = np.array(model.law_values(t))[:, costly]
    read = np.array(twin.law_values(t))[:, costly]
    scale = np.abs(exact).max(axis=2, keepdims=True)
    assert (np.abs(read - exact) / scale).max() <= 10 * 1e-8
    # periodic laws: one period from 0, built once per model and tolerance, whatever the run
    # (a window of a long motion reuses the table and the kernels its twin has built)
    assert tabulated_model(model, 0.0, 1.2, 1e-8)[0] is twin
    assert tabulated_model(model, 0.73, 0.75, 1e-8)[0] is twin


def test_the_last_grids_predicted_error_is_its_error_at_every_midpoint(monkeypatch):
    """The last grid is checked by prediction (its error from the grid before's and the fall
    of the last halving) and by measurement around the grid before's largest errors: its
    error at every one of its midpoints, measured here, is within the tolerance and within a
    factor 2 of what the record says. Without the prediction (the fall taken as none) the full
    check gives the same grid."""
    from hexapod.model import tabulation

    model = hx.assemble(hx.load_scene("front-leg"))
    costly = [i for i, law in enumerate(model.laws) if law.costly]
    twin, record = tabulated_model(model, 0.0, 0.5, 1e-8)
    assert "checked" in record and "predicted" in record["checked"]
    times = twin.laws[costly[0]].table.times
    middle = 0.5 * (times[:-1] + times[1:])
    exact = np.array(model.law_values(middle))[:, costly]
    read = np.array(twin.law_values(middle))[:, costly]
    scale = np.maximum(np.abs(exact).max(axis=2), np.abs(twin.laws[costly[0]].table.table)
                       .max(axis=2))[:, :, None]
    measured = (np.abs(read - exact) / scale).max(axis=(1, 2))
    recorded = np.array([record["error"][k] for k in ("value", "rate", "acceleration")])
    assert measured.max() <= 1e-8
    assert np.all(measured <= 2 * recorded) and np.all(recorded <= 2 * measured)
    monkeypatch.setattr(tabulation, "HALVING_GAINS", np.ones(3))
    full, checked = tabulated_model(hx.assemble(hx.load_scene("front-leg")), 0.0, 0.5, 1e-8)
    assert "checked" not in checked and checked["intervals"] == record["intervals"]
    assert np.array_equal(full.laws[costly[0]].table.times, times)


def test_the_grid_holds_the_laws_changes_of_regime():
    """The front leg's guided joints change regime at 0.2 s of their 0.5 s period (a foot's
    touch-down), which no uniform grid of 2^k intervals holds: an interval straddling it
    converges slowly and took the whole table to 2,048 intervals. On a grid uniform between the
    breaks and holding them, 1,024 meet the same tolerance."""
    model = hx.assemble(hx.load_scene("front-leg"))
    costly = [i for i, law in enumerate(model.laws) if law.costly]
    twin, record = tabulated_model(model, 0.0, 1.2, 1e-8)
    breaks = law_breaks([model.laws[i] for i in costly], 0.0, PERIOD)
    assert breaks.size >= 1
    times = twin.laws[costly[0]].table.times
    assert all(np.min(np.abs(times - b)) == 0.0 for b in breaks)
    edges = np.concatenate([[0.0], breaks, [PERIOD]])
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        steps = np.diff(times[(times >= a) & (times <= b)])
        assert np.ptp(steps) <= 1e-12 * PERIOD  # uniform between the breaks
    assert record["intervals"] <= 1024 and max(record["error"].values()) <= 1e-8


def test_a_model_keeps_its_recent_times_law_values_and_its_twins_their_own():
    """The values at the last few single times are kept (an adaptive step asks for its end's
    again and again), returned as copies, and never served to a twin with other laws."""
    model = hx.assemble(hx.load_scene("front-leg"))
    costly = [i for i, law in enumerate(model.laws) if law.costly]
    first = model.law_values(0.3)
    first[0][:] = np.nan  # a caller's change does not reach what is kept
    again = model.law_values(0.3)
    assert np.array_equal(again[0][costly], [model.laws[i].evaluate(0.3)[0] for i in costly])
    scaled = model.with_laws(tuple(law._scaled(2.0) if i in costly else law
                                   for i, law in enumerate(model.laws)), "scaled")
    assert np.array_equal(scaled.law_values(0.3)[0][costly], 2.0 * again[0][costly])
    for t in np.linspace(0.0, 0.1, 10):  # more times than are kept: the oldest go
        model.law_values(t)
    assert np.array_equal(model.law_values(0.3)[1], again[1])


def test_a_tolerance_below_the_exact_laws_round_off_keeps_them_exact():
    model = hx.assemble(hx.load_scene("front-leg"))
    twin, record = tabulated_model(model, 0.0, 0.1, 1e-15)
    assert twin is model
    assert "evaluated exactly" in record["exact"]


def test_a_simulation_with_tabulated_laws_agrees_with_the_exact_laws():
    model = hx.assemble(hx.load_scene("front-leg"))
    # a fixed step, so that both runs take the same steps and differ by the laws alone
    options = dict(method="rk4", step=2e-3, t0=0.1)
    fast = hx.simulate(model, 0.14, **options)
    exact = hx.simulate(model, 0.14, exact_laws=True, **options)
    assert fast.status == exact.status == "finished"
    record = fast.options["laws"]
    assert record["tabulated"] == 3 and "laws" not in exact.options
    assert record["tolerance"] == pytest.approx(1e-2 * hx.simulation.DEFAULT_RTOL)
    assert fast.model is model  # the result speaks of the user's model
    assert np.array_equal(fast.t, exact.t)
    # joint angles of order 1 rad and coordinates of order 0.05 m moved by laws off by 1e-8
    # of their scale: a few 1e-10 at most
    assert np.abs(fast.q - exact.q).max() < 1e-9
    assert np.abs(fast.q - exact.q).max() > 0.0  # the table is not the law


def test_a_table_keeps_the_breaks_of_the_laws_it_replaces():
    # the front leg's gait laws change regime at lift-off and touch-down: the table's columns
    # say so over any window, periods after the one tabulated included
    model = hx.assemble(hx.load_scene("front-leg"))
    costly = [i for i, law in enumerate(model.laws) if law.costly]
    twin, _ = tabulated_model(model, 0.0, 1.2, 1e-8)
    for start, stop in ((0.0, 0.5), (0.2, 1.9), (3.01, 3.7)):
        for i in costly:
            exact, read = model.laws[i].breaks(start, stop), twin.laws[i].breaks(start, stop)
            assert exact.size >= int(2 * (stop - start) / PERIOD) - 1  # two a period
            assert np.allclose(read, exact, rtol=0, atol=1e-12)


def test_adaptive_steps_end_on_the_touch_downs_and_lift_offs():
    model = hx.assemble(hx.load_scene("front-leg"))
    breaks = law_breaks(model.laws, 0.05, 0.6)
    assert breaks.size >= 2
    result = hx.simulate(model, 0.6, t0=0.05)
    assert result.status == "finished"
    for t in breaks:  # each an accepted step's end, exactly
        assert np.min(np.abs(result.t - t)) == 0.0


def test_a_controllers_target_speed_is_the_rate_of_its_targets_table():
    """A joint controller reads its target's rate as a law of its own (``Rate``): in the
    tabulated twin it is the rate of the target's table, not the costly law solved again at
    every step (which made the walking robot's time-stepping spend half its time in the gait's
    inverse kinematics), and agrees with the exact rate to the table's tolerance."""
    scene = hx.load_scene("front-leg")
    leg = hx.assemble(scene)  # a joint that follows the foot's guides: its motion, costly
    driver = next(d for d in leg.drivers if d.kind == "joint" and leg.laws[d.law].costly)
    scene.add(JointController("servo", leg.joints[driver.joint].name,
                              target=leg.laws[driver.law], kp=1.0))
    model = hx.assemble(scene)
    rates = [i for i, law in enumerate(model.laws) if isinstance(law, Rate)]
    assert len(rates) == 1 and model.laws[rates[0]].law.costly
    twin, record = tabulated_model(model, 0.0, 1.2, 1e-8)
    assert not twin.laws[rates[0]].law.costly
    t = np.random.default_rng(2).uniform(0.0, 1.2, 200)
    exact = np.array(model.law_values(t))[:2, rates[0]]
    read = np.array(twin.law_values(t))[:2, rates[0]]
    scale = np.abs(exact).max(axis=1, keepdims=True)
    assert (np.abs(read - exact) / scale).max() <= 10 * max(record["error"].values())


def test_a_rate_of_a_law_in_the_same_list_is_read_from_its_values():
    """A controller's target speed is its target's rate: evaluated with its target, it is read
    from the target's rate and acceleration, the same numbers as its own evaluation."""
    from hexapod.model.law_values import batches, evaluate_together

    law = Harmonic(offset=0.1, cos=(0.3, 0.05), sin=(0.2,), frequency=1 / PERIOD)
    alone = Rate(Harmonic(offset=0.2, cos=(0.1,), frequency=2.0))  # its law not in the list
    laws = [Rate(law), law, alone]
    plan = batches(laws)
    assert plan.rates.tolist() == [[0, 1]]
    t = np.linspace(0.0, 1.0, 7)
    values = evaluate_together(laws, t)
    for k, each in enumerate(laws):
        assert np.array_equal(values[:, k], np.array(each.evaluate(t)))
