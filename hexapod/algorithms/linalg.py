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

from dataclasses import dataclass

import numpy as np
from scipy.linalg.lapack import dpotrf, dpotrs

from hexapod.algorithms.rows import (
    RowSplit,
    as_dense,
    gram_exceeds,
    is_sparse,
    require_finite,
    solve_triangular,
)
from hexapod.algorithms.sparse_qr import (
    SparseRowSplit,
    large_and_sparse,
    scaled_rows,
    sparse_equilibrate,
    sparse_form,
    sparse_split,
)
from hexapod.errors import SingularSystemError

__all__ = ["RowSplit", "SaddleSolution", "SparseRowSplit", "as_dense", "check_consistency",
           "distribute", "equilibrate", "hold_rows", "is_sparse", "multiplier_null_space",
           "least_norm_psd", "require_finite", "solve_or_least_squares", "solve_saddle",
           "solve_triangular", "split_rows"]


def equilibrate(Phi_v: np.ndarray, mass_inv_sqrt) -> tuple[np.ndarray, np.ndarray]:
    """``W = D^-1 Phi_v M^-1/2`` and the row norms ``d`` (zero rows keep ``d = 1``); a sparse
    ``Phi_v`` (a large model's) gives a sparse ``W`` in CSR format, never densified.

    Raises :class:`SingularSystemError` when ``Phi_v`` is not finite (an overflow, typically from
    coordinates or lengths far out of range: check the scene's magnitudes and unit)."""
    require_finite(Phi_v, "the constraint Jacobian Phi_v")
    if is_sparse(Phi_v):
        return scaled_rows(Phi_v.tocsr() @ mass_inv_sqrt.sparse())
    if large_and_sparse(Phi_v) and hasattr(mass_inv_sqrt, "sparse"):
        return sparse_equilibrate(Phi_v, mass_inv_sqrt.sparse())
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
    if is_sparse(W) or sparse_form(W) is not None or large_and_sparse(W):
        labels = np.arange(order.size) if groups is None else np.asarray(groups)
        return (sparse_split(W, scale, order, labels, tol, pivoting=False)
                or sparse_split(W, scale, order, labels, tol, pivoting=True))
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
    return RowSplit(np.array(kept, dtype=int), np.array(redundant, dtype=int), basis, None,
                    scale, W)


def hold_rows(W: np.ndarray, scale: np.ndarray, split: RowSplit, tol: float
              ) -> RowSplit | None:
    """The decision ``split`` held at another ``W`` (the next Newton iterate, the next state
    of a simulation): its kept rows factorised again, in one QR, the same rows left out; None
    when a kept row has come within ``tol`` of the span of those before it, or a row left out
    has moved farther than ``tol`` from the span of the kept ones (then decide again), or for
    a large sparse ``W``."""
    if is_sparse(W) or sparse_form(W) is not None or not split.rank:
        return None
    from scipy.linalg import qr  # NumPy's QR with its checks and copies costs a fifth more

    I = split.independent
    basis, R = qr(W[I].T, mode="economic", check_finite=False)
    if not np.all(np.abs(np.diag(R)) > tol):
        return None
    if split.redundant.size:
        left_out = W[split.redundant]
        off = left_out - (left_out @ basis) @ basis.T
        if np.any(np.linalg.norm(off, axis=1) > tol):
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
    """Solve ``[[M, Phi_v^T], [Phi_v, 0]] [v_dot; lam] = [Q; gamma]`` (``Q`` and ``gamma`` may
    be matrices: their columns are solved together, on one rank decision).

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
    lam = np.zeros(W.shape[:1] + np.shape(Q)[1:])
    d = _columns(d, lam)
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


def _columns(vector: np.ndarray, like: np.ndarray) -> np.ndarray:
    """``vector`` shaped to broadcast over the columns of ``like`` (a vector, or a matrix of
    right-hand sides solved together)."""
    return np.reshape(vector, (-1,) + (1,) * (np.ndim(like) - 1))


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
    d = _columns(split.scale, rhs)
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
        offset = offset + _columns(wrench_offset, offset)
    z = np.linalg.lstsq(wrench_map @ N, -offset, rcond=None)[0]
    return lam + N @ z


def solve_or_least_squares(A: np.ndarray, b: np.ndarray, pivot_ratio: float = 1e-10,
                           rcond: float = 1e-12) -> np.ndarray | None:
    """``A x = b`` (``b`` a vector or columns) for a square ``A`` that may be nearly singular
    (the iteration matrix of an implicit method near a singular configuration): the rows are
    equilibrated, then LU with partial pivoting when its smallest pivot is above
    ``pivot_ratio`` times the largest, else the least-squares solution of least norm (singular
    values below ``rcond`` of the largest dropped), which moves along the nearly dependent
    directions no more than ``b`` asks.
    None when neither gives finite numbers, or LAPACK fails."""
    import warnings

    from scipy.linalg import LinAlgWarning, lu_factor, lu_solve

    scale = np.abs(A).max(axis=1) if A.size else np.ones(0)
    scale[~(scale > 0)] = 1.0
    A, b = A / scale[:, None], b / scale.reshape((-1,) + (1,) * (np.ndim(b) - 1))
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


def least_norm_psd(A: np.ndarray, b: np.ndarray, rcond: float = 1e-12) -> np.ndarray:
    """The least-norm solution of ``A x = b`` for a symmetric positive semi-definite ``A`` (a
    Delassus operator, a Gram matrix), singular values below ``rcond`` of the largest dropped
    as :func:`numpy.linalg.lstsq` drops them. By Cholesky when a shifted Cholesky factor
    certifies every eigenvalue of ``A`` above ``rcond trace(A)`` (:func:`~hexapod.algorithms.
    rows.gram_exceeds`), so above ``rcond`` times the largest: none is dropped and the
    solution is unique; a few microseconds where the SVD's least squares take tens, in a time
    step's loop. By least squares otherwise (contacts that share their load: a block on four
    corners)."""
    A = np.asarray(A, dtype=float)
    if A.size == 0:
        return np.zeros(A.shape[1:2] + np.shape(b)[1:])
    shift = rcond * float(np.trace(A))
    if shift > 0.0 and gram_exceeds(A, np.sqrt(shift), A.shape[0]):
        factor, info = dpotrf(A, lower=1, clean=0)
        if info == 0:
            x, info = dpotrs(factor, b, lower=1)
            if info == 0 and np.all(np.isfinite(x)):
                return x
    return np.linalg.lstsq(A, b, rcond=rcond)[0]
