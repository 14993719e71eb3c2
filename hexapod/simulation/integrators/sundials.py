"""Variable-order BDF through SUNDIALS IDAS, as CasADi exposes it, on the index-1 equations with
the constraint drift damped inside the DAE and a projection restart as its bound.

The equations of motion are written as a semi-explicit DAE of index 1, differential states
``x = (q, v)``, algebraic states ``z = (a, lambda_I)``:

    q' = B(q) v + (alpha / 2) (1 - p^T p) p    (the second term for Euler parameters only)
    v' = a
    0  = M a + Phi_I^T lambda_I - Q
    0  = Phi_I a - gamma_I + 2 alpha (Phi_I v - nu_I) + alpha^2 phi_I

``I`` the rows found independent by the rank decision at the (re)start (a redundant row adds
nothing to the motion). The last row is Baumgarte's stabilisation (Baumgarte 1972) written into
the algebraic equation: a drift of the constraints obeys ``e'' + 2 alpha e' + alpha^2 e = 0``
(plus the local errors) instead of growing, and the norm of the Euler parameters is pulled back
to 1 at the same rate. Both terms vanish on the exact motion. IDAS (Hindmarsh et al., *ACM TOMS*
31, 2005) integrates the DAE by variable-order (1 to 5), variable-step BDF, its residuals,
Newton iterations and Jacobians (derived by CasADi) evaluated inside CasADi, not in Python; one
call covers a whole window of output times, so BDF keeps its order across them. The time laws
enter as CasADi expressions of ``t`` where they have a closed form
(:meth:`hexapod.scene.laws.Law.symbolic`), otherwise through a callback to their numeric
evaluation.

The drift is checked at every output time: when ``|phi_i| / s_i`` or
``|Phi_v v - nu|_i / (s_i max(alpha, 1/s))`` passes ``drift_tol`` (default ``max(rtol,
atol / L)``, ``s_i`` and ``L`` the characteristic length, 1 for angle rows), the state there is
projected onto ``phi = 0`` and ``Phi_v v = nu`` (as ``dopri5-projection`` does after every step)
and IDAS restarts from it, the states after it in the window being dropped. Every restart
(after a projection, at the end of a window, or after a failed call) starts BDF again at order 1
from a consistent state and derivative, ``x' = (B v, a)`` handed to IDAS (no IDACalcIC); the
run's counters report them (``restarts``, ``projections``). With ``alpha = 0`` the method is the
plain index-1 formulation with projection restarts.

Why both: the drift of the plain index-1 equations grows until a projection, and every projection
costs a restart, BDF climbing back from order 1. The Baumgarte terms keep the drift at the level of
the local errors, so the projection becomes a bound rarely reached. The closed-loop pendulum of
Richard, Anderson and Andrews over 15 s at rtol 1e-9, atol 1e-11: 8463 steps, no restart, with
``alpha = 10/s``; 24674 steps, 26 restarts (17 projections) with ``alpha = 0``; both within 2e-9 m
of the exact motion.

CasADi takes ``x'`` at the start as an option of the integrator Function, so each restart builds
that Function again (about 1 ms for the closed-loop pendulum, 25 ms for a driven leg; the first
build of a model, with the derivatives of its Functions, takes longer). The accelerations and
multipliers of the returned states are solved at those states (one saddle-point solve each, with the
redundancy policy), not taken from IDAS's algebraic states, which are interpolated between its steps
without error control. A failed call of IDAS is retried over
fewer output times, then over shorter intervals, so that a run ends close to the time it
cannot pass; the work of the failed calls is not counted (CasADi does not report it). Between
two output times IDAS may take ten times the steps the run's pace so far gives them (IDAS's
``mxstep``; 5000 before any call succeeded): towards a singular configuration it creeps on in
ever smaller and dearer steps, and a call there took 16 to 52 s before its corrector gave up.

**Singular configurations.** Where ``Phi_v`` loses rank (the N-four-bar lying flat) the algebraic
part of the index-1 equations is singular, and BDF steps across onto either branch of the
motion: on the N-four-bar it came out on the other one at the first flat pose (0.18 of the
motion's size off the reference) and stopped four passages later. The smallest singular value of
the equilibrated ``Phi_v`` is watched at every output state: when it falls below a hundredth of
its largest over the last 20 states the run stops there, with a message naming the pose and the
methods that cross it (below a quarter, the output times are brought eight times closer so that
the fall is seen).
"""

from __future__ import annotations

import contextlib
import io
from collections import deque
from dataclasses import dataclass

import casadi as ca
import numpy as np

from hexapod._support import signals
from hexapod.algorithms.dynamics import forward_dynamics
from hexapod.algorithms.linalg import as_dense
from hexapod.algorithms.step import sparse_dm
from hexapod.errors import HexapodError, IntegrationError
from hexapod.simulation.integrators.base import Counters, Integrator
from hexapod.simulation.methods import METHODS


@dataclass
class RestartCounters(Counters):
    """The counters of :class:`Counters`, and the restarts of a multistep method.

    Attributes
    ----------
    restarts :
        Calls of the solver after the first: each starts BDF again at order 1.
    projections :
        States projected onto the constraints because their drift passed the tolerance (each
        followed by a restart).
    """

    restarts: int = 0
    projections: int = 0


class _LawCallback(ca.Callback):
    """``t -> (w, wd, wdd)`` of the given laws, by their numeric evaluation."""

    def __init__(self, laws):
        ca.Callback.__init__(self)
        self.laws = laws
        self.construct("laws", {})

    def get_n_in(self):
        return 1

    def get_n_out(self):
        return 3

    def get_sparsity_in(self, i):
        return ca.Sparsity.dense(1, 1)

    def get_sparsity_out(self, i):
        return ca.Sparsity.dense(len(self.laws), 1)

    def eval(self, arg):
        t = float(arg[0])
        values = np.array([law.evaluate(t) for law in self.laws], dtype=float).reshape(-1, 3)
        return [values[:, 0], values[:, 1], values[:, 2]]


class _Equations:
    """The symbols and expressions of the DAE of one model, built once; the DAE itself for a row
    set and a Baumgarte rate (cached)."""

    def __init__(self, model, alpha: float):
        self.model = model
        laws = model.laws
        t_sx = ca.SX.sym("t")
        forms = [law.symbolic(t_sx) for law in laws]
        self.callback = None
        if all(form is not None for form in forms):
            kind, t = ca.SX, t_sx
        else:
            # a law without a closed form: MX with a callback for those laws, not expanded
            kind, t = ca.MX, ca.MX.sym("t")
            closed = [i for i, form in enumerate(forms) if form is not None]
            numeric = [i for i, form in enumerate(forms) if form is None]
            self.callback = _LawCallback([laws[i] for i in numeric])
            w_num = self.callback(t)
            forms = [None] * len(laws)
            for i in closed:
                forms[i] = laws[i].symbolic(t)
            for k, i in enumerate(numeric):
                forms[i] = tuple(w_num[j][k] for j in range(3))
        self.kind, self.t = kind, t
        self.q, self.v = kind.sym("q", model.n_q), kind.sym("v", model.n_v)
        if laws:
            w, wd, wdd = (ca.vertcat(*[form[j] for form in forms]) for j in range(3))
        else:
            w = wd = wdd = kind(0, 1)
        values = {"q": self.q, "v": self.v, "w": w, "wd": wd, "wdd": wdd}

        def call(function):
            return function(*[values[n] for n in function.name_in()])

        self.Phi_v, self.gamma, self.Q = call(model.dynamics_terms)
        self.phi, self.nu = call(model.phi), call(model.nu)
        qdot = call(model.qdot)
        # the norm of each body's Euler parameters pulled back to 1 at the rate alpha
        for body in model.bodies:
            if body.kind == "spatial":
                p = self.q[body.q.start + 3: body.q.stop]
                index = list(range(body.q.start + 3, body.q.stop))
                qdot[index] = qdot[index] + alpha / 2 * (1 - ca.dot(p, p)) * p
        self.qdot = qdot
        self.alpha = alpha
        self.mass = sparse_dm(model.mass.sparse())  # a dense one: n_v^2 products per call
        self._daes: dict = {}

    def dae(self, rows: np.ndarray) -> dict:
        """The DAE on the rows ``rows`` (CasADi's dict of ``t, x, z, ode, alg``)."""
        key = tuple(int(r) for r in rows)
        if key not in self._daes:
            model, kind, alpha = self.model, self.kind, self.alpha
            a = kind.sym("a", model.n_v)
            lam = kind.sym("lam", len(key))
            force = ca.mtimes(self.mass, a) - self.Q
            alg = [force]
            if key:
                index = list(key)
                Phi = self.Phi_v[index, :]
                force = force + ca.mtimes(Phi.T, lam)
                rate = ca.mtimes(Phi, self.v) - self.nu[index]
                alg = [force, ca.mtimes(Phi, a) - self.gamma[index] + 2 * alpha * rate
                       + alpha**2 * self.phi[index]]
            self._daes[key] = {"t": self.t, "x": ca.vertcat(self.q, self.v),
                               "z": ca.vertcat(a, lam), "ode": ca.vertcat(self.qdot, a),
                               "alg": ca.vertcat(*alg)}
        return self._daes[key]


class IdasBDF(Integrator):
    """Variable-order BDF (IDAS) on the index-1 DAE, drift damped by Baumgarte terms in the DAE,
    projected and restarted when it passes a tolerance (see the module's description).

    ``step``: the interval of the output times (default: the run over 1000); IDAS chooses its
    own steps between them. ``alpha`` (1/s, 10 by default): the Baumgarte rate inside the DAE
    (0: none, the plain index-1 equations). ``drift_tol``: the largest scaled drift let pass
    before a projection (default ``max(rtol, atol / L)``). IDAS is given tolerances
    ``tolerance_factor`` (0.03) times the requested ones: it controls the local error of each
    step, and its global error on the exact pendulum over two periods is 1 to 4 times the
    requested tolerance (about 10 to 40 times its own).
    """

    name = "idas-bdf"
    order, index, adaptive, stabilisation = METHODS[name]
    counts_own_steps = True
    description = ("variable-order BDF (SUNDIALS IDAS through CasADi), index 1, Baumgarte-"
                   "stabilised, projection restarts")
    tolerance_factor = 0.03
    #: the caller's output times, when given (:meth:`set_output_times`)
    output_times: np.ndarray | None = None
    #: the solver's steps per call before it gives up (the call is then retried shorter)
    max_num_steps = 500_000
    #: IDAS may take this many times the steps that the run's pace so far gives an interval
    #: between output times (at least ``min_interval_steps``; ``first_interval_steps`` before
    #: any call succeeded): towards a singular configuration it creeps on in ever smaller
    #: steps, each dearer than the last (the spatial N-four-bar: 16 to 52 s in one call before
    #: its corrector gave up), and such a call then ends within a second; a call that merely
    #: needs more steps than that is retried over fewer output times
    pace_factor = 10.0
    min_interval_steps = 1000
    first_interval_steps = 5000
    #: a singular configuration: the smallest singular value of the equilibrated ``Phi_v`` at
    #: an output state falls below ``singular_drop`` times the largest of the last
    #: ``singular_memory`` states (below ``singular_approach`` times it, the output times are
    #: brought closer, so that the passage is seen). The index-1 equations' algebraic part is
    #: singular there and BDF steps across it onto whichever branch: on the N-four-bar it
    #: came out on the wrong one at the first flat pose (0.18 of the motion's size off the
    #: reference) and stopped four passages later
    singular_drop = 1e-2
    singular_approach = 0.25
    singular_memory = 20

    def __init__(self, *args, alpha: float = 10.0, drift_tol: float | None = None, **kwargs):
        if not alpha >= 0:
            raise ValueError(f"alpha must be non-negative, got {alpha}")
        if drift_tol is not None and not drift_tol > 0:
            raise ValueError(f"drift_tol must be positive, got {drift_tol}")
        self.alpha = float(alpha)
        self._drift_tol = drift_tol
        super().__init__(*args, **kwargs)

    # ------------------------------------------------------------------ set-up

    def _start(self) -> None:
        model = self.model
        self.counters = RestartCounters(**self.counters.as_dict())
        span = self.t_bound - self.t0
        self.n_out = max(1, int(np.ceil(span / self.h - 1e-9)))
        self.h = span / self.n_out
        self.drift_tol = (self._drift_tol if self._drift_tol is not None
                          else max(self.rtol, self.atol / model.characteristic_length))
        self.equations = _Equations(model, self.alpha)
        self.drift_function = self._drift_function()
        self.window = self.n_out  # output times per call: all of them, until a projection
        self.reach = np.inf  # the farthest a call may go (shortened after a failed call)
        self.min_reach = 1e-9 * max(1.0, span)
        self.successes = 0
        self.calls = 0
        self.covered = 0.0  # the time IDAS covered in successful calls, and its steps there
        self.covered_steps = 0
        self.pending: deque = deque()
        self.scratch = model.create_data()  # for solves that must not overwrite ``data``
        self.deferred: HexapodError | None = None  # a failure after states still to return
        self.rows = self.data.independent_rows  # the start was solved by _dynamics
        # the smallest singular values at the last output states, and the feet down then
        self.conditioning: deque = deque([self._smallest_singular_value()],
                                         maxlen=self.singular_memory)
        self.conditioning_feet = self._contact_set(self.t)
        self.approaching = False

    @property
    def _baumgarte(self):
        return (self.alpha, self.alpha) if self.alpha else None

    def _drift_function(self) -> ca.Function:
        """``(q, v, w, wd) -> (max |phi_i| / s_i, max |Phi_v v - nu|_i / (s_i rate))``."""
        model = self.model
        sym = model._sym
        scale = ca.DM(model.row_scale if model.n_c else np.ones(0))
        rate = max(self.alpha, 1.0)
        names = [n for n in ("q", "v", "w", "wd") if n in ("q", "v") or model.n_w]
        if model.n_c:
            values = {n: getattr(sym, n) for n in names}
            phi = model.phi(*[values[n] for n in model.phi.name_in()])
            Phi_v = model.Phi_v(*[values[n] for n in model.Phi_v.name_in()])
            nu = model.nu(*[values[n] for n in model.nu.name_in()])
            position = ca.mmax(ca.fabs(phi / scale))
            velocity = ca.mmax(ca.fabs((ca.mtimes(Phi_v, sym.v) - nu) / scale)) / rate
        else:
            position = velocity = ca.SX(0.0)
        return ca.Function("drift", [getattr(sym, n) for n in names], [position, velocity],
                           names, ["position", "velocity"])

    # ------------------------------------------------------------------ stepping

    def _step(self) -> None:
        if not self.pending:
            if self.deferred is not None:
                raise self.deferred
            self._window()
        self.t, self.q, self.v, self.v_dot, self.lam = self.pending.popleft()

    def _times(self) -> np.ndarray:
        """The output times of the next call: the grid times after ``t`` (at most ``window``
        of them, none past ``reach``), or ``t + reach`` when no grid time is that close."""
        if self.output_times is not None:  # the caller's (set_output_times)
            first = int(np.searchsorted(self.output_times, self.t, side="right"))
            times = self.output_times[first:first + self.window].copy()
        else:
            first = int(np.floor((self.t - self.t0) / self.h + 1e-9)) + 1
            last = min(self.n_out, first + self.window - 1)
            times = self.t0 + self.h * np.arange(first, last + 1)
            times[times > self.t_bound] = self.t_bound
            if last == self.n_out:
                times[-1] = self.t_bound
        times = times[times <= self.t + self.reach]
        self.off_grid = not times.size
        if self.off_grid:
            times = np.array([self.t + self.reach])
        return times

    def _window(self) -> None:
        """Run IDAS from the current state over the next window of output times; queue the
        states up to the first whose drift passed the tolerance, projected, from which the
        next window restarts."""
        model = self.model
        times = self._times()
        try:
            X = self._run(times)
        except _Failure as failure:
            self.counters.rejected += 1
            if times.size > 1:  # retry over fewer output times
                self.window = max(1, times.size // 4)
            elif times[0] - self.t > self.min_reach:
                # retry over a shorter interval: towards a singular configuration the run
                # goes on to within min_reach of the time where IDAS cannot pass
                self.reach = (times[0] - self.t) / 4
                self.successes = 0
            else:
                where = self._singular_pose()
                raise IntegrationError(f"IDAS stopped ({failure.reason})"
                                       + (f": {where}" if where else "")) from None
            return self._window()
        n_q = model.n_q
        Q = np.array([model.normalize(x[:n_q]) for x in X])
        V = X[:, n_q:]
        values = {"q": Q.T, "v": V.T}
        if model.n_w:
            values["w"], values["wd"], _ = model.law_values(times, self.data)
        # one call over all the window's states (CasADi maps over the columns)
        position, velocity = (d.full().reshape(-1) for d in self.drift_function(
            *[values[n] for n in self.drift_function.name_in()]))
        drifted = np.flatnonzero(np.maximum(position, velocity) > self.drift_tol)
        count = drifted[0] + 1 if drifted.size else times.size
        count = self._watch_conditioning(times[:count], Q[:count], count)
        for k in range(count):
            t, q, v = times[k], Q[k], V[k]
            if drifted.size and k == drifted[0]:
                try:
                    q, v = self._project(t, q, v)
                except HexapodError as error:  # no consistent state: the states before first
                    if not self.pending:
                        raise
                    self.deferred = error
                    break
                self.counters.projections += 1
            # accelerations and multipliers solved at the state (IDAS's algebraic states are
            # interpolated between its steps without error control: kinks of a spline law's
            # third derivative show there), with the redundancy policy, as every method does
            v_dot, lam = self._solve_state(t, q, v)
            self.pending.append((t, q, v, v_dot, lam))
        # the next window: twice as many output times as this one reached (after a
        # projection the drift will pass the tolerance about as soon again)
        self.window = max(1, min(self.n_out, 2 * count))
        # a reach cut by a failed call is doubled only after four calls in a row succeed:
        # within four reaches of a time IDAS cannot pass that never happens, so the approach
        # to it ends (at min_reach); past a passing difficulty the reach grows back
        self.successes += 1
        if np.isfinite(self.reach) and self.successes >= 4:
            self.reach, self.successes = 2 * self.reach, 0
        if self.reach >= self.h or not self.off_grid:
            self.reach = np.inf
        if self.approaching:  # a singular configuration ahead: seen at eight times the rate
            self.reach, self.successes, self.approaching = min(self.reach, self.h / 8), 0, False

    def _watch_conditioning(self, times: np.ndarray, Q: np.ndarray, count: int) -> int:
        """How many of the window's states to keep: all of them, or those up to a singular
        configuration (see :attr:`singular_drop`), after which the run stops with a message
        naming it. Brings the output times closer when one is approached."""
        if not self.model.n_c:
            return count
        feet = self._contact_set(times[0])
        if feet != self.conditioning_feet:  # other rows now: their own conditioning
            self.conditioning.clear()
            self.conditioning_feet = feet
        for k, (t, q) in enumerate(zip(times, Q, strict=True)):
            sigma = self._smallest_singular_value(q, t)
            recent = max(self.conditioning, default=sigma)
            if sigma < self.singular_drop * recent:
                self.deferred = IntegrationError(
                    f"IDAS stopped at a singular configuration at t = {t:.6g} s (smallest "
                    f"singular value of the equilibrated constraint Jacobian {sigma:.2g}, "
                    f"{sigma / recent:.1g} of its value just before): the index-1 equations' "
                    "algebraic part is singular there and BDF steps across onto either branch "
                    f"of the motion; {' and '.join(self.crossing_methods)} cross such poses")
                return k + 1
            self.approaching |= sigma < self.singular_approach * recent
            self.conditioning.append(sigma)
        return count

    def _solve_state(self, t: float, q: np.ndarray, v: np.ndarray):
        """The stabilised accelerations and the multipliers at a state: the compiled solve when
        no row is redundant (the multipliers are unique then), else the rank-deciding one with
        the redundancy policy. Sets ``rows``, those IDAS may solve with from this state."""
        if self._compiled.complete:
            solution = self._compiled.solve(t, q, v, self.alpha)
            if solution is not None:
                self.counters.rhs += 1
                self.rows = self._compiled.rows
                return solution[1], solution[2]
        v_dot, lam = self._dynamics(t, q, v, self._baumgarte)
        self.rows = self.data.independent_rows
        return v_dot, lam

    def _run(self, times: np.ndarray) -> np.ndarray:
        """IDAS from the current state to ``times``: the states ``x = (q, v)`` there, one row
        per time. The start is consistent: ``v_dot`` and ``lam`` hold the stabilised dynamics
        at ``(t, q, v)`` (see :meth:`_solve_state`), and ``x' = (B v, v_dot)`` is handed to
        IDAS as it is."""
        model = self.model
        if self.calls:
            self.counters.restarts += 1
        self.calls += 1
        # IDAS solves with the rows independent at the start (the multipliers of redundant
        # rows follow the policy at the output states; ``data`` holds the dynamics there)
        rows = self.rows
        lam = self.lam[rows]
        if rows.size < model.n_c and rows.size:  # the multipliers of the rows IDAS solves with
            Phi = as_dense(self.data.Phi_v[rows])
            rhs = self.data.Q - model.mass @ self.v_dot
            lam = np.linalg.lstsq(Phi.T, rhs, rcond=None)[0]
        xdot = np.concatenate([model.call("qdot", self.data, q=self.q, v=self.v), self.v_dot])
        options = {"abstol": self.tolerance_factor * self.atol,
                   "reltol": self.tolerance_factor * self.rtol,
                   "calc_ic": False, "init_xdot": xdot.tolist(), "suppress_algebraic": True,
                   "max_num_steps": self._interval_steps(times),
                   "expand": self.equations.callback is None}
        if np.any(self.atol_vector != self.atol):  # per kind: a vector over x and z (which the
            # error test leaves out: at the smallest), taken before abstol
            options["abstolv"] = (self.tolerance_factor * np.concatenate(
                [self.atol_vector, np.full(model.n_v + lam.size, self.atol)])).tolist()
        if np.isfinite(self.max_step):
            options["max_step_size"] = self.max_step
        options["step0"] = self._first_step(xdot, times[0] - self.t)
        dae = self.equations.dae(rows)
        messages = io.StringIO()
        with contextlib.redirect_stderr(messages):  # IDAS's own report of a failure
            try:
                solver = ca.integrator("idas", "idas", dae, self.t, times.tolist(), options)
                out = solver(x0=np.concatenate([self.q, self.v]),
                             z0=np.concatenate([self.v_dot, lam]))
            except RuntimeError as error:
                if signals.received() is not None:  # CasADi's form of an interruption
                    raise KeyboardInterrupt from None
                raise _Failure(_idas_reason(str(error), messages.getvalue())) from None
        stats = solver.stats()  # (a failed call's statistics are lost with it)
        self._count(stats)
        self.covered += times[-1] - self.t
        self.covered_steps += int(stats.get("nsteps", 0))
        return out["xf"].full().T

    def _interval_steps(self, times: np.ndarray) -> int:
        """The most steps IDAS may take between two output times of a call over ``times``
        (IDAS's ``mxstep``, see :attr:`pace_factor`)."""
        if not self.covered > 0:
            return min(self.max_num_steps, self.first_interval_steps)
        interval = float(np.max(np.diff(np.concatenate([[self.t], times]))))
        expected = self.covered_steps / self.covered * interval
        return int(min(self.max_num_steps,
                       max(self.min_interval_steps, self.pace_factor * expected)))

    def _first_step(self, xdot: np.ndarray, interval: float) -> float:
        """A first step for BDF at order 1 (IDAS's own guess, from ``x'`` alone, is far too
        small at tight tolerances, and a restart then doubles its way up for tens of steps):
        local error ``h^2 |x''| / 2`` at a quarter of the tolerance, ``x''`` by a difference of
        ``x'`` along the motion over 1e-6 s (one more solve of the dynamics)."""
        model, delta = self.model, 1e-6
        x = np.concatenate([self.q, self.v])
        weights = 1.0 / (self.tolerance_factor * (self.rtol * np.abs(x) + self.atol_vector))
        q1 = model.normalize(self.q + delta * xdot[:model.n_q])
        v1 = self.v + delta * xdot[model.n_q:]
        v_dot1 = forward_dynamics(model, self.scratch, self.t + delta, q1, v1,
                                  baumgarte=self._baumgarte)
        self.counters.rhs += 1  # counted as _dynamics counts its solve
        self.counters.jacobians += 1
        self.counters.factorisations += 1
        xdot1 = np.concatenate([model.call("qdot", self.data, q=q1, v=v1), v_dot1])
        second = np.sqrt(np.mean(((xdot1 - xdot) / delta * weights) ** 2))
        if not (np.isfinite(second) and second > 0):
            return min(interval, 1e-3)
        return float(min(interval, np.sqrt(0.5 / second)))

    def _count(self, stats: dict) -> None:
        c = self.counters
        c.steps += int(stats.get("nsteps", 0))
        c.rejected += int(stats.get("netfails", 0)) + int(stats.get("nncfails", 0))
        c.rhs += int(stats.get("nfevals", 0))
        c.jacobians += int(stats.get("nlinsetups", 0))
        c.factorisations += int(stats.get("nlinsetups", 0))
        c.newton += int(stats.get("nniters", 0))

    def set_output_times(self, times: np.ndarray) -> None:
        """Return the states at ``times`` (and at ``t_bound``) instead of every ``step``: they
        are IDAS's output times, where it interpolates its own BDF polynomial (IDAGetDky)."""
        times = np.asarray(times, dtype=float)
        times = times[(times > self.t0) & (times < self.t_bound)]
        self.output_times = np.append(times, self.t_bound)
        self.n_out = self.window = self.output_times.size


class _Failure(Exception):
    """A call of IDAS that stopped, with the reason."""

    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


_FLAGS = (("IDA_TOO_MUCH_WORK", "too many steps"),
          ("IDA_CONV_FAIL", "the corrector iteration does not converge"),
          ("IDA_ERR_FAIL", "the error test fails repeatedly: the step fell to nothing"),
          ("IDA_LSETUP_FAIL", "the iteration matrix could not be factorised"),
          ("IDA_LSOLVE_FAIL", "the linear solve failed"),
          ("IDA_RES_FAIL", "the residual could not be evaluated"))


def _idas_reason(error: str, report: str) -> str:
    """A one-line reason from CasADi's exception and IDAS's own report (which says where)."""
    where = " ".join(report.split())[:200]
    for flag, meaning in _FLAGS:
        if flag in error:
            return f"{flag}: {meaning}" + (f"; {where}" if where else "")
    lines = error.strip().splitlines()
    return (lines[-1][:200] if lines else "unknown error") + (f"; {where}" if where else "")
