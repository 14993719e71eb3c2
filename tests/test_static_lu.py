"""The LU factorisation with fixed pivots written as CasADi expressions
(``hexapod/algorithms/static_lu.py``), against the definition: ``A x = b`` and ``A^T x = b``
hold to round-off for sparse matrices with fill-in, and SuperLU's pivots are kept.

Tolerance: the matrices are diagonally weighted random sparse matrices of norm ~10 with
partial pivoting; the residuals of a backward-stable solve are a few hundred units of
round-off of ``|A| |x|``; 1e-11 leaves a margin of about 100 over what is found (4e-14)."""

import casadi as ca
import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms.static_lu import StaticLU, steady


@pytest.mark.parametrize("n", [1, 5, 30, 80])
def test_solves_and_transposed_solves_meet_their_equations(n):
    rng = np.random.default_rng(n)
    A = rng.normal(size=(n, n)) * (rng.random((n, n)) < 0.15) + 3.0 * np.eye(n)
    A[0, -1] = A[-1, 0] = 1.0  # a fill-in across the whole matrix
    rows, columns = np.nonzero(A)
    lu = StaticLU.pivoted(rows, columns, n, A[rows, columns])
    assert lu.nnz >= rows.size  # fill-in included
    values, b = ca.SX.sym("values", rows.size), ca.SX.sym("b", n)
    factors = lu.factor(values)
    solve = ca.Function("solve", [values, b], [lu.solve(factors, b),
                                                lu.solve(factors, b, transpose=True)])
    for _ in range(3):
        entries = A[rows, columns] * (1 + 0.1 * rng.normal(size=rows.size))  # same pattern
        M = np.zeros((n, n))
        M[rows, columns] = entries
        rhs = rng.normal(size=n)
        x, xt = (np.array(out).ravel() for out in solve(entries, rhs))
        scale = np.abs(M).max() * max(np.abs(x).max(), np.abs(xt).max())
        assert np.abs(M @ x - rhs).max() <= 1e-11 * scale
        assert np.abs(M.T @ xt - rhs).max() <= 1e-11 * scale


@pytest.mark.parametrize("n", [5, 30, 80])
def test_the_levelled_elimination_is_the_pivot_by_pivot_one_bit_for_bit(n):
    """The factors, built level by level, are those of the textbook right-looking elimination
    in the pivots' order (the same operations in the same order per entry), on numbers."""
    rng = np.random.default_rng(10 + n)
    A = rng.normal(size=(n, n)) * (rng.random((n, n)) < 0.15) + 3.0 * np.eye(n)
    A[0, -1] = A[-1, 0] = 1.0
    rows, columns = np.nonzero(A)
    lu = StaticLU.pivoted(rows, columns, n, A[rows, columns])
    values = ca.SX.sym("values", rows.size)
    factor = ca.Function("factor", [values], [lu.factor(values)])
    entries = A[rows, columns] * (1 + 0.1 * rng.normal(size=rows.size))
    F = np.zeros(lu.nnz)
    F[lu._entries] = entries
    at = lu._at
    for k in range(n):  # pivot by pivot: the column divided, then the rank-one update
        below = [i for i in range(k + 1, n) if k in at[i]]
        for i in below:
            F[at[i][k]] /= F[at[k][k]]
        for i in below:
            for j in (j for j in lu.structure[k] if j > k):
                F[at[i][j]] -= F[at[i][k]] * F[at[k][j]]
    assert np.array_equal(np.array(factor(entries)).ravel(), F)
    assert len(lu._eliminations) < n  # fewer vector operations than pivots


def _saddle_matrix(model):
    """The pattern and values of the integrators' saddle-point matrix (the kept rows of the
    equilibrated ``Phi_v``, :func:`~hexapod.algorithms.step.kept_matrix`) at the start."""
    from hexapod.algorithms.step import equilibrated, kept_matrix, mass_factors
    from hexapod.simulation.integrators import DormandPrince853

    method = DormandPrince853(model, 0.0, 0.1)
    symbols = {"q": ca.SX.sym("q", model.n_q), "w": ca.SX.sym("w", model.n_w)}
    Phi_v = model.Phi_v(*[symbols[n] for n in model.Phi_v.name_in()])
    K = kept_matrix(*equilibrated(Phi_v, mass_factors(model)[0]),
                    method._compiled.rows.tolist())
    w = model.law_values(0.0)[0] if model.n_w else np.zeros(0)
    values = np.array(ca.Function("K", list(symbols.values()), [K])(method.q, w).nonzeros())
    rows, columns = K.sparsity().get_triplet()
    return np.array(rows), np.array(columns), K.size1(), values


def _assert_solves(lu, rows, columns, n, values):
    """The pivots ``lu`` solve the matrix of this pattern and these values to round-off."""
    entries, b = ca.SX.sym("values", rows.size), ca.SX.sym("b", n)
    x = np.array(ca.Function("solve", [entries, b], [lu.solve(lu.factor(entries), b)])(
        values, np.ones(n))).ravel()
    K = np.zeros((n, n))
    K[rows, columns] = values
    assert np.abs(K @ x - 1.0).max() <= 1e-10 * np.abs(K).max() * np.abs(x).max()


def test_round_off_in_the_values_does_not_move_the_pivots():
    """Entries equal in exact arithmetic (here, blocks [[a, a], [a, -a]] whose first column
    ties) differ by round-off from one computation to the next; the pivots are chosen on the
    values rounded to 26 bits (``steady``), so noise of 1e-15 leaves them where they were
    (without the rounding SuperLU follows the noise: several orders in ten tries, checked
    too), and the chosen pivots factor the noisy values."""
    from scipy.sparse import csc_array
    from scipy.sparse.linalg import splu

    rng = np.random.default_rng(3)
    blocks = 40
    scales = rng.uniform(0.5, 2.0, blocks)
    rows = np.concatenate([[2 * k, 2 * k + 1, 2 * k, 2 * k + 1] for k in range(blocks)])
    columns = np.concatenate([[2 * k, 2 * k, 2 * k + 1, 2 * k + 1] for k in range(blocks)])
    exact = np.concatenate([[a, a, a, -a] for a in scales])
    orders, raw = set(), set()
    for _ in range(10):
        noisy = exact * (1 + 1e-15 * rng.standard_normal(exact.size))
        lu = StaticLU.pivoted(rows, columns, 2 * blocks, noisy)
        orders.add((lu.row_order.tobytes(), lu.column_order.tobytes()))
        assert np.isfinite(lu.growth(noisy))
        A = csc_array((noisy, (rows, columns)), shape=(2 * blocks, 2 * blocks))
        raw.add(splu(A, permc_spec="COLAMD").perm_r.tobytes())
    assert len(orders) == 1
    assert len(raw) > 1  # what the rounding is for


@pytest.mark.parametrize("scene", ["chain", "hexapod-standing"])
def test_the_pivots_are_those_of_the_cheaper_order(scene):
    """``pivoted`` takes the pivots of the order whose elimination costs fewer operations
    (COLAMD's, or the minimum degree of ``A^T + A``), by an estimate from SuperLU: the choice
    is the one the written-out elimination's own count (:class:`StaticLU`'s symbolic
    factorisation, independent of that estimate) makes, on a chain of 10 links (where COLAMD
    wins, 4,525 multiply-adds against 19,309) and on the robot standing on its six feet (where
    the minimum degree does, 39,310 against 46,474), and its solves meet their equations."""
    from robots import builtin_model
    from scipy.sparse import csc_array
    from scipy.sparse.linalg import splu

    from mechanisms import random_tree

    model = (hx.assemble(random_tree(7, 10, chain=True, driven=False)) if scene == "chain"
             else builtin_model(scene))
    rows, columns, n, values = _saddle_matrix(model)
    A = csc_array((steady(values), (rows, columns)), shape=(n, n))  # what the choice reads
    counts = []
    for order in ({"permc_spec": "COLAMD"},
                  {"permc_spec": "MMD_AT_PLUS_A", "diag_pivot_thresh": 0.1,
                   "options": {"SymmetricMode": True}}):
        lu = splu(A, **order)
        candidate = StaticLU(rows, columns, n, np.argsort(lu.perm_r), np.argsort(lu.perm_c))
        counts.append((sum(len(level[2]) for level in candidate._eliminations),
                       order["permc_spec"], candidate))
    (cheap, name, best), (dear, _, _) = sorted(counts, key=lambda c: c[0])
    assert cheap < dear and name == ("COLAMD" if scene == "chain" else "MMD_AT_PLUS_A")
    chosen = StaticLU.pivoted(rows, columns, n, values)
    assert np.array_equal(chosen.row_order, best.row_order)
    assert np.array_equal(chosen.column_order, best.column_order)
    _assert_solves(chosen, rows, columns, n, values)


def test_the_tree_order_factors_any_state_and_fills_less_than_superlus():
    """:func:`~hexapod.algorithms.step.tree_order` (the articulated-body recursion's order of
    the saddle-point matrix, each body's velocities after its children, then its joint's rows)
    is a valid set of pivots whatever the values: the solves meet their equations at the start
    and with the rows' entries perturbed by a tenth; on a tree of 10 bodies its elimination
    fills no more than SuperLU's cheaper order chosen at the start; a loop-closing joint's rows
    have no place in it (None)."""
    from hexapod.algorithms.step import tree_order
    from hexapod.simulation.integrators import DormandPrince853

    from mechanisms import four_bar, random_tree

    model = hx.assemble(random_tree(3, 10, driven=False))
    kept = DormandPrince853(model, 0.0, 0.1)._compiled.rows
    rows, columns, n, values = _saddle_matrix(model)
    order = tree_order(model, kept)
    assert sorted(order.tolist()) == list(range(n))
    lu = StaticLU(rows, columns, n, order, order)
    assert lu.nnz <= StaticLU.pivoted(rows, columns, n, values).nnz
    entries, b = ca.SX.sym("values", rows.size), ca.SX.sym("b", n)
    solve = ca.Function("solve", [entries, b], [lu.solve(lu.factor(entries), b)])
    rng = np.random.default_rng(0)
    for scale in (0.0, 0.1, 0.1):
        perturbed = values * (1 + scale * rng.normal(size=values.size) * (rows != columns))
        K = np.zeros((n, n))
        K[rows, columns] = perturbed
        rhs = rng.normal(size=n)
        x = np.array(solve(perturbed, rhs)).ravel()
        assert np.abs(K @ x - rhs).max() <= 1e-11 * np.abs(K).max() * np.abs(x).max()
    loop = hx.assemble(four_bar(3, 0.3))
    assert tree_order(loop, np.arange(loop.n_c)) is None


@pytest.mark.parametrize("chain", [False, True])
def test_kernels_take_the_tree_order_where_it_is_cheaper(chain):
    """The integrators' kernels weigh the body-joint tree's order with SuperLU's
    (:func:`~hexapod.algorithms.step.kept_pivots`): on a tree of 10 bodies it writes fewer
    operations and is taken, on a chain of 10 links COLAMD's writes fewer and is kept; the
    pivots taken solve the matrix to round-off."""
    from hexapod.algorithms.static_lu import _operations
    from hexapod.algorithms.step import kept_pivots, tree_order
    from hexapod.simulation.integrators import DormandPrince853

    from mechanisms import random_tree

    model = hx.assemble(random_tree(3 if not chain else 7, 10, chain=chain, driven=False))
    method = DormandPrince853(model, 0.0, 0.1)
    kept = method._compiled.rows
    rows, columns, n, values = _saddle_matrix(model)  # at the method's start, as below
    order = tree_order(model, kept)
    superlu = StaticLU.pivoted(rows, columns, n, values)
    tree_cheaper = (_operations(rows, columns, n, order, order)
                    < _operations(rows, columns, n, superlu.row_order, superlu.column_order))
    assert tree_cheaper == (not chain)
    chosen = kept_pivots(model, kept.tolist(), method.q, np.zeros(model.n_w))
    taken = order if tree_cheaper else superlu.row_order
    assert np.array_equal(chosen.row_order, taken)
    _assert_solves(chosen, rows, columns, n, values)
