"""The sparse Householder QR behind the rank decision of large constraint matrices.

:func:`hexapod.algorithms.linalg.split_rows` factorises ``A = W[order].T`` (columns: the rows of
the equilibrated ``W`` in priority order) panel by panel with :class:`FrontalQR`. A velocity
coordinate enters the dense front at the first row of ``W`` that touches it and leaves once no
later row does, so the front of a chain or a tree, whose rows (a joint's) touch two bodies
each, stays a few bodies wide whatever its length: the work and the memory grow linearly with
the number of bodies. A loop-closing joint's rows keep the coordinates of their two bodies in
the front from their first row to the last (the rows are in priority order: tree joints,
loop-closing joints, drivers), the few extra rows a loop costs.
"""

from __future__ import annotations

import weakref

import numpy as np

from hexapod.algorithms.rows import RowSplit, as_dense

PANEL = 32  # rows of W factorised together


class FrontalQR:
    """The sparse Householder QR of ``A = W[order].T`` (columns: the rows of ``W`` in priority
    order) panel by panel. A row of ``A`` (a velocity coordinate) enters the front at the first
    column where it is not zero and leaves it as a row of ``R`` or once it is zero beyond the
    columns done; the front is dense over the columns it still reaches, so a chain's stays
    small whatever its length."""

    def __init__(self, Wo, tol: float):
        self.Wo, self.tol = Wo, tol  # Wo: W[order] in CSC, indices sorted
        n = Wo.shape[0]
        filled = np.diff(Wo.indptr) > 0
        first, self.last = np.full(Wo.shape[1], n), np.full(Wo.shape[1], -1)
        first[filled] = Wo.indices[Wo.indptr[:-1][filled]]
        self.last[filled] = Wo.indices[Wo.indptr[1:][filled] - 1]
        self.arrivals = np.argsort(first, kind="stable")
        self.first = first[self.arrivals]
        self.entered = 0
        self.values, self.slots, self.start = np.zeros((0, 0)), np.zeros(0, dtype=int), 0
        self.transforms, self.pivots, self.kept, self.redundant = [], [], [], []
        self.entries: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # R, as triplets

    def enter(self, a: int, b: int) -> None:
        """Move the window to start at column ``a`` and let in the rows starting before ``b``."""
        stop = max(int(np.searchsorted(self.first, b)), self.entered)
        new = self.arrivals[self.entered:stop]
        self.entered = stop
        end = max(self.start + self.values.shape[1], b,
                  int(self.last[new].max()) + 1 if new.size else 0)
        values = np.zeros((self.slots.size + new.size, end - a))
        kept = self.values[:, a - self.start:]
        values[:self.slots.size, :kept.shape[1]] = kept
        if new.size:  # the arriving columns' entries, read from the CSC arrays directly
            starts, counts = self.Wo.indptr[new], self.Wo.indptr[new + 1] - self.Wo.indptr[new]
            column = np.repeat(np.arange(new.size), counts)
            before = np.cumsum(counts) - counts  # the entries of the columns before each
            where = np.arange(counts.sum()) + (starts - before)[column]
            values[self.slots.size + column, self.Wo.indices[where] - a] = self.Wo.data[where]
        self.values, self.slots, self.start = values, np.concatenate([self.slots, new]), a

    def reduce(self, a: int, b: int, pivoting: bool) -> bool:
        """Factorise columns ``a:b``: in order, refusing (False, nothing changed) when one is
        within ``tol`` of the span of those before; or with column pivoting, the columns
        within ``tol`` of the span of those kept being redundant."""
        from scipy.linalg import qr

        self.enter(a, b)
        p = b - a
        S = np.flatnonzero(np.any(self.values[:, :p] != 0, axis=1))
        block = self.values[S]
        if pivoting:
            if S.size:
                Q, Rp, P = qr(block[:, :p], pivoting=True)
                diagonal = np.abs(np.diag(Rp))
            else:
                Q, Rp, P, diagonal = np.eye(0), np.zeros((0, p)), np.arange(p), np.zeros(0)
            m = int(np.argmin(diagonal > self.tol)) if np.any(diagonal <= self.tol) \
                else diagonal.size
        else:
            if S.size < p:
                return False
            Q, Rp = qr(block[:, :p])
            if np.any(np.abs(np.diag(Rp)) <= self.tol):
                return False
            P, m = np.arange(p), p
        signs = np.sign(np.diag(Rp)[:m])
        Q[:, :m] *= signs
        Rp[:m] *= signs[:, None]
        rest = Q.T @ block[:, p:]
        if m < S.size and rest.shape[1]:  # the rows left: triangular, the others zero and out
            Q2, rest[m:] = qr(rest[m:])
            Q[:, m:] = Q[:, m:] @ Q2
        columns = a + P[:m]
        within, beyond = np.triu_indices(m), np.nonzero(rest[:m])  # R's rows, as triplets
        self.entries.append((len(self.kept) + np.concatenate([within[0], beyond[0]]),
                             np.concatenate([columns[within[1]], b + beyond[1]]),
                             np.concatenate([Rp[within], rest[beyond]])))
        self.kept += columns.tolist()
        self.redundant += (a + P[m:]).tolist()
        self.transforms.append((self.slots[S], Q))
        self.pivots += self.slots[S[:m]].tolist()
        self.values[S[m:], p:] = rest[m:]
        staying = np.ones(self.slots.size, dtype=bool)
        staying[S[:m]] = False
        values = self.values[staying, p:]
        staying[staying] = np.any(values != 0, axis=1)  # rows done are zero from here on
        self.values, self.slots, self.start = self.values[staying, p:], self.slots[staying], b
        return True


def panel_ranges(labels: np.ndarray, pivoting: bool):
    """Column ranges ``(a, b, pivot)``: runs of at most ``PANEL`` columns, or with
    ``pivoting`` each group of several rows on its own (pivoted) and runs of single rows."""
    n, a = labels.size, 0
    while a < n:
        b = a + 1
        while b < n and labels[b] == labels[a]:
            b += 1
        if pivoting and b - a > 1:
            yield a, b, True
        else:
            b = a + 1
            while b < min(n, a + PANEL) and (not pivoting or (
                    labels[b] != labels[b - 1] and (b + 1 == n or labels[b + 1] != labels[b]))):
                b += 1
            yield a, b, False
        a = b


def ordered_columns(W, order: np.ndarray, sparse=None):
    """``W[order]`` in CSC format (sorted indices): the columns of ``A = W[order].T``. ``W``
    dense (``sparse``: its CSR form when known) or a SciPy sparse array."""
    from scipy.sparse import csc_array

    if hasattr(W, "tocsr"):
        sparse = W.tocsr()
    if sparse is None:
        rows, columns = np.nonzero(W)
        values = W[rows, columns]
    else:
        rows = np.repeat(np.arange(W.shape[0]), np.diff(sparse.indptr))
        columns, values = sparse.indices, sparse.data
    position = np.full(W.shape[0], -1)
    position[order] = np.arange(order.size)
    taken = position[rows] >= 0  # rows left out of the decision (feet in swing)
    out = csc_array((values[taken], (position[rows[taken]], columns[taken])),
                    shape=(order.size, W.shape[1]))
    out.sort_indices()
    return out


#: matrices of more entries than this (mostly zeros) are split by the sparse factorisation
#: below: the dense QR of the 5000 x 6000 Jacobian of a chain of a thousand bodies takes some
#: fifteen seconds, and its SVD longer. The two cost the same near 1e5 entries (a forward solve
#: of a chain of 50 bodies, 75,000 entries: 3.2 ms dense, 4.1 ms sparse; of 100 bodies, 300,000
#: entries: 21 ms and 7.6 ms), and the sparse one grows linearly with the bodies
SPARSE_ABOVE = 100_000
SPARSE_DENSITY = 0.05  # ... and fewer nonzeros than this fraction of them
#: ARPACK's relative tolerance on the extreme eigenvalues of R^T R and its inverse: the top of
#: a long chain's spectrum is a near continuum, where a tighter one takes seconds more; the
#: values come out within about 1e-7 (relative) there, to round-off where they stand apart
_ARPACK_TOL = 1e-5
#: a smallest singular value below this is found again to ``_REFINED_TOL``: near singular poses
#: (below 1e-4, the integrators' SINGULAR_BAND) they difference it along the motion, over a
#: thousandth of a step. Long chains stand above it where nothing is singular (1.1e-2 at 100
#: bodies, 3.7e-3 at 300, 1.1e-3 at 1000)
_REFINE_BELOW = 1e-3
_REFINED_TOL = 1e-12


def large_and_sparse(A: np.ndarray) -> bool:
    return A.size > SPARSE_ABOVE and np.count_nonzero(A) < SPARSE_DENSITY * A.size


#: the last matrix :func:`_sparse_equilibrate` gave, and its sparse form: the split that follows
#: takes it from here rather than scanning the dense one again
_LAST: tuple = (lambda: None, None)


def scaled_rows(W):
    """``D^-1 W`` and ``d`` for a CSR ``W`` (scaled in place), zero rows keeping ``d = 1``."""
    row = np.repeat(np.arange(W.shape[0]), np.diff(W.indptr))
    d = np.sqrt(np.bincount(row, weights=W.data**2, minlength=W.shape[0]))
    d[d == 0.0] = 1.0
    W.data /= d[row]
    return W, d


def sparse_equilibrate(Phi_v: np.ndarray, mass_inv_sqrt) -> tuple[np.ndarray, np.ndarray]:
    """:func:`equilibrate` of a dense ``Phi_v`` through a sparse product (the dense one reads
    every zero)."""
    from scipy.sparse import csr_array

    global _LAST
    W, d = scaled_rows(csr_array(Phi_v) @ mass_inv_sqrt)
    dense = W.toarray()
    _LAST = (weakref.ref(dense), W)
    return dense, d


def sparse_form(W: np.ndarray):
    """``W`` in CSR format when it is the last matrix equilibrated, else None."""
    reference, sparse = _LAST
    return sparse if reference() is W else None


class SparseRowSplit(RowSplit):
    """A :class:`RowSplit` of a large sparse ``W``: ``R`` sparse, and ``Q_I`` kept as the
    orthogonal transforms of the factorisation's panels (``basis`` and ``R`` are formed dense
    only when asked). The condition number comes from the extreme singular values (ARPACK)."""

    def __init__(self, independent, redundant, R, transforms, pivots, scale, W):
        self.independent, self.redundant, self.scale, self.W = independent, redundant, scale, W
        self.R_sparse = R  # (r, r) upper triangular, CSR
        self.transforms = transforms  # [(slots, Q)]: W[independent].T = G[:, pivots] R,
        self.pivots = pivots  # G the product of the Q placed on their slots
        self._factor = None
        self._smallest: dict[float, float] = {}  # by ARPACK's tolerance

    def __repr__(self) -> str:
        return f"SparseRowSplit(rank={self.rank}, redundant={self.redundant.tolist()})"

    @property
    def basis(self) -> np.ndarray:
        return self.expand(np.eye(self.rank))

    @property
    def R(self) -> np.ndarray:
        return self.R_sparse.toarray()

    def expand(self, z: np.ndarray) -> np.ndarray:
        """``Q_I z``."""
        x = np.zeros((self.W.shape[1],) + z.shape[1:])
        x[self.pivots] = z
        for slots, Q in reversed(self.transforms):
            x[slots] = Q @ x[slots]
        return x

    def project(self, y: np.ndarray) -> np.ndarray:
        """``Q_I^T y``."""
        x = np.array(y, dtype=float)
        for slots, Q in self.transforms:
            x[slots] = Q.T @ x[slots]
        return x[self.pivots]

    def solve_r(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        """``R^-1 b`` (or ``R^-T b``) by the sparse triangular factor."""
        if self._factor is None:
            from scipy.sparse.linalg import splu

            self._factor = splu(self.R_sparse.tocsc(), permc_spec="NATURAL",
                                diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        return self._factor.solve(np.asarray(b, dtype=float), trans=trans)

    def extreme_singular_values(self) -> tuple[float, float]:
        if self.rank < 3:  # too few for ARPACK
            return super().extreme_singular_values()
        from scipy.sparse.linalg import LinearOperator, eigsh

        R, Rt, r = self.R_sparse.tocsr(), self.R_sparse.T.tocsr(), self.rank

        def largest(matvec) -> float:  # the largest eigenvalue of a symmetric operator
            operator = LinearOperator((r, r), matvec=matvec, dtype=float)
            return float(eigsh(operator, k=1, v0=np.ones(r), tol=_ARPACK_TOL,
                               return_eigenvectors=False)[0])

        s_max = np.sqrt(largest(lambda x: Rt @ (R @ x)))  # of R^T R
        return self.smallest_singular_value(), float(s_max)

    def smallest_singular_value(self, tol: float = _ARPACK_TOL) -> float:
        """By ARPACK, from the largest eigenvalue of ``(R^T R)^-1`` (two sparse triangular
        solves a product): linear in the number of bodies where the dense SVD of ``R`` is
        cubic (1.4 s for a chain of 300 bodies). ``tol``: ARPACK's relative tolerance; a
        value below :data:`_REFINE_BELOW` (near a singular pose, where the integrators take
        differences of it along the motion) is found again to :data:`_REFINED_TOL`."""
        if self.rank < 3:  # too few for ARPACK
            return super().smallest_singular_value()
        if tol not in self._smallest:
            from scipy.sparse.linalg import LinearOperator, eigsh

            r = self.rank
            operator = LinearOperator(
                (r, r), matvec=lambda x: self.solve_r(self.solve_r(x, trans="T")), dtype=float)
            largest = eigsh(operator, k=1, v0=np.ones(r), tol=tol, return_eigenvectors=False)
            self._smallest[tol] = float(1.0 / np.sqrt(largest[0]))
        if self._smallest[tol] < _REFINE_BELOW and tol > _REFINED_TOL:
            return self.smallest_singular_value(_REFINED_TOL)
        return self._smallest[tol]

    def smallest_exceeds(self, bound: float) -> bool:
        """By the smallest singular value itself (ARPACK: linear in the bodies already)."""
        return self.smallest_singular_value() > bound

    def condition_number(self, n_v: int) -> float:
        if self.rank == 0:
            return 1.0
        s_min, s_max = self.extreme_singular_values()  # the extremes set the extremes:
        largest = (1.0 + np.sqrt(1.0 + 4.0 * s_max**2)) / 2.0  # see RowSplit.condition_number
        smallest = (np.sqrt(1.0 + 4.0 * s_min**2) - 1.0) / 2.0
        if n_v > self.rank:
            smallest = min(smallest, 1.0)
        return float(largest / smallest) if smallest > 0 else float("inf")

    def min_norm_correction(self, residual: np.ndarray) -> np.ndarray:
        if self.rank == 0:
            return np.zeros(self.W.shape[1])
        I = self.independent
        return self.expand(self.solve_r(residual[I] / self.scale[I], trans="T"))

    def kept_solve(self, y0: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        z = self.solve_r(rhs, trans="T")
        Qty0 = self.project(y0)
        return y0 + self.expand(z - Qty0), self.solve_r(Qty0 - z)

    def redundant_coefficients(self) -> np.ndarray:
        return self.solve_r(self.project(as_dense(self.W[self.redundant]).T))


def sparse_split(W, scale, order, labels, tol: float, pivoting: bool):
    """:func:`split_rows` by a sparse QR; without ``pivoting`` None unless every row is kept
    (then the rows are taken as in the dense path's first attempt)."""
    from scipy.sparse import csr_array

    front = FrontalQR(ordered_columns(W, order, sparse_form(W)), tol)
    for a, b, pivot in panel_ranges(labels, pivoting):
        if front.reduce(a, b, pivot):
            continue
        if not pivoting:
            return None
        for k in range(a, b):  # a run of single rows with a redundant one: one by one
            front.reduce(k, k + 1, True)
    kept = np.array(front.kept, dtype=int)
    rank = np.full(order.size, -1)  # each column's place among those kept
    rank[kept] = np.arange(kept.size)
    rows, columns, values = (np.concatenate(x) for x in zip(*front.entries, strict=True)) \
        if front.entries else (np.zeros(0, dtype=int), np.zeros(0, dtype=int), np.zeros(0))
    columns = rank[columns]
    inside = columns >= 0  # entries in redundant columns are not part of R
    R = csr_array((values[inside], (rows[inside], columns[inside])),
                  shape=(kept.size, kept.size))
    return SparseRowSplit(order[kept], order[np.sort(np.array(front.redundant, dtype=int))],
                          R, front.transforms, np.array(front.pivots, dtype=int), scale, W)
