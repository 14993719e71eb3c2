"""Event-driven integration of unilateral contacts: smooth phases with the contacts' modes
fixed, events located on their conditions, impacts by an impulse map (Pfeiffer and Glocker,
*Multibody Dynamics with Unilateral Contacts*, 1996; Acary and Brogliato 2008, ch. 7).

**Smooth phases.** Each contact is ``open``, ``stick`` or ``slip``. Between events the motion
is smooth and integrated by DOP853 with its error control and its projection (the embedded
pair of :class:`~.embedded.DormandPrince853`), on accelerations that hold the closed contacts:
the engine's constrained step with the contacts' forces ``F`` on its right-hand side
(:class:`~hexapod.simulation.contact_kernel.CompiledContactStep`), so that the contacts'
accelerations are ``c + W F`` (``c = J a_free + J_dot v``, ``W`` the Delassus operator).
A sticking contact keeps all its acceleration zero (``d`` unknowns); a slipping one its normal
acceleration, with the tangential force ``-mu F_N s`` against its slip ``s`` (one unknown).
When a slipping contact's normal acceleration falls as its normal force grows (``W_NN - mu
W_NT s < 0`` for a contact alone; with others closed, the Schur complement of their unknowns),
no force holds it and none lets it go: Painleve's paradox, which this scheme reports by name
(the time-stepping scheme resolves it by a tangential impact). After each step the closed
contacts' gaps and velocities are projected to zero, as the bilateral rows are.

**Events.** Each contact has two event functions that are positive while its mode holds: an
open contact's gap (once its arming condition holds, see
:class:`~hexapod.scene.GroundContact`) and a closed one's normal force; a sticking contact's
cone margin ``mu F_N - |F_T|``, a slipping one's slip speed along its direction at the step's
start. A function that falls below zero in a step has a root located on the step's dense
output by Illinois' method (to round-off in time); a gap is also watched inside the step
(a ball's bounce may be shorter than the step) when the contact's normal speed and
acceleration could take it to the ground within the step. A function zero at the step's
start (a contact that has just left, or begun to slip) is divided by the time since, so that
its root there is not found again. A contact whose force let it go (a lift-off, not a rebound)
leaves at zero speed, often tangent to the ground to high order (a walking foot's path: its
height grows as the fifth power of the time since), so that its gap stays within round-off
of zero for a while: until the gap has passed the gap tolerance, it touches down again only
once that far into the ground (a foot that falls back), else it would touch and leave again
at the same instant, endlessly.

**Impacts.** At a touch-down the velocities jump by the impulse map ``M (v+ - v-) = J^T P``
under the bilateral rows: the frictional contact problem of the touching contacts
(:func:`~hexapod.algorithms.frictional.solve_contacts`) with Newton's restitution, as a
Moreau-Jean step of zero length. A rebound whose flight would last less than
:data:`ZENO_FLIGHT` ends an accumulation of impacts (a Zeno point) with the contact closed.
After every event the modes are settled: a closed contact that would pull opens, a sticking
one outside its cone slips, an open one at zero gap that would be pressed into the ground
closes, until the modes are consistent.
"""

from __future__ import annotations

import numpy as np

from hexapod.algorithms.contact_frames import (
    armed,
    contact_bias,
    contact_frames,
    contact_gaps,
    ground_contacts,
)
from hexapod.algorithms.frictional import solve_contacts
from hexapod.algorithms.linalg import least_norm_psd
from hexapod.errors import HexapodError, IntegrationError
from hexapod.simulation.contact_kernel import CompiledContactStep, contact_solution
from hexapod.simulation.integrators.embedded import DormandPrince853
from hexapod.simulation.integrators.moreau_jean import GAP_TOLERANCE, ContactEvent
from hexapod.simulation.methods import CONTACT_METHODS
from hexapod.simulation.scales import ROUND_OFF

#: a rebound flying for less than this (s) ends the impacts' accumulation: the contact closes
ZENO_FLIGHT = 1e-9
#: points per step at which the open contacts' gaps are watched inside the step
GAP_WATCH = 16
#: relative tolerance of the modes' conditions (a force's sign, the cone)
MODE_TOLERANCE = 1e-9
#: a slipping contact's normal compliance below minus this (relative to the contact system's
#: largest entry) is Painleve's paradox; round-off around zero is redundancy
PAINLEVE_TOLERANCE = 1e-9


class EventDriven(DormandPrince853):
    """Event-driven integration with unilateral contacts (see the module's description).

    Attributes
    ----------
    modes : list of str
        ``open``, ``stick`` or ``slip`` per contact.
    contact_forces : ndarray, shape (m, d)
        The contacts' forces at the current state (the ground's on each body, world axes, N).
    events : list of ContactEvent
        The run's contact events so far.
    """

    name = "event-driven"
    order, index, adaptive, stabilisation = CONTACT_METHODS[name]
    description = "event-driven: DOP853 between contact events, impacts by an impulse map"
    impulsive = True
    starts_by_kernels = False  # its start: the exact solve, every contact open

    def _start(self) -> None:
        model = self.model
        self._kernels: dict = {}  # level -> CompiledContactStep (every contact's columns)
        self._free_kept: tuple | None = None  # (state, terms) of _free_motion's last state
        self._here: tuple = ()  # the current state's clearance (_refresh)
        self.contacts = ground_contacts(model)
        self.contact_names = tuple(c.name for c in self.contacts)
        m, d = len(self.contacts), model.dimension
        self._mu = np.array([c.contact.mu for c in self.contacts])
        self._restitution = np.array([c.contact.restitution for c in self.contacts])
        self.events: list[ContactEvent] = []
        self.modes = ["open"] * m
        self._direction = np.zeros((m, d - 1))  # each slip's direction, contact axes
        self._just = np.zeros(m, bool)  # left the ground or began to slip at the step's start
        self._lifted = np.zeros(m, bool)  # let go by its force, its gap not yet past the tolerance
        self._gap_tol = GAP_TOLERANCE * model.characteristic_length
        # both kernels made (compiled) before the time loop, whose CPU they would count
        laws = model.law_values(self.t, self.data)
        for level, arrays in (("acceleration", 3), ("impulse", 2)):
            self._kernels[level] = self._kernel(level, self.q, self.v, laws[:arrays])
        frames = contact_frames(model, self.q, self.contacts, self.data)
        touching = np.flatnonzero((frames.gaps <= self._gap_tol)
                                  & armed(frames, self.contacts))
        u = (frames.jacobian @ self.v).reshape(m, d)
        speed = ROUND_OFF * max(1.0, np.abs(self.v).max())
        if np.any(u[touching, 0] < -speed):  # an impact at the start
            self.v = self._impact(self.t, self.q, self.v, touching)
            u = (frames.jacobian @ self.v).reshape(m, d)
        # the state the run starts from (not events); a contact sliding slower than the
        # modes' tolerance (a foot leaving the ground at zero speed, to round-off) sticks
        resting = MODE_TOLERANCE * max(1.0, np.abs(self.v).max())
        for k in touching:
            sliding = np.linalg.norm(u[k, 1:])
            if self.modes[k] == "open" and u[k, 0] <= speed:
                self.modes[k] = "slip" if sliding > resting else "stick"
                if sliding > resting:
                    self._direction[k] = u[k, 1:] / sliding
        try:
            self._settle(self.t, self.q, self.v)  # what changes at once (events)
            self._refresh()
        except HexapodError as error:  # a result, as a step's failure is
            self.status, self.message = "failed", f"{self.name} failed at the start: {error}"
            self.contact_forces = np.zeros((m, d))
            return
        super()._start()

    # ---------------------------------------------------------------- dynamics with contacts

    def _solve(self, t: float, q: np.ndarray, v: np.ndarray, modes=None) -> tuple:
        """At a state with ``modes`` (default the current ones): the accelerations, the
        multipliers, the contacts' forces (contact axes, (m, d)), the contacts' accelerations
        (m d) and the Delassus operator ``W`` (m d, m d)."""
        modes = self.modes if modes is None else modes
        frames, y, lam, Y, Lam, free, W = self._free_motion(t, q, v)
        F = self._forces(t, frames.jacobian @ v, free, W, modes)
        x = F.reshape(-1)
        return self.model.mass_inv_sqrt @ (y + Y @ x), lam + Lam @ x, F, free + W @ x, W

    def _free_motion(self, t: float, q: np.ndarray, v: np.ndarray) -> tuple:
        """What :meth:`_solve` needs at a state whatever the modes: the contacts' frames, the
        solve without contact forces ``(y, lam)`` and its response to unit contact forces
        ``(Y, Lam)``, the contacts' accelerations without forces ``free`` and the Delassus
        operator ``W``. Kept for the last state asked: a step's end is asked for by the
        sticking contacts' check, the accelerations there and the watch on slips alike."""
        key = (t, q.tobytes(), v.tobytes())
        if self._free_kept is not None and self._free_kept[0] == key:
            return self._free_kept[1]
        model = self.model
        laws = tuple(np.array(x) for x in model.law_values(t, self.data))
        frames = contact_frames(model, q, self.contacts, self.data)
        G = frames.scaled.T  # M^-1/2 J^T
        y, lam, Y, Lam = self._contact_solve("acceleration", t, q, v, laws, G)
        self.counters.rhs += 1
        self.counters.factorisations += 1
        free = G.T @ y + contact_bias(model, q, v, self.contacts, self.data)
        terms = (frames, y, lam, Y, Lam, free, G.T @ Y)
        self._free_kept = (key, terms)
        return terms

    def _forces(self, t, u, free, W, modes) -> np.ndarray:
        """The closed contacts' forces that keep their accelerations as their modes say."""
        m, d = len(self.contacts), self.model.dimension
        F = np.zeros((m, d))
        closed = [k for k in range(m) if modes[k] != "open"]
        if not closed:
            return F
        columns, equations, slipping = [], [], {}
        for k in closed:
            if modes[k] == "stick":
                for i in range(d):
                    columns.append(_unit(m * d, k * d + i))
                    equations.append(k * d + i)
            else:
                column = _unit(m * d, k * d)
                column[k * d + 1:(k + 1) * d] = -self._mu[k] * self._slip(k, u)
                slipping[k] = len(columns)  # its unknown, and its equation, in the system
                columns.append(column)
                equations.append(k * d)
        B = np.array(columns).T
        A = W[equations] @ B
        for k, j in slipping.items():
            if _normal_compliance(A, j) < -PAINLEVE_TOLERANCE * np.abs(A).max():
                raise IntegrationError(_painleve(self.contact_names[k], t, self._mu[k]))
        rhs = -free[equations]
        x = np.linalg.lstsq(A, rhs, rcond=None)[0]
        scale = max(np.abs(rhs).max(), np.abs(A @ x).max(), np.finfo(float).tiny)
        if np.abs(A @ x - rhs).max() > 1e-8 * scale:  # the contacts' conditions contradict
            names = ", ".join(f"'{self.contact_names[k]}'" for k in closed)
            raise IntegrationError(f"no contact forces hold the closed contacts ({names}) at "
                                   f"t = {t:.9g} s as their modes say")
        return (B @ x).reshape(m, d)

    def _slip(self, k: int, u: np.ndarray) -> np.ndarray:
        """Contact ``k``'s slip direction: its tangential velocity's while that has a part
        along the direction at the step's start; else (a slip beginning, or one that would
        reverse within the step: its end is an event) that direction, so that the motion
        stays smooth within the step."""
        d = self.model.dimension
        tangential = u[k * d + 1:(k + 1) * d]
        speed = np.linalg.norm(tangential)
        if tangential @ self._direction[k] > ROUND_OFF * max(1.0, np.abs(u).max()):
            return tangential / speed
        return self._direction[k]

    def _rates(self, t, q, v, alpha=0.0):
        """The rates at a stage; a stage that blew up, or whose contact problem has no
        solution, gives NaN: the step is rejected and shortened (a stiff controller makes a
        long step's stages blow up), and its cause is kept for the message should the step
        fall to nothing."""
        if np.all(np.isfinite(q)) and np.all(np.isfinite(v)):
            try:
                return self.model.call("qdot", self.data, q=q, v=v), self._solve(t, q, v)[0]
            except (HexapodError, np.linalg.LinAlgError) as error:
                self._stage_error = f"{error}"
        return np.full(q.size, np.nan), np.full(v.size, np.nan)

    def _stick_states(self, t, q, v, candidates) -> tuple:
        """What the ``candidates`` (sticking, or open at zero gap and speed) do at a state:
        their frictional contact problem at acceleration level, Signorini on the normal
        acceleration and Coulomb's cone on the tangential one (well posed: none of them
        slips). Redundant contacts (a block's four corners) share their forces as it finds
        a distribution in the cones, which a least-norm distribution may leave.
        Returns the states and the contacts' accelerations (len(candidates), d)."""
        d = self.model.dimension
        modes = [("open" if k in candidates else mode) for k, mode in enumerate(self.modes)]
        accelerations, W = self._solve(t, q, v, modes=modes)[3:]
        rows = (np.asarray(candidates)[:, None] * d + np.arange(d)).reshape(-1)
        solution = solve_contacts(W[np.ix_(rows, rows)], accelerations[rows],
                                  self._mu[candidates], np.zeros(len(candidates)),
                                  tuple(self.contact_names[k] for k in candidates))
        # a slip, or a leaving, slower than the modes' tolerance of the accelerations is noise
        # on a contact that carries nothing (a foot at the instant it is unloaded): it sticks
        tol = MODE_TOLERANCE * max(float(np.linalg.norm(self.model.gravity)),
                                   float(np.abs(accelerations).max(initial=0.0)))
        a = solution.velocities
        states = tuple("stick" if (state == "slip" and np.linalg.norm(a[j, 1:]) <= tol)
                       or (state == "open" and a[j, 0] <= tol) else state
                       for j, state in enumerate(solution.states))
        return states, a

    def multipliers(self, t, q, v):
        return self._solve(t, q, v)[1]

    def _end_rates(self, t, q, v):
        # the step's end moves on (onto the contacts, back to an event): :meth:`_refresh`
        # solves for the accelerations where it stays
        return self.v_dot, None

    def _stages(self, t, h, y0, f0):  # the contacts' forces are not in the compiled kernel
        if self.model.n_w:  # the stages' laws in one pass over their times (a batch of
            # eleven costs about what one time does), kept in the run's workspace for them
            self.model.law_values(t + self.c[1:] * h, self.data)
        return self._stages_one_by_one(t, h, y0, f0)

    # ---------------------------------------------------------------- the step and its events

    def _step(self) -> None:
        t0 = self.t
        self._follow_slips()
        before = self._watch(t0, self.q, self.v, t0)
        start = self._here  # the state the last refresh left
        self._stage_error = ""
        try:
            super()._step()
        except IntegrationError as error:
            if not self._stage_error:
                raise
            raise IntegrationError(f"{error}; the last stage tried: {self._stage_error}") \
                from None
        self.q, self.v = self._onto_contacts(self.t, self.q, self.v)
        after = self._watch(self.t, self.q, self.v, t0)
        near = self._near(self.t - t0, start, self._clearance(self.t, self.q, self.v))
        fired = self._first_root(t0, before, after, near)
        if not self._sticking(self.t, self.q, self.v):  # a sticking contact slips or leaves
            t_stick = self._bisect(t0)
            if fired is None or t_stick < fired[0]:
                fired = (t_stick, None)
        if fired is not None:
            t_event, index = fired
            q, v = self.dense_output()(t_event)
            self.t = t_event
            self.q, self.v = self._project(t_event, q, v)
            self._handle(index)
        else:
            self._just[:] = False
        if self._lifted.any():  # those clear of the ground from here touch at zero gap again
            self._lifted &= contact_gaps(self.model, self.q, self.contacts,
                                         self.data) <= self._gap_tol
        self._refresh()

    def _follow_slips(self) -> None:
        """Each slipping contact's direction, the one its slip speed is watched along, turned
        to its slip at the step's start."""
        if "slip" not in self.modes:
            return
        u = contact_frames(self.model, self.q, self.contacts, self.data).jacobian @ self.v
        for k, mode in enumerate(self.modes):
            if mode == "slip" and not self._just[k]:
                self._direction[k] = self._slip(k, u)

    def _sticking(self, t, q, v) -> bool:
        """Whether every sticking contact still sticks at a state (see :meth:`_stick_states`)."""
        sticking = [k for k, mode in enumerate(self.modes) if mode == "stick"]
        return not sticking or all(s == "stick" for s in self._stick_states(t, q, v,
                                                                            sticking)[0])

    def _bisect(self, t0: float) -> float:
        """The first time of the step from ``t0`` at which a sticking contact no longer sticks,
        by bisection on the dense output (to round-off in time)."""
        interpolant = self.dense_output()
        a, b = t0, self.t
        while b - a > 4 * np.finfo(float).eps * max(1.0, abs(b)):
            s = 0.5 * (a + b)
            if self._sticking(s, *interpolant(s)):
                a = s
            else:
                b = s
        return b

    def _refresh(self) -> None:
        """The accelerations, multipliers and contact forces of the current state, and its
        contacts' clearance (:meth:`_clearance`), where the next step starts."""
        self.v_dot, lam, F, accelerations = self._solve(self.t, self.q, self.v)[:4]
        self.lam = lam
        axes = contact_frames(self.model, self.q, self.contacts, self.data).axes
        self.contact_forces = np.einsum("mij,mi->mj", axes, F)
        self.contact_states = tuple(self.modes)
        self._here = self._clearance(self.t, self.q, self.v, accelerations)

    def _watch(self, t, q, v, t0) -> np.ndarray:
        """The event functions (m, 2) at a state of the step from ``t0`` (see the module's
        description): column 0 the gap (open) or normal force (slip), column 1 the slip speed
        along its direction (slip); positive while the modes hold. Sticking contacts are
        watched together (:meth:`_sticking`): theirs stay 1."""
        m, d = len(self.contacts), self.model.dimension
        values = np.ones((m, 2))
        if not m:
            return values
        F = self._solve(t, q, v)[2] if any(x == "slip" for x in self.modes) else np.zeros(
            (m, d))
        frames = contact_frames(self.model, q, self.contacts, self.data)
        u = (frames.jacobian @ v).reshape(m, d)
        ready = armed(frames, self.contacts)
        for k, mode in enumerate(self.modes):
            if mode == "open":
                values[k, 0] = self._gap_value(k, frames.gaps[k], u[k, 0], t - t0,
                                               ready[k])
                continue
            if mode == "stick":  # watched together, by _sticking
                continue
            values[k, 0] = F[k, 0]
            along = u[k, 1:] @ self._direction[k]
            values[k, 1] = along / (t - t0) if self._just[k] and t > t0 else along
        return values

    def _gap_value(self, k, gap, normal_speed, since, ready) -> float:
        """An open contact's gap event function: its gap (plus the gap tolerance while it has
        not cleared the ground since its force let it go), divided by the time since it left
        when it left at the step's start (its speed there); NaN while it is not armed."""
        if not ready:
            return np.nan
        if self._lifted[k]:
            gap = gap + self._gap_tol
        if self._just[k]:
            return gap / since if since > 0 else normal_speed
        return gap

    def _clearance(self, t, q, v, accelerations=None) -> tuple:
        """Each contact's gap, normal speed and normal acceleration (magnitudes) at a state
        (``accelerations``: the contacts', when solved already; infinite where the modes'
        forces have no solution there)."""
        d = self.model.dimension
        frames = self._free_motion(t, q, v)[0]
        if accelerations is None:
            try:
                accelerations = self._solve(t, q, v)[3]
            except (HexapodError, np.linalg.LinAlgError):
                accelerations = np.full(len(self.contacts) * d, np.inf)
        return frames.gaps, np.abs(frames.jacobian[::d] @ v), np.abs(accelerations[::d])

    def _near(self, h, start, end) -> np.ndarray:
        """Which contacts may touch the ground inside a step ``h`` whose ends are both clear
        of it: those whose gap at either end is within what their normal speed and twice
        their normal acceleration (the larger of the ends') cover in the step. The others'
        gaps are watched at the step's ends alone, without the dense output (four more
        solves a step): a smooth phase's accelerations change little within a step its
        error control accepts."""
        (g0, u0, a0), (g1, u1, a1) = start, end
        reach = h * np.maximum(u0, u1) + h * h * np.maximum(a0, a1) + self._gap_tol
        return np.minimum(g0, g1) <= reach

    def _first_root(self, t0, before, after, near):
        """The first event of the step ``(t0, t]``: ``(t, (contact, column))`` or None.
        ``near``: the open contacts whose gaps are also watched inside the step."""
        if self._dense_step is None:
            return None
        m = before.shape[0]
        crossed = (before >= 0.0) & (after < 0.0)  # (NaN: not armed)
        watched = [k for k in range(m) if self.modes[k] == "open" and (near[k]
                                                                       or crossed[k, 0])]
        if not watched and not crossed.any():
            return None
        interpolant = self.dense_output()
        best = None
        grid = np.linspace(t0, self.t, GAP_WATCH + 1)
        # the open contacts' gaps inside the step too (a short flight), all of them from one
        # evaluation of the watch at each point
        inside = np.array([self._watch(s, *interpolant(s), t0)[:, 0] for s in grid[1:-1]]
                          ) if watched else None
        for k in range(m):
            for column in (0, 1):
                values = [before[k, column], after[k, column]]
                times = [t0, self.t]
                if column == 0 and k in watched:
                    times = list(grid)
                    values = [before[k, 0], *inside[:, k], after[k, 0]]
                for a in range(len(times) - 1):
                    if values[a] >= 0.0 and values[a + 1] < 0.0:  # (NaN: not armed)
                        root = self._locate(interpolant, k, column, t0, times[a], times[a + 1],
                                            values[a], values[a + 1])
                        if best is None or root < best[0]:
                            best = (root, (k, column))
                        break
        return best

    def _value(self, interpolant, t, k, column, t0) -> float:
        q, v = interpolant(t)
        return float(self._watch(t, q, v, t0)[k, column])

    def _locate(self, interpolant, k, column, t0, a, b, fa, fb) -> float:
        """The root of event function ``(k, column)`` in ``[a, b]`` (``fa >= 0 > fb``), by
        Illinois' method on the dense output, to round-off in time."""
        if fa == 0.0:
            return a
        side = 0
        for _ in range(100):
            if b - a <= 4 * np.finfo(float).eps * max(1.0, abs(b)):
                break
            s = b - fb * (b - a) / (fb - fa)
            if not a < s < b:
                s = 0.5 * (a + b)
            fs = self._value(interpolant, s, k, column, t0)
            if fs >= 0.0:
                a, fa = s, fs
                if side == -1:
                    fb /= 2
                side = -1
            else:
                b, fb = s, fs
                if side == 1:
                    fa /= 2
                side = 1
        return b

    # ---------------------------------------------------------------- what an event changes

    def _handle(self, index: tuple[int, int]) -> None:
        """Apply the event ``(contact, column)`` at the current state, then settle the modes."""
        t = self.t
        self._just[:] = False
        if index is None:  # the sticking contacts' problem changed: settled below
            self._settle(t, self.q, self.v)
            return
        k, column = index
        if self.modes[k] == "open":  # a touch-down, with the contacts touching at once
            frames = contact_frames(self.model, self.q, self.contacts, self.data)
            closed = np.array([mode != "open" for mode in self.modes])
            touching = np.flatnonzero((frames.gaps <= max(self._gap_tol, frames.gaps[k]))
                                      & (armed(frames, self.contacts) | closed))
            self.v = self._impact(t, self.q, self.v, np.union1d(touching, [k]))
        elif column == 0:
            self._mode(k, "open", t)
            self._just[k] = True
        else:  # a slip ends, with those ending at once: they stick, or slip back (below)
            m, d = len(self.contacts), self.model.dimension
            u = (contact_frames(self.model, self.q, self.contacts, self.data).jacobian
                 @ self.v).reshape(m, d)
            resting = MODE_TOLERANCE * max(1.0, np.abs(self.v).max())
            for j, mode in enumerate(self.modes):
                if j == k or (mode == "slip" and np.linalg.norm(u[j, 1:]) <= resting):
                    self._mode(j, "stick", t)
        self._settle(t, self.q, self.v)

    def _mode(self, k: int, mode: str, t: float) -> None:
        """Contact ``k`` enters ``mode`` at ``t``: its event recorded."""
        old, d = self.modes[k], self.model.dimension
        kind = ("touch-down" if old == "open" else "lift-off" if mode == "open"
                else "slip-start" if mode == "slip" else "slip-end")
        if old != mode:
            self.events.append(ContactEvent(t, kind, self.contact_names[k], np.zeros(d)))
            self.modes[k] = mode
        self._lifted[k] = mode == "open"  # a lift-off; a rebound clears it (_impact)

    def _impact(self, t, q, v, touching) -> np.ndarray:
        """The velocities after the impulse map of the ``touching`` contacts (see the module's
        description); their modes and events follow."""
        model, d = self.model, self.model.dimension
        half = model.mass_inv_sqrt
        rows = (touching[:, None] * d + np.arange(d)).reshape(-1)
        frames, G, y, Y = self._velocity_response(t, q, v, rows)
        before = (frames.jacobian[rows] @ v).reshape(-1, d)
        approach = np.maximum(-before[:, 0], 0.0)
        restitution = self._restitution[touching].copy()
        flying = self._free_normal_acceleration(t, q, v, touching)
        for _ in range(2):  # again with restitution 0 where a rebound would not fly
            solution = solve_contacts(G.T @ Y, G.T @ y, self._mu[touching],
                                      restitution * approach,
                                      tuple(self.contact_names[k] for k in touching))
            rebound = solution.velocities[:, 0]
            short = (rebound > 0) & (2 * rebound < ZENO_FLIGHT * np.maximum(-flying, 0.0))
            if not short.any():
                break
            restitution[short] = 0.0
        world = np.einsum("mij,mi->mj", frames.axes[touching], solution.impulses)
        scale = ROUND_OFF * max(1.0, np.abs(v).max())
        # a slip after the impulse slower than the modes' tolerance is the impact's round-off
        # on a contact that stays put (a sticking foot beside a foot landing at nearly zero
        # speed): it sticks, as at the start
        resting = MODE_TOLERANCE * max(1.0, np.abs(v).max())
        for j, k in enumerate(touching):
            pushed = solution.impulses[j, 0] > 0.0
            leaving = rebound[j] > scale
            if self.modes[k] == "open" and not (pushed or not leaving):
                continue  # grazed, and gone
            self._mode(k, "stick", t)  # a touch-down, if it was open
            if pushed and approach[j] > scale:
                self.events.append(ContactEvent(t, "impact", self.contact_names[k], world[j]))
            if leaving:  # a rebound
                self._mode(k, "open", t)
                self._just[k] = True
                self._lifted[k] = False
            elif (solution.states[j] == "slip"
                  and np.linalg.norm(solution.velocities[j, 1:]) > resting):
                slip = solution.velocities[j, 1:]
                self._direction[k] = slip / np.linalg.norm(slip)
                self._mode(k, "slip", t)
        return half @ (y + Y @ solution.impulses.reshape(-1))

    def _free_normal_acceleration(self, t, q, v, touching) -> np.ndarray:
        """The ``touching`` contacts' normal accelerations with every contact open."""
        d = self.model.dimension
        accelerations = self._solve(t, q, v, modes=["open"] * len(self.contacts))[3]
        return accelerations[touching * d]

    def _settle(self, t, q, v) -> None:
        """Change modes until they are consistent: a slipping contact that would pull opens;
        the sticking ones, and the open ones touching at zero speed, take the states of their
        frictional problem at acceleration level (:meth:`_stick_states`): stick, slip (along
        their tangential acceleration) or open."""
        m, d = len(self.contacts), self.model.dimension
        frames = contact_frames(self.model, q, self.contacts, self.data)
        u = (frames.jacobian @ v).reshape(m, d)
        speed = ROUND_OFF * max(1.0, np.abs(v).max())
        ready = armed(frames, self.contacts)
        for _ in range(2 * m + 1):
            F = self._solve(t, q, v)[2]
            size = MODE_TOLERANCE * max(np.abs(F).max(initial=0.0), np.finfo(float).tiny)
            pulling = [k for k, mode in enumerate(self.modes)
                       if mode == "slip" and F[k, 0] < -size]
            if pulling:
                self._mode(pulling[0], "open", t)
                self._just[pulling[0]] = True
                continue
            # (a contact its force let go is not closed again here: at the instant it left,
            # tangent to the ground, its acceleration open is round-off, which the modes'
            # tolerance reads as sticking; it comes back by a touch-down, past the tolerance)
            candidates = [k for k, mode in enumerate(self.modes) if mode == "stick" or (
                mode == "open" and not self._lifted[k] and frames.gaps[k] <= self._gap_tol
                and u[k, 0] <= speed and ready[k])]
            if not candidates:
                return
            states, accelerations = self._stick_states(t, q, v, candidates)
            changes = [(k, state, a) for k, state, a in zip(candidates, states, accelerations,
                                                           strict=True)
                       if state != self.modes[k]]
            if not changes:
                return
            for k, state, a in changes:
                if state == "slip":
                    self._direction[k] = a[1:] / np.linalg.norm(a[1:])
                self._mode(k, state, t)
                self._just[k] = state != "stick"
        raise IntegrationError(f"no consistent contact modes at t = {t:.9g} s ("
                               + ", ".join(f"'{n}' {x}" for n, x in
                                           zip(self.contact_names, self.modes, strict=True))
                               + ")")

    def _velocity_response(self, t, q, v, rows) -> tuple:
        """At a state, the velocity-level solve on the bilateral rows (``v`` projected onto
        ``Phi_v v = nu``, ``y = M^1/2 v``) and its response ``Y`` to unit impulses along the
        contact ``rows`` (indices into the contacts' Jacobian), with the contacts' frames and
        ``G = M^-1/2 J_rows^T``: what an impact and the contact projection solve on."""
        model = self.model
        laws = model.law_values(t, self.data)[:2]
        frames = contact_frames(model, q, self.contacts, self.data)
        # every contact's columns, of which the rows': one kernel serves every set of rows
        y, _, Y, _ = self._contact_solve("impulse", t, q, v, laws, frames.scaled.T)
        self.counters.factorisations += 1
        return frames, frames.scaled[rows].T, y, Y[:, rows]

    def _contact_solve(self, level: str, t, q, v, laws, G) -> tuple:
        """The engine's solve with the contacts' columns ``G`` at ``level``
        (:class:`~hexapod.simulation.contact_kernel.CompiledContactStep`: ``acceleration`` or
        ``impulse``; ``G`` every contact's columns), its kernel kept per level (made at the
        start), its rows decided again at ``(t, q)`` when they no longer serve."""
        self._kernels[level], solution = contact_solution(
            self._kernels[level], lambda: self._rank_split(q, t), q, v, laws, G)
        return solution

    def _kernel(self, level: str, q, v, laws) -> CompiledContactStep:
        """The ``level``'s kernel for every contact's columns, of the rows decided at the
        start, made now (compiled: by an LU whose pivots follow the tree, where it applies)."""
        columns = len(self.contacts) * self.model.dimension
        return CompiledContactStep.started(self.model, self.data, columns, level).pivoted(
            q, v, laws).made()

    def _onto_contacts(self, t, q, v) -> tuple[np.ndarray, np.ndarray]:
        """The closed contacts' gaps, normal velocities and (sticking) tangential velocities
        put back to zero by the least ``M``-norm corrections under the bilateral rows. The
        gaps only where one has left the gap tolerance: a step on accelerations that hold
        the contacts leaves them at round-off (the walking robot's feet: 1e-16 m, where the
        tolerance is 3e-13), and their correction would cost a solve a step for nothing."""
        model, d = self.model, self.model.dimension
        closed = [k for k in range(len(self.contacts)) if self.modes[k] != "open"]
        if not closed:
            return q, v
        half = model.mass_inv_sqrt
        held = np.abs(contact_gaps(model, q, self.contacts, self.data)[closed]).max() <= (
            self._gap_tol)
        for stage in ("velocities",) if held else ("positions", "velocities"):
            rows = [k * d + i for k in closed
                    for i in range(d if stage == "velocities" and self.modes[k] == "stick"
                                   else 1)]
            frames, G, y, Y = self._velocity_response(t, q, v, rows)
            if stage == "positions":
                gaps = frames.gaps[closed]
                x = least_norm_psd(Y.T @ Y, -gaps)
                q = model.integrate(q, half @ (Y @ x))
            else:
                x = least_norm_psd(Y.T @ Y, -(G.T @ y))
                v = half @ (y + Y @ x)
        return q, v


def _normal_compliance(A: np.ndarray, j: int) -> float:
    """How fast slipping contact ``j``'s normal acceleration grows with its normal force, the
    other closed contacts' conditions kept: the Schur complement of ``A``'s other unknowns at
    ``(j, j)`` (``W_NN - mu W_NT s`` for a contact alone). Negative: Painleve's paradox; zero:
    the force is shared with redundant contacts (a block's four corners), which is not."""
    rest = [i for i in range(A.shape[0]) if i != j]
    if not rest:
        return float(A[j, j])
    return float(A[j, j] - A[j, rest] @ np.linalg.pinv(A[np.ix_(rest, rest)]) @ A[rest, j])


def _unit(n: int, i: int) -> np.ndarray:
    column = np.zeros(n)
    column[i] = 1.0
    return column


def _painleve(name: str, t: float, mu: float) -> str:
    return (f"Painleve's paradox at contact '{name}', t = {t:.9g} s: slipping with mu = {mu:g}, "
            "its normal acceleration falls as its normal force grows, so no contact force "
            "holds it and none lets it go (the acceleration-level contact problem has no "
            "solution); simulate it with method moreau-jean, which resolves it by a "
            "tangential impact")
