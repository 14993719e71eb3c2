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
  call for 300 bodies, the kernels' largest cost there), and :func:`solve_kept` eliminates
  the identity block: ``(W W^T) mu = W y0 - D^-1 gamma``, ``y = y0 - W^T mu``. ``W W^T``
  couples two joints' rows only when they share a body: block-tridiagonal for a chain, as
  sparse as the tree for a tree, with a loop-closing joint's rows coupled along the loop.
  CasADi's sparse Cholesky (CSparse, rows in approximate-minimum-degree order, which on this
  graph is the tree order, leaves first) fills 7 nonzeros per row of a chain's factor at 30,
  100 and 300 bodies and 13 for a tree (a dense factor: 750 per row at 300 bodies).

  The Schur complement squares the conditioning of ``W`` -- but so does the saddle-point
  matrix itself, whose smallest eigenvalue is ``sigma^2`` for a small singular value
  ``sigma`` of ``W`` (:meth:`hexapod.algorithms.linalg.RowSplit.condition_number`), and its
  sparse QR, used before, was no more accurate. Measured on the N-four-bar (10 windows) near
  its flat pose against the closed-form accelerations: at ``sigma = 1.3e-4`` the sparse QR of
  the saddle-point matrix was 3.5e-11 off and the Cholesky of ``W W^T`` 1.5e-11; at 1.3e-5,
  1.5e-9 and 1.9e-9; the dense QR of ``W_I^T`` of the exact solve 8.8e-13 and 3.0e-12 (below
  ``sigma = 1e-4`` the integrators cross with the nearly dependent rows left out, or refuse
  the compiled solve by its residual). The Cholesky costs a fifth of a call less (the
  300-body chain's rates 3.26 -> 2.62 ms). A matrix that is not positive definite fails the
  evaluation, and the caller falls back on the exact solve, as the QR's zero pivot did.
  ``LDL^T`` of the saddle-point matrix itself in tree order (each body, then the joint to its
  parent) would need no product ``W W^T``, but CasADi's sparse ``LDL^T`` breaks down on the
  zero diagonal of the multipliers' block (measured: NaN).
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
    """``(y, mu)`` solving ``[[I, W^T], [W, -Z]] [y; mu] = [top; bottom / d]`` on the kept
    ``rows``, ``W = D^-1 W_all`` there, through the Schur complement of the identity block:
    ``(W W^T + Z) mu = W top - bottom / d``, ``y = top - W^T mu``, by CasADi's sparse Cholesky
    (see the module's description). ``Z`` is zero, except 1 for a kept row that is
    identically zero (a foot's contact in swing), whose multiplier is then solved as zero
    instead of leaving the matrix singular. ``bottom``: all rows' right-hand sides (those of
    the kept rows are used). A matrix that is not positive definite (a singular
    configuration) fails the evaluation: the caller falls back on the exact solve."""
    W, S = schur_matrix(W_all, d, zero, rows)
    mu = ca.solve(S, ca.mtimes(W, top) - bottom[rows] / d[rows], "csparsecholesky")
    return top - ca.mtimes(W.T, mu), mu


def schur_matrix(W_all: ca.MX, d: ca.MX, zero: ca.MX, rows: list[int]) -> tuple[ca.MX, ca.MX]:
    """``W = D^-1 W_all`` on the kept ``rows`` and the Schur complement ``W W^T + Z`` of
    :func:`solve_kept`, as sparse as the body-joint graph (block-tridiagonal for a chain)."""
    W = ca.mtimes(ca.diag(1.0 / d[rows]), W_all[rows, :])  # sparse: never a dense node
    return W, ca.mtimes(W, W.T) + ca.diag(zero[rows])


# ---------------------------------------------------------------------- numeric (implicit methods)

def kept_multipliers(split: linalg.RowSplit, Phi_v, lam: np.ndarray,
                     mass_inv_sqrt) -> np.ndarray:
    """Multipliers on the kept rows ``split.independent`` that exert the forces ``Phi_v^T lam``
    of multipliers on all rows (the redundant rows' forces are the kept rows' combinations).
    A dense split: NumPy's least squares on ``Phi_v[kept]^T``; a sparse one (a large model):
    its QR, ``W_I^T = Q_I R``, so that ``lam_I = R^-1 Q_I^T M^-1/2 Phi_v^T lam / d_I`` (the same
    solution when the forces are the kept rows', which they are to the rank tolerance)."""
    I = split.independent
    if not isinstance(split, linalg.SparseRowSplit):
        Phi_v = linalg.as_dense(Phi_v)
        return np.linalg.lstsq(Phi_v[I].T, Phi_v.T @ lam, rcond=None)[0]
    if not I.size:
        return np.zeros(0)
    y = mass_inv_sqrt @ (Phi_v.T @ lam)
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
