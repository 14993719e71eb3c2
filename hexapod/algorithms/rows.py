"""The outcome of a rank decision on the equilibrated constraint matrix, and what every solve with
it needs: which rows are kept (and the orthonormal basis and triangular factor of their span),
which are redundant, and the row scales (:mod:`hexapod.algorithms.linalg` decides;
:mod:`hexapod.algorithms.sparse_qr` for large sparse matrices)."""

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
        Upper triangular, ``W[independent].T = basis @ R`` (given as None, formed from the
        basis when first asked: a rank decision alone, such as which feet's rows a new contact
        set keeps, does not need it; 0.6 ms of the walking robot's 2.2 ms decision).
    scale : ndarray (n_c,)
        Row norms ``d`` of ``Phi_v M^-1/2`` (1 for rows that are zero).
    W : ndarray (n_c, n_v)
        The equilibrated matrix.
    """

    independent: np.ndarray
    redundant: np.ndarray
    basis: np.ndarray
    _R: np.ndarray | None
    scale: np.ndarray
    W: np.ndarray

    @property
    def rank(self) -> int:
        return int(self.independent.size)

    @property
    def R(self) -> np.ndarray:
        if self._R is None:
            self._R = (np.triu(self.basis.T @ self.W[self.independent].T) if self.rank
                       else np.zeros((0, 0)))
        return self._R

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

    def smallest_exceeds(self, bound: float) -> bool:
        """Whether the smallest singular value of the kept rows of ``W`` is above ``bound`` by
        more than round-off could hide: ``R R^T - s I`` has a Cholesky factor, ``s`` above
        ``bound^2`` by a thousandth of it and by ``10 r eps trace(R R^T)`` (a bound on the
        product's and the factorisation's errors). A fifth of an SVD's cost, or less (the
        walking robot's 222 rows: 0.6 against 3.7 ms); False where it cannot tell, so that
        a caller decides by :meth:`smallest_singular_value` there, as it would have."""
        if not self.rank:
            return True  # no row: the smallest is inf
        if "_sigma" in self.__dict__:
            return self.smallest_singular_value() > bound
        from scipy.linalg import lapack

        if "_gram" not in self.__dict__:  # R R^T, its upper triangle (R's singular values)
            self._gram = lapack.dlauum(self.R, lower=0)[0]
        return gram_exceeds(self._gram, bound, self.rank)

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


def gram_exceeds(gram: np.ndarray, bound: float, inner: int) -> bool:
    """Whether the smallest singular value of ``A`` is above ``bound`` by more than round-off
    could hide, from ``gram = A A^T`` (its upper triangle suffices; ``inner``: the columns of
    ``A``, the length of the products): ``gram - s I`` has a Cholesky factor, ``s`` above
    ``bound^2`` by a thousandth of it and by ``10 max(r, inner) eps trace(gram)`` (a bound on
    the product's and the factorisation's errors). False where it cannot tell."""
    from scipy.linalg import lapack

    r = gram.shape[0]
    shift = bound**2 * (1.0 + 1e-3) + 10.0 * max(r, inner) * np.finfo(float).eps * np.trace(gram)
    shifted = np.array(gram, dtype=float, order="F")  # LAPACK's order: factored in place
    shifted.flat[::r + 1] -= shift  # the diagonal (an identity's product: a tenth of a check)
    return lapack.dpotrf(shifted, lower=0, clean=0, overwrite_a=1)[1] == 0


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
