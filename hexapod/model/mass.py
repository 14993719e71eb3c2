"""The constant mass matrix: block-diagonal, scalar entries and the 3 x 3 inertia blocks of
spatial bodies, with its powers (``M^-1``, ``M^-1/2``) taken block by block."""

from __future__ import annotations

import numpy as np


class BlockDiagonal:
    """A symmetric block-diagonal matrix: scalar entries plus 3 x 3 blocks (spatial rotations).

    ``diagonal`` holds the scalar entries (zero where a block sits); ``blocks[k]`` sits at rows
    and columns ``block_index[k]``.
    """

    # make NumPy defer ``ndarray @ BlockDiagonal`` to __rmatmul__
    __array_ufunc__ = None

    def __init__(self, diagonal: np.ndarray, blocks: np.ndarray, block_index: np.ndarray):
        self.diagonal = np.asarray(diagonal, dtype=float)
        self.blocks = np.asarray(blocks, dtype=float).reshape(-1, 3, 3)
        self.block_index = np.asarray(block_index, dtype=int).reshape(-1, 3)
        self._block_columns = self.block_index.reshape(-1)

    def map_blocks(self, fn) -> BlockDiagonal:
        """Apply a matrix function (inverse, square root ...) to every block and scalar; ``fn``
        takes a stack of matrices (k, n, n), as NumPy's linear algebra does."""
        diagonal = self.diagonal.copy()
        scalar = np.ones(diagonal.size, dtype=bool)
        scalar[self._block_columns] = False
        if scalar.any():
            diagonal[scalar] = fn(diagonal[scalar][:, None, None])[:, 0, 0]
        blocks = fn(self.blocks) if self.blocks.size else self.blocks.copy()
        return BlockDiagonal(diagonal, blocks, self.block_index)

    def power(self, exponent: float) -> BlockDiagonal:
        """The matrix to the power ``exponent`` (symmetric positive definite blocks: ``-1/2``
        gives ``M^-1/2``)."""
        return self.map_blocks(lambda J: _sym_sqrt(J, exponent))

    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        """``self @ x`` for a vector or a matrix with n rows."""
        x = np.asarray(x, dtype=float)
        out = self.diagonal.reshape((-1,) + (1,) * (x.ndim - 1)) * x
        if self.blocks.size:
            xb = x[self.block_index]  # (n_b, 3, ...)
            out[self.block_index] = np.einsum("bij,bj...->bi...", self.blocks, xb)
        return out

    def __rmatmul__(self, A: np.ndarray) -> np.ndarray:
        """``A @ self`` for a matrix with n columns."""
        return (self @ np.asarray(A, dtype=float).T).T

    def dense(self) -> np.ndarray:
        return self @ np.eye(self.diagonal.size)

    def sparse(self):
        """The matrix in SciPy's CSR format (for products with large sparse matrices)."""
        from scipy.sparse import csr_array

        n = self.diagonal.size
        scalar = np.ones(n, dtype=bool)
        scalar[self._block_columns] = False
        index = np.flatnonzero(scalar)
        rows = np.broadcast_to(self.block_index[:, :, None], self.blocks.shape).reshape(-1)
        columns = np.broadcast_to(self.block_index[:, None, :], self.blocks.shape).reshape(-1)
        return csr_array((np.concatenate([self.diagonal[index], self.blocks.reshape(-1)]),
                          (np.concatenate([index, rows]), np.concatenate([index, columns]))),
                         shape=(n, n))


def _sym_sqrt(J: np.ndarray, power: float) -> np.ndarray:
    """``J**power`` of symmetric positive definite matrices (a stack of them)."""
    values, vectors = np.linalg.eigh(J)
    return (vectors * values[..., None, :]**power) @ np.swapaxes(vectors, -1, -2)
