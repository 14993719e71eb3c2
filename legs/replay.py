"""Inverse and forward agree: the efforts of the hexapod's inverse dynamics replayed in a forward
simulation of the same robot.

:func:`replay_scene` turns a driven walking scene (every revolute joint prescribed by a
:class:`hexapod.JointDriver`, the feet held by :class:`hexapod.Contact` joints on their stance
schedule) into its **forward twin**: the same bodies, joints and contacts, each driver replaced
by a :class:`hexapod.JointEffort` whose law reproduces the efforts that
:func:`hexapod.inverse_dynamics` found, and the bodies starting at the first sample's state.
:func:`replay` simulates the twin between the feet's switch times (touch-down, lift-off),
restarting each phase from the state the previous one reached, and :func:`agreement` compares
its joint angles with the prescribed ones.

**The efforts as laws of time** (:class:`EffortTable`). The inverse efforts are smooth
between the times :func:`effort_breaks` lists and lose smoothness there: at each foot's
touch-down and lift-off (the set of stance rows changes, the foot paths change from swing to
stance) and at the ends of each foot's load ramps (the load-sharing weight, a quintic smooth
step clipped to 1, is only C2 there). One spline across such a time would interpolate a
function with a jump in its third derivative: a local error of order ``h^3``. So each effort is
interpolated by a separate quintic spline (not-a-knot, :class:`hexapod.Spline` of degree 5) on
each interval between consecutive breaks, sampled on a uniform grid that includes both ends
(:func:`sample_times`): on each interval the error is that of a quintic spline of an analytic
function, ``O(h^6)``, and the law is exact at every sample. ``scripts/walking_forward.py
--convergence`` measures it against inverse dynamics at the midpoints of the grid: with
``spacing = 2.5 ms`` the largest error is some ``1e-6`` of the largest effort, a force error far
smaller than the integration error of ``rtol = 1e-8``, see the test.

**The schedule.** A foot in swing has zero rows (gate 0); at touch-down it is at its foothold
with zero velocity and acceleration by design and its load grows from zero, at lift-off its
load is zero. The motion is therefore smooth across the switches, but the integrators compile
their right-hand side for the rows independent at their start, so a single run across a switch
would fall back on the exact (slow) solve at every stage after it. Restarting at each switch
time gives each phase its own compiled kernel; the state is carried over unchanged (it is
consistent with both row sets at a switch).

Angles here are radians and efforts SI; the twin keeps the scene's length unit.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

import hexapod as hx
from hexapod import (
    Contact,
    Joint,
    JointDriver,
    JointEffort,
    Law,
    Particle,
    PlanarBody,
    Revolute,
    Scene,
    SpatialBody,
    )
from legs.cockroach import STRIDE_PERIOD
from legs.robot import hexapod_scene

#: Degree of the effort splines (C4; 5 is the largest :class:`hexapod.Spline` offers).
EFFORT_DEGREE = 5
#: Default grid step of the inverse-dynamics samples (s): see the module's description.
EFFORT_SPACING = 2.5e-3
#: Fewest intervals per piece (a quintic not-a-knot spline needs at least 6 samples).
MIN_INTERVALS = 6


# ------------------------------------------------------------------ the schedule

def _contacts(source) -> list:
    """The contact schedules of a scene (its :class:`hexapod.Contact` joints) or of a model (the
    schedules of ``model.contacts``, in SI)."""
    if isinstance(source, Scene):
        return [j for j in source.joints.values() if isinstance(j, Contact)]
    return [c.schedule for c in source.contacts]


def _times(contact, fractions, t0: float, t1: float) -> list[float]:
    """The times ``(lift_off + k - f) period`` inside ``[t0, t1]`` for each ``f`` of
    ``fractions`` (fractions of the period before lift-off) and every cycle ``k``."""
    out = []
    period = contact.period
    for f in fractions:
        base = (contact.lift_off - f) * period
        for k in range(int(np.floor((t0 - base) / period)) - 1,
                       int(np.ceil((t1 - base) / period)) + 2):
            t = base + k * period
            if t0 <= t <= t1:
                out.append(t)
    return out


def _merge(times, t0: float, t1: float, tol: float) -> np.ndarray:
    """Sorted times in ``[t0, t1]``, those closer than ``tol`` taken as one, with both ends."""
    out: list[float] = []
    for t in sorted([t0, t1, *times]):
        if not out or t - out[-1] > tol:
            out.append(t)
    out[0], out[-1] = t0, t1
    if len(out) > 1 and out[-1] - out[-2] <= tol:
        out.pop(-2)
    return np.array(out)


def switch_times(source, t0: float, t1: float) -> np.ndarray:
    """``t0``, every touch-down and lift-off of the contacts of a scene or model inside
    ``(t0, t1)``, and ``t1``: the ends of the phases in which the set of feet on the ground is
    constant (s)."""
    times = []
    for c in _contacts(source):
        if c.duty < 1.0:
            times += _times(c, (0.0, c.duty), t0, t1)
    return _merge(times, t0, t1, 1e-12 * max(1.0, abs(t1)))


def effort_breaks(source, t0: float, t1: float) -> np.ndarray:
    """The times of :func:`switch_times` and the ends of every foot's load ramps (touch-down
    plus, lift-off minus ``ramp duty period``), between ``t0`` and ``t1`` and including them:
    between two of them the efforts of a walking scene are smooth (s)."""
    times = list(switch_times(source, t0, t1))
    for c in _contacts(source):
        if c.duty < 1.0:
            times += _times(c, (c.ramp * c.duty, c.duty * (1.0 - c.ramp)), t0, t1)
    return _merge(times, t0, t1, 1e-12 * max(1.0, abs(t1)))


def sample_times(source, t0: float, t1: float, spacing: float = EFFORT_SPACING,
                 min_intervals: int = MIN_INTERVALS) -> np.ndarray:
    """Times at which to sample the inverse dynamics for :func:`replay_scene`: every break of
    :func:`effort_breaks`, and between two consecutive breaks a uniform grid of steps at most
    ``spacing`` (s), with at least ``min_intervals`` steps."""
    breaks = effort_breaks(source, t0, t1)
    pieces = [np.linspace(a, b, max(min_intervals, int(np.ceil((b - a) / spacing - 1e-9))) + 1)
              for a, b in zip(breaks[:-1], breaks[1:], strict=True)]
    return np.concatenate([pieces[0]] + [p[1:] for p in pieces[1:]])


# ------------------------------------------------------------------ the effort laws

class EffortTable:
    """The efforts of several joints (``values``, N x J, at ``times``) as splines of time joined
    end to end: piece ``k``, on ``[breaks[k], breaks[k + 1]]``, is the not-a-knot spline of
    ``degree`` (the interpolant of :class:`hexapod.Spline`) through the samples in that interval,
    both ends included (neighbouring pieces share their end sample). Outside ``[breaks[0],
    breaks[-1]]`` the end pieces are continued. Exact at every sample; inside each piece as
    smooth as the spline, continuous at the breaks.

    All joints are evaluated together (one spline with J columns per piece) and the values at
    the last time asked for are kept: an integrator asks for every law at the same time, one
    law after the other."""

    def __init__(self, times, values, breaks, degree: int = EFFORT_DEGREE):
        from scipy.interpolate import make_interp_spline

        times = np.asarray(times, dtype=float).ravel()
        values = np.asarray(values, dtype=float).reshape(times.size, -1)
        breaks = np.asarray(breaks, dtype=float).ravel()
        if breaks.size < 2 or np.any(np.diff(breaks) <= 0):
            raise ValueError("breaks must be at least two increasing times")
        if np.any(np.diff(times) <= 0) or not np.all(np.isfinite(values)):
            raise ValueError("times must increase and values be finite")
        tol = 1e-9 * max(1.0, float(np.abs(times).max()))
        self.breaks, self.degree, self.columns = breaks, degree, values.shape[1]
        self.pieces = []
        for a, b in zip(breaks[:-1], breaks[1:], strict=True):
            inside = (times >= a - tol) & (times <= b + tol)
            ends = times[inside][[0, -1]] if inside.any() else (np.nan, np.nan)
            if abs(ends[0] - a) > tol or abs(ends[1] - b) > tol:
                raise ValueError(f"the breaks {a:.9g} s and {b:.9g} s must be sample times")
            if inside.sum() < degree + 1:
                raise ValueError(f"{inside.sum()} samples from {a:.9g} s to {b:.9g} s: a "
                                 f"spline of degree {degree} needs {degree + 1}")
            self.pieces.append(make_interp_spline(times[inside], values[inside], k=degree))
        self._last: tuple[float, np.ndarray] | None = None

    def _piece(self, t: np.ndarray) -> np.ndarray:
        return np.clip(np.searchsorted(self.breaks, t, side="right") - 1, 0,
                       len(self.pieces) - 1)

    def evaluate(self, t) -> np.ndarray:
        """Values and first and second derivatives, shape ``(3,) + t.shape + (J,)``."""
        t = np.asarray(t, dtype=float)
        if t.ndim == 0:
            if self._last is None or self._last[0] != float(t):
                spline = self.pieces[int(self._piece(t))]
                self._last = (float(t), np.array([spline(t, nu=m) for m in range(3)]))
            return self._last[1]
        flat = t.ravel()
        index = self._piece(flat)
        out = np.zeros((3, flat.size, self.columns))
        for k in np.unique(index):
            at = index == k
            out[:, at] = [self.pieces[k](flat[at], nu=m) for m in range(3)]
        return out.reshape((3,) + t.shape + (self.columns,))


@dataclass(frozen=True, eq=False)
class TabulatedEffort(Law):
    """Column ``column`` of an :class:`EffortTable`: one joint's effort as a law of time."""

    table: EffortTable
    column: int
    kind = "tabulated-effort"

    def evaluate(self, t):
        values = self.table.evaluate(t)[..., self.column]
        return values[0], values[1], values[2]


# ------------------------------------------------------------------ the forward twin

def _drivers(scene: Scene) -> dict[str, JointDriver]:
    return {d.joint: d for d in scene.drivers.values() if isinstance(d, JointDriver)}


def replay_scene(scene: Scene, result, *, breaks=None, degree: int = EFFORT_DEGREE,
                 name: str | None = None) -> Scene:
    """The forward twin of a driven ``scene``: its bodies, joints, contacts and force elements,
    each joint driver replaced by a :class:`hexapod.JointEffort` named ``<driver>/effort`` whose
    law (a column of an :class:`EffortTable`) passes through the efforts of ``result`` (an
    :class:`hexapod.InverseResult` of the scene's model) at its sample times, and the bodies
    starting at the state of the first sample (pose and velocity). Every joint's frames are
    written out explicitly (as the original scene places them), so that moving the bodies to
    the first sample moves no joint.

    Parameters
    ----------
    breaks : array_like, optional
        The times where the efforts may lose smoothness, each a sample time (default
        :func:`effort_breaks` of the scene over the samples' span; with
        :func:`sample_times` they are samples).
    degree : {3, 5}
        Degree of the splines.

    Raises
    ------
    ValueError
        A driver on a joint that ``result`` does not have, or a break that is not a sample.
    """
    times = np.asarray(result.times, dtype=float)
    if breaks is None:
        breaks = effort_breaks(scene, float(times[0]), float(times[-1]))
    drivers = _drivers(scene)
    columns = {joint: k for k, joint in enumerate(result.joints)}
    missing = [j for j in drivers if j not in columns]
    if missing:
        raise ValueError(f"the inverse result has no joint {missing[0]!r}")
    unit = scene.unit
    joints = scene.joints
    # a torque is N L in the scene's unit; a force stays N
    factors = np.array([1.0 / unit if isinstance(joints[j], Revolute) else 1.0
                        for j in drivers])
    table = EffortTable(times, result.effort[:, [columns[j] for j in drivers]] * factors,
                        breaks, degree)
    law = {j: TabulatedEffort(table, k) for k, j in enumerate(drivers)}
    twin = Scene(name or f"{scene.name}-forward", scene.dimension, scene.length_unit,
                 scene.gravity, scene.characteristic_length, scene.source,
                 report_forces=scene.report_forces, ground=scene.ground)
    q0, v0 = np.asarray(result.q[0], dtype=float), np.asarray(result.v[0], dtype=float)
    offsets = _body_slices(scene)
    for element in scene.elements:
        if isinstance(element, JointDriver):
            twin.add(JointEffort(f"{element.name}/effort", element.joint, law[element.joint]))
        elif isinstance(element, Joint):
            parent_frame, child_frame = scene.joint_frames(element)
            twin.add(replace(element, origin=None, rotation=None, parent_frame=parent_frame,
                             child_frame=child_frame))
        elif isinstance(element, (SpatialBody, PlanarBody, Particle)):
            twin.add(_body_at(element, q0[offsets[element.name][0]],
                              v0[offsets[element.name][1]], unit))
        else:
            twin.add(element)
    return twin


def _body_slices(scene: Scene) -> dict[str, tuple[slice, slice]]:
    """Each body's slices of ``q`` and ``v`` (the model's order: the scene's bodies in order)."""
    out, nq, nv = {}, 0, 0
    for body in scene.bodies.values():
        if isinstance(body, SpatialBody):
            dq, dv = 7, 6
        elif body.kind == "planar":
            dq, dv = 3, 3
        else:
            dq = dv = body.dimension
        out[body.name] = (slice(nq, nq + dq), slice(nv, nv + dv))
        nq, nv = nq + dq, nv + dv
    return out


def _body_at(body, q: np.ndarray, v: np.ndarray, unit: float):
    """``body`` moved to the model state ``(q, v)`` of its centre of mass (SI), its reference
    frame's pose and velocity given in the scene's unit."""
    if not isinstance(body, SpatialBody):
        raise ValueError(f"body '{body.name}': only spatial bodies are replayed")
    rotation = hx.rotation_from_euler_parameters(q[3:7])
    omega = rotation @ v[3:6]  # world axes
    arm = rotation @ (np.asarray(body.com, dtype=float) * unit)  # origin -> centre of mass
    position = q[:3] - arm
    velocity = v[:3] - np.cross(omega, arm)
    return replace(body, position=position / unit, rotation=rotation,
                   velocity=velocity / unit, angular_velocity=omega)


# ------------------------------------------------------------------ joint angles

def _complement(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The triad ``u, w`` of the engine's revolute rows (``(u, w, a)`` right-handed: the
    coordinate axis least aligned with ``a``, made orthogonal to it)."""
    a = axis / np.linalg.norm(axis)
    e = np.eye(3)[int(np.argmin(np.abs(a)))]
    u = e - (e @ a) * a
    u /= np.linalg.norm(u)
    return u, np.cross(a, u)


def joint_angles(model, q: np.ndarray, joints) -> np.ndarray:
    """Angles (rad) of the revolute ``joints`` (names) of ``model`` at positions ``q``
    (N x n_q), from the parent frame to the child frame about the axis, as the engine's drivers
    measure them: ``atan2(w_p . u_c, u_p . u_c)``."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    info = {j.name: j for j in model.joints}
    rotations = {}

    def rotation(body: int, k: int) -> np.ndarray:
        if body < 0:
            return np.eye(3)
        key = (body, k)
        if key not in rotations:
            rotations[key] = model.body_pose(q[k], body).rotation
        return rotations[key]

    out = np.zeros((q.shape[0], len(joints)))
    for c, name in enumerate(joints):
        joint = info[name]
        u, w = _complement(np.asarray(joint.axis, dtype=float))
        Rp, Rc = joint.parent_frame.rotation, joint.child_frame.rotation
        for k in range(q.shape[0]):
            parent, child = rotation(joint.parent, k) @ Rp, rotation(joint.child, k) @ Rc
            u_c = child @ u
            out[k, c] = np.arctan2((parent @ w) @ u_c, (parent @ u) @ u_c)
    return out


def prescribed_angles(scene: Scene, times) -> tuple[tuple[str, ...], np.ndarray]:
    """The driven joints of ``scene`` (names) and their drivers' angles (rad) at ``times``
    (N x J)."""
    drivers = _drivers(scene)
    times = np.atleast_1d(np.asarray(times, dtype=float))
    return tuple(drivers), np.column_stack([drivers[j].law.evaluate(times)[0] for j in drivers])


def wrapped(x: np.ndarray) -> np.ndarray:
    """Angles brought into (-pi, pi]."""
    return np.arctan2(np.sin(x), np.cos(x))


# ------------------------------------------------------------------ the forward run

@dataclass
class Replay:
    """A forward run of a twin, phase by phase.

    Attributes
    ----------
    t, q, v : ndarray
        The saved states of every phase, end to end (the state at each restart once).
    phases : ndarray
        The phase ends (s): :func:`switch_times`.
    status, message : str
        ``finished``, or ``failed`` with the failing phase's message.
    steps, rejected : int
        Accepted and rejected steps over all phases.
    cpu_time, wall_time : float
        Of the simulations (s), kernels' compilation included.
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    phases: np.ndarray
    status: str
    message: str
    steps: int
    rejected: int
    cpu_time: float
    wall_time: float
    method: str
    rtol: float
    atol: float


def replay(model, t0: float, t1: float, q0: np.ndarray, v0: np.ndarray, *,
           method: str | None = None, rtol: float = 1e-8, atol: float = 1e-10,
           by_phase: bool = True, every: int = 1) -> Replay:
    """Simulate the twin ``model`` from ``(q0, v0)`` at ``t0`` to ``t1`` with
    :func:`hexapod.simulate`, restarting at every switch time of its contacts (``by_phase``) from
    the state reached; ``every``: save every so many steps (and each phase's ends)."""
    method = method or hx.DEFAULT_METHOD
    ends = switch_times(model, t0, t1) if by_phase else np.array([t0, t1])
    ts, qs, vs = [], [], []
    q, v = np.asarray(q0, dtype=float), np.asarray(v0, dtype=float)
    steps = rejected = 0
    status, message = "finished", ""
    cpu, wall = time.process_time(), time.perf_counter()
    for k, (a, b) in enumerate(zip(ends[:-1], ends[1:], strict=True)):
        run = hx.simulate(model, b, t0=a, q0=q, v0=v, method=method, rtol=rtol, atol=atol,
                          forces=False, every=every)
        first = 0 if k == 0 else 1
        ts.append(run.t[first:])
        qs.append(run.q[first:])
        vs.append(run.v[first:])
        steps += run.counters.steps
        rejected += run.counters.rejected
        if run.status != "finished":
            status, message = run.status, f"phase {a:.6g} s to {b:.6g} s: {run.message}"
            break
        q, v = run.q[-1], run.v[-1]
    return Replay(np.concatenate(ts), np.concatenate(qs), np.concatenate(vs), ends, status,
                  message, steps, rejected, time.process_time() - cpu,
                  time.perf_counter() - wall, method, rtol, atol)


@dataclass
class Agreement:
    """How a forward replay agrees with the prescribed motion.

    Attributes
    ----------
    angle_error : float
        Largest joint-angle error over the run's saved states (rad): simulated angle minus the
        driver's law, wrapped.
    worst_joint : str
    worst_time : float
    trunk_error : float
        Distance of the trunk's centre of mass at the end of the run from the prescribed one
        (m), the inverse result's last sample.
    reference_error : float
        The same angle measure on the inverse result's own positions (rad): round-off, the
        check of the measure itself.
    """

    angle_error: float
    worst_joint: str
    worst_time: float
    trunk_error: float
    reference_error: float


def agreement(scene: Scene, model, run: Replay, result, trunk: str = "trunk") -> Agreement:
    """Compare the joint angles of ``run`` (of the twin ``model``) with the drivers' laws of the
    original ``scene``, and the trunk's final position with that of ``result`` at the same
    time (``run`` must end at ``result``'s last sample)."""
    joints, wanted = prescribed_angles(scene, run.t)
    error = np.abs(wrapped(joint_angles(model, run.q, joints) - wanted))
    k, j = np.unravel_index(int(np.argmax(error)), error.shape)
    _, reference = prescribed_angles(scene, result.times)
    reference_error = float(np.abs(wrapped(joint_angles(model, result.q, joints)
                                           - reference)).max())
    index = [b.name for b in model.bodies].index(trunk)
    body = model.bodies[index]
    trunk_error = float(np.linalg.norm(run.q[-1][body.q][:3] - result.q[-1][body.q][:3]))
    if abs(run.t[-1] - result.times[-1]) > 1e-9:
        raise ValueError(f"the run ends at {run.t[-1]:.9g} s, the inverse result at "
                         f"{result.times[-1]:.9g} s")
    return Agreement(float(error[k, j]), joints[j], float(run.t[k]), trunk_error,
                     reference_error)


def replay_gait(gait: str, *, period: float | None = None, spacing: float = EFFORT_SPACING,
                method: str | None = None, rtol: float = 1e-8, atol: float = 1e-10,
                by_phase: bool = True) -> dict:
    """The whole check for one gait of the free-trunk hexapod over one stride: inverse dynamics
    at :func:`sample_times`, the twin, its forward run, the agreement. Returns a dict with
    ``scene, model, result, twin, twin_model, run, agreement`` and the times (s) of each part
    (``inverse_time``, ``assemble_time``; the run's own in ``run``)."""
    period = period or STRIDE_PERIOD
    started = time.perf_counter()
    scene = hexapod_scene(gait=gait, trunk="free", period=period)
    model = hx.assemble(scene)
    times = sample_times(scene, 0.0, period, spacing)
    result = hx.inverse_dynamics(model, times)
    inverse_time = time.perf_counter() - started
    started = time.perf_counter()
    twin = replay_scene(scene, result)
    twin_model = hx.assemble(twin)
    assemble_time = time.perf_counter() - started
    run = replay(twin_model, 0.0, period, result.q[0], result.v[0], method=method, rtol=rtol,
                 atol=atol, by_phase=by_phase)
    return {"scene": scene, "model": model, "result": result, "twin": twin,
            "twin_model": twin_model, "run": run,
            "agreement": agreement(scene, twin_model, run, result),
            "inverse_time": inverse_time, "assemble_time": assemble_time}
