"""The saddle-point solves of large models (:mod:`hexapod.algorithms.saddle`) against the paths
they replace: the sparse, linear-cost forward solve and rank decision against the dense ones
(the same accelerations, multipliers and row split to round-off on chains, trees, closed loops
and redundant mechanisms), the compiled kernels' sparse factorisation against the exact solve,
and the structure that keeps their cost linear (no node of a kernel, and no factor, denser
than a constant per body). Forced on models small enough for both paths."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms import linalg, rows, saddle, sparse_qr, step
from hexapod.algorithms.kinematics import rank_split
from hexapod.benchmarks import n_four_bar
from hexapod.benchmarks.redundant import bricard
from hexapod.simulation.kernels import compiled_projection, compiled_rates, row_gram

from mechanisms import four_bar, random_tree

SCENES = {
    "chain of 40": lambda: random_tree(7, 40, chain=True, driven=False),
    "driven tree of 30": lambda: random_tree(8, 30),
    "closed loop (planar N-four-bar)": lambda: n_four_bar(4, start_angle=0.3).scene,
    "redundant loop (four-bar in 3-D)": lambda: four_bar(3, 0.7, driven=False),
    "Bricard": lambda: bricard().scene,
    "spatial N-four-bar (loops, redundant)": lambda: n_four_bar(3, dimension=3,
                                                                start_angle=0.3).scene,
}


@pytest.fixture
def sparse_path(monkeypatch):
    """Every model takes the sparse path (as a large one does)."""
    monkeypatch.setattr(sparse_qr, "SPARSE_ABOVE", 0)
    monkeypatch.setattr(sparse_qr, "SPARSE_DENSITY", 2.0)


def _state(model, t=0.1, seed=0):
    data = model.create_data()
    q = hx.assemble_positions(model, data, t)
    guess = np.random.default_rng(seed).normal(size=model.n_v)
    return q, hx.solve_velocities(model, data, t, q, guess)


def _close(a, b, rel=1e-10):
    scale = max(np.abs(b).max(initial=0.0), 1e-300)
    return np.abs(np.asarray(a) - np.asarray(b)).max(initial=0.0) <= rel * scale


@pytest.mark.parametrize("name", SCENES)
def test_the_sparse_forward_solve_equals_the_dense_one(name, monkeypatch):
    """Accelerations, multipliers (the least-wrench policy's where rows are redundant), the
    rows kept and left out: the sparse QR of the sparse ``W`` against the dense QR."""
    model = hx.assemble(SCENES[name]())
    q, v = _state(model)
    dense = model.create_data()
    hx.forward_dynamics(model, dense, 0.1, q, v)
    assert not linalg.is_sparse(dense.Phi_v)
    monkeypatch.setattr(sparse_qr, "SPARSE_ABOVE", 0)
    monkeypatch.setattr(sparse_qr, "SPARSE_DENSITY", 2.0)
    assert saddle.is_large(model)
    data = model.create_data()
    hx.forward_dynamics(model, data, 0.1, q, v)
    assert linalg.is_sparse(data.Phi_v)  # never written densely
    assert np.array_equal(data.Phi_v.toarray(), dense.Phi_v)
    assert np.array_equal(np.sort(data.independent_rows), np.sort(dense.independent_rows))
    assert np.array_equal(np.sort(data.redundant_rows), np.sort(dense.redundant_rows))
    if name in ("redundant loop (four-bar in 3-D)", "Bricard",
                "spatial N-four-bar (loops, redundant)"):
        assert data.redundant_rows.size  # the policy applies
    assert _close(data.v_dot, dense.v_dot)
    assert _close(data.lam, dense.lam, 1e-8)  # the policy: a least-squares problem on top
    # the forces the multipliers exert balance the equations (the policy changes none)
    balance = model.mass @ data.v_dot + data.Phi_v.T @ data.lam - data.Q
    assert np.abs(balance).max() <= 1e-9 * max(np.abs(data.Q).max(), 1.0)


@pytest.mark.parametrize("name", ["chain of 40", "closed loop (planar N-four-bar)", "Bricard"])
def test_the_sparse_kinematics_equal_the_dense_ones(name, monkeypatch):
    model = hx.assemble(SCENES[name]())
    rng = np.random.default_rng(3)
    guess = model.integrate(model.q0, 1e-3 * rng.normal(size=model.n_v))
    v_guess = rng.normal(size=model.n_v)
    results = []
    for forced in (False, True):
        if forced:
            monkeypatch.setattr(sparse_qr, "SPARSE_ABOVE", 0)
            monkeypatch.setattr(sparse_qr, "SPARSE_DENSITY", 2.0)
        data = model.create_data()
        q = hx.assemble_positions(model, data, 0.1, guess)
        v = hx.solve_velocities(model, data, 0.1, q, v_guess)
        results.append((q, v, hx.degrees_of_freedom(model, data, 0.1, q)))
    (q0, v0, dof0), (q1, v1, dof1) = results
    # Newton's method stops within 1e-12 of the constraints: two rank paths, two such points
    # (Bricard's redundant row: 1.7e-12 apart)
    assert np.abs(q1 - q0).max() < 1e-10 and _close(v1, v0, 1e-9)
    assert dof1 == dof0


@pytest.mark.parametrize("name", ["chain of 40", "closed loop (planar N-four-bar)"])
def test_the_smallest_singular_value_of_a_sparse_split_is_the_dense_one(name, sparse_path):
    model = hx.assemble(SCENES[name]())
    q, _ = _state(model)
    Phi_v = saddle.constraint_jacobian(model, q, model.law_values(0.1)[0])
    sparse = rank_split(model, Phi_v, model.law_values(0.1)[0])
    assert isinstance(sparse, linalg.SparseRowSplit)
    dense = np.linalg.svd(sparse.W[sparse.independent].toarray(), compute_uv=False).min()
    assert sparse.smallest_singular_value() == pytest.approx(dense, rel=1e-6)


@pytest.mark.parametrize("name", ["closed loop (planar N-four-bar)", "Bricard",
                                  "spatial N-four-bar (loops, redundant)"])
@pytest.mark.parametrize("sparse", [False, True])
def test_a_split_tells_a_bound_below_its_smallest_singular_value(name, sparse, monkeypatch):
    """``smallest_exceeds`` (a Cholesky factorisation of the Gram matrix shifted, for the
    integrators' test of a singular pose) agrees with the SVD's value: true for bounds below
    it by more than the certificate's margin (a thousandth, and round-off), false for every
    bound at or above it (a large model's, by ARPACK's value); near a pose (its value 1e-4 of
    the standing one) likewise."""
    if sparse:
        monkeypatch.setattr(sparse_qr, "SPARSE_ABOVE", 0)
        monkeypatch.setattr(sparse_qr, "SPARSE_DENSITY", 2.0)
    for model in (hx.assemble(SCENES[name]()),
                  hx.assemble(n_four_bar(4, start_angle=np.pi / 2 - 1e-4, start_rate=0.0).scene)):
        q, _ = _state(model, 0.0)
        w = model.law_values(0.0)[0]
        split = rank_split(model, saddle.constraint_jacobian(model, q, w), w)
        kept = split.W[split.independent]
        smallest = np.linalg.svd(kept.toarray() if hasattr(kept, "toarray") else kept,
                                 compute_uv=False).min()
        for factor in (0.5, 0.99):
            assert split.smallest_exceeds(factor * smallest), (name, factor)
        for factor in (1.001 if sparse else 1.0, 1.01, 2.0):  # ARPACK's: to 1e-5
            assert not split.smallest_exceeds(factor * smallest), (name, factor)
    assert split.smallest_exceeds(0.0) and smallest < 1e-3


@pytest.mark.parametrize("name", ["chain of 40", "closed loop (planar N-four-bar)", "Bricard"])
def test_the_gram_certificate_of_every_row_agrees_with_the_svd(name):
    """``gram_exceeds`` on ``W W^T`` (the integrators' check of a rejected step where every
    row is kept, without a rank decision) says what the SVD of the whole ``W`` says: true for
    bounds below its smallest singular value by more than the margin, false at or above it;
    where rows are dependent (Bricard's linkage: redundant) it is never true above zero, so
    the rank decision decides there. ``row_gram`` (one call) gives that ``W W^T``."""
    model = hx.assemble(SCENES[name]())
    q, _ = _state(model, 0.0)
    w = model.law_values(0.0)[0]
    W, _ = linalg.equilibrate(saddle.constraint_jacobian(model, q, w), model.mass_inv_sqrt)
    gram, smallest = W @ W.T, np.linalg.svd(W, compute_uv=False).min()
    # the integrators' one call gives the same product (rows of unit length: entries <= 1)
    assert np.abs(row_gram(model, None, q, w) - gram).max() <= 1e-14
    for factor in (0.5, 0.99):
        assert rows.gram_exceeds(gram, factor * smallest, model.n_v) == (smallest > 1e-6), name
    for factor in (1.0, 1.01, 2.0):
        assert not rows.gram_exceeds(gram, factor * smallest, model.n_v), (name, factor)
    assert not rows.gram_exceeds(gram, 1e-7, model.n_v) or smallest > 1e-7
    if name == "Bricard":
        assert smallest < 1e-9  # the case of dependent rows

def test_the_least_norm_psd_solve_is_the_least_squares_one():
    """``least_norm_psd`` (a time step's contact solves: Cholesky where the shifted matrix is
    positive definite) gives ``lstsq``'s least-norm solution, with singular values below
    ``rcond`` dropped as it drops them: on a well-conditioned Delassus-like matrix (by
    Cholesky), on a rank-deficient one (four contacts of one rigid block, 12 x 12 of rank 6:
    by least squares, the load shared) and on one just below and above the threshold."""
    rng = np.random.default_rng(3)
    B = rng.standard_normal((12, 12))
    corners = rng.standard_normal((12, 6))  # four contacts of 3 rows on 6 dofs
    for A in (B @ B.T, corners @ corners.T):
        for b in (rng.standard_normal(12), A @ rng.standard_normal(12)):
            reference = np.linalg.lstsq(A, b, rcond=1e-12)[0]
            x = linalg.least_norm_psd(A, b)
            assert np.abs(x - reference).max() <= 1e-9 * np.abs(reference).max()
    U = np.linalg.qr(B)[0]
    for smallest, kept in ((1e-13, False), (1e-11, True)):  # eigenvalues: 1 ... smallest
        A = U @ np.diag(np.r_[np.linspace(1.0, 0.1, 11), smallest]) @ U.T
        b = U[:, -1] + U[:, 0]
        x = linalg.least_norm_psd(A, b, rcond=1e-12)
        # the last eigenvector's part is 1 / smallest when kept, none when dropped
        assert (U[:, -1] @ x) == pytest.approx(1 / smallest if kept else 0.0, abs=1e-3,
                                               rel=1e-4)  # its round-off: 1e-16 / smallest
    assert linalg.least_norm_psd(np.zeros((0, 0)), np.zeros(0)).shape == (0,)


def test_near_a_singular_pose_the_smallest_singular_value_is_found_to_round_off(sparse_path):
    """The integrators take differences of it along the motion there: ARPACK's value is
    refined below 1e-3."""
    model = hx.assemble(n_four_bar(4, start_angle=np.pi / 2 - 1e-4, start_rate=0.0).scene)
    q, _ = _state(model, 0.0)
    w = model.law_values(0.0)[0]
    split = rank_split(model, saddle.constraint_jacobian(model, q, w), w)
    dense = np.linalg.svd(split.W[split.independent].toarray(), compute_uv=False).min()
    assert dense < 1e-3
    assert split.smallest_singular_value() == pytest.approx(dense, rel=1e-9)


def test_a_run_on_the_sparse_path_is_the_dense_run(monkeypatch):
    """DOP853 on a chain and DOPRI5 through the N-four-bar's flat pose (a crossing: the rank
    split, the smallest singular value and the rows left out all from the sparse QR): the same
    steps and states as on the dense path, to round-off."""
    runs = []
    for forced in (False, True):
        if forced:
            monkeypatch.setattr(sparse_qr, "SPARSE_ABOVE", 0)
            monkeypatch.setattr(sparse_qr, "SPARSE_DENSITY", 2.0)
        chain = hx.assemble(SCENES["chain of 40"]())
        first = hx.simulate(chain, 0.05, method="dop853-projection", rtol=1e-8, atol=1e-10)
        case = n_four_bar(3, t_end=1.0)
        model = hx.assemble(case.scene)
        second = hx.simulate(model, 1.0, rtol=1e-10, atol=1e-12)
        assert first.success and second.success, (first.message, second.message)
        assert second.counters.crossings >= 1
        runs.append((first, second, case.error(model, second.t, second.q)))
    (chain0, four0, error0), (chain1, four1, error1) = runs
    assert chain0.counters.steps == chain1.counters.steps
    assert np.abs(chain1.q[-1] - chain0.q[-1]).max() < 1e-12
    assert four1.counters.crossings == four0.counters.crossings
    assert error1 < 1e-8 and abs(error1 - error0) < 1e-9


# ------------------------------------------------------------------ the compiled kernels

@pytest.mark.parametrize("name", SCENES)
def test_the_kernels_sparse_factorisation_equals_the_exact_solve(name):
    model = hx.assemble(SCENES[name]())
    q, v = _state(model, seed=1)
    data = model.create_data()
    exact = hx.forward_dynamics(model, data, 0.1, q, v)
    rates = compiled_rates(model, data.independent_rows)
    solution = rates.solve(0.1, q, v)
    assert solution is not None
    assert _close(solution[1], exact, 1e-9)
    if rates.complete:
        assert _close(solution[2], data.lam, 1e-9)
    rng = np.random.default_rng(2)
    drifted = model.integrate(q, 1e-8 * rng.normal(size=model.n_v))
    projected = compiled_projection(model, data.independent_rows)(0.1, drifted, v)
    assert projected is not None
    w = model.law_values(0.1)[0]
    assert np.abs(model.call("phi", q=projected[0], w=w) / model.row_scale).max() < 1e-12


def _largest_node(function: ca.Function) -> int:
    """The most nonzeros any instruction of a CasADi MX Function produces."""
    largest = 0
    for k in range(function.n_instructions()):
        try:
            largest = max(largest, function.instruction_MX(k).nnz())
        except RuntimeError:  # instructions without an expression (outputs)
            continue
    return largest


def test_no_node_of_the_kernels_grows_faster_than_the_bodies():
    """Scaling the rows by a repeated matrix of their norms made a dense n_c x n_v node (2.7
    million entries per call for a 300-body chain); every node is now as sparse as
    ``Phi_v`` or the saddle-point matrix."""
    for n in (20, 60):
        model = hx.assemble(random_tree(7, n, chain=True, driven=False))
        rows = np.arange(model.n_c)
        size = model.n_v + model.n_c
        for kernel in (compiled_rates(model, rows), compiled_projection(model, rows)):
            function = getattr(kernel, "function", None) or kernel._fast.function
            assert _largest_node(function) <= 10 * size


@pytest.mark.parametrize("name", ["chain of 40", "driven tree of 30",
                                  "closed loop (planar N-four-bar)",
                                  "spatial N-four-bar (loops, redundant)"])
def test_the_kernels_factors_hold_a_constant_per_row(name):
    """CasADi's sparse QR of the saddle-point matrix, columns ordered by approximate minimum
    degree: on the body-joint graph its factors hold a few tens of nonzeros per row (a dense
    factor would hold half the rows': 110 to 250 here, 1650 for a 300-body chain)."""
    model = hx.assemble(SCENES[name]())
    q = ca.MX.sym("q", model.n_q)
    w = ca.MX.sym("w", model.n_w)
    Phi_v = model.Phi_v(*([q, w] if model.n_w else [q]))
    m_inv_sqrt, m_sqrt = step.mass_factors(model)
    assert np.allclose((m_inv_sqrt @ m_sqrt).full(), np.eye(model.n_v))
    W_all, d, zero = step.equilibrated(Phi_v, m_inv_sqrt)
    K = step.kept_matrix(W_all, d, zero, list(range(model.n_c)))
    V, R, _, _ = K.sparsity().qr_sparse(True)
    assert (V.nnz() + R.nnz()) / K.size1() < 40


# ------------------------------------------------------------------ the implicit methods

@pytest.mark.parametrize("method", ["generalized-alpha", "rattle", "radau5-ggl"])
@pytest.mark.parametrize("name", ["chain of 40", "Bricard"])
def test_an_implicit_method_on_the_sparse_path_is_the_dense_run(method, name, monkeypatch):
    """Newton's systems assembled and factorised sparse (SuperLU, COLAMD), the multipliers
    carried onto the kept rows through the sparse QR: the same steps, states and multipliers
    (the redundancy policy's on Bricard) as the dense LU."""
    runs = []
    for forced in (False, True):
        if forced:
            monkeypatch.setattr(sparse_qr, "SPARSE_ABOVE", 0)
            monkeypatch.setattr(sparse_qr, "SPARSE_DENSITY", 2.0)
        model = hx.assemble(SCENES[name]())
        result = hx.simulate(model, 0.05, method=method, step=5e-3)
        assert result.success, result.message
        runs.append(result)
    dense, sparse = runs
    assert sparse.counters.as_dict() == dense.counters.as_dict()
    # Radau's simplified Newton stops at a fraction of its tolerance (rtol 1e-6 here), not at
    # round-off: two LU factorisations' round-off end up 3e-10 apart on the chain
    tolerance = 1e-8 if method == "radau5-ggl" else 1e-11
    assert np.abs(sparse.q - dense.q).max() < tolerance
    assert _close(sparse.lam, dense.lam, 1e-6 if method == "radau5-ggl" else 1e-8)
