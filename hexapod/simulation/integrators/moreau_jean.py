"""Moreau-Jean time-stepping: unilateral contacts with Coulomb friction and impacts, at
velocity level (Moreau 1988, Jean 1999; Acary and Brogliato, *Numerical Methods for Nonsmooth
Dynamical Systems*, 2008, ch. 10).

Each step of ``h`` from ``(t_k, q_k, v_k)`` is one saddle-point solve of the engine's
constrained step with the contacts' impulses ``P`` on its right-hand side, at velocity level:

    M (v_k+1 - v_k) = h Q(t_k+theta, q_k+theta, v_k) - Phi_v^T Lambda + J^T P,
    Phi_v v_k+1 = nu(t_k+1),                          the bilateral rows, at q_k+theta
    q_k+1 = q_k (+) h ((1 - theta) v_k + theta v_k+1),  theta = 1/2

with ``J`` the contacts' Jacobian in their own axes (:mod:`hexapod.algorithms.contact_frames`),
everything taken where the step's forces act on average: the time laws at ``t_k+theta = t_k +
theta h``, the positions (the forces, the rows' and the contacts' Jacobians, the contacts'
gaps) at ``q_k+theta = q_k (+) theta h v_k`` (Acary and Brogliato's theta-gamma scheme,
gamma = theta). A controller's target read at the step's start lagged it by ``theta h`` (the
walking robot's joints, turning at up to 18 rad/s, trailed their targets by 10 mrad at a 1 ms
step; 3 mrad with the laws at mid-step), and the Jacobians at the step's start turned the
rows' and the feet's forces by half a step's rotation (3.06 mrad; 1.48 at mid-step, the
error still of order 1: ``scripts/benchmarks/bench_walking_contacts.py``).
The solve is linear in ``P``: ``v_k+1 = v_free + A J^T P``, ``A`` the mechanism's inverse mass
under its bilateral rows, so the contacts see ``u = J v_k+1 = b + W P`` with the Delassus
operator ``W = J A J^T``; the impulses come from the frictional contact problem
(:func:`hexapod.algorithms.frictional.solve_contacts`) of the contacts whose gap would close
in the step without them (the position update applied to the free velocity): Signorini with
Newton's restitution on ``u_N + e u_N,k`` and the exact Coulomb cone. No acceleration-level
complementarity problem is solved: the scheme is well posed in Painleve's configurations,
where it answers with a tangential impact.

Positions are then put back on the bilateral rows (Newton, :meth:`Integrator._project`) and
on the ground: the gaps of the contacts the ground pushed are closed by the least ``M``-norm
correction under the bilateral rows (a position correction, not an impulse: the velocities
are kept), out of the ground and, where a plastic touch-down stopped a contact a little above
it, down onto it. The method is of order 1 (its impacts and friction are resolved within
a step); the saved accelerations are the step's mean ``(v_k+1 - v_k) / h`` and the saved
multipliers the mean forces ``Lambda / h``, so that an impact shows as a force of one step.

Contacts and their events: after each step every contact is ``open``, ``stick`` or ``slip``;
a change from the step before is an event (touch-down, lift-off, slip start and end), and a
touch-down whose approach speed is more than twice what the smooth forces change the contact's
normal velocity by in the step is an **impact** (its impulse the step's). ``contact_forces``
holds each contact's force of the ground on the body, world axes, the step's impulse over
``h``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.algorithms.contact_frames import (
    armed,
    contact_frames,
    contact_gaps,
    ground_contacts,
)
from hexapod.algorithms.frictional import solve_contacts
from hexapod.algorithms.linalg import least_norm_psd
from hexapod.simulation.contact_kernel import CompiledContactStep, contact_solution
from hexapod.simulation.integrators.base import Integrator
from hexapod.simulation.methods import CONTACT_METHODS
from hexapod.simulation.scales import ROUND_OFF

#: the weight of the new velocity in the position update (1/2: the trapezoidal rule)
THETA = 0.5
#: how many steps' time laws are evaluated together, ahead of them (a fixed step's times are
#: known): on the walking robot, its 512 times cost what 19 cost one at a time (6 against
#: 157 us a time)
LAWS_AHEAD = 256
#: the gap (relative to the scene's characteristic length) past which a closed contact's
#: position is corrected onto the ground
GAP_TOLERANCE = 1e-12


@dataclass(frozen=True)
class ContactEvent:
    """One event of a contact: ``kind`` one of ``touch-down``, ``lift-off``, ``slip-start``,
    ``slip-end``, ``impact``; ``impulse`` the ground's on the body, world axes (N s; zero but
    for impacts)."""

    t: float
    kind: str
    contact: str
    impulse: np.ndarray


class MoreauJean(Integrator):
    """Moreau-Jean time-stepping with unilateral contacts (see the module's description).

    Attributes
    ----------
    contact_forces : ndarray, shape (m, d)
        The last step's contact forces (the ground's on each body, world axes, N).
    contact_states : tuple of str
        ``open``, ``stick`` or ``slip`` per contact after the last step.
    events : list of ContactEvent
        The run's contact events so far.
    """

    name = "moreau-jean"
    order, index, adaptive, stabilisation = CONTACT_METHODS[name]
    description = "time-stepping with unilateral contacts, Coulomb friction and impacts"
    impulsive = True
    default_steps = 1000

    def _start(self) -> None:
        self.contacts = ground_contacts(self.model)
        self.contact_names = tuple(c.name for c in self.contacts)
        d = self.model.dimension
        self.contact_forces = np.zeros((len(self.contacts), d))
        self.events: list[ContactEvent] = []
        self._mu = np.array([c.contact.mu for c in self.contacts])
        self._restitution = np.array([c.contact.restitution for c in self.contacts])
        self._last_impulses = np.zeros((len(self.contacts), d))  # where the sweeps start
        frames = contact_frames(self.model, self.q, self.contacts, self.data)
        self._unconditional = np.array([c.contact.armed_ahead_of is None
                                        for c in self.contacts], dtype=bool)
        self._armed = armed(frames, self.contacts) & ((frames.gaps >= 0.0)
                                                      | self._unconditional)
        closed = frames.gaps <= GAP_TOLERANCE * self.model.characteristic_length
        sliding = np.linalg.norm((frames.jacobian @ self.v).reshape(-1, d)[:, 1:], axis=1) > (
            ROUND_OFF * max(np.abs(self.v).max(), 1.0))
        self.contact_states = tuple("open" if not c else "slip" if s else "stick"
                                    for c, s in zip(closed, sliding, strict=True))
        self._kernel = CompiledContactStep.started(self.model, self.data, len(self.contacts) * d)
        h = self.next_step()  # compiled, the LU's pivots are chosen at the first step's call
        laws = (*self.model.law_values(self.t + THETA * h, self.data),
                *self.model.law_values(self.t + h, self.data)[:2])
        self._kernel = self._kernel.pivoted(self.q, self.v, laws, h, THETA)
        # by columns, the rows kept at the start: made (compiled) before the time loop
        self._kernels = {columns: self._kernel.with_columns(columns).made() for columns
                         in {self._columns_for(0), self._columns_for(len(self.contacts))}}
        self._speed_change = np.full(len(self.contacts), np.inf)  # unknown before a step
        self._closed = np.array([state != "open" for state in self.contact_states], dtype=bool)

    def _step(self) -> None:
        model, data = self.model, self.data
        h = self.next_step()
        t0, q0, v0 = self.t, self.q, self.v
        t1 = t0 + h
        if model.n_w and not self._laws_kept(t0 + THETA * h):
            self._laws_ahead()
        mid = model.law_values(t0 + THETA * h, data)
        d = model.dimension
        q_mid = model.integrate(q0, THETA * h * v0)
        frames = contact_frames(model, q_mid, self.contacts, self.data)
        start = frames.jacobian @ v0  # the contacts' velocities, their axes
        carried = self._candidates(frames, start[::d], h)
        y, lam, Y, Lam = self._constrained(t1, q_mid, v0, mid, frames, h, carried)
        free = frames.scaled @ y  # at the step's end without contact impulses
        active = self._active(h, frames, start[::d], free[::d])
        if (active & ~carried).any():  # one closes that was not foreseen: all of them
            carried = np.ones(len(self.contacts), dtype=bool)
            y, lam, Y, Lam = self._constrained(t1, q_mid, v0, mid, frames, h, carried)
            free = frames.scaled @ y
        impulses, states = self._impulses(frames, start[::d], free,
                                          Y[:, _columns(active, carried, d)], active)
        y = y + Y @ impulses[carried].reshape(-1)
        lam = lam + Lam @ impulses[carried].reshape(-1)
        end = frames.scaled @ y
        v1 = model.mass_inv_sqrt @ y
        q1 = model.integrate(q0, h * ((1 - THETA) * v0 + THETA * v1))
        staying = np.array([state != "open" for state in states])
        if staying.any():  # those that rebound leave at their normal speed
            staying &= end[::d] <= ROUND_OFF * max(np.abs(v0).max(), np.abs(v1).max())
        q1 = self._onto_ground(q1, impulses, staying, Y, carried)
        q1, v1 = self._project(t1, q1, v1)
        self._record(t1, h, frames, impulses, states, start, free, end)
        self.t, self.q, self.v = t1, q1, v1
        self.v_dot, self.lam = (v1 - v0) / h, lam / h

    def _laws_kept(self, t: float) -> bool:
        kept = self.data.laws
        return kept is not None and float(t) in kept[0]

    def _laws_ahead(self) -> None:
        """The laws at the mid-step and end times of the next :data:`LAWS_AHEAD` steps, as
        :meth:`next_step` will take them, evaluated in one call and kept in the run's
        workspace, where each step reads its own (the same values as one time at a time)."""
        times, t = [], self.t
        for _ in range(LAWS_AHEAD):
            h = self.next_step(t)
            times += [t + THETA * h, t + h]
            t = t + h
            if self._at_end(t):
                break
        self.model.law_values(np.array(times), self.data)

    def _candidates(self, frames, normal_speed, h) -> np.ndarray:
        """The contacts (a mask) whose unit impulses the step's solve carries: those closed,
        and those whose gap could close in the step, their normal speed changed by up to four
        times the change of the step before (all of them at the first step). A contact that
        closes unforeseen has the solve made again with all of them: the impulses are the
        same, and the walking robot's solve carries its three feet down instead of six."""
        lowest = frames.gaps + h * ((1 - THETA) * normal_speed
                                    - THETA * 4.0 * self._speed_change)
        return self._closed | (lowest <= 0.0)

    def _constrained(self, t1, q_mid, v0, mid, frames, h, carried):
        """The saddle-point solve of the step on the bilateral rows kept, at the mid-step
        positions ``q_mid``, in one call
        (:class:`~hexapod.simulation.contact_kernel.CompiledContactStep`): the free velocity
        (``y = M^1/2 v``, with the rows' impulses ``lam``) and the response to the unit
        impulses of the ``carried`` contacts (a mask; ``Y``, ``Lam``: their columns in
        order). Forces that depend on the state (a controller's gains, dampers, springs, the
        gyroscopic terms) enter linearly implicit at ``theta`` (Acary and Brogliato 2008,
        10.1): stable for gains an explicit force would need steps far shorter than the
        controller's period for. When the rows kept at the start no longer serve, they are
        decided again here."""
        d, n_v = self.model.dimension, self.model.n_v
        count = int(carried.sum())
        columns = self._columns_for(count)
        kernel = self._kernels.get(columns) or self._kernel.with_columns(columns)
        G_carried = np.zeros((n_v, columns))  # M^-1/2 J^T, padded with zero columns
        G_carried[:, :count * d] = frames.scaled[np.repeat(carried, d)].T
        end = self.model.law_values(t1, self.data)[:2]
        self._kernel, (y, lam, Y, Lam) = contact_solution(
            kernel, lambda: self._rank_split(q_mid, self.t + THETA * h), q_mid, v0,
            (*mid, *end), G_carried, h, THETA)
        if self._kernel is not kernel:  # the rows were decided again: the others no longer serve
            self._kernels = {}
        self._kernels[columns] = self._kernel
        self.counters.rhs += 1
        self.counters.jacobians += 1
        self.counters.factorisations += 1
        return y, lam, Y[:, :count * d], Lam[:, :count * d]

    def _columns_for(self, count: int) -> int:
        """The kernel's contact columns for ``count`` contacts carried: there are kernels for
        half of the contacts and for all of them, the carried padded with zero columns."""
        m, d = len(self.contacts), self.model.dimension
        return d * (m if count > (m + 1) // 2 else (m + 1) // 2)

    def _active(self, h, frames, normal_speed, free_speed) -> np.ndarray:
        """The contacts (a mask) whose gap would close in the step without their impulses (the
        position update applied to the normal speeds ``free_speed`` at the step's end without
        them), armed or closed."""
        self._speed_change = np.abs(free_speed - normal_speed)
        # the gaps at q_k+theta (the frames') and the rest of the way, q_k+1 = q_k+theta (+)
        # h ((1 - 2 theta) v_k + theta v_k+1)
        predicted = frames.gaps + h * ((1 - 2 * THETA) * normal_speed + THETA * free_speed)
        # a contact with an arming condition may touch down ahead of its other contact once
        # above the ground there (a scuffing swing foot, below it when it passes, is not
        # pushed out); one closed stays so whatever its condition
        if not self._unconditional.all():
            self._armed = armed(frames, self.contacts) & (
                self._armed | (frames.gaps > 0.0) | self._unconditional)
        return (predicted <= 0.0) & (self._armed | self._closed)

    def _impulses(self, frames, normal_speed, free, Y, active):
        """Each contact's impulse in its axes (m, d) and its state after the step; ``free`` the
        contacts' velocities at the step's end without contact impulses, ``Y`` the unit
        impulses' responses of the ``active`` contacts (a mask)."""
        m, d = len(self.contacts), self.model.dimension
        impulses = np.zeros((m, d))
        states = ["open"] * m
        active = np.flatnonzero(active)
        if active.size:
            rows = (active[:, None] * d + np.arange(d)).reshape(-1)
            W = frames.scaled[rows] @ Y
            approach = np.where(_impacting(normal_speed[active], free[rows][::d]),
                                -normal_speed[active], 0.0)
            solution = solve_contacts((W + W.T) / 2, free[rows], self._mu[active],
                                      self._restitution[active] * approach,
                                      tuple(self.contact_names[a] for a in active),
                                      initial=self._last_impulses[active])
            impulses[active] = solution.impulses
            for a, state in zip(active, solution.states, strict=True):
                states[a] = state
        self._last_impulses = impulses
        return impulses, tuple(states)

    def _onto_ground(self, q1, impulses, staying, Y, carried):
        """The gaps of the contacts the ground pushed in the step closed by the least
        ``M``-norm correction along their normals, under the bilateral rows (linearised at the
        step's start). Closed both ways: out of the ground, and down onto it where a plastic
        touch-down stopped a contact short of it (which would otherwise fall again, and hop):
        ``staying`` says which stay (their normal speed is zero at the step's end); ``Y`` the
        unit impulses' responses of the ``carried`` contacts."""
        model, d = self.model, self.model.dimension
        pushing = impulses[:, 0] > 0.0
        pushed = np.flatnonzero(pushing)
        if not pushed.size:
            return q1
        gaps = contact_gaps(model, q1, self.contacts, self.data)[pushed]
        # a contact that rebounds (leaving at its normal speed) is only pushed out
        gaps = np.where(staying[pushed], gaps, np.minimum(gaps, 0.0))
        if np.max(np.abs(gaps)) <= GAP_TOLERANCE * model.characteristic_length:
            return q1
        G = Y[:, _columns(pushing, carried, d)[::d]]  # the normal columns
        correction = least_norm_psd(G.T @ G, -gaps)
        return model.integrate(q1, model.mass_inv_sqrt @ (G @ correction))

    def _record(self, t1, h, frames, impulses, states, start, free, end) -> None:
        """The step's contact forces and events; ``start``, ``free`` and ``end`` the contacts'
        velocities (their axes) at the step's start, at its end without contact impulses and
        with them."""
        d = self.model.dimension
        world = (impulses[:, None, :] @ frames.axes)[:, 0]  # axes as rows: J^T P
        m = len(self.contacts)
        if not m:
            return
        start, free, end = start.reshape(m, d), free.reshape(m, d), end.reshape(m, d)
        # an impact: an approach faster than twice what the smooth forces change the contact's
        # velocity by in the step, or a slip stopped (or started) by more than that: a
        # tangential impact (Painleve's rod)
        smooth = np.linalg.norm(free - start, axis=1)
        slip_jump = np.linalg.norm(end[:, 1:] - free[:, 1:], axis=1)
        impacting = _impacting(start[:, 0], free[:, 0]) | (
            (slip_jump > 2.0 * smooth) & (slip_jump > ROUND_OFF * np.abs(start).max()))
        changed = [a for a, (old, new) in enumerate(zip(self.contact_states, states, strict=True))
                   if old != new or impacting[a]]
        for a in changed:
            old, new, name = self.contact_states[a], states[a], self.contact_names[a]
            if impacting[a] and new != "open":
                self.events.append(ContactEvent(t1, "impact", name, world[a].copy()))
            if old == "open" and new != "open":
                self.events.insert(len(self.events) - bool(impacting[a]),
                                   ContactEvent(t1, "touch-down", name, np.zeros(d)))
            elif old != "open" and new == "open":
                self.events.append(ContactEvent(t1, "lift-off", name, np.zeros(d)))
            elif old == "stick" and new == "slip":
                self.events.append(ContactEvent(t1, "slip-start", name, np.zeros(d)))
            elif old == "slip" and new == "stick":
                self.events.append(ContactEvent(t1, "slip-end", name, np.zeros(d)))
        self.contact_states = states
        self._closed = np.array([state != "open" for state in states], dtype=bool)
        self.contact_forces = world / h


def _columns(chosen: np.ndarray, carried: np.ndarray, d: int) -> np.ndarray:
    """The columns, among those of the ``carried`` contacts (``d`` each, in order), of the
    ``chosen`` ones (both masks over all contacts; the chosen are carried)."""
    first = (np.cumsum(carried) - 1)[chosen] * d
    return (first[:, None] + np.arange(d)).reshape(-1)


def _impacting(before: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Whether contacts approaching at normal speeds ``before`` (at the step's start) impact:
    when they approach faster than twice what the smooth forces change their normal speed by
    in the step (``free - before``). Restitution applies to impacts only: a contact resting
    under gravity approaches at ``g h`` each step, and bouncing it back would make it chatter
    forever at that speed instead of resting."""
    return (before < 0.0) & (-before > 2.0 * np.abs(free - before))
