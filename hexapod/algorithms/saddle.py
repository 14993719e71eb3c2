"""The constraint matrices of large models, kept sparse, and the numeric solves of the implicit
methods on them.

``Phi_v`` has a few nonzeros per row: a joint's rows touch the velocities of its two bodies
only. Merely writing it densely costs ``O(n^2)`` (at a thousand bodies, 30 million entries,
nearly all zero), and a dense factorisation ``O(n^3)``. A model is **large** (:func:`is_large`)
when its ``Phi_v`` has more than :data:`hexapod.algorithms.sparse_qr.SPARSE_ABOVE` entries, few of
them nonzero: CasADi then gives ``Phi_v`` as its nonzeros (:func:`constraint_jacobian`,
:func:`dynamics_terms`), ``W`` is formed and scaled as a sparse matrix
(:func:`hexapod.algorithms.linalg.equilibrate`), and the rank decision is the sparse
Householder QR of ``W_I^T`` in priority order (:mod:`hexapod.algorithms.sparse_qr`), whose
front stays a few bodies wide along a chain or a tree; below that size the dense path is as
fast and its numbers are the reference. The symbolic solve on the kept rows, used by the
compiled kernels, is :mod:`hexapod.algorithms.step`'s.
"""

from __future__ import annotations

import numpy as np

from hexapod._support.fastcall import ScatteredFunction
from hexapod.algorithms import linalg, sparse_qr
from hexapod.model.data import kept
from hexapod.model.model import Data, Model


def is_large(model: Model) -> bool:
    """Whether ``model``'s forward solves take the sparse path: its ``Phi_v`` has more than
    ``sparse_qr.SPARSE_ABOVE`` entries and, structurally, fewer than ``sparse_qr.SPARSE_DENSITY`` of
    them nonzero."""
    entries = model.n_c * model.n_v
    return (entries > sparse_qr.SPARSE_ABOVE
            and model.Phi_v.nnz_out(0) < sparse_qr.SPARSE_DENSITY * entries)


def _scattered(model: Model, data: Data | None, name: str) -> ScatteredFunction:
    """The model's Function ``name`` evaluated on its nonzeros, with the buffers of ``data``
    (made once per workspace). Not :meth:`Model.fast`: the sparse path's threshold
    (:func:`is_large`) is its own."""
    return kept(data, f"scattered {name}", lambda: ScatteredFunction(getattr(model, name)))


def constraint_jacobian(model: Model, q: np.ndarray, w: np.ndarray, data: Data | None = None):
    """``Phi_v`` at ``(q, w)``: dense (n_c, n_v), or for a large model (:func:`is_large`) a
    SciPy CSR array built from its nonzeros; through the call buffers of ``data``."""
    if not is_large(model):
        return model.call("Phi_v", data, q=q, w=w)
    values = {"q": q, "w": w}
    function = _scattered(model, data, "Phi_v")
    return function.sparse(*[values[n] for n in function.name_in])[0]


def dynamics_terms(model: Model, values: dict, data: Data | None = None) -> tuple:
    """``(Phi_v, gamma, Q)`` at the state in ``values`` (by input name), ``Phi_v`` as
    :func:`constraint_jacobian` gives it."""
    if is_large(model):
        function = _scattered(model, data, "dynamics_terms")
        return tuple(function.sparse(*[values[n] for n in function.name_in]))
    terms = model.fast("dynamics_terms", data)
    Phi_v, gamma, Q = terms(*[values[n] for n in terms.name_in])
    return Phi_v.reshape(model.n_c, model.n_v), gamma, Q


# ---------------------------------------------------------------------- numeric (implicit methods)

def kept_multipliers(split: linalg.RowSplit, Phi_v, lam: np.ndarray,
                     mass_inv_sqrt) -> np.ndarray:
    """Multipliers on the kept rows ``split.independent`` that exert the forces ``Phi_v^T lam``
    of multipliers on all rows (the redundant rows' forces are the kept rows' combinations)."""
    return force_multipliers(split, Phi_v, np.asarray(Phi_v.T @ lam), mass_inv_sqrt)


def force_multipliers(split: linalg.RowSplit, Phi_v, force: np.ndarray,
                      mass_inv_sqrt) -> np.ndarray:
    """Multipliers on the kept rows ``split.independent`` whose constraint force
    ``Phi_v[kept]^T lam_I`` is nearest ``force`` (exactly ``force`` when it is a combination
    of the rows' forces). A dense split: NumPy's least squares on ``Phi_v[kept]^T``; a sparse
    one (a large model): its QR, ``W_I^T = Q_I R``, so that
    ``lam_I = R^-1 Q_I^T M^-1/2 force / d_I`` (least squares in the kinetic-energy norm: the
    same solution when the force is the kept rows')."""
    I = split.independent
    if not isinstance(split, sparse_qr.SparseRowSplit):
        Phi_v = linalg.as_dense(Phi_v)
        return np.linalg.lstsq(Phi_v[I].T, force, rcond=None)[0]
    if not I.size:
        return np.zeros(0)
    y = mass_inv_sqrt @ force
    return split.solve_r(split.project(y)) / split.scale[I]


def solve_sparse(A, b: np.ndarray, pivot_ratio: float = 1e-10) -> np.ndarray | None:
    """``A x = b`` for a square sparse ``A`` (the iteration matrix of an implicit method on a
    large model) by SuperLU, columns ordered by COLAMD, after the rows are equilibrated: the
    factors of a matrix on the body-joint graph stay as sparse as it. Where the smallest pivot
    falls below ``pivot_ratio`` times the largest (near a singular configuration) the dense
    :func:`~hexapod.algorithms.linalg.solve_or_least_squares` decides, as for a small model.
    None when neither gives finite numbers."""
    from scipy.sparse import diags
    from scipy.sparse.linalg import splu

    A = A.tocsr()
    scale = (np.asarray(abs(A).max(axis=1).todense(), dtype=float).reshape(-1) if A.shape[0]
             else np.ones(0))
    scale[~(scale > 0)] = 1.0
    As, bs = (diags(1.0 / scale) @ A).tocsc(), b / scale
    if not (np.all(np.isfinite(As.data)) and np.all(np.isfinite(bs))):
        return None
    try:
        lu = splu(As, permc_spec="COLAMD")
    except RuntimeError:  # exactly singular
        lu = None
    if lu is not None:
        pivots = np.abs(lu.U.diagonal())
        if pivots.size and pivots.min() > pivot_ratio * pivots.max():
            x = lu.solve(bs)
            if np.all(np.isfinite(x)):
                return x
    return linalg.solve_or_least_squares(A.toarray(), b, pivot_ratio)
