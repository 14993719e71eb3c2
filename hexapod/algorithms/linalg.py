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
        """Singular values of the kept rows of ``W`` (those of ``R``)."""
        if self.rank == 0:
            return np.zeros(0)
        return np.linalg.svd(self.R, compute_uv=False)

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

    def min_norm_correction(self, residual: np.ndarray) -> np.ndarray:
        """``dy`` of least norm with ``W_I dy = residual_I / d_I`` (in ``M^1/2``-scaled space)."""
        if self.rank == 0:
            return np.zeros(self.W.shape[1])
        rhs = residual[self.independent] / self.scale[self.independent]
        return self.basis @ solve_triangular(self.R, rhs, trans="T")


def require_finite(array: np.ndarray, what: str) -> None:
    """Raise a clear error instead of letting NaN or infinity into a factorisation."""
    if not np.all(np.isfinite(array)):
        raise SingularSystemError(
            f"{what} has non-finite entries (an overflow or NaN: check the scene's magnitudes, "
            "its length unit and the state)")


def equilibrate(Phi_v: np.ndarray, mass_inv_sqrt) -> tuple[np.ndarray, np.ndarray]:
    """``W = D^-1 Phi_v M^-1/2`` and the row norms ``d`` (zero rows keep ``d = 1``).

    Raises :class:`SingularSystemError` when ``Phi_v`` is not finite (an overflow, typically from
    coordinates or lengths far out of range: check the scene's magnitudes and unit)."""
    require_finite(Phi_v, "the constraint Jacobian Phi_v")
    W = Phi_v @ mass_inv_sqrt
    d = np.linalg.norm(W, axis=1)
    d[d == 0.0] = 1.0
    return W / d[:, None], d


def split_rows(W: np.ndarray, scale: np.ndarray, priority: np.ndarray, tol: float,
               groups: np.ndarray | None = None) -> RowSplit:
    """Decide the rank of ``W`` (rows of unit length) and which rows are redundant.

    A single QR factorisation in priority order settles the usual full-rank case; when some
    diagonal entry falls below ``tol`` the rows are taken one by one (Gram-Schmidt, twice), so
    a redundant row never leaves a spurious direction in the basis. ``groups`` (a label per
    entry of ``priority``, equal within consecutive runs) lets rows of one group be taken in the
    order of their distance from the span already kept (default: each row its own group).
    """
    n_c, n_v = W.shape
    order = np.asarray(priority, dtype=int)
    if n_c == 0:
        return RowSplit(order, order, np.zeros((n_v, 0)), np.zeros((0, 0)), scale, W)
    if n_c <= n_v:
        basis, R = np.linalg.qr(W[order].T, mode="reduced")
        if np.all(np.abs(np.diag(R)) > tol):
            signs = np.sign(np.diag(R))
            return RowSplit(order, np.zeros(0, dtype=int), basis * signs, signs[:, None] * R,
                            scale, W)
    # rows are taken group by group (see Model.row_groups); within a group the row farthest
    # from the span of those kept comes first (column pivoting), so that a nearly dependent row
    # is not kept where a better one exists: in index order a standing hexapod kept drivers
    # whose smallest singular value was 5.6e-7 where 4.4e-4 was to be had
    labels = np.arange(order.size) if groups is None else np.asarray(groups)
    kept = []
    columns = np.zeros((n_v, min(n_c, n_v)))  # the kept rows' orthonormal basis, filled in
    m = 0
    begin = 0
    while begin < order.size:
        end = begin
        while end < order.size and labels[end] == labels[begin]:
            end += 1
        candidates = list(order[begin:end])
        begin = end
        residual = W[candidates].copy()
        if m:
            Qb = columns[:, :m]
            for _ in range(2):  # twice is enough (Giraud et al.)
                residual -= (residual @ Qb) @ Qb.T
        while candidates:
            norms = np.linalg.norm(residual, axis=1)
            j = int(np.argmax(norms))
            if norms[j] <= tol or m >= n_v:
                break
            u = residual[j] / norms[j]
            if m:
                Qb = columns[:, :m]
                u -= Qb @ (Qb.T @ u)
                u /= np.linalg.norm(u)
            kept.append(candidates.pop(j))
            columns[:, m] = u
            m += 1
            residual = np.delete(residual, j, axis=0)
            residual -= np.outer(residual @ u, u)
    taken = set(kept)
    redundant = [row for row in order if row not in taken]
    basis = columns[:, :m]
    R = np.triu(basis.T @ W[kept].T) if kept else np.zeros((0, 0))
    return RowSplit(np.array(kept, dtype=int), np.array(redundant, dtype=int), basis, R,
                    scale, W)


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
        z = solve_triangular(split.R, gamma[I] / d[I], trans="T")
        Qty0 = split.basis.T @ y0
        y = y0 - split.basis @ Qty0 + split.basis @ z
        lam[I] = solve_triangular(split.R, Qty0 - z) / d[I]
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
    C = solve_triangular(split.R, split.basis.T @ split.W[red].T)  # (r, n_red)
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
