"""Inverse and forward agree: the efforts of the hexapod's inverse dynamics replayed in a forward
simulation of the same robot with the same contact schedule.

:func:`replay_scene` turns a driven walking scene (every revolute joint prescribed by a
:class:`hexapod.scene.JointDriver`, the feet held by :class:`hexapod.scene.Contact` joints on
their stance schedule, see :func:`legs.robot.hexapod_scene`) into its **forward twin**: the
same bodies, joints and contacts, each driver replaced by a :class:`hexapod.scene.JointEffort`
whose law reproduces the efforts :func:`hexapod.inverse_dynamics` found, the bodies starting at
the first sample's state. :func:`replay` simulates the twin (:func:`hexapod.simulate`),
:func:`agreement` compares its joint angles with the drivers' laws; :func:`replay_gait` does
all of it for one gait.

**The twin is unstable, so it is replayed in windows.** A robot whose joints are driven by
efforts fixed in time, with nothing feeding back its state, has nothing to hold it on its path:
a stance leg is a loaded chain of six free joints between the trunk and its foothold (it
buckles), a swing leg a free chain under gravity. :func:`hexapod.diagnose` at states of the
tripod gait finds 19 to 34 growing modes of the motion linearised on the constraints, the
fastest growing as ``exp(130 t)`` to ``exp(210 t)``, and one run over the stride shows it
(default tolerances, ``scripts/studies/walking_forward.py --unbroken 0.15``): the tripod's
joint-angle error is ``1e-8`` rad at 25 ms, ``9e-5`` at 0.1 s, ``3`` at 0.15 s, growing as
``exp(131 t)``, the wave's ``2e-8`` at 24 ms, ``4e-4`` at 75 ms, ``0.3`` at 0.1 s
(``exp(178 t)``). Round-off alone would grow past any tolerance within a stride
(``exp(150 x 0.5) ~ 1e32``). So
:func:`replay` starts a new run every ``window`` (10 ms: a growth of ``exp(2) ~ 7`` at most)
from the prescribed state at that time and compares each run with the prescribed motion up to
the next start: every instant of the stride, every touch-down and lift-off, is covered by a run
of at most one window, and a disagreement of the efforts with the motion would show within it.

**The efforts as laws of time** (:class:`EffortTable`). The inverse efforts are smooth between
the times :func:`effort_breaks` lists and lose smoothness there: each foot's touch-down and
lift-off (its rows and its path switch) and the ends of its load ramps (the load-sharing weight,
a quintic smooth step clipped to 1, is C2 there). Each effort is therefore a separate quintic
spline (not-a-knot, the interpolant of :class:`hexapod.scene.Spline` of degree 5) on each interval
between consecutive breaks, exact at every sample. Close to a switch the efforts change fast but
smoothly: a foot's load reaches it over the first few milliseconds after touch-down and leaves
it over the last few before lift-off (inverse dynamics at 25 microsecond steps there: a quintic
spline through every 100 microseconds misses by ``2e-7`` N m at most, through every 400 by
``8e-5``, the ``h^6`` of a smooth function). Uniform samples would need some 0.2 ms steps all
along; :func:`adaptive_inverse` instead bisects, round after round, the intervals whose midpoint
the spline misses, until each joint's effort is within ``tol`` of its largest.

**The schedule.** A foot in swing has zero rows (gate 0); at touch-down it is at its foothold
with zero velocity and acceleration by design and carries nothing yet; at lift-off it carries
nothing. The motion is smooth across the switches, but ``hexapod.simulate`` cannot cross them in
one call: its explicit integrators compile their right-hand side for the rows independent at the
run's start, and later rows are handled wrongly. A touch-down inside a run is accepted with the
new foot's rows left out while they disagree by less than ``1e-3`` (the tripod's replay from
0.195 s to 0.205 s in one call: ``3e-6`` rad off, against ``4e-9`` restarted at the touch-down),
and at a lift-off the lifting feet's rows vanish and the compiled saddle-point solve, singular
then, returns wrong accelerations that its check (constraint rows only) does not notice (0.245 s
to 0.255 s in one call: ``0.9`` rad off, and the run "finished";
``scripts/studies/walking_forward.py --one-call``). So :func:`replay` restarts at every switch
time, from the state reached, and keeps each run off the lift-off instants by
:data:`LIFT_OFF_GAP` (see :func:`replay`).

Angles are radians and efforts SI; the twin keeps the scene's length unit.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

import hexapod as hx
from hexapod import Scene
from hexapod.scene import (
    Contact,
    GroundContact,
    Guided,
    Joint,
    JointController,
    JointDriver,
    JointEffort,
    Particle,
    PlanarBody,
    PostureDriver,
    SpatialBody,
)
from legs.cockroach import STRIDE_PERIOD
from legs.efforts import (
    EFFORT_DEGREE,
    EFFORT_SPACING,
    EFFORT_TOL,
    EffortTable,
    TabulatedEffort,
    adaptive_inverse,
    effort_breaks,
    lift_off_times,
    switch_times,
)
from legs.robot import hexapod_scene

#: Default length of the replay's windows (s): see the module's description.
WINDOW = 10e-3
#: Default: save every so many accepted steps of a run (each phase's ends always). Saving asks
#: ``hexapod.simulate`` for the multipliers, one exact, rank-deciding solve each.
EVERY = 10
#: A phase that ends at a lift-off ends this much earlier, one that starts at a lift-off starts
#: this much later (s): see :func:`replay`.
LIFT_OFF_GAP = 1e-12
def _drivers(scene: Scene) -> dict[str, JointDriver]:
    return {d.joint: d for d in scene.drivers.values() if isinstance(d, JointDriver)}


def joint_laws(scene: Scene) -> dict[str, object]:
    """Each driven joint's law (joint name -> law): its driver's, or, for a joint that follows
    the scene's guides, the motion the guides give it (the assembled model's law, solved by
    the engine's kinematics at the times asked)."""
    drivers = _drivers(scene)
    out = {joint: d.law for joint, d in drivers.items() if not isinstance(d.law, Guided)}
    if len(out) < len(drivers):
        model = hx.assemble(scene)
        for d in model.drivers:
            joint = model.joints[d.joint].name if d.kind == "joint" else None
            if joint in drivers and joint not in out:
                out[joint] = model.laws[d.law]
    return out


def replay_scene(scene: Scene, result, *, breaks=None, degree: int = EFFORT_DEGREE,
                 name: str | None = None, periodic: bool = False) -> Scene:
    """The forward twin of a driven ``scene``: its bodies, joints, contacts and force elements,
    each joint driver replaced by a :class:`hexapod.scene.JointEffort` named ``<driver>/effort``
    whose law (a column of an :class:`EffortTable`) passes through the efforts of ``result`` (an
    :class:`hexapod.InverseResult` of the scene's model) at its sample times, and the bodies
    starting at the state of the first sample (pose and velocity). Every joint's frames are
    written out explicitly (as the original scene places them), so that moving the bodies to
    the first sample moves no joint.

    Parameters
    ----------
    breaks : array_like, optional
        The times where the efforts may lose smoothness, each a sample time (default
        :func:`effort_breaks` of the scene over the samples' span, which the samples of
        :func:`adaptive_inverse` include).
    degree : {3, 5}
        Degree of the splines.
    periodic : bool
        The samples span one cycle of a periodic gait: the efforts repeat after it.

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
    factors = np.array([1.0 / unit if joints[j].effort_unit == "N m" else 1.0
                        for j in drivers])
    table = EffortTable(times, result.effort[:, [columns[j] for j in drivers]] * factors,
                        breaks, degree, periodic)
    law = {j: TabulatedEffort(table, k) for k, j in enumerate(drivers)}
    twin = Scene(name or f"{scene.name}-forward", scene.dimension, scene.length_unit,
                 scene.gravity, scene.characteristic_length, scene.source,
                 report_forces=scene.report_forces, ground=scene.ground)
    q0, v0 = np.asarray(result.q[0], dtype=float), np.asarray(result.v[0], dtype=float)
    offsets = _body_slices(scene)
    for element in scene.elements:
        if getattr(element, "guide", False) or isinstance(element, PostureDriver):
            continue  # a guide and a posture rule exert nothing: the efforts replace them
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


def grounded_scene(scene: Scene, result, *, kp, kd, mu: float | None = None,
                   breaks=None, degree: int = EFFORT_DEGREE, periodic: bool = False,
                   actuators=None) -> Scene:
    """The driven walking ``scene`` on real ground under joint control: its forward twin
    (:func:`replay_scene`, starting at the first sample's state) with each joint's effort
    replaced by a :class:`hexapod.scene.JointController` named ``<driver>/servo`` (target the
    driver's law, feedforward the efforts of ``result``, gains ``kp`` (N m/rad) and ``kd``
    (N m s/rad): one number for every joint, or a dict by joint name, e.g.
    :func:`hexapod.simulation.critical_gains`), and each foot's scheduled contact by a
    :class:`hexapod.scene.GroundContact` on the same foot point, against the horizontal plane
    of its footholds, friction ``mu`` (default the scene's ``[ground] mu``), plastic. The feet then
    land and lift off where the controlled motion takes them, not where the schedule says;
    simulate it with ``moreau-jean``. ``periodic``: the efforts of ``result`` (one cycle)
    repeat, for runs of many strides. ``actuators`` (a
    :class:`hexapod.scene.ActuatorTable`): each controller whose joint has a motor there is
    limited by it (``max_effort`` its stall torque times the gear ratio, ``no_load_speed`` its
    no-load speed over it; a rated envelope limits the effort alone)."""
    twin = replay_scene(scene, result, breaks=breaks, degree=degree,
                        name=f"{scene.name}-on-ground", periodic=periodic)
    drivers, targets = _drivers(scene), joint_laws(scene)
    gain = 1.0 / scene.unit  # N m per rad in the scene's unit of length (N L)
    motors = actuators.assign(list(drivers)) if actuators is not None else {}

    def grounded(element):
        if isinstance(element, JointEffort):
            driver = drivers[element.joint]
            p, d = ((g[element.joint] if isinstance(g, dict) else g) for g in (kp, kd))
            limit, no_load = None, None
            if element.joint in motors:
                limit, no_load, _ = motors[element.joint].joint_limits()
                limit *= gain
            return JointController(f"{driver.name}/servo", element.joint,
                                   target=targets[element.joint], kp=p * gain, kd=d * gain,
                                   feedforward=element.law, max_effort=limit,
                                   no_load_speed=no_load)
        if isinstance(element, Contact):
            return GroundContact(element.name, element.child,  # the plane of its footholds
                                 point=element.child_frame.position,
                                 surface_point=element.foothold, mu=mu)
        return element

    return twin.with_elements(grounded(element) for element in twin.elements)


#: The gains of the built-in ``hexapod-on-ground`` (N m/rad, N m s/rad, every joint): its
#: joints track their laws to 3 mrad over a stride (``scripts/studies/walking_on_ground.py``).
GROUND_KP, GROUND_KD = 200.0, 2.0
#: Its efforts' sampling tolerance: the study's stride at 1e-4 (197 samples) and at 3e-6 (317)
#: gives the same touch-downs, normal forces and tracking errors to three digits, in half the
#: inverse dynamics' time.
ON_GROUND_TOL = 1e-4


def hexapod_on_ground(*, gait: str = "tripod", kp: float = GROUND_KP, kd: float = GROUND_KD,
                      mu: float | None = None, tol: float = ON_GROUND_TOL) -> Scene:
    """Built-in ``hexapod-on-ground``: the walking robot on real ground under joint control,
    its feet landing and lifting off where the controlled motion takes them (simulate it:
    Moreau-Jean, the ground's forces and the contact events written).

    The free-trunk hexapod walking its ``gait`` over strides of
    :data:`legs.cockroach.STRIDE_PERIOD` (:func:`grounded_scene`): each joint a controller
    (target its law, feedforward the inverse dynamics' efforts at samples chosen to ``tol`` by
    :func:`adaptive_inverse`, repeating with the stride; gains ``kp`` N m/rad, ``kd`` N m
    s/rad), each foot a unilateral contact with Coulomb friction ``mu`` (default the scene's)
    and plastic impacts. Building it runs the inverse dynamics of a stride (seconds)."""
    scene = hexapod_scene(gait=gait, trunk="free", period=STRIDE_PERIOD)
    inverse, _ = adaptive_inverse(hx.assemble(scene), scene, 0.0, STRIDE_PERIOD, tol=tol)
    return grounded_scene(scene, inverse, kp=kp, kd=kd, mu=mu, periodic=True)


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
    rotation = hx.spatial.rotation_from_euler_parameters(q[3:7])
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
    """The driven joints of ``scene`` (names) and their laws' angles (rad) at ``times``
    (N x J, :func:`joint_laws`)."""
    laws = joint_laws(scene)
    times = np.atleast_1d(np.asarray(times, dtype=float))
    return tuple(laws), np.column_stack([laws[j].evaluate(times)[0] for j in laws])


def wrapped(x: np.ndarray) -> np.ndarray:
    """Angles brought into (-pi, pi]."""
    return np.arctan2(np.sin(x), np.cos(x))


def grazes(events) -> list[tuple[float, str, np.ndarray]]:
    """The contacts that touch and leave at the same instant (a simulation's ``events``): a foot
    arriving at nearly zero speed, stopped by a plastic impulse, then drawn on along its path
    by its controller, with no time on the ground. ``(t, contact, impulse)`` each, the impulse
    of its impact (world axes, N s; zero where there is none)."""
    events = list(events or ())  # in time order, as a run records them
    out = []
    for k, event in enumerate(events):
        if event.kind != "touch-down":
            continue
        at_once = []
        for later in (events[j] for j in range(k + 1, len(events))):
            if later.t != event.t:
                break
            if later.contact == event.contact:
                at_once.append(later)
        if any(e.kind == "lift-off" for e in at_once):
            impulse = next((np.asarray(e.impulse, dtype=float) for e in at_once
                            if e.kind == "impact"), np.zeros(3))
            out.append((float(event.t), event.contact, impulse))
    return out


def event_times(events, *, with_grazes: bool = True) -> dict:
    """Contact events (``t``, ``kind``, ``contact``: a simulation's) as the times of each
    kind per contact, ``{contact: {kind: [t, ...]}}``; ``with_grazes=False`` leaves out the
    touch-down and lift-off of each :func:`grazes` (a contact without time on the ground)."""
    touched = {(t, name) for t, name, _ in grazes(events)} if not with_grazes else set()
    times: dict = {}
    for event in events or ():
        if event.kind in ("touch-down", "lift-off") and (event.t, event.contact) in touched:
            continue
        times.setdefault(event.contact, {}).setdefault(event.kind, []).append(event.t)
    return times


def schedule_lateness(model, times: dict, t_end: float) -> dict[str, float]:
    """The largest ``|simulated - scheduled|`` time (s) of the touch-downs and of the
    lift-offs of ``model``'s contacts up to ``t_end`` (``times``: :func:`event_times`).
    Each scheduled touch-down is matched with its foot's first simulated touch-down from the
    middle of the swing before it to the middle of the stance after it, each lift-off with the
    last simulated lift-off from the middle of its stance to the middle of the swing after it:
    a foot that lands early and bounces counts by its first landing, one that leaves, lands
    again and leaves counts by its last leaving (a foot with none there: infinite)."""
    worst = {"touch-down": 0.0, "lift-off": 0.0}
    reach = t_end + (model.cycle_time() or 1.0)  # a stride or more beyond the run's ends
    for contact in model.contacts:
        scheduled = [(when, kind) for start, stop in contact.stances(-reach, t_end + reach)
                     for when, kind in ((start, "touch-down"), (stop, "lift-off"))]
        for k, (when, kind) in enumerate(scheduled):
            if not 0.0 < when < t_end or not 0 < k < len(scheduled) - 1:
                continue  # not the run's own ends
            low, high = (0.5 * (when + scheduled[k + j][0]) for j in (-1, 1))
            near = np.asarray(times.get(contact.name, {}).get(kind, []), dtype=float)
            near = near[(near > low) & (near < high)]
            if not near.size:
                worst[kind] = np.inf
                continue
            chosen = near.min() if kind == "touch-down" else near.max()
            worst[kind] = max(worst[kind], abs(float(chosen) - when))
    return worst


# ------------------------------------------------------------------ the forward run

@dataclass
class Replay:
    """A forward run of a twin: windows, each from the prescribed state at its start, each
    simulated phase by phase between the feet's switch times.

    Attributes
    ----------
    t, q, v : ndarray
        The saved states, window after window (a window's last state and the next one's first
        share their time: the state reached, then the prescribed one it restarts from).
    window : ndarray of int
        The window of each saved state.
    starts : ndarray
        The windows' start times (s), the last entry the end of the run.
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
    window: np.ndarray
    starts: np.ndarray
    status: str
    message: str
    steps: int
    rejected: int
    cpu_time: float
    wall_time: float
    method: str
    rtol: float
    atol: float


def window_starts(times, window: float | None) -> np.ndarray:
    """Indices of the samples ``times`` nearest to ``times[0] + k window`` (``k = 0, 1, ...``,
    each used once, the last sample left out): where windows of about ``window`` s start. Only
    the first sample without a ``window``."""
    times = np.asarray(times, dtype=float)
    if window is None:
        return np.array([0])
    targets = np.arange(times[0], times[-1] - window / 2, window)
    index = np.unique(np.abs(times[None, :] - targets[:, None]).argmin(axis=1))
    return index[index < times.size - 1]


def _phase(model, a: float, b: float, lift_offs: np.ndarray) -> tuple[float, float]:
    """The span ``[a, b]`` of a phase between switch times, moved off the lift-offs by
    :data:`LIFT_OFF_GAP`; raises when a contact's gate still changes inside it (a touch-down
    at ``b`` itself is harmless: the foot is at its foothold with zero velocity and
    acceleration and carries nothing yet)."""
    def near(t):
        return bool(np.any(np.abs(lift_offs - t) <= 1e-9 * max(1.0, abs(t))))

    a = a + LIFT_OFF_GAP if near(a) else a
    b = b - LIFT_OFF_GAP if near(b) else b
    inside = np.array([a, (a + b) / 2, b - 1e-9 * (b - a)])
    for contact in model.contacts:
        if len(set(contact.in_stance(inside).tolist())) > 1:
            raise RuntimeError(f"contact {contact.name} switches between {a!r} and {b!r} s")
    return a, b


def replay(model, result, *, window: float | None = WINDOW, method: str | None = None,
           rtol: float = hx.simulation.DEFAULT_RTOL, atol: float = hx.simulation.DEFAULT_ATOL,
           every: int = EVERY, until: float | None = None) -> Replay:
    """Simulate the twin ``model`` with :func:`hexapod.simulate` over the span of ``result``
    (the inverse result it was made from).

    With ``window`` (s): windows of about that length, each starting from the prescribed state
    (``result.q, result.v``) at a sample time (:func:`window_starts`); with ``window=None``
    one run from the first sample's state to the last sample's time (it diverges: see the
    module's description). Inside a window the run is restarted at every switch time of the
    contacts (:func:`switch_times`) from the state reached, so that each phase has the
    integrator's compiled kernel for its own rows. ``every``: save every so many steps (each
    phase's ends always); ``until``: end there (s) rather than at the last sample.

    A phase that ends at a lift-off ends :data:`LIFT_OFF_GAP` before it, one that starts at a
    lift-off starts that much after it (from the state reached, or the prescribed one, at the
    lift-off: a shift of ``1e-12`` s, some ``1e-11`` rad of motion), so that the lifting feet
    are in stance over the whole of one phase and in swing over the whole of the next. At the
    lift-off their rows vanish, and the integrators' compiled kernel, built for the rows of the
    phase's start, then returns wrong accelerations without noticing (a limitation of
    ``hexapod.simulate`` in this version: its check covers the constraint rows, not the
    singular saddle-point system. Without the gap the tripod's replay jumped by 1e-3 rad at
    each lift-off, and the wave's, whose sample at a lift-off falls 1e-17 s before it, failed
    on non-finite numbers)."""
    method = method or hx.simulation.DEFAULT_METHOD
    times = np.asarray(result.times, dtype=float)
    end = times[-1] if until is None else float(until)
    if not times[0] < end <= times[-1]:
        raise ValueError(f"until must be inside the samples' span, got {until}")
    first = window_starts(times[times <= end], window)
    starts = np.append(times[first], end)
    lift_offs = lift_off_times(model, times[0], times[-1])
    ts, qs, vs, ws = [], [], [], []
    steps = rejected = 0
    status, message = "finished", ""
    cpu, wall = time.process_time(), time.perf_counter()
    for w, k in enumerate(first):
        q, v = np.asarray(result.q[k], dtype=float), np.asarray(result.v[k], dtype=float)
        ends = switch_times(model, starts[w], starts[w + 1])
        for p, (a, b) in enumerate(zip(ends[:-1], ends[1:], strict=True)):
            a, b = _phase(model, a, b, lift_offs)
            run = hx.simulate(model, b, t0=a, q0=q, v0=v, method=method, rtol=rtol,
                              atol=atol, forces=False, every=every)
            skip = 0 if p == 0 else 1  # the state at a switch once
            ts.append(run.t[skip:])
            qs.append(run.q[skip:])
            vs.append(run.v[skip:])
            ws.append(np.full(run.t.size - skip, w))
            steps += run.counters.steps
            rejected += run.counters.rejected
            if run.status != "finished":
                status = run.status
                message = f"phase {a:.6g} s to {b:.6g} s: {run.message}"
                break
            q, v = run.q[-1], run.v[-1]
        if status != "finished":
            break
    return Replay(np.concatenate(ts), np.concatenate(qs), np.concatenate(vs),
                  np.concatenate(ws), starts, status, message, steps, rejected,
                  time.process_time() - cpu, time.perf_counter() - wall, method, rtol, atol)


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
    errors : ndarray
        The largest joint-angle error at each saved state (rad).
    trunk_error : float
        Distance of the trunk's centre of mass at the end of the run from the prescribed one,
        the inverse result's last sample (m); NaN when the run ended early.
    reference_error : float
        The same angle measure on the inverse result's own positions (rad): round-off, the
        check of the measure itself.
    """

    angle_error: float
    worst_joint: str
    worst_time: float
    errors: np.ndarray
    trunk_error: float
    reference_error: float


def agreement(scene: Scene, model, run: Replay, result, trunk: str = "trunk") -> Agreement:
    """Compare the joint angles of ``run`` (of the twin ``model``) with the drivers' laws of the
    original ``scene``, and the trunk's final position with that of ``result`` at the same
    time."""
    joints, wanted = prescribed_angles(scene, run.t)
    error = np.abs(wrapped(joint_angles(model, run.q, joints) - wanted))
    k, j = np.unravel_index(int(np.argmax(error)), error.shape)
    _, reference = prescribed_angles(scene, result.times)
    reference_error = float(np.abs(wrapped(joint_angles(model, result.q, joints)
                                           - reference)).max())
    body = model.bodies[[b.name for b in model.bodies].index(trunk)]
    trunk_error = (float(np.linalg.norm(run.q[-1][body.q][:3] - result.q[-1][body.q][:3]))
                   if abs(run.t[-1] - result.times[-1]) <= 1e-9 else float("nan"))
    return Agreement(float(error[k, j]), joints[j], float(run.t[k]), error.max(axis=1),
                     trunk_error, reference_error)


def replay_gait(gait: str, t0: float = 0.0, t1: float | None = None, *,
                period: float = STRIDE_PERIOD, tol: float = EFFORT_TOL,
                spacing: float = EFFORT_SPACING, window: float | None = WINDOW,
                method: str | None = None, rtol: float = hx.simulation.DEFAULT_RTOL,
                atol: float = hx.simulation.DEFAULT_ATOL, every: int = EVERY) -> dict:
    """The whole check for one gait of the free-trunk hexapod from ``t0`` to ``t1`` (default:
    one stride): inverse dynamics at the samples of :func:`adaptive_inverse`, the twin, its
    replay (:func:`replay`), the agreement. Returns a dict with ``scene, model, result,
    sampling, twin, twin_model, run, agreement`` and the wall times (s) ``assemble_time`` (the
    driven model and the twin), ``inverse_time`` (all rounds), ``run_time`` (the replay,
    compilation of its kernels included) and ``total_time``."""
    t1 = period if t1 is None else t1
    started = time.perf_counter()
    scene = hexapod_scene(gait=gait, trunk="free", period=period)
    model = hx.assemble(scene)
    assemble_time = time.perf_counter() - started
    mark = time.perf_counter()
    result, sampling = adaptive_inverse(model, scene, t0, t1, tol=tol, spacing=spacing)
    inverse_time = time.perf_counter() - mark
    mark = time.perf_counter()
    twin = replay_scene(scene, result)
    twin_model = hx.assemble(twin)
    assemble_time += time.perf_counter() - mark
    mark = time.perf_counter()
    run = replay(twin_model, result, window=window, method=method, rtol=rtol, atol=atol,
                 every=every)
    run_time = time.perf_counter() - mark
    return {"scene": scene, "model": model, "result": result, "sampling": sampling,
            "twin": twin, "twin_model": twin_model, "run": run,
            "agreement": agreement(scene, twin_model, run, result),
            "assemble_time": assemble_time, "inverse_time": inverse_time, "run_time": run_time,
            "total_time": time.perf_counter() - started}
