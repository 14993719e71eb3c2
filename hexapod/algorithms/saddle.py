"""The equilibrated saddle-point system in time linear in the number of bodies.

Every forward solve of the package solves, on the rows kept by the rank decision,

    [[I, W^T], [W, 0]] [y; mu] = [M^-1/2 Q; D^-1 gamma],   W = D^-1 Phi_v M^-1/2,

(:mod:`hexapod.algorithms.linalg`). ``Phi_v`` has a few nonzeros per row: a joint's rows touch
the velocities of its two bodies only. The system is sparse along the body-joint graph, and a
factorisation that follows the graph costs a constant per body: a chain's or a tree's factors
are as sparse as the matrix (no fill beyond a body's neighbours), and a loop-closing joint adds
its rows along the loop. A dense factorisation costs ``O(n^3)``, and merely writing ``Phi_v``
densely ``O(n^2)``: at a thousand bodies, 30 million entries, nearly all zero.

Two forms, one for each kind of caller:

- **numeric** (the exact, rank-deciding solve of
  :func:`hexapod.algorithms.dynamics.forward_dynamics` and the kinematics, on a large
  model): ``Phi_v`` comes from CasADi as its nonzeros (:func:`constraint_jacobian`,
  :func:`dynamics_terms`), ``W`` is formed and scaled as a sparse matrix
  (:func:`hexapod.algorithms.linalg.equilibrate`), and the rank decision and the solve are the
  sparse Householder QR of ``W_I^T`` in priority order (:mod:`hexapod.algorithms.sparse_qr`),
  whose front stays a few bodies wide along a chain or a tree. Its smallest singular value,
  which the integrators watch near singular poses, is found by ARPACK on ``(R^T R)^-1`` (two
  sparse triangular solves a product), not by a dense SVD of ``R``. A model is **large**
  (:func:`is_large`) when its ``Phi_v`` has more than
  :data:`hexapod.algorithms.linalg.SPARSE_ABOVE` entries, few of them nonzero; below that the
  dense path is as fast and its numbers are the reference.

- **symbolic** (the compiled kernels of :mod:`hexapod.simulation.kernels`, built once in CasADi
  ``MX``): :func:`mass_factors` gives ``M^-1/2`` and ``M^1/2`` as sparse matrices from their
  3 x 3 blocks (a dense ``n_v x n_v`` one, and its inverse, cost ``O(n^2)`` and ``O(n^3)`` to
  build), :func:`equilibrated` scales the rows by a sparse diagonal product (scaling by a
  repeated matrix of the row norms made a dense ``n_c x n_v`` node: 2.7 million entries per
  call for 300 bodies, the kernels' largest cost there), and :func:`solve_kept` factorises
  the saddle-point matrix by CasADi's sparse QR. That QR orders the columns by approximate
  minimum degree of ``K^T K``, which on the body-joint graph's matrix finds the tree order:
  its factors hold 25 nonzeros per row of ``K`` for chains of 30, 100 and 300 bodies (83
  thousand at 300, where a dense factor would hold 1650 per row). An ``LDL^T``
  factorisation in tree order (leaves first, each body then the joint to its parent) has a
  quarter of the fill, but its pivots follow the mass ratios of neighbouring bodies rather
  than the geometry, and CasADi's sparse ``LDL^T`` breaks down on the zero diagonal of the
  multipliers' block (measured: NaN); the QR is kept.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod._support.fastcall import ScatteredFunction
from hexapod.algorithms import linalg
from hexapod.model.model import Model


def is_large(model: Model) -> bool:
    """Whether ``model``'s forward solves take the sparse path: its ``Phi_v`` has more than
    ``linalg.SPARSE_ABOVE`` entries and, structurally, fewer than ``linalg.SPARSE_DENSITY`` of
    them nonzero."""
    entries = model.n_c * model.n_v
    return (entries > linalg.SPARSE_ABOVE
            and model.Phi_v.nnz_out(0) < linalg.SPARSE_DENSITY * entries)


def _scattered(model: Model, name: str):
    """The model's Function ``name`` evaluated on its nonzeros (built once per model)."""
    return model.built_once(("scattered", name),
                            lambda m: ScatteredFunction(getattr(m, name)))


def constraint_jacobian(model: Model, q: np.ndarray, w: np.ndarray):
    """``Phi_v`` at ``(q, w)``: dense (n_c, n_v), or for a large model (:func:`is_large`) a
    SciPy CSR array built from its nonzeros."""
    if not is_large(model):
        return model.call("Phi_v", q=q, w=w)
    values = {"q": q, "w": w}
    function = _scattered(model, "Phi_v")
    return function.sparse(*[values[n] for n in function.name_in])[0]


def dynamics_terms(model: Model, values: dict) -> tuple:
    """``(Phi_v, gamma, Q)`` at the state in ``values`` (by input name), ``Phi_v`` as
    :func:`constraint_jacobian` gives it."""
    if is_large(model):
        function = _scattered(model, "dynamics_terms")
        return tuple(function.sparse(*[values[n] for n in function.name_in]))
    terms = model.fast("dynamics_terms")
    Phi_v, gamma, Q = terms(*[values[n] for n in terms.name_in])
    return Phi_v.reshape(model.n_c, model.n_v), gamma, Q


# ---------------------------------------------------------------------- symbolic (kernels)

def sparse_dm(matrix) -> ca.DM:
    """A SciPy sparse matrix as a CasADi DM of the same pattern (explicit zeros dropped)."""
    csc = matrix.tocsc()
    csc.eliminate_zeros()
    csc.sort_indices()
    pattern = ca.Sparsity(csc.shape[0], csc.shape[1], csc.indptr.tolist(),
                          csc.indices.tolist())
    return ca.DM(pattern, csc.data.tolist())


def mass_factors(model: Model) -> tuple[ca.DM, ca.DM]:
    """``M^-1/2`` and ``M^1/2`` as sparse DMs (block-diagonal: scalars and 3 x 3 blocks), built
    from the blocks and built once per model."""
    def build(m: Model) -> tuple[ca.DM, ca.DM]:
        half = m.mass_inv_sqrt
        return sparse_dm(half.sparse()), sparse_dm(half.map_blocks(np.linalg.inv).sparse())

    return model.built_once(("mass factors",), build)


def equilibrated(Phi_v: ca.MX, m_inv_sqrt: ca.DM) -> tuple[ca.MX, ca.MX, ca.MX]:
    """``(W_all, d, zero)``: ``Phi_v M^-1/2`` (unscaled), its row norms ``d`` (1 for a zero
    row) and which rows are zero (a foot's contact in swing)."""
    W_all = ca.mtimes(Phi_v, m_inv_sqrt)
    norms = ca.sqrt(ca.sum2(W_all * W_all))
    zero = norms <= 0
    return W_all, ca.if_else(zero, 1.0, norms), zero


def solve_kept(W_all: ca.MX, d: ca.MX, zero: ca.MX, rows: list[int], top: ca.MX,
               bottom: ca.MX) -> tuple[ca.MX, ca.MX]:
    """``(y, mu)`` solving ``[[I, W^T], [W, Z]] [y; mu] = [top; bottom / d]`` on the kept
    ``rows``, ``W = D^-1 W_all`` there, by CasADi's sparse QR (see the module's description).
    ``Z`` is zero, except -1 for a kept row that is identically zero, whose multiplier is then
    solved as zero instead of leaving the matrix singular. ``bottom``: all rows' right-hand
    sides (those of the kept rows are used)."""
    n_v = W_all.size2()
    K = kept_matrix(W_all, d, zero, rows)
    solution = ca.solve(K, ca.vertcat(top, bottom[rows] / d[rows]), "qr")
    return solution[:n_v], solution[n_v:]


def kept_matrix(W_all: ca.MX, d: ca.MX, zero: ca.MX, rows: list[int]) -> ca.MX:
    """The saddle-point matrix ``[[I, W^T], [W, Z]]`` of :func:`solve_kept`, as sparse as
    ``Phi_v``."""
    n_v = W_all.size2()
    W = ca.mtimes(ca.diag(1.0 / d[rows]), W_all[rows, :])  # sparse: never a dense node
    return ca.vertcat(ca.horzcat(ca.MX.eye(n_v), W.T), ca.horzcat(W, -ca.diag(zero[rows])))


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
    if not isinstance(split, linalg.SparseRowSplit):
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
