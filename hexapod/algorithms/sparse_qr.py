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

import numpy as np

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
