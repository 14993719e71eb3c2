"""The contact schemes' kernel: the engine's constrained solve with contact forces or impulses
on its right-hand side, linear in them, in one CasADi call (:class:`CompiledContactStep`), and
the rank decision it is built for (:func:`contact_solution`). Moreau-Jean's time step, the
event-driven scheme's smooth phases and their impacts each take one call a solve."""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod._support.execution import current
from hexapod._support.fastcall import FastFunction
from hexapod.algorithms.static_lu import StaticLU
from hexapod.algorithms.step import (
    equilibrated,
    kept_matrix,
    mass_factors,
    solve_kept,
    tree_order,
)
from hexapod.errors import IntegrationError
from hexapod.model.model import Model
from hexapod.simulation.kernels import (
    REDUNDANT_TOLERANCE,
    RESIDUAL_TOLERANCE,
    evaluated_as_set,
    pivot_key,
)


class CompiledContactStep:
    """The engine's constrained solve with contact forces or impulses on its right-hand side,
    linear in them, in one call. With ``M^1/2``-scaled unknowns ``y = M^1/2 x``, the
    equilibrated saddle-point system of the kept ``rows`` (:func:`~hexapod.algorithms.step.
    solve_kept`: CasADi's sparse QR, or an LU written out, :meth:`pivoted`)
    is solved for the forces in ``top`` alone, ``(y, lam)``,
    and for unit contact forces (``G = M^-1/2 J^T`` given), ``(Y, Lam)``: the contacts then
    see ``J x = G^T y + W F`` with the Delassus operator ``W = G^T Y``. The ``level``:

    * ``"step"`` (Moreau-Jean's time step, :mod:`hexapod.simulation.integrators.moreau_jean`):
      ``x`` the new velocity, the forces that depend on the state linearly implicit at
      ``theta``,

          (M + h theta C + (h theta)^2 K) (v1 - v) + Phi_v^T lam = h Q + J^T P,
          Phi_v v1 = nu(t + h),

      ``K`` and ``C`` the derivatives of ``-Q`` along the positions and in the velocities,
      all at ``(q, v)``, ``q`` the positions where the step's forces act (mid-step: their
      change over the step's second half, ``theta h (v1 - v)``, is the ``K`` term), the laws'
      values, rates and accelerations at ``t + theta h`` and the values and rates at ``t + h``
      given (``laws``: the five arrays);
    * ``"acceleration"`` (the event-driven scheme's smooth phases): ``x`` the acceleration,
      ``M a + Phi_v^T lam = Q + J^T F``, ``Phi_v a = gamma`` (``laws``: values, rates,
      accelerations);
    * ``"impulse"`` (an impact, a projection onto the contacts): ``x`` the velocity,
      ``M (x - v) + Phi_v^T lam = J^T P``, ``Phi_v x = nu`` (``laws``: values and rates).

    Its residuals (the kept rows', the rows ``left_out`` as redundant) say when the rows no
    longer serve: the call returns None, and :func:`contact_solution` decides them again."""

    def __init__(self, model: Model, rows: np.ndarray, left_out: np.ndarray, columns: int,
                 level: str = "step", lu: StaticLU | None = None):
        self.model, self.rows, self.columns = model, np.asarray(rows, dtype=int), columns
        self.left_out, self.level, self.lu = np.asarray(left_out, dtype=int), level, lu
        self._to_c = current().compiled
        self._key = ("contact " + level, tuple(self.rows.tolist()),
                     tuple(self.left_out.tolist()), columns, self._to_c, pivot_key(lu))
        self._fast: FastFunction | None = None  # built (compiled) at the first call

    def made(self) -> CompiledContactStep:
        """Itself, its Function built (compiled) now rather than at its first call."""
        if self._fast is None:
            self._fast = FastFunction(self.function)
        return self

    @property
    def function(self) -> ca.Function:
        """The kernel's Function, built (and compiled) once per model at its first use."""
        return self.model.built_once(self._key, lambda m: evaluated_as_set(self._build(),
                                                                          self._to_c))

    @classmethod
    def started(cls, model: Model, data, columns: int, level: str = "step"):
        """The kernel of the rows a run's workspace ``data`` decided at its start."""
        rows, none = data.independent_rows, np.zeros(0, int)
        return cls(model, none if rows is None else rows,
                   none if rows is None else data.redundant_rows, columns, level)

    def with_columns(self, columns: int) -> CompiledContactStep:
        """The same solve (rows, level, pivots) for ``columns`` contact columns."""
        return CompiledContactStep(self.model, self.rows, self.left_out, columns, self.level,
                                   self.lu)

    def pivoted(self, q: np.ndarray, v: np.ndarray, laws: tuple, h: float = 0.0,
                theta: float = 0.0) -> CompiledContactStep:
        """The same solve by an LU of the saddle-point matrix, written out as straight-line
        code, when compiled. Its pivots follow the body-joint tree where every kept row is a
        tree joint's (:func:`~hexapod.algorithms.step.tree_order`): the same for every state,
        so one kernel serves every run of the model, and on the walking robot 55,000
        instructions to factor where SuperLU's pivots took 121,000 (the QR's kernel 0.42 ms
        of a step inside its loop, this LU's 0.24 ms; see the commits). Elsewhere SuperLU
        chooses them at this call's arguments (:meth:`__call__`'s without ``G``; pivots first
        chosen for these rows serve later runs whose matrix they still factor with little
        growth, :meth:`~hexapod.algorithms.static_lu.StaticLU.serves`). Every level: the
        event-driven scheme's acceleration and impulse solves, compiled, take 167 and 196 us
        by it where the QR took 353 and 349 (the walking robot's 18 contact columns; one-off
        timing). Itself where the LU does not apply (interpreted: CasADi's virtual machine
        gains nothing from it; no rows; as many rows as velocities: the square form). Stale
        pivots show in the residual check, which falls back to the QR's kernel
        (:func:`contact_solution`). ``h`` and ``theta``: the step's alone."""
        model = self.model
        if not current().compiled or not self.rows.size or self.rows.size == model.n_v:
            return self
        matrix = model.built_once(("contact matrix", self.level, tuple(self.rows.tolist())),
                                  lambda m: self._matrix())
        pattern_rows, pattern_columns = matrix.sparsity_out(0).get_triplet()
        size = matrix.size1_out(0)
        order = tree_order(model, self.rows)
        if order is not None:
            lu = model.built_once(
                ("contact tree LU", self.level, tuple(self.rows.tolist())),
                lambda m: StaticLU(pattern_rows, pattern_columns, size, order, order))
        else:
            arguments = [q, v, *(laws if model.n_w else ())] + (
                [h, theta] if self.level == "step" else [])
            values = np.asarray(matrix(*arguments).nonzeros(), dtype=float)
            first = model.built_once(("contact pivots", self.level), lambda m: {})
            lu = first.get(self.rows.tobytes())
            if lu is None or not lu.serves(values):
                lu = StaticLU.pivoted(pattern_rows, pattern_columns, size, values)
                first.setdefault(self.rows.tobytes(), lu)
        return CompiledContactStep(model, self.rows, self.left_out, self.columns, self.level,
                                   lu)

    def _terms(self) -> tuple:
        """The step's symbols by name, its inputs' names, and its expressions: the free
        right-hand side's first column and its rows' part, the metric's addition (None: the
        identity) and the rows' Jacobian: ``(named, inputs, first, bottom, extra, Phi_v)``."""
        model, level, n = self.model, self.level, self.model.n_w
        symbols = {"q": ca.MX.sym("q", model.n_q), "v": ca.MX.sym("v", model.n_v),
                   "w": ca.MX.sym("w", n), "wd": ca.MX.sym("wd", n), "wdd": ca.MX.sym("wdd", n),
                   "lam": ca.MX(model.n_c, 1)}
        end = {"w": ca.MX.sym("w1", n), "wd": ca.MX.sym("wd1", n)}
        G, h, theta = ca.MX.sym("G", model.n_v, self.columns), ca.MX.sym("h"), ca.MX.sym("theta")

        def call(function, **values):
            return function(*[values.get(name, symbols[name]) for name in function.name_in()])

        v = symbols["v"]
        m_inv_sqrt, m_sqrt = mass_factors(model)
        extra = None
        laws = {"step": ["w", "wd", "wdd", "w1", "wd1"], "acceleration": ["w", "wd", "wdd"],
                "impulse": ["w", "wd"]}[level] if n else []
        Phi_v = None  # the rows' Jacobian, when a level's terms give it
        if level == "acceleration":
            Phi_v, bottom, Q = call(model.dynamics_terms)
            first = ca.mtimes(m_inv_sqrt, Q)
        elif level == "impulse":
            first, bottom = ca.mtimes(m_sqrt, v), call(model.nu) if model.n_c else None
        else:
            K, C, Q = call(model.force_tangents)  # not dynamics_terms: no gamma needed
            a = h * theta
            force = h * Q + ca.mtimes(a * C + a * a * K, v)
            first = ca.mtimes(m_sqrt, v) + ca.mtimes(m_inv_sqrt, force)
            bottom = call(model.nu, **end) if model.n_c else None
            extra = ca.mtimes(ca.mtimes(m_inv_sqrt, a * C + a * a * K), m_inv_sqrt)
        named = {**symbols, "w1": end["w"], "wd1": end["wd"], "G": G, "h": h, "theta": theta}
        inputs = ["q", "v", *laws, "G"] + (["h", "theta"] if level == "step" else [])
        if model.n_c and Phi_v is None:
            Phi_v = call(model.Phi_v)
        return named, inputs, first, bottom, extra, Phi_v

    def _build(self) -> ca.Function:
        named, inputs, first, bottom, extra, Phi_v = self._terms()
        top = ca.horzcat(first, named["G"])
        y, lam, residual = self._solve(top, bottom, extra, Phi_v)
        return ca.Function("contact_" + self.level, [named[k] for k in inputs],
                           [y, lam, residual], inputs, ["y", "lam", "residual"])

    def _matrix(self) -> ca.Function:
        """The saddle-point matrix of the kept rows (:func:`~hexapod.algorithms.step.
        kept_matrix`, with the step's metric) from the step's arguments without ``G``."""
        named, inputs, _, _, extra, Phi_v = self._terms()
        K = kept_matrix(*equilibrated(Phi_v, mass_factors(self.model)[0]),
                        self.rows.tolist(), extra)
        inputs = [k for k in inputs if k != "G"]
        return ca.Function("contact_matrix", [named[k] for k in inputs], [K], inputs, ["K"])

    def _solve(self, top, bottom, extra, Phi_v) -> tuple:
        """``(y, lam, residual)`` of the kept rows' system (see the class's description);
        ``Phi_v`` the rows' Jacobian."""
        model, rows, columns = self.model, self.rows.tolist(), self.columns
        if model.n_c == 0:
            solved = extra is not None and extra.nnz()
            y = ca.solve(ca.MX.eye(model.n_v) + extra, top, "qr") if solved else top
            return y, ca.MX(0, columns + 1), ca.MX.zeros(2)
        m_inv_sqrt, _ = mass_factors(model)
        W_all, d, zero = equilibrated(Phi_v, m_inv_sqrt)
        y, mu = solve_kept(W_all, d, zero, rows, top,
                           ca.horzcat(bottom, ca.MX(model.n_c, columns)), self.lu, extra)
        lam = ca.MX(model.n_c, columns + 1)
        lam[rows, :] = mu / ca.repmat(d[rows], 1, columns + 1)
        scaled = ca.fabs(ca.mtimes(Phi_v, ca.mtimes(m_inv_sqrt, y[:, 0])) - bottom) / d
        size = ca.norm_inf(y[:, 0]) + ca.norm_inf(top[:, 0]) + 1e-300
        others = [i for i in range(model.n_c) if i not in set(rows)]
        residual = ca.vertcat(ca.mmax(scaled[rows]) / size,
                              ca.mmax(scaled[others]) / size if others else ca.MX(0.0))
        return y, lam, residual

    def __call__(self, q: np.ndarray, v: np.ndarray, laws: tuple, G: np.ndarray,
                 h: float = 0.0, theta: float = 0.0) -> tuple | None:
        """``(y, lam, Y, Lam)`` (see the class's description), or None when the residuals
        refuse the solve (a row kept has become dependent, one left out independent, or the
        numbers are not finite). ``laws``: the arrays the level takes, in order."""
        arguments = [q, v, *(laws if self.model.n_w else ()), G]
        if self.level == "step":
            arguments += [h, theta]
        try:
            y, lam, residual = self.made()._fast(*arguments)
        except RuntimeError:  # the factorisation failed: a singular matrix, or NaN in it
            return None
        columns = self.columns + 1
        y, lam = y.reshape(self.model.n_v, columns), lam.reshape(self.model.n_c, columns)
        if not (residual[0] <= RESIDUAL_TOLERANCE and residual[1] <= REDUNDANT_TOLERANCE
                and np.isfinite(y).all() and np.isfinite(lam).all()):
            return None
        return y[:, 0], lam[:, 0], y[:, 1:], lam[:, 1:]


def contact_solution(kernel: CompiledContactStep, decide, *arguments
                     ) -> tuple[CompiledContactStep, tuple]:
    """``kernel``'s solution (:meth:`CompiledContactStep.__call__` of ``arguments``); when it
    is refused, the rows decided again by ``decide()`` (a ``RowSplit``) and a kernel built for
    them. Returns the kernel that solved and the solution; raises :class:`IntegrationError`
    when the rows decided again do not serve either (a singular configuration)."""
    solution = kernel(*arguments)
    if solution is None:
        split = decide()
        kernel = CompiledContactStep(kernel.model, split.independent, split.redundant,
                                     kernel.columns, kernel.level)
        solution = kernel(*arguments)
    if solution is None:
        raise IntegrationError(f"the {kernel.level} solve with contacts has no reliable "
                               "solution (a singular configuration)")
    return kernel, solution
