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
    def pivoted(cls, rows, columns, n: int, values) -> StaticLU:
        """The pattern ``(rows, columns)`` with the pivots SuperLU chooses (partial pivoting,
        COLAMD column order) for the matrix of these values."""
        from scipy.sparse import csc_array
        from scipy.sparse.linalg import splu

        rows, columns = np.asarray(rows, dtype=int), np.asarray(columns, dtype=int)
        A = csc_array((np.asarray(values, dtype=float), (rows, columns)), shape=(n, n))
        lu = splu(A, permc_spec="COLAMD")
        # P_r A P_c = L U with (P_r A)[perm_r[i]] = A[i] and (A P_c)[:, perm_c[j]] = A[:, j]
        return cls(rows, columns, n, np.argsort(lu.perm_r), np.argsort(lu.perm_c))

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

    def factor(self, values: ca.SX) -> list[dict]:
        """The factors of the matrix with these values (SX, one per pattern entry): the rows of
        the permuted ``L`` (below the diagonal) and ``U`` (the rest), as dicts column -> SX."""
        rows: list[dict] = [{j: ca.SX(0) for j in row} for row in self.structure]
        for k, (i, j) in enumerate(zip(self._where_row[self.rows],
                                       self._where_column[self.columns], strict=True)):
            rows[i][j] = rows[i][j] + values[k]
        for k in range(self.n):
            pivot = rows[k][k]
            upper = [(j, x) for j, x in rows[k].items() if j > k]
            for i in range(k + 1, self.n):
                if k not in rows[i]:
                    continue
                factor = rows[i][k] / pivot
                rows[i][k] = factor
                for j, x in upper:
                    rows[i][j] = rows[i][j] - factor * x
        return rows

    def pack(self, rows: list[dict]) -> ca.SX:
        """The factors as one vector (row by row, columns ascending)."""
        return ca.vertcat(*[rows[i][j] for i, row in enumerate(self.structure) for j in row])

    def unpack(self, packed: ca.SX) -> list[dict]:
        out, k = [], 0
        for row in self.structure:
            out.append({j: packed[k + n] for n, j in enumerate(row)})
            k += len(row)
        return out

    def solve(self, rows: list[dict], b: ca.SX, transpose: bool = False) -> ca.SX:
        """``A^-1 b`` (or ``A^-T b``) from the factors of :meth:`factor`."""
        n = self.n
        if not transpose:
            y = [b[int(r)] for r in self.row_order]  # L y = P b
            for i in range(n):
                y[i] = y[i] - sum((rows[i][j] * y[j] for j in rows[i] if j < i), ca.SX(0))
            x = [None] * n
            for i in reversed(range(n)):
                rest = sum((rows[i][j] * x[j] for j in rows[i] if j > i), ca.SX(0))
                x[i] = (y[i] - rest) / rows[i][i]
            out = [None] * n
            for k, c in enumerate(self.column_order):
                out[int(c)] = x[k]
            return ca.vertcat(*out)
        # A^T = P_c U^T L^T P_r: U^T y = (b in column order), L^T x = y, then rows back
        y = [b[int(c)] for c in self.column_order]
        for i in range(n):  # U^T is lower triangular: column i of U is row i of U^T
            y[i] = y[i] / rows[i][i]
            for j in rows[i]:
                if j > i:
                    y[j] = y[j] - rows[i][j] * y[i]
        for i in reversed(range(n)):  # L^T is upper triangular (unit diagonal)
            for j in rows[i]:
                if j < i:
                    y[j] = y[j] - rows[i][j] * y[i]
        out = [None] * n
        for k, r in enumerate(self.row_order):
            out[int(r)] = y[k]
        return ca.vertcat(*out)
