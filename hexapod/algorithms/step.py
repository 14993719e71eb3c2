"""The constrained step of a row set, written once as CasADi expressions.

Every symbolic solve of the package works on the rows ``I`` a rank decision kept
(:func:`hexapod.algorithms.linalg.split_rows` decides them numerically; the batched drivers
hold them while their checks pass), equilibrated as the rank decision sees them:

    [[I, W_I^T], [W_I, Z]] [y; mu] = [top; bottom_I / d_I],   W = D^-1 Phi_v M^-1/2,

``y`` the velocity-space unknown in ``M^1/2``-scaled units (``v = M^-1/2 y``) and
``mu = D_I lambda_I`` the scaled multipliers. ``Z`` is zero, except -1 for a kept row that is
identically zero (a foot's contact in swing), whose multiplier is then solved as zero instead
of leaving the matrix singular. The same solve gives

* a Newton correction on the positions: ``top = 0``, ``bottom = -phi`` (the least-``M``-norm
  step onto the kept rows, applied with the Lie-group retraction);
* the velocities closest to a guess: ``top = M^1/2 v``, ``bottom = nu``;
* the accelerations and multipliers: ``top = M^-1/2 Q``, ``bottom = gamma``.

When the rows kept are as many as the velocities (a fully driven mechanism: inverse
dynamics), ``W_I`` is square and the system splits into ``y = W_I^-1 (bottom_I / d_I)`` and
``mu = W_I^-T (top - y)``: the same solve on half the unknowns. Both forms are factorised here
by CasADi's sparse QR (the ``qr`` linear solver: backward stable without pivoting, its
symbolic analysis done once per row set, its factors as sparse as the body-joint graph allows);
the batched inverse dynamics factorises its square ``W_I`` instead by an LU with pivots chosen
at the decision (:mod:`hexapod.algorithms.static_lu`, a tenth of the QR's operations), and so
do the integrators' kernels compiled to C in the saddle-point form, with pivots chosen at the
state where they are built (:func:`kept_pivots`; written out, the LU runs in 40 % of the
compiled QR's time, where CasADi's virtual machine gains nothing from it), or, for the
contact step's metric, in the body-joint tree's order whatever the state (:func:`tree_order`).
What
can go wrong as the state moves (a row that becomes dependent, a singular pose, pivots gone
stale) shows in the residual checks the callers evaluate.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod.algorithms.static_lu import StaticLU
from hexapod.model.model import GROUND_INDEX, Model


def equilibrated(Phi_v: ca.MX, m_inv_sqrt: ca.DM) -> tuple[ca.MX, ca.MX, ca.MX]:
    """``(W_all, d, zero)``: ``Phi_v M^-1/2`` (unscaled), its row norms ``d`` (1 for a zero
    row) and which rows are zero (a foot's contact in swing)."""
    W_all = ca.mtimes(Phi_v, m_inv_sqrt)
    norms = ca.sqrt(ca.sum2(W_all * W_all))
    zero = norms <= 0
    return W_all, ca.if_else(zero, 1.0, norms), zero


def kept_matrix(W_all: ca.MX, d: ca.MX, zero: ca.MX, rows: list[int],
                extra: ca.MX | None = None) -> ca.MX:
    """The saddle-point matrix ``[[I + E, W^T], [W, Z]]`` of the kept ``rows``, as sparse as
    ``Phi_v`` (MX or SX, as ``W_all``); ``E`` (``extra``, default none) adds the scaled
    stiffness and damping of a linearly implicit step to the metric."""
    n_v = W_all.size2()
    W = ca.mtimes(ca.diag(1.0 / d[rows]), W_all[rows, :])  # sparse: never a dense node
    metric = type(W_all).eye(n_v) if extra is None else type(W_all).eye(n_v) + extra
    return ca.vertcat(ca.horzcat(metric, W.T), ca.horzcat(W, -ca.diag(zero[rows])))


def kept_pivots(model: Model, rows: list[int], q: np.ndarray, w: np.ndarray) -> StaticLU:
    """Pivots for the LU of the saddle-point matrix of the kept ``rows`` (:func:`kept_matrix`,
    fewer rows than velocities), chosen by SuperLU at positions ``q`` and law values ``w``, or
    the body-joint tree's order (:func:`tree_order`) where it costs fewer operations (the
    18-joint robot's: 12,582 against 16,552; a chain's costs more): a kernel built with them
    serves the states near there, its residual checks saying when they no longer do."""
    tree = tree_order(model, rows)
    return StaticLU.pivoted(*kept_values(model, rows, q, w),
                            orders=() if tree is None else (tree,))


def tree_order(model: Model, rows) -> np.ndarray | None:
    """A symmetric elimination order of the saddle-point matrix of the kept ``rows``
    (:func:`kept_matrix`) that follows the body-joint tree: each body's velocities once its
    children's subtrees are eliminated, then the kept rows of the joint that holds it to its
    parent (its own and its drivers'). The articulated-body recursion's order: the pivots are
    the bodies' articulated metrics (positive definite with the metric) and the joints' rows
    seen through them (negative definite while the rows are independent), whatever the state,
    and nothing fills in beyond each body's parent. None where a kept row is no tree joint's
    (a loop-closing joint's, a coordinate driver's)."""
    n_v, rows = model.n_v, np.asarray(rows, dtype=int)
    place = {int(r): n_v + i for i, r in enumerate(rows)}
    holding, children = {}, {}
    for joint in model.joints:
        if not joint.loop_closing:
            holding[joint.child] = joint
            children.setdefault(joint.parent, []).append(joint.child)
    # the ground and the free bodies are the roots
    roots = [GROUND_INDEX] + [b for b in range(len(model.bodies)) if b not in holding]
    order: list[int] = []
    # post-order, without recursion (chains of thousands of bodies)
    stack = [(b, False) for b in reversed(roots)]
    while stack:
        body, done = stack.pop()
        if not done:
            stack.append((body, True))
            stack.extend((c, False) for c in reversed(children.get(body, [])))
            continue
        if body == GROUND_INDEX:
            continue
        v = model.bodies[body].v
        order.extend(range(v.start, v.stop))
        joint = holding.get(body)
        if joint is not None:
            order.extend(place[int(r)] for r in (*joint.rows, *joint.driver_rows)
                         if int(r) in place)
    if len(order) != n_v + rows.size or len(set(order)) != len(order):
        return None
    return np.asarray(order, dtype=int)


def kept_values(model: Model, rows: list[int], q: np.ndarray,
                w: np.ndarray) -> tuple[np.ndarray, np.ndarray, int, np.ndarray]:
    """The saddle-point matrix of the kept ``rows`` (:func:`kept_matrix`) at positions ``q``
    and law values ``w``: its pattern's rows and columns, its size and its values there (its
    Function built once per model and row set)."""
    def build(m: Model) -> tuple[ca.Function, np.ndarray, np.ndarray]:
        symbols = {"q": ca.SX.sym("q", m.n_q), "w": ca.SX.sym("w", m.n_w)}
        Phi_v = m.Phi_v(*[symbols[n] for n in m.Phi_v.name_in()])
        K = kept_matrix(*equilibrated(Phi_v, mass_factors(m)[0]), rows)
        pattern_rows, pattern_columns = K.sparsity().get_triplet()
        return (ca.Function("K", list(symbols.values()), [K]), np.array(pattern_rows),
                np.array(pattern_columns))

    function, pattern_rows, pattern_columns = model.built_once(
        ("kept matrix", tuple(int(r) for r in rows)), build)
    values = np.array(function(q, w).nonzeros())
    return pattern_rows, pattern_columns, function.size1_out(0), values


def solve_kept(W_all: ca.MX, d: ca.MX, zero: ca.MX, rows: list[int], top: ca.MX,
               bottom: ca.MX, lu: StaticLU | None = None,
               extra: ca.MX | None = None) -> tuple[ca.MX, ca.MX]:
    """``(y, mu)`` of the kept ``rows`` (see the module's description); ``bottom``: all rows'
    right-hand sides (those of the kept rows are used), ``top`` and ``bottom`` with as many
    columns as there are systems to solve with one factorisation. With ``lu`` (the pivots of
    :func:`kept_pivots`) the saddle-point form is factorised by that LU, written out, instead
    of CasADi's sparse QR (pivots chosen for the matrix with ``extra`` when it is given);
    the square form always by the QR. ``extra``: the metric's addition (:func:`kept_matrix`;
    the saddle-point form then)."""
    n_v = W_all.size2()
    scaled = bottom[rows, :] / ca.repmat(d[rows], 1, bottom.size2())
    if len(rows) == n_v and extra is None:
        W = ca.mtimes(ca.diag(1.0 / d[rows]), W_all[rows, :])
        y = ca.solve(W, scaled, "qr")
        return y, ca.solve(W.T, top - y, "qr")
    K = kept_matrix(W_all, d, zero, rows, extra)
    rhs = ca.vertcat(top, scaled)
    solution = (ca.solve(K, rhs, "qr") if lu is None else
                _lu_factored(lu, rhs.size2())(_lu_factor(lu, K.sparsity())(K), rhs))
    return solution[:n_v, :], solution[n_v:, :]


class KeptFactors:
    """The LU factors (by ``lu``'s fixed pivots) of the saddle-point matrix of the kept
    ``rows`` (:func:`kept_matrix`, the identity metric), formed once and solved with many
    times: the steps of a chord method, a projection's velocities after its positions.
    CasADi's sparse QR factorises at every solve, and cannot share them."""

    def __init__(self, W_all: ca.MX, d: ca.MX, zero: ca.MX, rows: list[int], lu: StaticLU):
        K = kept_matrix(W_all, d, zero, rows)
        self.n_v, self.rows, self.d, self.lu = W_all.size2(), rows, d, lu
        self.factors = _lu_factor(lu, K.sparsity())(K)

    def solve(self, top: ca.MX, bottom: ca.MX) -> tuple[ca.MX, ca.MX]:
        """``(y, mu)`` as :func:`solve_kept` gives them (``bottom``: all rows' right-hand
        sides), from the factors formed once."""
        rows = self.rows
        scaled = bottom[rows, :] / ca.repmat(self.d[rows], 1, bottom.size2())
        solution = _lu_factored(self.lu, top.size2())(self.factors, ca.vertcat(top, scaled))
        return solution[:self.n_v, :], solution[self.n_v:, :]


def _lu_factor(lu: StaticLU, pattern: ca.Sparsity) -> ca.Function:
    """``K -> F``: the packed factors of ``K`` (of ``pattern``, the one ``lu``'s pivots were
    chosen for) by ``lu``, one SX Function built once per LU and pattern."""
    key = ("factor", tuple(pattern.colind()), tuple(pattern.row()))
    functions = lu.__dict__.setdefault("_functions", {})
    if key not in functions:
        rows, columns = pattern.get_triplet()
        if not (np.array_equal(rows, lu.rows) and np.array_equal(columns, lu.columns)):
            raise ValueError("the LU's pivots were chosen for another pattern")
        K = ca.SX.sym("K", pattern)
        functions[key] = ca.Function("lu_factor", [K], [lu.factor(ca.vertcat(*K.nonzeros()))])
    return functions[key]


def _lu_factored(lu: StaticLU, columns: int) -> ca.Function:
    """``(F, B) -> K^-1 B`` from the packed factors ``F`` of :func:`_lu_factor`: one column's
    solve, mapped over the columns (compiled, a loop over one copy of its code, where the
    columns written out made a contact step's code, and its compiling, grow with them)."""
    key = ("solve", columns)
    functions = lu.__dict__.setdefault("_functions", {})
    if key not in functions:
        F, b = ca.SX.sym("F", lu.nnz), ca.SX.sym("b", lu.n)
        one = ca.Function("lu_factored_solve", [F, b], [lu.solve(F, b)])
        functions[key] = one if columns == 1 else one.map(
            f"lu_factored_solve_{columns}", "serial", columns, [0], [])
    return functions[key]


def retract(model: Model, q, dv):
    """``q (+) dv`` as :meth:`Model.integrate` computes it, on CasADi symbols: one call of the
    model's SX Function :attr:`Model.retract` (inlined on SX arguments; on MX one node, where
    the expression itself costs a tenth of a second per use to build on the walking robot)."""
    return model.retract(q, dv)


def newton(model: Model, position: ca.MX, residual, jacobian, rows: list[int],
           m_inv_sqrt: ca.DM, steps: int, lu: StaticLU | None = None) -> ca.MX:
    """``steps`` Newton corrections of ``position`` onto the kept ``rows``: each the least
    ``M``-norm step with ``Phi_v dv = -phi`` on those rows (:func:`solve_kept`, with ``lu``
    when given), applied with the retraction. ``residual(q)`` gives ``phi``, ``jacobian(q)``
    ``Phi_v``; the Jacobian is taken at the first position only (a chord method: the
    corrections are small)."""
    W_all, d, zero = equilibrated(jacobian(position), m_inv_sqrt)
    for _ in range(steps):
        y, _ = solve_kept(W_all, d, zero, rows, type(position).zeros(model.n_v),
                          -residual(position), lu)
        position = retract(model, position, ca.mtimes(m_inv_sqrt, y))
    return position


def sparse_dm(matrix) -> ca.DM:
    """A matrix (NumPy or SciPy sparse) as a CasADi DM with its nonzeros only, explicit zeros
    dropped: products with it skip the zeros."""
    from scipy.sparse import csc_array

    csc = csc_array(matrix)
    csc.eliminate_zeros()
    csc.sort_indices()
    pattern = ca.Sparsity(csc.shape[0], csc.shape[1], csc.indptr.tolist(), csc.indices.tolist())
    return ca.DM(pattern, csc.data.tolist())


def mass_factors(model: Model) -> tuple[ca.DM, ca.DM]:
    """``M^-1/2`` and ``M^1/2`` as sparse DMs (block-diagonal: scalars and 3 x 3 blocks), built
    from the blocks and built once per model."""
    def build(m: Model) -> tuple[ca.DM, ca.DM]:
        half = m.mass_inv_sqrt
        return sparse_dm(half.sparse()), sparse_dm(half.map_blocks(np.linalg.inv).sparse())

    return model.built_once(("mass factors",), build)
