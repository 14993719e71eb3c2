"""``assemble(scene) -> Model``: the scene's constraints and forces as CasADi expressions.

Only what the scene contains is built: a planar scene has 3 coordinates per body and no 3-D
terms; a scene without springs has no spring terms; constant laws are folded in as numbers, so
the law inputs ``w, wd, wdd`` carry only the laws that change with time.
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np

from hexapod._support.graphs import spanning_forest
from hexapod._support.limits import check_model_size
from hexapod.errors import HexapodError
from hexapod.model.digest import scene_digest
from hexapod.model.forces import ForceBuilder, gravity_potential, inertial_forces
from hexapod.model.frames import BodyState
from hexapod.model.guided_motion import with_guided_laws
from hexapod.model.infos import (
    GROUND_INDEX,
    BodyInfo,
    ContactInfo,
    DriverInfo,
    ForceInfo,
    Guidance,
    JointInfo,
    RowInfo,
    SurfaceContact,
)
from hexapod.model.mass import BlockDiagonal
from hexapod.model.model import Model, Symbolic
from hexapod.model.posture import posture_rows
from hexapod.scene.actuators import effort_limits
from hexapod.scene.bodies import Particle, PlanarBody, SpatialBody
from hexapod.scene.drivers import ORIENTATIONS, CoordinateDriver, JointDriver, PostureDriver
from hexapod.scene.element import GROUND
from hexapod.scene.forces import (
    AppliedForce,
    AppliedTorque,
    GroundContact,
    JointController,
    JointEffort,
    RotationalSpringDamper,
    SpringDamper,
)
from hexapod.scene.joints import Contact, JointGeometry
from hexapod.scene.joints.geometry import angle_rate, wrapped_angle
from hexapod.scene.laws import Constant, Guided, Law
from hexapod.scene.laws.base import rate_of
from hexapod.scene.scene import Scene
from hexapod.spatial import Placement, euler_parameters_from_rotation

__all__ = ["assemble"]


class _Laws:
    """Time laws as symbols; constant laws become numbers."""

    def __init__(self):
        self.laws: list[Law] = []
        self.where: list[tuple] = []  # what each law is in the scene: ("gate", contact)...
        self.w: list[ca.SX] = []
        self.wd: list[ca.SX] = []
        self.wdd: list[ca.SX] = []
        self.pending: list[tuple] = []  # laws whose slots come last (:meth:`last`)

    def value(self, law: Law, label: str, where: tuple = ()) -> tuple[ca.SX, int]:
        """The law's value as an expression, and its index (-1 for a constant); ``where`` says
        what it is in the scene (``("gate", contact)`` finds a foot's gate again)."""
        if isinstance(law, Constant):
            return ca.SX(law.value), -1
        index = len(self.laws)
        self.laws.append(law)
        self.where.append(where)
        for symbols, suffix in ((self.w, ""), (self.wd, "_d"), (self.wdd, "_dd")):
            symbols.append(ca.SX.sym(f"{label}{suffix}"))
        return self.w[index], index

    def last(self, law: Law, label: str) -> ca.SX:
        """The law's value as a symbol whose slot comes after every other law's (a design
        shift's: the model's other laws keep the slots they have without it)."""
        self.pending.append((law, label, ca.SX.sym(label)))
        return self.pending[-1][2]

    def symbols(self) -> tuple[ca.SX, ca.SX, ca.SX]:
        for law, label, w in self.pending:
            self.laws.append(law)
            self.where.append(())
            self.w.append(w)
            self.wd.append(ca.SX.sym(f"{label}_d"))
            self.wdd.append(ca.SX.sym(f"{label}_dd"))
        self.pending = []
        return tuple(ca.vertcat(*s) if s else ca.SX(0, 1) for s in (self.w, self.wd, self.wdd))


def _bodies(scene: Scene):
    """Body infos, initial coordinates and velocities, mass matrix parts."""
    infos, q0, v0 = [], [], []
    diagonal, blocks, block_index = [], [], []
    nq = nv = 0
    for index, body in enumerate(scene.bodies.values()):
        pose = body.com_pose
        arm = pose.position - body.position  # reference origin -> centre of mass, world
        if isinstance(body, SpatialBody):
            kind, dq, dv = "spatial", 7, 6
            inertia = body.body_inertia
            q0 += [*pose.position, *euler_parameters_from_rotation(pose.rotation)]
            v_com = body.velocity + np.cross(body.angular_velocity, arm)
            v0 += [*v_com, *(pose.rotation.T @ body.angular_velocity)]
            diagonal += [body.mass] * 3 + [0.0] * 3
            blocks.append(inertia)
            block_index.append(list(range(nv + 3, nv + 6)))
        elif isinstance(body, PlanarBody):
            kind, dq, dv = "planar", 3, 3
            inertia = np.array([[body.inertia]])
            q0 += [*pose.position, body.angle]
            v_com = body.velocity + body.angular_velocity * np.array([-arm[1], arm[0]])
            v0 += [*v_com, body.angular_velocity]
            diagonal += [body.mass, body.mass, body.inertia]
        else:
            assert isinstance(body, Particle)
            kind = "particle"
            dq = dv = body.dimension
            inertia = np.zeros((0, 0))
            q0 += list(body.position)
            v0 += list(body.velocity)
            diagonal += [body.mass] * dq
        infos.append(BodyInfo(body.name, kind, index, slice(nq, nq + dq), slice(nv, nv + dv),
                              body.mass, inertia, np.array(body.com, dtype=float),
                              {name: body.marker_in_com_frame(frame)
                               for name, frame in body.markers.items()}))
        nq += dq
        nv += dv
    mass = BlockDiagonal(np.array(diagonal), np.array(blocks).reshape(-1, 3, 3),
                         np.array(block_index, dtype=int).reshape(-1, 3))
    return tuple(infos), np.array(q0, dtype=float), np.array(v0, dtype=float), mass


def _state(info: BodyInfo, q: ca.SX, v: ca.SX) -> BodyState:
    build = {"spatial": BodyState.spatial, "planar": BodyState.planar,
             "particle": BodyState.particle}[info.kind]
    return build(q[info.q], v[info.v])


def _com_frame(bodies: dict, body: str, frame: Placement) -> Placement:
    """A frame in a body's reference frame (``bodies``: the scene's, by name), re-expressed in
    its centre-of-mass frame."""
    if body == GROUND:
        return frame
    return bodies[body].marker_in_com_frame(frame)


def _characteristic_length(scene: Scene, joint_points: list[np.ndarray]) -> float:
    """The scene's value, else the RMS distance of joint origins and centres of mass from
    their centroid at the initial pose (1 m when that is zero). SI, so unit-free."""
    if scene.characteristic_length is not None:
        return float(scene.characteristic_length)
    points = joint_points + [b.com_pose.position for b in scene.bodies.values()]
    if len(points) < 2:
        return 1.0
    spread = np.array(points) - np.mean(points, axis=0)
    largest = float(np.abs(spread).max())
    if not largest > 0:
        return 1.0
    # scaled before squaring, so that huge (but finite) coordinates do not overflow
    rms = largest * float(np.sqrt(np.mean(np.sum((spread / largest) ** 2, axis=1))))
    return rms if rms > 1e-12 else 1.0


class _Assembly:
    """The symbols and expressions of one model, built one concern at a time."""

    def __init__(self, si: Scene, moved_frames: tuple = (), scaled: Law | None = None):
        self.si = si
        self.moved_frames = moved_frames
        # (index into joint_points, the point's world change per unit, its shift symbol) of
        # each frame moved on its child: the characteristic length moves with them
        self.moved_points: list[tuple[int, np.ndarray, ca.SX]] = []
        self.dim = si.dimension
        self.scene_bodies = si.bodies  # looked up once: the scene builds the dict on each call
        self.bodies, self.q0, self.v0, self.mass = _bodies(si)
        self.index = {b.name: b.index for b in self.bodies}
        self.q = ca.SX.sym("q", self.q0.size)
        self.v = ca.SX.sym("v", self.v0.size)
        self.states = {b.name: _state(b, self.q, self.v) for b in self.bodies}
        self.states[GROUND] = BodyState.ground(self.dim)
        self.qdot = (ca.vertcat(*[self.states[b.name].qdot for b in self.bodies])
                     if self.bodies else ca.SX(0, 1))
        self.laws = _Laws()
        self.rows: list[RowInfo] = []
        self.residuals: list[ca.SX] = []
        self.tracking: list[ca.SX] = []  # each joint controller's coordinate minus its target
        self.geometries: dict[str, JointGeometry] = {}
        self.joint_points: list[np.ndarray] = []  # world joint origins at the initial pose
        self.contacts: list[ContactInfo] = []
        self.guided: list[tuple[int, ca.SX]] = []  # a guided law's index, its joint's coordinate
        self.ranged: list[ca.SX] = []  # the coordinate of each joint with a range
        # every length times 1 + sigma, sigma the law ``scaled`` (zero), or 1 (a number)
        self.scale = 1.0 if scaled is None else 1.0 + self.laws.last(scaled, "scale")
        if scaled is not None:
            for state in self.states.values():
                state.scale = self.scale

    def _add_row(self, name: str, owner: str, unit: str, expr: ca.SX) -> int:
        self.rows.append(RowInfo(name, owner, unit))
        self.residuals.append(expr)
        return len(self.rows) - 1

    def joints(self) -> list[dict]:
        """Rows of every joint (its type writes them); the spanning tree decides which joints
        close loops."""
        si = self.si
        scene_joints = list(si.joints.values())
        _, chords = spanning_forest([GROUND, *self.index],
                                    [(j.parent, j.child) for j in scene_joints])
        parts = []
        for k, joint in enumerate(scene_joints):
            on_parent, on_child = si.joint_frames(joint)  # reference frames of the bodies
            world_p = self._pose(joint.parent).transform_point(on_parent.position)
            world_c = self._pose(joint.child).transform_point(on_child.position)
            self.joint_points.append(world_c)
            frame_p = _com_frame(self.scene_bodies, joint.parent, on_parent)
            frame_c = _com_frame(self.scene_bodies, joint.child, on_child)
            axis = joint.unit_axis(self.dim)
            if isinstance(joint, Contact):  # a foot stands on the scene's ground
                joint = replace(joint, terrain=si.ground.terrain)
            shifts = self._shifts(joint.name)
            g = JointGeometry(self.states[joint.parent], self.states[joint.child], frame_p,
                              frame_c, axis, self.dim, (world_p, world_c), shifts, self.scale)
            self.geometries[joint.name] = g
            rows = [self._add_row(f"{joint.name}/{name}", joint.name, unit, expr)
                    for name, expr, unit in joint.rows(g, self.laws)]
            if joint.limits is not None:  # its coordinate, as its driver's row measures it
                self.ranged.append(joint.driver_row(g, 0.0))
            if isinstance(joint, Contact):  # a foot: its gate's index among the laws
                gate = self.laws.where.index(("gate", joint.name))
                self.contacts.append(ContactInfo(joint.name, k, np.array(rows, dtype=int),
                                                 joint, gate))
            parts.append(dict(name=joint.name, kind=joint.kind, index=k,
                              parent=self.index.get(joint.parent, GROUND_INDEX),
                              child=self.index.get(joint.child, GROUND_INDEX),
                              parent_frame=frame_p, child_frame=frame_c, axis=axis,
                              rows=np.array(rows, dtype=int), loop_closing=k in chords,
                              type=joint, child_shift=None if shifts is None else shifts[1]))
        return parts

    def _shifts(self, joint: str) -> tuple | None:
        """The symbolic shifts of a moved joint's frame origins on its parent and child (each
        shift a law symbol times its direction), None for a joint not moved."""
        moves = [m for m in self.moved_frames if m[0] == joint]
        if not moves:
            return None
        parent, child = ca.SX.zeros(self.dim), ca.SX.zeros(self.dim)
        body = self.si.joints[joint].child
        for _, on_parent, on_child, law in moves:
            w = self.laws.last(law, f"{joint}/shift")
            parent, child = parent + w * ca.DM(on_parent), child + w * ca.DM(on_child)
            if np.any(on_child):  # the joint's point, as the characteristic length sees it
                turned = self._pose(body).rotation @ np.asarray(on_child, dtype=float)
                self.moved_points.append((len(self.joint_points) - 1, turned, w))
        return parent, child

    def _length(self) -> tuple[float, ca.SX | None]:
        """The characteristic length, and where design parameters move the joint points it
        is the RMS spread of (frames moved on their children, every point scaled), its
        first-order expression in them (``Symbolic.length``: exact for derivatives); None
        when nothing moves it or the scene gives it."""
        length = _characteristic_length(self.si, self.joint_points)
        scaled = not isinstance(self.scale, float)
        if not (self.moved_points or scaled) or self.si.characteristic_length is not None:
            return length, None
        expression = length
        points = np.array(self.joint_points + [b.com_pose.position
                                               for b in self.si.bodies.values()])
        spread = points - points.mean(axis=0)
        if self.moved_points and float(np.abs(spread).max()) > 0 and length > 1e-12:
            # d rms = sum_i spread_i . d point_i / (n rms): the centroid's move is orthogonal
            change = sum(w * float(spread[i] @ turned) for i, turned, w in self.moved_points)
            expression = length + change / (len(points) * length)
        # every point scaled: the length measured on them with them
        return length, self.scale * expression if scaled else expression

    def drivers(self) -> tuple[list[DriverInfo], dict[str, list[int]]]:
        """Driver rows, and the rows of the drivers acting on each joint."""
        si = self.si
        joints = si.joints
        joint_index = {name: k for k, name in enumerate(joints)}
        offset = {"x": 0, "y": 1, "z": 2, "angle": 2}
        drivers, on_joint = [], {}
        for driver in si.drivers.values():
            if isinstance(driver, PostureDriver):
                drivers += self._posture(driver)
                continue
            f, law = self.laws.value(driver.law, driver.name, ("driver", driver.name))
            if isinstance(driver, JointDriver):
                joint = joints[driver.joint]
                if joint.coordinate_unit == "length":
                    f = self.scale * f
                row = self._add_row(driver.name, driver.name, joint.coordinate_unit,
                                    joint.driver_row(self.geometries[joint.name], f))
                on_joint.setdefault(joint.name, []).append(row)
                if isinstance(driver.law, Guided):
                    self.guided.append((law, joint.driver_row(self.geometries[joint.name], 0.0)))
                drivers.append(DriverInfo(driver.name, "joint", row, law, driver.law,
                                          joint=joint_index[joint.name]))
            else:
                assert isinstance(driver, CoordinateDriver)
                body = self.bodies[self.index[driver.body]]
                unit = "angle" if driver.coordinate == "angle" else "length"
                if driver.coordinate in ("x", "y", "z"):
                    f = self.scale * f
                if driver.coordinate in ORIENTATIONS:
                    unit = "angle"
                    delta = self._measured_angle(driver) - f
                    row_expr = ca.atan2(ca.sin(delta), ca.cos(delta))  # correct past +-pi
                elif driver.coordinate == "angle" or (driver.point is None
                                                      and driver.frame in ("world", GROUND)):
                    row_expr = self.q[body.q.start + offset[driver.coordinate]] - f
                else:
                    row_expr = self._measured_point(driver)[offset[driver.coordinate]] - f
                row = self._add_row(driver.name, driver.name, unit, row_expr)
                drivers.append(DriverInfo(driver.name, "coordinate", row, law, driver.law,
                                          body=body.index, coordinate=driver.coordinate,
                                          frame=self.index.get(driver.frame, GROUND_INDEX)))
        return drivers, on_joint

    def _posture(self, driver: PostureDriver) -> list[DriverInfo]:
        """The rows of a posture rule (:mod:`hexapod.model.posture`), one per joint beyond
        three, each a driver row named after its joint."""
        local, _ = self._point(driver.body, driver.point)
        foot = self.states[driver.body].point(local)
        columns, offsets = [], []
        for name, rest, weight in zip(driver.joints, driver.rest, driver.weights, strict=True):
            g = self.geometries[name]
            pivot = g.child.point(g.child_frame.position)
            columns.append(ca.cross(g.parent_vector(g.axis), foot - pivot))
            offsets.append(weight * self.si.joints[name].driver_row(g, rest))
        body = self.bodies[self.index[driver.body]].index
        return [DriverInfo(f"{driver.name}/{driver.joints[j]}", "posture",
                           self._add_row(f"{driver.name}/{driver.joints[j]}", driver.name,
                                         "angle", row), -1, body=body)
                for j, row in posture_rows(columns, offsets, self.q, self.q0)]

    def _reference_axes(self, body: str) -> tuple[ca.SX, ca.SX]:
        """World origin and axes (columns) of a body's reference frame; the world's for
        ``world`` or the ground."""
        if body in ("world", GROUND):
            return ca.DM.zeros(self.dim), ca.DM.eye(self.dim)
        reference = _com_frame(self.scene_bodies, body, Placement.identity(self.dim))
        state = self.states[body]
        return state.point(reference.position), ca.mtimes(state.R, ca.DM(reference.rotation))

    def _measured_point(self, driver: CoordinateDriver) -> ca.SX:
        """A coordinate driver's point in world axes, or in the axes of its ``frame`` body's
        reference frame from that frame's origin."""
        local, _ = self._point(driver.body, driver.point)
        origin, axes = self._reference_axes(driver.frame)
        return ca.mtimes(axes.T, self.states[driver.body].point(local) - origin)

    def _measured_angle(self, driver: CoordinateDriver) -> ca.SX:
        """A coordinate driver's Tait-Bryan angle (z-y-x) of its body's reference axes from its
        ``frame``'s: ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
        R = ca.mtimes(self._reference_axes(driver.frame)[1].T,
                      self._reference_axes(driver.body)[1])
        if driver.coordinate == "yaw":
            return ca.atan2(R[1, 0], R[0, 0])
        if driver.coordinate == "pitch":
            return ca.atan2(-R[2, 0], ca.sqrt(R[0, 0] ** 2 + R[1, 0] ** 2))
        return ca.atan2(R[2, 1], R[2, 2])

    def _point(self, body: str, ref) -> tuple[np.ndarray, np.ndarray]:
        """A point reference: in the body's centre-of-mass frame, and in the world initially."""
        local = self.si.point(body, ref)
        return (_com_frame(self.scene_bodies, body, Placement(local)).position,
                self._pose(body).transform_point(local))

    def _pose(self, body: str) -> Placement:
        """The initial pose of a body's reference frame (``Scene.pose``, without its lookup)."""
        if body == GROUND:
            return Placement.identity(self.dim)
        return self.scene_bodies[body].pose

    def _components(self, name: str, attribute: str, laws) -> ca.SX:
        return ca.vertcat(*[self.laws.value(law, f"{name}[{i}]", ("force", name, attribute, i))[0]
                            for i, law in enumerate(laws)])

    def forces(self) -> tuple[ForceBuilder, dict[str, list[str]], list[ForceInfo]]:
        """Generalized forces of every element, the elements acting across each joint (efforts
        and torsion springs on it; spring-dampers between its two bodies, given to the first
        such joint), and what each element acts on."""
        si = self.si
        builder = ForceBuilder(self.q, self.v, self.qdot)
        across: dict[str, list[str]] = {}
        infos: list[ForceInfo] = []
        joints = si.joints
        joint_index = {name: k for k, name in enumerate(joints)}

        def body(name):
            return self.index.get(name, GROUND_INDEX)

        def on_joint(element):
            joint = joints[element.joint]
            infos.append(ForceInfo(element.name, element.kind,
                                   (body(joint.parent), body(joint.child)),
                                   joint=joint_index[joint.name]))
            across.setdefault(joint.name, []).append(element.name)
            return joint, self.geometries[joint.name]

        pairs = {frozenset((j.parent, j.child)): j.name for j in reversed(si.joints.values())}
        for element in si.forces.values():
            name = element.name
            if isinstance(element, SpringDamper):
                a, b = element.body_a, element.body_b
                pa, world_a = self._point(a, element.point_a)
                pb, world_b = self._point(b, element.point_b)
                free = element.free_length
                if free is None:
                    free = float(np.linalg.norm(world_b - world_a))
                force = None if element.force is None else self.laws.value(
                    element.force, name, ("force", name, "force", None))[0]
                builder.spring_damper(name, self.states[a], pa, self.states[b], pb,
                                      element.stiffness, element.damping, free, force)
                if frozenset((a, b)) in pairs:
                    across.setdefault(pairs[frozenset((a, b))], []).append(name)
                infos.append(ForceInfo(name, element.kind, (body(a), body(b)), (pa, pb)))
            elif isinstance(element, AppliedForce):
                state = self.states[element.body]
                components = self._components(name, "force", element.force)
                if element.frame == "body":
                    components = ca.mtimes(state.R, components)
                point = self._point(element.body, element.point)[0]
                builder.force_at(name, state, point, components)
                builder.nonconservative.append(name)
                infos.append(ForceInfo(name, element.kind, (body(element.body),), (point,)))
            elif isinstance(element, AppliedTorque):
                state = self.states[element.body]
                components = self._components(name, "torque", element.torque)
                if element.frame == "body" and self.dim == 3:
                    components = ca.mtimes(state.R, components)
                builder.torque_on(name, state, components)
                builder.nonconservative.append(name)
                infos.append(ForceInfo(name, element.kind, (body(element.body),)))
            elif isinstance(element, JointEffort):
                joint, g = on_joint(element)
                rate = joint.rate(g, self.q, self.qdot)
                builder.effort(name, rate, self.laws.value(element.law, name,
                                                           ("force", name, "law", None))[0])
                builder.nonconservative.append(name)
            elif isinstance(element, RotationalSpringDamper):
                _, g = on_joint(element)
                rate = angle_rate(g)  # about the axis of a joint that turns
                twist = wrapped_angle(g, element.free_angle)
                torque = -element.stiffness * twist - element.damping * rate
                builder.potential = builder.potential + element.stiffness * twist**2 / 2
                if element.torque is not None:
                    torque = torque + self.laws.value(element.torque, name,
                                                      ("force", name, "torque", None))[0]
                if element.damping or element.torque is not None:
                    builder.nonconservative.append(name)
                builder.effort(name, rate, torque)
            elif isinstance(element, JointController):
                _, g = on_joint(element)
                builder.effort(name, angle_rate(g), self._servo(element, g))
                builder.nonconservative.append(name)
            elif isinstance(element, GroundContact):  # no force of the state: the scheme's
                point = self._point(element.body, element.point)[0]
                surface, normal = element.plane(self.dim)
                mu = si.ground.mu if element.mu is None else element.mu
                builder.nonconservative.append(name)  # impacts and friction dissipate
                infos.append(ForceInfo(name, element.kind, (body(element.body),), (point,),
                                       contact=SurfaceContact.plane(
                                           surface, normal, element.restitution, mu,
                                           element.armed_ahead_of, element.forward)))
        return builder, across, infos

    def _servo(self, element: JointController, g) -> ca.SX:
        """A joint controller's torque: feedforward, proportional and derivative terms on the
        wrapped angle error and the speed error, clipped to its actuator's envelope."""
        name, laws = element.name, self.laws
        target = laws.value(element.target, name, ("force", name, "target", None))[0]
        speed = laws.value(rate_of(element.target), f"{name}'",
                           ("force", name, "target-rate", None))[0]
        rate = angle_rate(g)
        error = wrapped_angle(g, target)
        self.tracking.append(error)
        torque = element.kp * -error + element.kd * (speed - rate)
        if element.feedforward is not None:
            torque = torque + laws.value(element.feedforward, f"{name}/ff",
                                         ("force", name, "feedforward", None))[0]
        if element.max_effort is None:
            return torque
        lower, upper = effort_limits(element.max_effort, element.no_load_speed, rate)
        return ca.fmin(ca.fmax(torque, lower), upper)

    def model(self, rank_tolerance: float, digest: str = "", source: str = "",
              kinematics: Model | None = None) -> Model:
        parts = self.joints()
        drivers, on_joint = self.drivers()
        builder, across, forces = self.forces()
        n_v = self.v0.size
        columns, joints = [], []
        for part in parts:
            names = tuple(across.get(part["name"], ()))
            if names:
                columns.append(sum((builder.terms[n] for n in names), ca.SX.zeros(n_v)))
            joints.append(JointInfo(**part, driver_rows=np.array(on_joint.get(part["name"], []),
                                                                 dtype=int),
                                    across=names, across_column=len(columns) - 1 if names else -1))
        w, wd, wdd = self.laws.symbols()
        length, length_expression = self._length()
        symbolic = Symbolic(
            q=self.q, v=self.v, w=w, wd=wd, wdd=wdd, qdot=self.qdot,
            phi=ca.cse(ca.vertcat(*self.residuals)) if self.residuals else ca.SX(0, 1),
            Q=inertial_forces(self.bodies, self.v, self.si.gravity, n_v) + builder.total(),
            Q_across=ca.horzcat(*columns) if columns else None,
            potential=gravity_potential(self.bodies, self.q, self.si.gravity)
            + builder.potential,
            tracking=ca.vertcat(*self.tracking) if self.tracking else None,
            guided=ca.vertcat(*[c for _, c in self.guided]) if self.guided else None,
            ranged=ca.vertcat(*self.ranged) if self.ranged else None,
            length=length_expression,
            scale=None if isinstance(self.scale, float) else self.scale)
        guidance = None if kinematics is None else Guidance(
            kinematics, np.array([law for law, _ in self.guided], dtype=int))
        # work is done by rheonomic drivers (time laws) and by the non-conservative elements
        working = [d.name for d in drivers if d.law >= 0] + builder.nonconservative
        return Model(name=self.si.name, dimension=self.dim, bodies=self.bodies,
                     joints=tuple(joints), drivers=tuple(drivers), rows=tuple(self.rows),
                     laws=tuple(self.laws.laws), gravity=self.si.gravity,
                     characteristic_length=length,
                     q0=self.q0, v0=self.v0, mass=self.mass, symbolic=symbolic,
                     forces=tuple(forces), rank_tolerance=rank_tolerance,
                     working_elements=tuple(working), report_forces=self.si.report_forces,
                     contacts=tuple(self.contacts), ground=self.si.ground, digest=digest,
                     source=source, guidance=guidance)


def assemble(scene: Scene, *, rank_tolerance: float = 1e-9, moved_frames: tuple = (),
             scaled: Law | None = None) -> Model:
    """Validate ``scene`` and build its :class:`~hexapod.model.model.Model` (SI units).

    Parameters
    ----------
    scene : Scene
        The description, in its own length unit (the model is in SI).
    rank_tolerance : float
        Rows of the equilibrated ``Phi_v`` whose distance to the span of the rows kept before
        them is below this are redundant (see :mod:`hexapod.algorithms.linalg`).
    moved_frames : tuple, optional
        ``(joint, on_parent, on_child, law)``: the joint's frame origins shifted by ``law``'s
        value (a :class:`~hexapod.scene.laws.base.DesignShift`, zero) times the directions
        ``on_parent`` and ``on_child`` (in each body's centre-of-mass axes, SI): the same model
        with the shifts as symbols, whose derivatives give a joint's position's
        (:mod:`hexapod.algorithms.law_tangents`).
    scaled : DesignShift, optional
        Every length of the model (its bodies' points, the world's, the length-valued laws
        and the characteristic length) times ``1 + sigma``, ``sigma`` this law's value (zero):
        the derivative with respect to the geometric scale at fixed masses.

    Returns
    -------
    Model

    Raises
    ------
    ModelError
        Listing every problem of the scene.
    HexapodError
        When the scene has more bodies or joints than the limit
        (:func:`hexapod._support.limits.max_bodies`, ``HEXAPOD_MAX_BODIES``).
    """
    where = f" ({scene.source})" if scene.source else ""
    check_model_size(len(scene.bodies), len(scene.joints), f"scene '{scene.name}'{where}",
                     sum(j.kind == "contact" for j in scene.joints.values()))
    scene.validate()
    si = scene.in_si()
    kinematics = None
    moved = tuple(moved_frames)
    unknown = sorted({m[0] for m in moved} - set(si.joints))
    if unknown:
        raise HexapodError(f"scene '{scene.name}'{where}: no joint '{unknown[0]}' to move")
    tag = "" if not moved else "|moved:" + ",".join(f"{m[0]}:{id(m[3])}" for m in moved)
    tag += "" if scaled is None else f"|scaled:{id(scaled)}"
    if any(isinstance(d, CoordinateDriver) and d.guide for d in si.drivers.values()):
        guides = _guides_driving(si)
        kinematics = _Assembly(guides, moved, scaled).model(
            rank_tolerance, scene_digest(guides, rank_tolerance) + tag, scene.source)
        si = _guides_left_out(si)
    return with_guided_laws(_Assembly(si, moved, scaled).model(
        rank_tolerance, scene_digest(si, rank_tolerance) + tag, scene.source, kinematics))


def _copy_with(scene: Scene, name: str, elements, ground) -> Scene:
    out = Scene(name, scene.dimension, "m", scene.gravity, scene.characteristic_length,
                scene.source, report_forces=scene.report_forces, ground=ground)
    out.add(*elements)
    return out


def _guides_driving(si: Scene) -> Scene:
    """The kinematics of a guided scene: its guides as drivers, the joints that follow them
    free, no force element and the cheapest ground policy (its forces serve nothing; a large
    load would only put its round-off into the accelerations)."""
    forces = set(si.forces)
    elements = [e.replace(guide=False) if isinstance(e, CoordinateDriver) else e
                for e in si.elements
                if not (isinstance(e, JointDriver) and isinstance(e.law, Guided))
                and e.name not in forces]
    ground = si.ground if si.ground is None else replace(si.ground, policy="min-wrench")
    return _copy_with(si, f"{si.name} (guides)", elements, ground)


def _guides_left_out(si: Scene) -> Scene:
    """The dynamics of a guided scene: the joints that follow the guides driven, the guides
    and the posture rules left out (they exert nothing)."""
    return _copy_with(si, si.name, [e for e in si.elements if not (
        isinstance(e, CoordinateDriver) and e.guide) and not isinstance(e, PostureDriver)],
        si.ground)
