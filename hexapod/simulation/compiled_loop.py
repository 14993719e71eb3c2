"""A compiled time loop for the explicit methods: the embedded Runge-Kutta pairs with projection
(DOPRI5, DOP853) and classical Runge-Kutta with Baumgarte's stabilisation (RK4).

The Python loop of :class:`~hexapod.simulation.integrators.embedded.EmbeddedRungeKutta` spends
about 0.3 ms of CPU per step on a one-body pendulum, nearly all of it in Python around compiled
calls of a few microseconds. A :class:`LoopKernel` is built once per model, method and row set:
one CasADi Function

    loop(carry, settings) -> (carry, trace)

that attempts up to :data:`ATTEMPTS` steps in one call, each exactly as the method's Python
step takes it. For DOPRI5 and DOP853 (:class:`EmbeddedKernel`, as
:meth:`EmbeddedRungeKutta._step`): the step cut at the end of the run, the stages through the
compiled saddle-point solve of :class:`~hexapod.simulation.kernels.CompiledRates` on the kept
rows, the error in the same weighted RMS norm, accept or reject with the same controller, on
acceptance the Euler parameters normalised, the projection of
:class:`~hexapod.simulation.kernels.CompiledProjection` and the accelerations at the projected
state. For ``rk4-baumgarte`` (:class:`BaumgarteKernel`): fixed steps, no error test, the same
numbers as its Python loop to the last bit on the cases tested. Each counts the work as the
Python loop counts it, and at every accepted step measures what the time loop watches (the
largest scaled constraint residuals, the energy).

``carry`` holds the time, the step, a code saying why the loop stopped (:data:`RUNNING` while
it runs), the counters and the state ``(q, v, v_dot)``; ``settings`` the end of the run, the
largest step, the tolerances, the time after which to stop for output and the caps on the
counters (the points where the Python loop weighs the run). ``trace`` has one column per
attempt: whether it was accepted, and then its state and what the loop watches.

Where the compiled path cannot be trusted the attempt is not taken: the carry is returned as
it was before it, with the code :data:`HANDOVER`, and the integrator takes that step in Python
with today's exact logic (the rank-deciding solve, crossings of singular poses), then resumes
the compiled loop. That happens when a compiled solve's residual check fails (a change of rank,
a singular configuration, non-finite values: the checks of ``CompiledRates`` and
``CompiledProjection``), when a rejected step may be near a singular pose (the smallest singular
value of the equilibrated ``Phi_v`` may be below :data:`SINGULAR_BAND`, the band where
:meth:`Integrator._cross_singular` may begin a crossing; a lower bound of it,
``1 / sqrt(trace((W W^T)^-1))``, decides), and when the step falls below the smallest the
method takes (it then fails in Python, with its message).

Models whose laws of time have no closed form (splines, gaits: :meth:`Law.symbolic` returns
None) and models with feet switching contacts keep the Python loop (:func:`unsupported`).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np

from hexapod._support.compiled import compiled
from hexapod._support.fastcall import FastFunction
from hexapod.algorithms.saddle import sparse_dm
from hexapod.model.model import Model
from hexapod.simulation.kernels import (
    REDUNDANT_TOLERANCE,
    RESIDUAL_TOLERANCE,
    compiled_projection,
    compiled_rates,
)
from hexapod.simulation.scales import BRANCH_JUMP, ENERGY_JUMP, ROUND_OFF, motion_scales

#: attempts of a step per call of the kernel, at most (the integrator's side asks for fewer
#: when its steps are slow: :class:`~hexapod.simulation.compiled_steps.CompiledStepper`)
ATTEMPTS = 256
#: why the loop stopped: still running (all attempts made), the end of the run reached, an
#: accepted step reached the output time, a cap on the counters reached, the next attempt
#: handed over to Python, or a step rejected whose state Python must weigh (its smallest
#: singular value, with more than :data:`GRAM_ROWS` rows kept)
RUNNING, FINISHED, OUTPUT, PAUSED, HANDOVER, CHECK = 0, 1, 2, 3, 4, 5
#: the head of the carried vector: the time, the step to try next, the code, the counters, the
#: last accepted step's length and the last rejected one's; the state ``(q, v, v_dot)`` follows
_HEAD = ("t", "h", "code", "steps", "rejected", "rhs", "jacobians", "factorisations", "newton",
         "accepted_step", "h_rejected")
#: where each of them sits in the carried vector
HEAD = {name: i for i, name in enumerate(_HEAD)}
#: the counters among them
COUNTERS = _HEAD[3:9]
#: a rejected step stays in the kernel, the rank decision that may begin a crossing replaced by
#: a bound of the smallest singular value from the Gram matrix of the kept rows, when they are
#: at most this many; with more, the bound (a factorisation of that matrix and as many solves
#: as rows) costs more than the Python loop's rank decision (the N-four-bar with 40 windows,
#: 242 rows: 40 ms per rejection in the virtual machine), and the kernel returns after each
#: rejected step for Python to weigh its state (:data:`CHECK`)
GRAM_ROWS = 40
#: bytes of generated C the compiler takes per CPU second, about (gcc -O2: 1.2 s for DOP853's
#: kernel of the pendulum, 144 kB; 13 s for a chain of 18 spatial bodies, 1.7 MB)
COMPILE_RATE = 130e3
#: the C compiler's options. DOP853's kernel of the pendulum: -O2 compiles in 1.1 s of CPU, its
#: steps take 22 us; -O1 in 0.7 s, 25 us; -O0 in 0.24 s
FLAGS = ("-O2",)
#: entries of ``settings`` before the absolute tolerances
_SETTINGS = ("t_bound", "max_step", "rtol", "t_stop", "steps_cap", "tried_cap")


def unsupported(model: Model) -> str:
    """Why ``model`` cannot run in the compiled loop (empty when it can): feet that switch
    contacts (their rows come and go with the gait), or a law of time without a closed form."""
    if model.contacts:
        return "its feet switch contacts"
    t = ca.MX.sym("t")
    for law in model.laws:
        if law.symbolic(t) is None:
            return f"its {type(law).__name__.lower()} law has no closed form"
    return ""


@dataclass
class Layout:
    """Where each quantity sits in the carried vector and in a column of the trace."""

    n_q: int
    n_v: int
    n_c: int

    def __post_init__(self):
        head = len(_HEAD)
        self.index = HEAD
        self.q = slice(head, head + self.n_q)
        self.v = slice(self.q.stop, self.q.stop + self.n_v)
        self.v_dot = slice(self.v.stop, self.v.stop + self.n_v)
        self.carry = self.v_dot.stop
        self.state = slice(head, self.carry)
        self.settings = len(_SETTINGS) + self.n_q + self.n_v
        # trace: accepted, t, q, v, v_dot, lam, phi, velocity, kinetic, total
        self.row_q = slice(2, 2 + self.n_q)
        self.row_v = slice(self.row_q.stop, self.row_q.stop + self.n_v)
        self.row_v_dot = slice(self.row_v.stop, self.row_v.stop + self.n_v)
        self.row_lam = slice(self.row_v_dot.stop, self.row_v_dot.stop + self.n_c)
        self.row_watch = slice(self.row_lam.stop, self.row_lam.stop + 4)
        self.row = self.row_watch.stop


class _Pieces:
    """The model's compiled pieces called on symbols: laws of time, rates, projection, what
    the loop watches."""

    def __init__(self, model: Model, rows: np.ndarray):
        self.model = model
        self.rates_function = compiled_rates(model, rows).function
        self.projection = compiled_projection(model, rows)
        self.newton = self.projection.newton

    def laws(self, t) -> list:
        """``[w, wd, wdd]`` at ``t`` (empty without laws)."""
        if not self.model.n_w:
            return []
        forms = [law.symbolic(t) for law in self.model.laws]
        return [ca.vertcat(*[form[k] for form in forms]) for k in range(3)]

    def rates(self, t, q, v, alpha: float = 0.0):
        """``(q_dot, v_dot, lam, ok)``, with Baumgarte's rate ``alpha``: ``ok`` when the
        compiled solve passes the checks of :meth:`CompiledRates.solve`."""
        q_dot, v_dot, lam, residual = self.rates_function(q, v, *self.laws(t), alpha)
        ok = ca.logic_and(ca.logic_and(residual[0] <= RESIDUAL_TOLERANCE,
                                       residual[1] <= REDUNDANT_TOLERANCE), _finite(v_dot))
        return q_dot, v_dot, lam, ok

    def project(self, t, q, v):
        """``(q, v, ok)``: the projection, ``ok`` as :class:`CompiledProjection` decides."""
        laws = self.laws(t)[:2]
        position, velocity, phi_error, rate_error = self.projection.function(q, v, *laws)
        ok = ca.logic_and(ca.logic_and(phi_error <= self.projection.tol,
                                       rate_error <= RESIDUAL_TOLERANCE),
                          _finite(ca.vertcat(position, velocity)))
        return position, velocity, ok

    def watched(self, t, q, v):
        """What the time loop watches at an accepted state: the largest scaled residuals of
        ``phi`` and of ``Phi_v v - nu``, the kinetic and the total energy."""
        model = self.model
        laws = self.laws(t)
        values = {"q": q, "v": v, "w": laws[0] if laws else None,
                  "wd": laws[1] if laws else None}

        def call(function):
            return function(*[values[n] for n in function.name_in()])

        if model.n_c:
            scale = ca.DM(model.row_scale)
            phi = ca.mmax(ca.fabs(call(model.phi) / scale))
            rate = ca.mtimes(call(model.Phi_v), v) - call(model.nu)
            velocity = ca.mmax(ca.fabs(rate / scale))
        else:
            phi = velocity = ca.MX(0.0)
        if model.energy_conserved:
            kinetic, potential = model.energy(q, v)
        else:
            kinetic = potential = ca.MX(0.0)
        return ca.vertcat(phi, velocity, kinetic, kinetic + potential)

    def singular_bound(self, t, q):
        """``trace((W W^T)^-1)`` of the kept rows of the equilibrated ``Phi_v`` at ``(t, q)``:
        its inverse square root is a lower bound of their smallest singular value."""
        model, rows = self.model, self.projection.rows.tolist()
        if not rows:
            return ca.MX(0.0)
        laws = self.laws(t)[:1]
        Phi_v = model.Phi_v(q, *laws)
        m_inv_sqrt = ca.DM(model.mass_inv_sqrt.dense())
        W = ca.mtimes(Phi_v[rows, :], m_inv_sqrt)
        norms = ca.sqrt(ca.sum2(W * W))
        W = W / ca.repmat(norms, 1, model.n_v)
        gram = ca.mtimes(W, W.T)
        inverse = ca.solve(gram, ca.MX.eye(len(rows)), "qr")
        return ca.trace(inverse)


def _finite(x) -> ca.MX:
    """1 when every entry of ``x`` is finite (a sum of magnitudes: NaN and inf propagate)."""
    return ca.sum1(ca.fabs(x)) < ca.inf


def _combination(weights, stages):
    """``sum_j weights[j] stages[j]`` over the nonzero weights, in order."""
    total = None
    for weight, stage in zip(weights, stages, strict=False):
        if weight != 0.0:
            term = float(weight) * stage
            total = term if total is None else total + term
    return total if total is not None else 0 * stages[0]


class LoopKernel:
    """Up to :data:`ATTEMPTS` attempts of a method's step in one call (see the module's
    description); a subclass builds the attempt (:meth:`_attempt`) and names the kernel.

    The kernel is evaluated by CasADi's virtual machine; :meth:`compiled_copy` is the same
    compiled to C.
    """

    name = "loop"
    #: right-hand sides an attempt evaluates (those a rejection undoes, see ``CHECK``)
    stage_count = 0

    def __init__(self, model: Model, rows: np.ndarray):
        self.model = model
        self.layout = Layout(model.n_q, model.n_v, model.n_c)
        self.pieces = _Pieces(model, np.asarray(rows, dtype=int))
        self.function = self._loop()
        self.compiled, self.compile_error = False, ""
        self._fast = FastFunction(self.function)
        #: the key of its compiled library in the cache on disk (set by the integrator's
        #: side: the model's content hash, the method, the rows and the options), or None
        self.cache_key: str | None = None

    @cached_property
    def source(self) -> str:
        """The kernel as C (CasADi's code generator)."""
        generator = ca.CodeGenerator(f"{self.function.name()}.c", {"with_header": False})
        generator.add(self.function)
        return generator.dump()

    def compile_seconds(self) -> float:
        """The CPU seconds the compiler is foreseen to take (:data:`COMPILE_RATE`)."""
        return len(self.source) / COMPILE_RATE

    def compiled_copy(self) -> LoopKernel:
        """The kernel compiled to C (:data:`FLAGS`), from the cache on disk when a run of the
        same model compiled it before (:attr:`cache_key`); itself, with ``compile_error``
        saying why, when no compiler is found or it fails (a warning says how)."""
        function = compiled(self.cache_key, lambda: self.function, flags=FLAGS,
                            what=f"compiled time loop ({self.name}) of {self.model.name}")
        if function is self.function:  # the interpreted Function: the virtual machine serves
            self.compile_error = ("no C compiler found (or HEXAPOD_NO_JIT is set), or it "
                                  "failed")
            return self
        twin = copy.copy(self)
        twin.function, twin.compiled, twin._fast = function, True, FastFunction(function)
        return twin

    def run(self, carry: np.ndarray, settings: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One call: the carry after it and the trace (one row per attempt)."""
        out, trace = self._fast(carry, settings)
        return out, trace.T

    # ------------------------------------------------------------------ building blocks

    def _attempt(self) -> ca.Function:
        """``(carry, settings) -> (carry, row)``: one attempt of a step."""
        raise NotImplementedError

    def _symbols(self):
        L = self.layout
        return ca.MX.sym("carry", L.carry), ca.MX.sym("settings", L.settings)

    def _loop(self) -> ca.Function:
        """``(carry, settings) -> (carry, trace)``: :data:`ATTEMPTS` attempts, those after the
        loop stopped idle."""
        L = self.layout
        carry, settings = self._symbols()
        idle = ca.Function("idle", [carry, settings], [carry, ca.MX.zeros(L.row)])
        switch = ca.Function.if_else("running", self._attempt(), idle)
        step = ca.Function("step", [carry, settings],
                           switch(carry[L.index["code"]] == RUNNING, carry, settings))
        loop = step.mapaccum("attempts", ATTEMPTS)
        states, trace = loop(carry, ca.repmat(settings, 1, ATTEMPTS))
        return ca.Function(f"loop_{self.name}", [carry, settings], [states[:, -1], trace],
                           ["carry", "settings"], ["carry_out", "trace"])

    @staticmethod
    def _next_step(carry, settings, L: Layout):
        """The step to take, as :meth:`Integrator.next_step` cuts it at the end of the run."""
        t, remaining = carry[L.index["t"]], settings[0] - carry[L.index["t"]]
        h = ca.fmin(carry[L.index["h"]], settings[1])
        return t, ca.if_else(h >= 0.99 * remaining, remaining, h)

    def _taken(self, carry, settings, step: dict, counts: dict, check=None):
        """``(carry, row)`` of an accepted step: ``step`` holds its length ``h``, its end
        ``t, q, v, v_dot, lam``, the step to try next ``h_next`` and ``ok`` (its compiled
        solves passed); ``counts`` what to add to the counters; ``check(watched, steps)``
        further conditions on what the loop watches at the end. The end time is snapped to the
        end of the run as :meth:`Integrator.step` snaps it; the code says why to stop; the carry
        is handed over when a check fails."""
        L = self.layout
        t_bound = settings[0]
        finished = step["t"] >= t_bound - 1e-12 * ca.fmax(1.0, ca.fabs(t_bound))
        t_new = ca.if_else(finished, t_bound, step["t"])
        head = [carry[L.index[name]] + counts.get(name, 0) for name in _HEAD]
        head[L.index["t"]], head[L.index["h"]] = t_new, step["h_next"]
        head[L.index["accepted_step"]] = step["h"]
        steps = head[L.index["steps"]]
        tried = steps + head[L.index["rejected"]]
        head[L.index["code"]] = ca.if_else(finished, FINISHED, ca.if_else(
            t_new >= settings[3], OUTPUT,
            ca.if_else(ca.logic_or(steps >= settings[4], tried >= settings[5]), PAUSED,
                       RUNNING)))
        q, v, v_dot = step["q"], step["v"], step["v_dot"]
        watched = self.pieces.watched(t_new, q, v)
        ok = step["ok"] if check is None else ca.logic_and(step["ok"], check(watched, steps))
        taken = ca.vertcat(*head, q, v, v_dot)
        row = ca.vertcat(1.0, t_new, q, v, v_dot, step["lam"], watched)
        return (ca.if_else(ok, taken, _handed_over(L, carry)),
                ca.if_else(ok, row, ca.MX.zeros(L.row)))


class EmbeddedKernel(LoopKernel):
    """The compiled loop of an embedded pair with projection (DOPRI5, DOP853).

    Parameters
    ----------
    model : Model
    method : type
        The integrator class: its tableau ``A, b, b_hat, c``, ``error_order``,
        ``error_estimate`` (``"difference"`` of the pair's two solutions, or ``"dop853"``:
        the combined 5th and 3rd order estimates and one more stage at the step's end) and its
        controller's ``safety, min_factor, max_factor``.
    rows : ndarray of int
        The kept rows the compiled solves work with.
    singular_band : float
        A rejected step hands over when the smallest singular value may be below this.
    """

    def __init__(self, model: Model, method: type, rows: np.ndarray, *, singular_band: float):
        self.method, self.singular_band = method, float(singular_band)
        self.name = method.__name__.lower()
        self.stage_count = len(method.c) + (1 if method.error_estimate == "dop853" else 0)
        super().__init__(model, rows)

    # ------------------------------------------------------------------ the attempt

    def _stages(self, carry, settings):
        """The step to try, its stages, the propagated solution and the error: ``(h, K, y1,
        error, ok)``, ``ok`` when every compiled solve passed its checks and the step is not
        below the smallest the method takes."""
        L, method, pieces, n_q = self.layout, self.method, self.pieces, self.model.n_q
        t, h = self._next_step(carry, settings, L)
        rtol = settings[2]
        ok = h >= 1e-14 * ca.fmax(1.0, ca.fabs(t))
        q, v = carry[L.q], carry[L.v]
        y0 = ca.vertcat(q, v)
        stages = [ca.vertcat(self.model.qdot(q, v), carry[L.v_dot])]
        for i in range(1, len(method.c)):
            y = y0 + h * _combination(method.A[i, :i], stages)
            q_dot, v_dot, _, ok_i = pieces.rates(t + float(method.c[i]) * h, y[:n_q], y[n_q:])
            stages.append(ca.vertcat(q_dot, v_dot))
            ok = ca.logic_and(ok, ok_i)
        y1 = y0 + h * _combination(method.b, stages)
        weight = settings[len(_SETTINGS):] + rtol * ca.fmax(ca.fabs(y0), ca.fabs(y1))
        if method.error_estimate == "dop853":
            q_dot, v_dot, _, ok_end = pieces.rates(t + h, y1[:n_q], y1[n_q:])
            stages.append(ca.vertcat(q_dot, v_dot))
            ok = ca.logic_and(ok, ok_end)
            err5 = ca.sumsqr(_combination(method.E5, stages) / weight)
            err3 = ca.sumsqr(_combination(method.E3, stages) / weight)
            error = ca.if_else(ca.logic_and(err5 == 0, err3 == 0), 0.0,
                               h * err5 / ca.sqrt((err5 + 0.01 * err3) * y0.numel()))
        else:
            x = h * _combination(method.b - method.b_hat, stages)
            error = ca.sqrt(ca.sumsqr(x / weight) / y0.numel())
        error = ca.if_else(_finite(y1), error, ca.inf)
        return h, y1, error, ok

    def _accepted(self) -> ca.Function:
        """``(carry, settings, h, y1, error) -> (carry, row)`` of an accepted step: normalised,
        projected, its accelerations solved, counted, watched; handed over when a compiled
        solve refuses."""
        L, method, pieces, model = self.layout, self.method, self.pieces, self.model
        carry, settings, h, y1, error = self._branch_symbols()
        factor = ca.if_else(error == 0, method.max_factor, ca.fmin(
            method.max_factor, method.safety * error ** (-1.0 / (method.error_order + 1))))
        t_new = carry[L.index["t"]] + h
        q, v, ok = pieces.project(t_new, _normalised(model, y1[:model.n_q]), y1[model.n_q:])
        _, v_dot, lam, ok_rates = pieces.rates(t_new, q, v)
        step = {"h": h, "t": t_new, "q": q, "v": v, "v_dot": v_dot, "lam": lam,
                "h_next": h * factor, "ok": ca.logic_and(ok, ok_rates)}
        counts = {"steps": 1, "rhs": self.stage_count, "newton": pieces.newton,
                  "jacobians": pieces.newton + 1, "factorisations": pieces.newton + 1}
        out, row = self._taken(carry, settings, step, counts)
        return ca.Function("accepted", [carry, settings, h, y1, error], [out, row])

    def _rejected(self) -> ca.Function:
        """``(carry, settings, h, y1, error) -> (carry, row)`` of a rejected step: the step
        shrunk by the controller, counted; handed over when the state may be near a singular
        pose."""
        L, method, pieces, model = self.layout, self.method, self.pieces, self.model
        carry, settings, h, y1, error = self._branch_symbols()
        factor = ca.if_else(error < ca.inf, ca.fmax(
            method.min_factor, method.safety * error ** (-1.0 / (method.error_order + 1))),
            method.min_factor)
        counts = {"rejected": 1, "rhs": self.stage_count - 1}
        if model.n_c:  # the rank decision Integrator._cross_singular makes on a rejection
            counts.update(jacobians=1, factorisations=1)
        head = [carry[L.index[name]] + counts.get(name, 0) for name in _HEAD]
        head[L.index["h"]] = h * factor
        head[L.index["h_rejected"]] = h
        taken = ca.vertcat(*head, carry[L.state])
        kept = pieces.projection.rows.size
        if kept > GRAM_ROWS:  # the bound costs more than Python's rank decision: Python's
            head[L.index["code"]] = ca.MX(CHECK)
            taken = ca.vertcat(*head, carry[L.state])
        elif kept:
            bound = pieces.singular_bound(carry[L.index["t"]], carry[L.q])
            near = ca.logic_not(bound * self.singular_band**2 <= 1.0)
            taken = ca.if_else(near, _handed_over(L, carry), taken)
        return ca.Function("rejected", [carry, settings, h, y1, error],
                           [taken, ca.MX.zeros(L.row)])

    def _branch_symbols(self):
        return (*self._symbols(), ca.MX.sym("h"),
                ca.MX.sym("y1", self.model.n_q + self.model.n_v), ca.MX.sym("error"))

    def _attempt(self) -> ca.Function:
        """``(carry, settings) -> (carry, row)``: one attempt, its branch (handed over,
        accepted, rejected) evaluated alone."""
        carry, settings = self._symbols()
        h, y1, error, ok = self._stages(carry, settings)
        branches = [self._handover(), self._accepted()]
        branch = ca.Function.conditional("branch", branches, self._rejected())
        which = ca.if_else(ok, ca.if_else(error <= 1.0, 1, 2), 0)
        out, row = branch(which, carry, settings, h, y1, error)
        return ca.Function("attempt", [carry, settings], [out, row])

    def _handover(self) -> ca.Function:
        carry, settings, h, y1, error = self._branch_symbols()
        return ca.Function("handover", [carry, settings, h, y1, error],
                           [_handed_over(self.layout, carry), ca.MX.zeros(self.layout.row)])


class BaumgarteKernel(LoopKernel):
    """The compiled loop of classical Runge-Kutta with Baumgarte stabilisation
    (``rk4-baumgarte``), each step as :meth:`RungeKutta4Baumgarte._step` takes it: three new
    stages with the stabilisation's rate ``alpha``, the Euler parameters normalised, the
    accelerations at the end with the same stabilisation and, when every row is kept, the
    multipliers there without it (those the saved states have); the position drift checked every
    ``drift_every`` steps against ``drift_limit`` (past it, Python takes the step and fails).

    Parameters
    ----------
    model : Model
    rows : ndarray of int
        The kept rows the compiled solves work with.
    alpha, drift_limit : float
    drift_every : int
    """

    name = "rk4_baumgarte"
    stage_count = 4

    def __init__(self, model: Model, rows: np.ndarray, *, alpha: float, drift_limit: float,
                 drift_every: int):
        self.alpha, self.drift_limit, self.drift_every = alpha, drift_limit, drift_every
        super().__init__(model, rows)

    def _attempt(self) -> ca.Function:
        L, pieces, model, alpha = self.layout, self.pieces, self.model, self.alpha
        carry, settings = self._symbols()
        t, h = self._next_step(carry, settings, L)
        q, v = carry[L.q], carry[L.v]
        dq1, dv1 = model.qdot(q, v), carry[L.v_dot]
        dq2, dv2, _, ok2 = pieces.rates(t + h / 2, q + h / 2 * dq1, v + h / 2 * dv1, alpha)
        dq3, dv3, _, ok3 = pieces.rates(t + h / 2, q + h / 2 * dq2, v + h / 2 * dv2, alpha)
        dq4, dv4, _, ok4 = pieces.rates(t + h, q + h * dq3, v + h * dv3, alpha)
        q = _normalised(model, q + h / 6 * (dq1 + 2 * dq2 + 2 * dq3 + dq4))
        v = v + h / 6 * (dv1 + 2 * dv2 + 2 * dv3 + dv4)
        _, v_dot, lam, ok5 = pieces.rates(t + h, q, v, alpha)
        ok = ca.logic_and(ca.logic_and(ok2, ok3), ca.logic_and(ok4, ok5))
        if pieces.projection.rows.size == model.n_c:  # unique multipliers: the saved ones
            _, _, lam, ok_lam = pieces.rates(t + h, q, v)
            ok = ca.logic_and(ok, ok_lam)
        step = {"h": h, "t": t + h, "q": q, "v": v, "v_dot": v_dot, "lam": lam,
                "h_next": carry[L.index["h"]], "ok": ok}

        plausible = _plausible_step(model, h, carry[L.q], carry[L.v], dv1, q, v, v_dot)

        def check(watched, steps):
            due = ca.fmod(steps, self.drift_every) == 0
            return ca.logic_and(plausible,
                                ca.logic_or(ca.logic_not(due), watched[0] <= self.drift_limit))

        out, row = self._taken(carry, settings, step, {"steps": 1, "rhs": 4}, check)
        return ca.Function("attempt", [carry, settings], [out, row])


def _plausible_step(model: Model, h, q0, v0, a0, q1, v1, a1) -> ca.MX:
    """1 when a fixed step passes the tests :meth:`Integrator.step` makes of it: the velocity
    change explained by the accelerations at its ends, and on a conservative scene the energy
    held (:data:`~.integrators.base.BRANCH_JUMP`, :data:`~.integrators.base.ENERGY_JUMP`),
    the energy measured against the kinetic energy at both ends instead of the run's largest,
    which is stricter: a step that fails here is handed over, and Python judges it."""
    mass = sparse_dm(model.mass.sparse())
    _, acceleration, energy = motion_scales(model)

    def size(x):
        return ca.sqrt(ca.fmax(ca.dot(x, ca.mtimes(mass, x)), 0.0))

    allowed = (BRANCH_JUMP * h * ca.fmax(ca.fmax(size(a0), size(a1)), ROUND_OFF * acceleration)
               + ROUND_OFF * ca.fmax(size(v0), size(v1)))
    ok = size(v1 - v0) <= allowed
    if model.energy_conserved:
        kinetic0, potential0 = model.energy(q0, v0)
        kinetic1, potential1 = model.energy(q1, v1)
        peak = ca.fmax(ca.fmax(kinetic0, kinetic1), ROUND_OFF * energy)
        change = ca.fabs(kinetic1 + potential1 - kinetic0 - potential0)
        ok = ca.logic_and(ok, change <= ENERGY_JUMP * peak)
    return ok


def _handed_over(L: Layout, carry):
    """The carry as it was, with the code :data:`HANDOVER`."""
    parts = [carry[i] for i in range(len(_HEAD))]
    parts[L.index["code"]] = ca.MX(HANDOVER)
    return ca.vertcat(*parts, carry[L.state])


def _normalised(model: Model, q):
    """Euler parameters scaled to unit length, as :meth:`Model.normalize`."""
    if not model._quat_q.size:
        return q
    parts = [q[i] for i in range(model.n_q)]
    for quat in model._quat_q:
        p = ca.vertcat(*[q[int(i)] for i in quat])
        p = p / ca.norm_2(p)
        for k, i in enumerate(quat):
            parts[int(i)] = p[k]
    return ca.vertcat(*parts)


# ---------------------------------------------------------------------- compilation
