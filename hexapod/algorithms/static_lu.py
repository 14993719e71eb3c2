"""Sparse LU factorisation with pivots chosen once, written as CasADi SX expressions.

The compiled inverse dynamics of closed loops (:mod:`hexapod.algorithms.phase_plan`) solves
many systems with the kept rows ``J`` of the constraint Jacobian, whose sparsity pattern is
fixed while the kept rows are. SuperLU (through SciPy) factorises ``J`` at one sample with
partial pivoting and a fill-reducing column order; :class:`StaticLU` keeps those row and column
orders and writes the elimination for the pattern as straight-line SX code (``J = P_r^T L U
P_c^T``), so that every later factorisation costs only its arithmetic (for the walking hexapod,
about 1 400 multiply-adds: the tree structure of the legs leaves almost no fill, where a sparse
QR of the same matrix needs some 25 000 operations).

Pivots fixed in advance are not guaranteed to stay large as the matrix changes. The callers
therefore check every solve by its residual and by an estimate of the smallest singular value,
and redo a sample that fails with the exact, pivoting solve (the growth of the factors of the
hexapod's Jacobian over a whole stride with the pivots of its first sample stays below 1.8).
"""

from __future__ import annotations

import casadi as ca
import numpy as np


class StaticLU:
    """The LU factorisation of square matrices of one sparsity pattern, with fixed pivots.

    Parameters
    ----------
    rows, columns : ndarray of int
        The pattern: entry ``k`` of the values vector is ``A[rows[k], columns[k]]``.
    n : int
        The matrix is n x n.
    row_order, column_order : ndarray of int
        Pivot order: ``A[row_order][:, column_order] = L U``, ``L`` unit lower triangular.
    """

    def __init__(self, rows, columns, n: int, row_order, column_order):
        self.n = n
        self.rows = np.asarray(rows, dtype=int)
        self.columns = np.asarray(columns, dtype=int)
        self.row_order = np.asarray(row_order, dtype=int)
        self.column_order = np.asarray(column_order, dtype=int)
        self._pattern()

    @classmethod
    def pivoted(cls, rows, columns, n: int, values, orders=()) -> StaticLU:
        """The pattern ``(rows, columns)`` with the pivots SuperLU chooses for the matrix of
        these values, in the order of the two that costs fewer operations: partial pivoting
        with COLAMD's column order, or threshold pivoting (0.1, SuperLU's advice for a pattern
        near symmetric) with the minimum degree order of ``A^T + A``. Neither wins everywhere:
        on the integrators' saddle-point matrices the second wrote a quarter fewer operations
        for the 18-joint robot (its run to 1e-6: 51 -> 38 ms of CPU) and twice as many for a
        chain of 10 links; the checks of every solve catch pivots the matrix has outgrown.
        ``orders``: symmetric pivot orders weighed with them (the body-joint tree's,
        :func:`~hexapod.algorithms.step.tree_order`), each taken where it costs fewer
        operations still and factors these values (no zero pivot). The pivots are chosen on the
        values rounded (:func:`steady`), so that round-off in them does not decide a tie
        between equal candidates (the legs of a symmetric robot): the same matrix gives the
        same pivots, and the same compiled code, whatever its last bits."""
        from scipy.sparse import csc_array
        from scipy.sparse.linalg import splu

        rows, columns = np.asarray(rows, dtype=int), np.asarray(columns, dtype=int)
        A = csc_array((steady(values), (rows, columns)), shape=(n, n))
        superlu_orders = ({"permc_spec": "COLAMD"},
                          {"permc_spec": "MMD_AT_PLUS_A", "diag_pivot_thresh": 0.1,
                           "options": {"SymmetricMode": True}})
        # P_r A P_c = L U with (P_r A)[perm_r[i]] = A[i] and (A P_c)[:, perm_c[j]] = A[:, j]
        least, chosen = min(((_operations(rows, columns, n, *p), p) for p in (
            (np.argsort(lu.perm_r), np.argsort(lu.perm_c))
            for lu in (splu(A, **order) for order in superlu_orders))), key=lambda c: c[0])
        lu = cls(rows, columns, n, *chosen)
        lu.chosen_growth = lu.growth(values)  # what serves() measures others against
        for order in orders:
            cost = _operations(rows, columns, n, order, order)
            if cost < least:
                given = cls(rows, columns, n, order, order)
                growth = given.growth(values)
                if np.isfinite(growth):
                    lu, least = given, cost
                    lu.chosen_growth = growth
        return lu

    def growth(self, values) -> float:
        """The growth of these pivots' factors on the matrix of these values (of this
        pattern): the largest entry of ``U`` over the matrix's (what bounds a solve's error);
        ``inf`` where a pivot is zero."""
        values = np.asarray(values, dtype=float)
        try:
            lu = _in_order(self.rows, self.columns, self.n, self.row_order, self.column_order,
                           values)
        except RuntimeError:  # exactly singular with these pivots
            return float("inf")
        if not np.array_equal(lu.perm_r, np.arange(self.n)):
            return float("inf")  # a pivot of these was zero: SuperLU took another
        growth = float(abs(lu.U).max() / max(np.abs(values).max(), 1e-300))
        return growth if np.isfinite(growth) else float("inf")

    def serves(self, values, bound: float = 10.0) -> bool:
        """Whether these pivots serve the matrix of these values (of this pattern): their
        factors' growth there within ``bound`` times what it was on the matrix they were
        chosen for (:meth:`pivoted`). A kernel built with pivots chosen at another state keeps
        them (its compiled library too) where they serve."""
        chosen = getattr(self, "chosen_growth", None)
        if chosen is None:
            return False
        return self.growth(values) <= bound * chosen

    def _pattern(self) -> None:
        """The symbolic factorisation: the entries of ``L`` (strictly lower) and ``U`` in the
        permuted matrix, and the elimination's operations."""
        where_row = np.empty(self.n, dtype=int)
        where_row[self.row_order] = np.arange(self.n)
        where_column = np.empty(self.n, dtype=int)
        where_column[self.column_order] = np.arange(self.n)
        structure: list[set] = [set() for _ in range(self.n)]
        for i, j in zip(where_row[self.rows], where_column[self.columns], strict=True):
            structure[i].add(j)
        for i in range(self.n):
            structure[i].add(i)  # the diagonal (a structural zero there is a zero pivot)
        below: list[set] = [set() for _ in range(self.n)]  # rows with an entry in column k
        for i, row in enumerate(structure):
            for j in row:
                if j < i:
                    below[j].add(i)
        for k in range(self.n):
            upper = [j for j in structure[k] if j > k]
            for i in sorted(below[k]):
                for j in upper:
                    if j not in structure[i]:
                        structure[i].add(j)
                        if j < i:
                            below[j].add(i)
        self.structure = [sorted(row) for row in structure]
        self.nnz = sum(len(row) for row in self.structure)
        self._where_row, self._where_column = where_row, where_column
        self._positions()

    def _positions(self) -> None:
        """Where each factor entry lies in the packed vector (row by row, columns ascending),
        where each matrix entry goes there, the triangles' patterns (column-major, with the
        positions of their entries) and the elimination's operations by level
        (:func:`_levels`): the factorisation is then a few vector operations per level instead
        of one per entry."""
        self._at: list[dict[int, int]] = []
        k = 0
        for row in self.structure:
            self._at.append({j: k + m for m, j in enumerate(row)})
            k += len(row)
        at = self._at
        self._diagonal = np.array([at[i][i] for i in range(self.n)], dtype=int)
        self._entries = [at[i][j] for i, j in zip(self._where_row[self.rows],
                                                  self._where_column[self.columns], strict=True)]
        if len(set(self._entries)) != len(self._entries):
            raise ValueError("the pattern repeats an entry")
        self._triangles = (_sparsity(self.n, [(j, i, at[i][j]) for i, row in
                                              enumerate(self.structure) for j in row if j < i]),
                           _sparsity(self.n, [(j, i, at[i][j]) for i, row in
                                              enumerate(self.structure) for j in row if j >= i]))
        self._eliminations = _levels([
            ([i for i in range(k + 1, self.n) if k in at[i]],
             [j for j in self.structure[k] if j > k]) for k in range(self.n)], at)

    def factor(self, values: ca.SX) -> ca.SX:
        """The factors of the matrix with these values (SX, one per pattern entry), packed:
        the rows of the permuted ``L`` (below the diagonal) and ``U`` (the rest), row by row,
        columns ascending."""
        F = ca.SX.zeros(self.nnz)
        F[self._entries] = values  # one call: indexing SX entry by entry costs 20 us each
        for column, pivot, targets, left, right in self._eliminations:
            F[column] = F[column] / F[pivot]
            if targets:
                F[targets] = F[targets] - F[left] * F[right]
        return F

    def solve(self, F: ca.SX, b: ca.SX, transpose: bool = False) -> ca.SX:
        """``A^-1 b`` (or ``A^-T b``) from the packed factors ``F`` of :meth:`factor`: the
        triangles as sparse SX matrices, solved by CasADi's substitution (one call each, where
        writing it row by row costs a hundred times longer to build; the same operations)."""
        (lower, at_lower), (upper, at_upper) = self._triangles
        L = ca.SX(lower, F[at_lower]) + ca.SX.eye(self.n)  # unit diagonal
        U = ca.SX(upper, F[at_upper])
        out = ca.SX.zeros(self.n)
        if not transpose:  # L U x = P b
            out[self.column_order.tolist()] = ca.solve(U, ca.solve(L, b[self.row_order.tolist()]))
        else:  # A^T = P_c U^T L^T P_r
            out[self.row_order.tolist()] = ca.solve(L.T, ca.solve(U.T,
                                                                  b[self.column_order.tolist()]))
        return out


def steady(values) -> np.ndarray:
    """``values`` rounded to 26 significant bits (some 8 digits): what a pivot choice reads.
    A matrix's entries that are equal in exact arithmetic (the mirrored legs of a robot) differ
    by round-off, which then decided SuperLU's pivots: 1e-15 of noise on the walking robot's
    Jacobian gave 20 pivot orders in 20 tries (one-off script), so a run whose positions
    differed in their last bits from an earlier one's (another process's BLAS, say) compiled
    its plans' code again."""
    mantissa, exponent = np.frexp(np.asarray(values, dtype=float))
    return np.ldexp(np.round(np.ldexp(mantissa, 26)), exponent - 26)


def _sparsity(n: int, entries: list[tuple[int, int, int]]) -> tuple[ca.Sparsity, list[int]]:
    """The n x n pattern of ``entries`` (column, row, position in the packed factors), and the
    positions in its column-major order."""
    entries = sorted(entries)
    counts = np.bincount([j for j, _, _ in entries], minlength=n)
    colind = np.concatenate([[0], np.cumsum(counts)]).tolist()
    return (ca.Sparsity(n, n, colind, [i for _, i, _ in entries]),
            [position for _, _, position in entries])


def _in_order(rows, columns, n: int, row_order, column_order, values, diagonal: float = 0.0):
    """SuperLU's factors of the matrix of these values permuted to the pivots' order, without
    pivoting (SuperLU takes another pivot only where one of these is zero), ``diagonal`` added
    to it (to keep the pivots' places for a pattern's count); raises ``RuntimeError`` where
    a pivot is exactly zero and none other is found."""
    from scipy.sparse import csc_array
    from scipy.sparse.linalg import splu

    where_row, where_column = np.argsort(row_order), np.argsort(column_order)
    entries = (where_row[np.asarray(rows)], where_column[np.asarray(columns)])
    permuted = csc_array((np.asarray(values, dtype=float), entries), shape=(n, n))
    if diagonal:
        permuted = permuted + csc_array((np.full(n, diagonal), (np.arange(n), np.arange(n))),
                                        shape=(n, n))
    return splu(permuted, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                options={"SymmetricMode": True})


def _operations(rows, columns, n: int, row_order, column_order) -> int:
    """What the elimination of the pattern with these pivots costs written out: its divisions
    and multiply-adds (pivot ``k``: the entries of ``L`` below it, each times one plus those
    of ``U`` right of it) and a solve's (the factors' entries). From SuperLU's factors of the
    permuted pattern with random values and no pivoting (their pattern is the symbolic one:
    no cancellation), milliseconds where :class:`StaticLU`'s own symbolic pass takes tens."""
    values = np.random.default_rng(0).uniform(1.0, 2.0, len(rows))
    lu = _in_order(rows, columns, n, row_order, column_order, values, diagonal=4.0 * n)
    below = np.diff(lu.L.tocsc().indptr) - 1  # each column's entries; L holds its diagonal
    right = np.diff(lu.U.tocsr().indptr) - 1  # each row's, right of the diagonal
    return int(np.sum(below * (1 + right)) + lu.L.nnz + lu.U.nnz)


def _levels(pivots, at) -> list[tuple[list[int], ...]]:
    """The elimination's operations grouped by level: per level, the entries of ``L`` that
    its pivots divide and the pivot each is divided by, then the entries their updates
    write, with the two factors of each update (positions in the packed factors, ``at[i][j]``
    that of entry ``(i, j)``). ``pivots[k]`` gives the rows below pivot ``k`` with an entry
    in its column and the columns right of it with one in its row. A pivot's level is one more
    than that of the last pivot that wrote any entry it reads or writes, so that a level's
    operations are independent and every entry sees its updates in the pivots' order: the
    same operations in the same order per entry as pivot by pivot (the same numbers), in a
    few dozen vector operations instead of several per pivot (building a plan's factors took
    0.05 s of SX indexing for the walking robot)."""
    written: dict[int, int] = {}  # entry -> level of its last write
    levels: list[list[list[int]]] = []
    for k, (below, upper) in enumerate(pivots):
        if not below:
            continue
        column = [at[i][k] for i in below]
        targets = [at[i][j] for i in below for j in upper]
        reads = column + [at[k][k]] + [at[k][j] for j in upper]
        level = 1 + max((written.get(e, -1) for e in reads + targets), default=-1)
        for e in column + targets:
            written[e] = level
        while len(levels) <= level:
            levels.append([[], [], [], [], []])
        batch = levels[level]
        batch[0] += column
        batch[1] += [at[k][k]] * len(column)
        batch[2] += targets
        batch[3] += [at[i][k] for i in below for _ in upper]
        batch[4] += [at[k][j] for _ in below for j in upper]
    return [tuple(batch) for batch in levels]
