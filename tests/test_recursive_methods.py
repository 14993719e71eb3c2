"""The three methods of Vukobratović and Potkonjak of forming W q_dd = P + V (basic theorems,
Lagrange, Gibbs-Appell): against each other, against the absolute-coordinate engine, and the
operation counter."""

from __future__ import annotations

import numpy as np
import pytest
from script_loader import load_script

import hexapod as hx
from hexapod.minimal import forming as rm
from hexapod.minimal.chain import ChainModel

from mechanisms import random_tree

# (seed, bodies, chain?): chains and trees, revolute and prismatic joints with random axes
CASES = [(21, 1, True), (22, 3, True), (23, 5, False), (24, 6, True), (25, 8, False)]


def _state(seed, dof):
    rng = np.random.default_rng(seed + 100)
    return rng.normal(size=dof) * 0.7, rng.normal(size=dof), rng.normal(size=dof)


def _close(a, b, tol=1e-10):
    scale = max(np.abs(a).max(), np.abs(b).max(), 1e-300)
    return np.abs(np.asarray(a) - np.asarray(b)).max() <= tol * scale


def _has_prismatic(chain):
    return any(link.kind == "prismatic" for link in chain.links)


def test_the_cases_mix_revolute_and_prismatic_joints():
    kinds = set()
    for seed, n, chain in CASES:
        model = ChainModel.from_model(hx.assemble(random_tree(seed, n, chain=chain)))
        kinds |= {link.kind for link in model.links}
    assert kinds == {"revolute", "prismatic"}


@pytest.mark.parametrize("seed, n, chain", CASES)
def test_the_three_methods_form_the_same_model(seed, n, chain):
    model = ChainModel.from_model(hx.assemble(random_tree(seed, n, chain=chain)))
    q, q_d, _ = _state(seed, model.dof)
    W0, V0 = model.matrices(q, q_d)  # Part I, the vectorised form of hexapod.minimal.chain
    for method in rm.METHODS:
        W, V = rm.form(model.layout, q, q_d, method)  # "basic": the same arithmetic as the rest
        assert _close(W, W0), method
        assert _close(V, V0), method
        assert np.array_equal(W, W.T), method  # half formed, half by symmetry
        if method != "basic":
            W1, V1 = model.matrices(q, q_d, method=method)
            assert np.array_equal(W1, W) and np.array_equal(V1, V)
    assert np.linalg.eigvalsh(W0).min() > 0


def _engine_effort(seed, n, chain, q, q_d, q_dd):
    """The engine's driving efforts with every joint driven through (q, q_d, q_dd) at t = 0."""
    scene = random_tree(seed, n, chain=chain)
    for k in range(n):
        scene.drivers[f"d{k}"].law = hx.scene.Polynomial([q[k], q_d[k], q_dd[k] / 2])
    model = hx.assemble(scene)
    data = model.create_data()
    x = hx.assemble_positions(model, data, 0.0)
    v = hx.solve_velocities(model, data, 0.0, x)
    hx.forward_dynamics(model, data, 0.0, x, v)
    return hx.joint_wrenches(model, data, frame="world").effort


@pytest.mark.parametrize("seed, n, chain", [CASES[1], CASES[2]])
def test_w_and_v_of_every_method_equal_the_engines(seed, n, chain):
    """The engine's inverse dynamics P(q_dd) = W q_dd - V at q_dd = 0 and at the unit vectors
    gives V and every column of W; each method's W and V equal them to 1e-10."""
    model = ChainModel.from_model(hx.assemble(random_tree(seed, n, chain=chain)))
    assert model.dof == n
    q, q_d, _ = _state(seed, n)
    V = -_engine_effort(seed, n, chain, q, q_d, np.zeros(n))
    W = np.column_stack([_engine_effort(seed, n, chain, q, q_d, unit) + V
                         for unit in np.eye(n)])
    for method in rm.METHODS:
        W_m, V_m = model.matrices(q, q_d, method=method)
        assert _close(W_m, W), method
        assert _close(V_m, V), method


@pytest.mark.parametrize("seed, n, chain", CASES[3:])
def test_inverse_dynamics_of_every_method_equal_the_engines(seed, n, chain):
    model = ChainModel.from_model(hx.assemble(random_tree(seed, n, chain=chain)))
    q, q_d, q_dd = _state(seed, n)
    effort = _engine_effort(seed, n, chain, q, q_d, q_dd)
    for method in rm.METHODS:
        assert _close(model.inverse(q, q_d, q_dd, method=method), effort), method


@pytest.mark.parametrize("seed, n, chain", CASES)
def test_forward_and_inverse_dynamics_are_inverse_of_each_other(seed, n, chain):
    model = ChainModel.from_model(hx.assemble(random_tree(seed, n, chain=chain, driven=False)))
    q, q_d, q_dd = _state(seed, model.dof)
    for method in rm.METHODS:
        P = model.inverse(q, q_d, q_dd, method=method)
        assert _close(model.forward(q, q_d, P, method=method), q_dd), method
        for other in rm.METHODS:  # and across methods
            assert _close(model.inverse(q, q_d, model.forward(q, q_d, P, method=other),
                                        method=method), P), (method, other)


def test_unknown_method_is_refused():
    model = ChainModel.from_model(hx.assemble(random_tree(21, 2, chain=True)))
    with pytest.raises(ValueError, match="unknown method"):
        model.matrices(np.zeros(2), np.zeros(2), method="kane")


# ---------------------------------------------------------------- the counting instrument


def test_counter_counts_known_expressions():
    a, b = rm.counted([1.0, 2.0, 3.0]), rm.counted([4.0, -5.0, 6.0])
    with rm.counting() as tally:
        d = rm._dot(a, b)
    assert (tally.mul, tally.add, tally.fun) == (3, 2, 0)
    assert float(d) == 12.0
    with rm.counting() as tally:
        c = rm._cross(a, b)
    assert (tally.mul, tally.add) == (6, 3)
    assert np.array_equal(rm.values(c), np.cross([1.0, 2.0, 3.0], [4.0, -5.0, 6.0]))
    R = rm.counted(np.arange(9.0).reshape(3, 3))
    with rm.counting() as tally:
        rm._matvec(R, a)
        rm._cos(a[0])
    assert (tally.mul, tally.add, tally.fun) == (9, 6, 1)
    # constants: products of plain numbers are not counted, nor exact zeros and ones
    with rm.counting() as tally:
        x = 2.0 * 3.0 + a[0] * 0.0 + a[1] * 1.0 + 0.0
        y = a[2] * 2.5 - 1.0
        z = a[0] / b[0]
    assert (tally.mul, tally.add) == (2, 2)  # a[2] * 2.5, a[0] / b[0]; 6.0 + a[1], y - 1.0
    assert (float(x), float(y), float(z)) == (8.0, 6.5, 0.25)
    with rm.counting() as outer:
        with rm.counting() as inner:
            a[0] * b[0]
        a[0] + b[0]
    assert (inner.mul, inner.add, outer.mul, outer.add) == (1, 0, 0, 1)


def test_counted_runs_give_the_float_results():
    model = ChainModel.from_model(hx.assemble(random_tree(23, 5, chain=False)))
    q, q_d, _ = _state(23, model.dof)
    for method in rm.METHODS:
        W, V = rm.form(model.layout, q, q_d, method)
        Wc, Vc = rm.form(model.layout, rm.counted(q), rm.counted(q_d), method)
        assert _close(rm.values(Wc), W, 1e-13) and _close(rm.values(Vc), V, 1e-13)


def test_operation_counts_grow_as_the_methods_predict():
    """Forming by Lagrange with Christoffel symbols is O(n^4) on a chain; the basic theorems
    and Gibbs-Appell are O(n^3) at most; counts do not depend on the state."""
    chain_scene = load_script("scripts/papers/seed000_efficiency.py").chain_scene

    counts = {}
    for n in (4, 8, 16):
        layout = ChainModel.from_model(hx.assemble(chain_scene(n))).layout
        for method in rm.METHODS:
            counts[n, method] = rm.count_operations(layout, method)
            assert counts[n, method].fun == 2 * n  # one sine and one cosine per joint
    again = rm.count_operations(layout, "lagrange", q=np.full(16, 0.3), q_d=np.ones(16))
    assert again == counts[16, "lagrange"]
    for method in rm.METHODS:
        slope = np.log2(counts[16, method].mul / counts[8, method].mul)
        if method == "lagrange":
            assert 3.3 < slope < 4.0
        else:
            assert 1.5 < slope < 3.0
        assert counts[16, "lagrange"].mul > 10 * counts[16, method].mul or method == "lagrange"


def test_efficiency_script_writes_csv_and_figures(tmp_path):
    seed000_efficiency = load_script("scripts/papers/seed000_efficiency.py")

    result = seed000_efficiency.main(["--out", str(tmp_path), "--count-sizes", "1", "2", "3",
                                      "--time-sizes", "1", "3", "--repeats", "1"])
    names = {p.name for p in result["files"]}
    assert names == {"seed000_efficiency.csv", "seed000_operations.png", "seed000_cpu_time.png"}
    lines = (tmp_path / "seed000_efficiency.csv").read_text().splitlines()
    assert lines[0] == "n,method,mul,add,fun,cpu_ms"
    assert len(lines) == 1 + 3 * 3 + 2 * 2  # counted rows (3 of which timed too) + timed only
    assert any(line.startswith("3,engine,,,,") for line in lines)
