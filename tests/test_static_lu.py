"""The LU factorisation with fixed pivots written as CasADi expressions
(``hexapod/algorithms/static_lu.py``), against the definition: ``A x = b`` and ``A^T x = b``
hold to round-off for sparse matrices with fill-in, and SuperLU's pivots are kept.

Tolerance: the matrices are diagonally weighted random sparse matrices of norm ~10 with
partial pivoting; the residuals of a backward-stable solve are a few hundred units of
round-off of ``|A| |x|``; 1e-11 leaves a margin of about 100 over what is found (4e-14)."""

import casadi as ca
import numpy as np
import pytest

from hexapod.algorithms.static_lu import StaticLU


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
