"""Saddle-point solves on the equilibrated constraint matrix, with an explicit rank decision.

Everything is done on ``W = D^-1 Phi_v M^-1/2``: the columns are scaled by the (block-diagonal,
constant) ``M^-1/2`` and the rows by their norms ``D``. Each row of ``W`` is then dimensionless
and of unit length whatever the length unit, the mass unit or the scaling of the residual, so
the rank decision and everything built on it are unit-free.

Rank decision: rows are taken in a priority order (tree joints, loop-closing joints, drivers);
a row is **redundant** when its distance to the span of the rows kept before it is at most
``tol`` (the sine of its angle to that span). This names redundant rows deterministically.

Accelerations solve ``min |M^1/2 (v_dot - M^-1 Q)|`` subject to the kept rows (Gauss's
principle); with ``W_I^T = Q_I R_I`` (thin QR, never the squared Schur complement)::

    y0 = M^-1/2 Q,   z = R^-T (gamma_I / d_I),   y = y0 - Q_I Q_I^T y0 + Q_I z
    v_dot = M^-1/2 y,   lambda_I = R^-1 (Q_I^T y0 - z) / d_I
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from hexapod.algorithms.sparse_qr import FrontalQR, ordered_columns, panel_ranges
from hexapod.errors import SingularSystemError


def solve_triangular(R, b, trans: str = "N"):
    """SciPy's triangular solve, imported when first needed (SciPy's import is slow and a
    command such as ``hexapod inverse`` on a tree never needs it)."""
    from scipy.linalg import solve_triangular as solve

    return solve(R, b, trans=trans, check_finite=False)  # inputs are checked finite upstream


@dataclass
class RowSplit:
    """Independent and redundant rows of an equilibrated constraint matrix.

    Attributes
    ----------
    independent, redundant : ndarray of int
        Row indices, in priority order.
    basis : ndarray (n_v, r)
        Orthonormal basis ``Q_I`` of the span of the kept rows of ``W``.
    R : ndarray (r, r)
        Upper triangular, ``W[independent].T = basis @ R``.
    scale : ndarray (n_c,)
        Row norms ``d`` of ``Phi_v M^-1/2`` (1 for rows that are zero).
    W : ndarray (n_c, n_v)
        The equilibrated matrix.
    """

    independent: np.ndarray
    redundant: np.ndarray
    basis: np.ndarray
    R: np.ndarray
    scale: np.ndarray
    W: np.ndarray

    @property
    def rank(self) -> int:
        return int(self.independent.size)

    def singular_values(self) -> np.ndarray:
        """Singular values of the kept rows of ``W`` (those of ``R``), computed once."""
        if "_sigma" not in self.__dict__:
            self._sigma = (np.linalg.svd(self.R, compute_uv=False) if self.rank
                           else np.zeros(0))
        return self._sigma

    def smallest_singular_value(self) -> float:
        """The smallest singular value of the kept rows of ``W`` (``inf`` when none is kept)."""
        s = self.singular_values()
        return float(s.min()) if s.size else float("inf")

    def condition_number(self, n_v: int) -> float:
        """2-norm condition number of the equilibrated saddle-point matrix
        ``[[I, W_I^T], [W_I, 0]]`` of the kept rows, from the singular values of ``W_I``: its
        eigenvalues are ``(1 +- sqrt(1 + 4 s^2)) / 2`` and 1 (``n_v - r`` times)."""
        s = self.singular_values()
        if s.size == 0:
            return 1.0
        root = np.sqrt(1.0 + 4.0 * s**2)
        magnitudes = np.concatenate([(1.0 + root) / 2.0, (root - 1.0) / 2.0,
                                     np.ones(1 if n_v > s.size else 0)])
        smallest = magnitudes.min()
        return float(magnitudes.max() / smallest) if smallest > 0 else float("inf")

    def extreme_singular_values(self) -> tuple[float, float]:
        """The smallest and the largest singular value of the kept rows of ``W`` (``inf`` and
        0 when no row is kept)."""
        s = self.singular_values()
        return (float(s.min()), float(s.max())) if s.size else (float("inf"), 0.0)

    def min_norm_correction(self, residual: np.ndarray) -> np.ndarray:
        """``dy`` of least norm with ``W_I dy = residual_I / d_I`` (in ``M^1/2``-scaled space)."""
        if self.rank == 0:
            return np.zeros(self.W.shape[1])
        rhs = residual[self.independent] / self.scale[self.independent]
        return self.basis @ solve_triangular(self.R, rhs, trans="T")

    def kept_solve(self, y0: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The saddle-point solve on the kept rows (rank > 0): ``y`` closest to ``y0`` with
        ``W_I y = rhs``, and the scaled multipliers ``R^-1 (Q_I^T y0 - z)``, ``z = R^-T rhs``."""
        z = solve_triangular(self.R, rhs, trans="T")
        Qty0 = self.basis.T @ y0
        y = y0 - self.basis @ Qty0 + self.basis @ z
        return y, solve_triangular(self.R, Qty0 - z)

    def redundant_coefficients(self) -> np.ndarray:
        """``C`` (r, n_redundant): each redundant row of ``W`` as ``sum_i C_ik W_Ii``."""
        return solve_triangular(self.R, self.basis.T @ self.W[self.redundant].T)


def is_sparse(A) -> bool:
    """Whether ``A`` is a SciPy sparse array (the constraint Jacobian of a large model)."""
    return hasattr(A, "tocsr")


def as_dense(A) -> np.ndarray:
    """``A`` as a NumPy array (a sparse one densified: for the few dense uses of a large model's
    matrices, such as diagnostics, or the rows of a redundancy)."""
    return A.toarray() if is_sparse(A) else A


def require_finite(array: np.ndarray, what: str) -> None:
    """Raise a clear error instead of letting NaN or infinity into a factorisation."""
    if not np.all(np.isfinite(array.data if is_sparse(array) else array)):
        raise SingularSystemError(
            f"{what} has non-finite entries (an overflow or NaN: check the scene's magnitudes, "
            "its length unit and the state)")


def equilibrate(Phi_v: np.ndarray, mass_inv_sqrt) -> tuple[np.ndarray, np.ndarray]:
    """``W = D^-1 Phi_v M^-1/2`` and the row norms ``d`` (zero rows keep ``d = 1``); a sparse
    ``Phi_v`` (a large model's) gives a sparse ``W`` in CSR format, never densified.

    Raises :class:`SingularSystemError` when ``Phi_v`` is not finite (an overflow, typically from
    coordinates or lengths far out of range: check the scene's magnitudes and unit)."""
    require_finite(Phi_v, "the constraint Jacobian Phi_v")
    if is_sparse(Phi_v):
        return _scaled_rows(Phi_v.tocsr() @ mass_inv_sqrt.sparse())
    if _large_and_sparse(Phi_v) and hasattr(mass_inv_sqrt, "sparse"):
        return _sparse_equilibrate(Phi_v, mass_inv_sqrt.sparse())
    W = Phi_v @ mass_inv_sqrt
    d = np.linalg.norm(W, axis=1)
    d[d == 0.0] = 1.0
    return W / d[:, None], d


def split_rows(W: np.ndarray, scale: np.ndarray, priority: np.ndarray, tol: float,
               groups: np.ndarray | None = None) -> RowSplit:
    """Decide the rank of ``W`` (rows of unit length) and which rows are redundant.

    Rows are taken in ``priority`` order, group by group (``groups``: a label per entry of
    ``priority``, equal within consecutive runs; default each row its own group). A row is
    redundant when its distance to the span of the rows kept before it is at most ``tol``.
    Runs of one-row groups are taken in order and rows of one group the farthest from the span
    already kept first (column pivoting), each run by one LAPACK QR of its rows' components
    off that span (:func:`_take_ordered`, :func:`_take_pivoted`), so that the usual case, every
    row kept, costs one factorisation. A redundant row never leaves a spurious direction in the
    basis: the rows after it are taken again against the span of the kept rows alone.
    """
    n_c, n_v = W.shape
    order = np.asarray(priority, dtype=int)
    if n_c == 0:
        return RowSplit(order, order, np.zeros((n_v, 0)), np.zeros((0, 0)), scale, W)
    if is_sparse(W) or _sparse_form(W) is not None or _large_and_sparse(W):
        labels = np.arange(order.size) if groups is None else np.asarray(groups)
        return (_sparse_split(W, scale, order, labels, tol, pivoting=False)
                or _sparse_split(W, scale, order, labels, tol, pivoting=True))
    if n_c <= n_v:  # the usual case first: every row kept, in priority order
        basis, R = np.linalg.qr(W[order].T, mode="reduced")
        if np.all(np.abs(np.diag(R)) > tol):
            signs = np.sign(np.diag(R))
            return RowSplit(order, np.zeros(0, dtype=int), basis * signs, signs[:, None] * R,
                            scale, W)
    labels = np.arange(order.size) if groups is None else np.asarray(groups)
    basis, kept = np.zeros((n_v, 0)), []
    for rows, pivoted in _runs(order, labels):
        take = _take_pivoted if pivoted else _take_ordered
        chosen, basis = take(W, rows, basis, tol)
        kept += chosen
    taken = set(kept)
    redundant = [row for row in order if row not in taken]
    R = np.triu(basis.T @ W[kept].T) if kept else np.zeros((0, 0))
    return RowSplit(np.array(kept, dtype=int), np.array(redundant, dtype=int), basis, R,
                    scale, W)


def hold_rows(W: np.ndarray, scale: np.ndarray, split: RowSplit, tol: float
              ) -> RowSplit | None:
    """The decision ``split`` held at another ``W`` (the next Newton iterate): its kept rows
    factorised again, in one QR, the same rows left out; None when a kept row has come within
    ``tol`` of the span of those before it (then decide again), or for a large sparse ``W``."""
    if is_sparse(W) or _sparse_form(W) is not None or not split.rank:
        return None
    I = split.independent
    basis, R = np.linalg.qr(W[I].T, mode="reduced")
    if not np.all(np.abs(np.diag(R)) > tol):
        return None
    signs = np.sign(np.diag(R))
    return RowSplit(I, split.redundant, basis * signs, signs[:, None] * R, scale, W)


def _runs(order: np.ndarray, labels: np.ndarray):
    """``(rows, pivoted)``: each group of several rows (pivoted), and each run of consecutive
    one-row groups (in order)."""
    begin = 0
    while begin < order.size:
        end = begin + 1
        while end < order.size and labels[end] == labels[begin]:
            end += 1
        if end - begin > 1:
            yield order[begin:end], True
        else:
            while end < order.size and labels[end] != labels[end - 1] and (
                    end + 1 == order.size or labels[end + 1] != labels[end]):
                end += 1
            yield order[begin:end], False
        begin = end


def _off_span(W: np.ndarray, rows, basis: np.ndarray) -> np.ndarray:
    """The rows' components off the span of ``basis`` (as columns), projected twice (twice is
    enough: Giraud et al.)."""
    A = W[rows].T
    for _ in range(2 if basis.shape[1] else 0):
        A = A - basis @ (basis.T @ A)
    return A


def _extended(basis: np.ndarray, Q: np.ndarray, separation: float) -> np.ndarray:
    """``basis`` with the orthonormal columns ``Q`` (nearly orthogonal to it) appended. The
    components of nearly dependent rows lose their orthogonality to the span in the
    factorisation, by the ratio of their size to their distance (``separation``, the smallest
    such ratio's inverse): below 1e-3, the columns are made orthogonal to it again and
    orthonormal."""
    if Q.shape[1] and basis.shape[1] and separation < 1e-3:
        Q = Q - basis @ (basis.T @ Q)
        Q, R = np.linalg.qr(Q)
        Q = Q * np.sign(np.diag(R))
    return np.hstack([basis, Q])


def _take_ordered(W: np.ndarray, rows, basis: np.ndarray, tol: float):
    """Rows taken in order: the first whose distance to the span of those kept is at most
    ``tol`` is redundant, and the rows after it are taken again. Returns the rows kept and the
    extended basis."""
    from scipy.linalg import qr

    kept, rows = [], list(rows)
    while rows and basis.shape[1] < W.shape[1]:
        Q, R = qr(_off_span(W, rows, basis), mode="economic", check_finite=False)
        distance = np.abs(np.diag(R))
        room = W.shape[1] - basis.shape[1]
        small = np.flatnonzero(distance <= tol)
        first = int(small[0]) if small.size else distance.size
        first = min(first, room)
        signs = np.sign(np.diag(R)[:first])
        basis = _extended(basis, Q[:, :first] * signs, _separation(distance, first))
        kept += rows[:first]
        # the row at ``first`` is redundant (or no room is left): the rest again, without it
        rows = rows[first + 1:] if first < room else []
    return kept, basis


def _take_pivoted(W: np.ndarray, rows, basis: np.ndarray, tol: float):
    """Rows of one group, the farthest from the span of those kept first (QR with column
    pivoting), until the farthest left is within ``tol`` of it. Returns the rows kept and the
    extended basis."""
    from scipy.linalg import qr

    room = W.shape[1] - basis.shape[1]
    if room == 0:
        return [], basis
    Q, R, P = qr(_off_span(W, rows, basis), mode="economic", pivoting=True, check_finite=False)
    distance = np.abs(np.diag(R))
    small = np.flatnonzero(distance <= tol)
    count = min(int(small[0]) if small.size else distance.size, room)
    signs = np.sign(np.diag(R)[:count])
    chosen = [int(rows[i]) for i in P[:count]]
    return chosen, _extended(basis, Q[:, :count] * signs, _separation(distance, count))


def _separation(distance: np.ndarray, count: int) -> float:
    """The smallest distance of the ``count`` rows taken to the span before them, over their
    size (rows of unit length: the distance itself); 1 when none is taken."""
    return float(distance[:count].min()) if count else 1.0


# ------------------------------------------------------------------ large sparse matrices

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


def _large_and_sparse(A: np.ndarray) -> bool:
    return A.size > SPARSE_ABOVE and np.count_nonzero(A) < SPARSE_DENSITY * A.size


#: the last matrix :func:`_sparse_equilibrate` gave, and its sparse form: the split that follows
#: takes it from here rather than scanning the dense one again
_LAST: tuple = (lambda: None, None)


def _scaled_rows(W):
    """``D^-1 W`` and ``d`` for a CSR ``W`` (scaled in place), zero rows keeping ``d = 1``."""
    row = np.repeat(np.arange(W.shape[0]), np.diff(W.indptr))
    d = np.sqrt(np.bincount(row, weights=W.data**2, minlength=W.shape[0]))
    d[d == 0.0] = 1.0
    W.data /= d[row]
    return W, d


def _sparse_equilibrate(Phi_v: np.ndarray, mass_inv_sqrt) -> tuple[np.ndarray, np.ndarray]:
    """:func:`equilibrate` of a dense ``Phi_v`` through a sparse product (the dense one reads
    every zero)."""
    from scipy.sparse import csr_array

    global _LAST
    W, d = _scaled_rows(csr_array(Phi_v) @ mass_inv_sqrt)
    dense = W.toarray()
    _LAST = (weakref.ref(dense), W)
    return dense, d


def _sparse_form(W: np.ndarray):
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


def _sparse_split(W, scale, order, labels, tol: float, pivoting: bool):
    """:func:`split_rows` by a sparse QR; without ``pivoting`` None unless every row is kept
    (then the rows are taken as in the dense path's first attempt)."""
    from scipy.sparse import csr_array

    front = FrontalQR(ordered_columns(W, order, _sparse_form(W)), tol)
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


@dataclass
class SaddleSolution:
    """Result of :func:`solve_saddle`."""

    v_dot: np.ndarray
    lam: np.ndarray
    split: RowSplit
    #: largest violation of the redundant rows by the accelerations, in ``M^1/2``-scaled units
    #: relative to the size of the problem (0 when no row is redundant)
    inconsistency: float


def solve_saddle(mass_inv_sqrt, Phi_v: np.ndarray, Q: np.ndarray, gamma: np.ndarray,
                 priority: np.ndarray, tol: float, *, row_names=None,
                 wrench_map=None, wrench_offset=None, consistency_tol: float = 1e-6,
                 split: RowSplit | None = None) -> SaddleSolution:
    """Solve ``[[M, Phi_v^T], [Phi_v, 0]] [v_dot; lam] = [Q; gamma]``.

    Parameters
    ----------
    mass_inv_sqrt :
        ``M^-1/2`` (anything supporting ``@`` from both sides, e.g. a ``BlockDiagonal``).
    priority : ndarray of int
        Row order for the rank decision (earlier rows are kept).
    tol : float
        Rank tolerance on the equilibrated rows.
    wrench_map, wrench_offset :
        When rows are redundant, multipliers are chosen to minimise
        ``|wrench_map @ lam + wrench_offset|^2`` among all that satisfy the equations (the
        unit-free default policy: joint wrenches, moments divided by a stated length).
        Without a map the redundant rows get zero multipliers.
    split :
        A row split computed earlier for the same ``Phi_v`` (skips the rank decision).

    Raises
    ------
    SingularSystemError
        When the redundant rows' ``gamma`` contradicts the kept rows (inconsistent
        constraints, e.g. two drivers prescribing incompatible motions).
    """
    require_finite(Q, "the applied forces Q")
    require_finite(gamma, "the acceleration right-hand side gamma")
    if split is None:
        W, d = equilibrate(Phi_v, mass_inv_sqrt)
        split = split_rows(W, d, priority, tol)
    W, d = split.W, split.scale
    I = split.independent
    y0 = mass_inv_sqrt @ Q
    lam = np.zeros(W.shape[0])
    if split.rank:
        y, scaled = split.kept_solve(y0, gamma[I] / d[I])
        lam[I] = scaled / d[I]
    else:
        y = y0
    inconsistency = check_consistency(split, y, gamma, np.linalg.norm(y0), row_names,
                                      consistency_tol)
    if split.redundant.size and wrench_map is not None and split.rank:
        lam = distribute(split, lam, wrench_map, wrench_offset)
    return SaddleSolution(mass_inv_sqrt @ y, lam, split, inconsistency)


def check_consistency(split: RowSplit, y: np.ndarray, rhs: np.ndarray, size: float = 0.0,
                      row_names=None, tol: float = 1e-6, what: str = "constraints") -> float:
    """Relative violation of the redundant rows by a solution ``y`` (``M^1/2``-scaled) of the
    kept rows ``W_I y = rhs_I / d_I``; raises when it exceeds ``tol``, naming the rows.

    Redundant rows are dropped from the solve, so this is where contradicting constraints (two
    drivers prescribing incompatible motions, say) are caught instead of silently ignored.
    """
    red = split.redundant
    if red.size == 0:
        return 0.0
    d = split.scale
    violation = np.abs(split.W[red] @ y - rhs[red] / d[red])
    scale = max(size, np.linalg.norm(y), np.linalg.norm(rhs / d), np.finfo(float).tiny)
    inconsistency = float(violation.max() / scale)
    if inconsistency > tol:
        worst = red[np.argsort(-violation)[:5]]
        names = [row_names[i] if row_names is not None else str(i) for i in worst]
        raise SingularSystemError(
            f"the {what} are inconsistent: redundant rows " + ", ".join(names)
            + f" cannot be met together with the others (relative violation "
            f"{inconsistency:.1e})")
    return inconsistency


def multiplier_null_space(split: RowSplit, n_c: int) -> np.ndarray:
    """``N`` (n_c, n_redundant): its columns span the multipliers that change no constraint
    force (the null space of ``Phi_v^T``), one per redundant row."""
    I, red, d = split.independent, split.redundant, split.scale
    # each redundant row k: W_k = sum_i c_ki W_Ii, so e_k - sum_i c_ki e_Ii is a null vector of
    # W^T (multiplier space scaled by d), i.e. (e_k - sum c_ki e_Ii) / d of Phi_v^T
    C = split.redundant_coefficients()  # (r, n_red)
    N = np.zeros((n_c, red.size))
    N[red, np.arange(red.size)] = 1.0
    N[I, :] = -C
    return N / d[:, None]


def distribute(split: RowSplit, lam: np.ndarray, wrench_map: np.ndarray,
               wrench_offset) -> np.ndarray:
    """Among ``lam + N z`` (``N`` spans the null space of ``Phi_v^T``: the multipliers that
    give the same constraint forces), those of least ``|wrench_map lam + wrench_offset|``."""
    N = multiplier_null_space(split, lam.size)
    offset = wrench_map @ lam
    if wrench_offset is not None:
        offset = offset + wrench_offset
    z = np.linalg.lstsq(wrench_map @ N, -offset, rcond=None)[0]
    return lam + N @ z


def solve_or_least_squares(A: np.ndarray, b: np.ndarray, pivot_ratio: float = 1e-10,
                           rcond: float = 1e-12) -> np.ndarray | None:
    """``A x = b`` for a square ``A`` that may be nearly singular (the iteration matrix of an
    implicit method near a singular configuration): the rows are equilibrated, then LU with
    partial pivoting when its smallest pivot is above ``pivot_ratio`` times the largest, else
    the least-squares solution of least norm (singular values below ``rcond`` of the largest
    dropped), which moves along the nearly dependent directions no more than ``b`` asks.
    None when neither gives finite numbers, or LAPACK fails."""
    import warnings

    from scipy.linalg import LinAlgWarning, lu_factor, lu_solve

    scale = np.abs(A).max(axis=1) if A.size else np.ones(0)
    scale[~(scale > 0)] = 1.0
    A, b = A / scale[:, None], b / scale
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(b))):
        return None
    x = None
    if A.size:
        with warnings.catch_warnings():  # a singular matrix is what the test below is for
            warnings.simplefilter("ignore", LinAlgWarning)
            lu, pivots = lu_factor(A, check_finite=False)
        diagonal = np.abs(np.diag(lu))
        if diagonal.min() > pivot_ratio * diagonal.max():
            x = lu_solve((lu, pivots), b, check_finite=False)
    if x is None or not np.all(np.isfinite(x)):
        try:
            x = np.linalg.lstsq(A, b, rcond=rcond)[0]
        except np.linalg.LinAlgError:  # LAPACK's SVD fails on finite entries of extreme range
            return None
    return x if np.all(np.isfinite(x)) else None
