"""``assemble(scene) -> Model``: the scene's constraints and forces as CasADi expressions.

Only what the scene contains is built: a planar scene has 3 coordinates per body and no 3-D
terms; a scene without springs has no spring terms; constant laws are folded in as numbers, so
the law inputs ``w, wd, wdd`` carry only the laws that change with time.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod.assembly.forces import ForceBuilder, inertial_forces
from hexapod.assembly.frames import BodyState
from hexapod.assembly.joints import (
    ROWS,
    JointGeometry,
    distance_rows,
    driver_row,
    joint_rate,
)
from hexapod.graph import spanning_forest
from hexapod.model import (
    GROUND_INDEX,
    BlockDiagonal,
    BodyInfo,
    DriverInfo,
    JointInfo,
    Model,
    RowInfo,
    Symbolic,
)
from hexapod.scene.bodies import Particle, PlanarBody, SpatialBody
from hexapod.scene.drivers import CoordinateDriver, JointDriver
from hexapod.scene.element import GROUND
from hexapod.scene.forces import AppliedForce, AppliedTorque, JointEffort, SpringDamper
from hexapod.scene.joints import Distance
from hexapod.scene.laws import Constant, Law
from hexapod.scene.scene import Scene
from hexapod.spatial import Placement, euler_parameters_from_rotation

__all__ = ["assemble"]


class _Laws:
    """Time laws as symbols; constant laws become numbers."""

    def __init__(self):
        self.laws: list[Law] = []
        self.w: list[ca.SX] = []
        self.wd: list[ca.SX] = []
        self.wdd: list[ca.SX] = []

    def value(self, law: Law, label: str) -> tuple[ca.SX, int]:
        """The law's value as an expression, and its index (-1 for a constant)."""
        if isinstance(law, Constant):
            return ca.SX(law.value), -1
        index = len(self.laws)
        self.laws.append(law)
        for store, suffix in ((self.w, ""), (self.wd, "_d"), (self.wdd, "_dd")):
            store.append(ca.SX.sym(f"{label}{suffix}"))
        return self.w[index], index

    def symbols(self) -> tuple[ca.SX, ca.SX, ca.SX]:
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
                              body.mass, inertia, np.array(body.com, dtype=float)))
        nq += dq
        nv += dv
    mass = BlockDiagonal(np.array(diagonal), np.array(blocks).reshape(-1, 3, 3),
                         np.array(block_index, dtype=int).reshape(-1, 3))
    return tuple(infos), np.array(q0, dtype=float), np.array(v0, dtype=float), mass


def _state(info: BodyInfo, q: ca.SX, v: ca.SX) -> BodyState:
    build = {"spatial": BodyState.spatial, "planar": BodyState.planar,
             "particle": BodyState.particle}[info.kind]
    return build(q[info.q], v[info.v])


def _com_frame(scene: Scene, body: str, frame: Placement) -> Placement:
    """A frame in a body's reference frame, re-expressed in its centre-of-mass frame."""
    if body == GROUND:
        return frame
    return scene.bodies[body].marker_in_com_frame(frame)


def _joint_axis(joint, dimension: int) -> np.ndarray | None:
    """The unit axis in the joint frame: revolute (z by default; always z in the plane, where it
    is not stored) and prismatic (z in space, x in the plane by default); None otherwise."""
    if joint.kind == "revolute":
        axis = joint.axis if dimension == 3 else None
    elif joint.kind == "prismatic":
        axis = joint.axis if joint.axis is not None else (
            [0.0, 0.0, 1.0] if dimension == 3 else [1.0, 0.0])
    else:
        return None
    if axis is None:
        return None
    axis = np.array(axis, dtype=float)
    return axis / np.linalg.norm(axis)


def _characteristic_length(scene: Scene, joint_points: list[np.ndarray]) -> float:
    """The scene's value, else the RMS distance of joint origins and centres of mass from
    their centroid at the initial pose (1 m when that is zero). SI, so unit-free."""
    if scene.characteristic_length is not None:
        return float(scene.characteristic_length)
    points = joint_points + [b.com_pose.position for b in scene.bodies.values()]
    if len(points) < 2:
        return 1.0
    P = np.array(points)
    rms = float(np.sqrt(np.mean(np.sum((P - P.mean(axis=0)) ** 2, axis=1))))
    return rms if rms > 1e-12 else 1.0


def assemble(scene: Scene, *, rank_tolerance: float = 1e-9) -> Model:
    """Validate ``scene`` and build its :class:`~hexapod.model.Model` (SI units).

    Parameters
    ----------
    scene : Scene
    rank_tolerance : float
        Rows of the equilibrated ``Phi_v`` whose distance to the span of the rows kept before
        them is below this are redundant (see :mod:`hexapod.linalg`).

    Raises
    ------
    ModelError
        Listing every problem of the scene.
    """
    scene.validate()
    si = scene.in_si()
    dim = si.dimension
    bodies, q0, v0, mass = _bodies(si)
    index = {b.name: b.index for b in bodies}
    n_q, n_v = q0.size, v0.size
    q = ca.SX.sym("q", n_q)
    v = ca.SX.sym("v", n_v)
    states = {b.name: _state(b, q, v) for b in bodies}
    states[GROUND] = BodyState.ground(dim)
    qdot = ca.vertcat(*[states[b.name].qdot for b in bodies]) if bodies else ca.SX(0, 1)
    laws = _Laws()

    # joints: frames, tree, rows
    scene_joints = list(si.joints.values())
    _, chords = spanning_forest([GROUND, *index],
                                [(j.parent, j.child) for j in scene_joints])
    chords = set(chords)
    rows: list[RowInfo] = []
    residuals: list[ca.SX] = []
    geometries: dict[str, JointGeometry] = {}
    joint_parts = []
    joint_points = []
    for k, joint in enumerate(scene_joints):
        frame_p, frame_c = si.joint_frames(joint)
        frame_p = _com_frame(si, joint.parent, frame_p)
        frame_c = _com_frame(si, joint.child, frame_c)
        axis = _joint_axis(joint, dim)
        g = JointGeometry(states[joint.parent], states[joint.child], frame_p, frame_c, axis, dim)
        geometries[joint.name] = g
        joint_points.append(si.pose(joint.child).transform_point(
            si.frame(joint.child, joint.child_frame).position)
            if joint.origin is None else joint.origin)
        if isinstance(joint, Distance):
            length = joint.length
            if length is None:
                on_parent, on_child = si.joint_frames(joint)
                world_p = si.pose(joint.parent).transform_point(on_parent.position)
                world_c = si.pose(joint.child).transform_point(on_child.position)
                length = float(np.linalg.norm(world_c - world_p))
            joint_rows = distance_rows(g, length)
        else:
            joint_rows = ROWS[joint.kind](g)
        start = len(rows)
        for row_name, expr, unit in joint_rows:
            rows.append(RowInfo(f"{joint.name}/{row_name}", joint.name, unit))
            residuals.append(expr)
        joint_parts.append(dict(
            name=joint.name, kind=joint.kind, index=k,
            parent=index.get(joint.parent, GROUND_INDEX),
            child=index.get(joint.child, GROUND_INDEX),
            parent_frame=frame_p, child_frame=frame_c, axis=axis,
            rows=np.arange(start, len(rows)), loop_closing=k in chords))

    # drivers
    joint_index = {j.name: k for k, j in enumerate(scene_joints)}
    drivers: list[DriverInfo] = []
    driver_rows: dict[str, list[int]] = {}
    coordinate_offset = {"x": 0, "y": 1, "z": 2, "angle": 2}
    for driver in si.drivers.values():
        f, law_index = laws.value(driver.law, driver.name)
        row = len(rows)
        if isinstance(driver, JointDriver):
            joint = si.joints[driver.joint]
            expr = driver_row(joint.kind, geometries[joint.name], f)
            unit = "length" if joint.kind == "prismatic" else "angle"
            driver_rows.setdefault(joint.name, []).append(row)
            info = DriverInfo(driver.name, "joint", row, law_index,
                              joint=joint_index[joint.name])
        else:
            assert isinstance(driver, CoordinateDriver)
            body = bodies[index[driver.body]]
            expr = q[body.q.start + coordinate_offset[driver.coordinate]] - f
            unit = "angle" if driver.coordinate == "angle" else "length"
            info = DriverInfo(driver.name, "coordinate", row, law_index, body=body.index,
                              coordinate=driver.coordinate)
        rows.append(RowInfo(driver.name, driver.name, unit))
        residuals.append(expr)
        drivers.append(info)

    # forces
    builder = ForceBuilder(q, v, qdot)
    across: dict[str, list[str]] = {}
    body_pairs = {frozenset((j.parent, j.child)): j.name for j in reversed(scene_joints)}
    for element in si.forces.values():
        name = element.name
        if isinstance(element, SpringDamper):
            a, b = element.body_a, element.body_b
            pa = _com_frame(si, a, Placement(si.point(a, element.point_a))).position
            pb = _com_frame(si, b, Placement(si.point(b, element.point_b))).position
            free = element.free_length
            if free is None:
                wa = si.pose(a).transform_point(si.point(a, element.point_a))
                wb = si.pose(b).transform_point(si.point(b, element.point_b))
                free = float(np.linalg.norm(wb - wa))
            force = None if element.force is None else laws.value(element.force, name)[0]
            builder.spring_damper(name, states[a], pa, states[b], pb, element.stiffness,
                                  element.damping, free, force)
            pair = frozenset((a, b))
            if pair in body_pairs:
                across.setdefault(body_pairs[pair], []).append(name)
        elif isinstance(element, AppliedForce):
            state = states[element.body]
            point = _com_frame(si, element.body,
                               Placement(si.point(element.body, element.point))).position
            components = ca.vertcat(*[laws.value(law, f"{name}[{i}]")[0]
                                      for i, law in enumerate(element.force)])
            if element.frame == "body":
                components = ca.mtimes(state.R, components)
            builder.force_at(name, state, point, components)
        elif isinstance(element, AppliedTorque):
            state = states[element.body]
            components = ca.vertcat(*[laws.value(law, f"{name}[{i}]")[0]
                                      for i, law in enumerate(element.torque)])
            if element.frame == "body" and dim == 3:
                components = ca.mtimes(state.R, components)
            builder.torque_on(name, state, components)
        elif isinstance(element, JointEffort):
            joint = si.joints[element.joint]
            value = laws.value(element.law, name)[0]
            builder.effort(name, joint_rate(joint.kind, geometries[joint.name], q, qdot), value)
            across.setdefault(joint.name, []).append(name)

    Q = inertial_forces(bodies, v, si.gravity, n_v) + builder.total()
    across_columns = []
    joints = []
    for part in joint_parts:
        names = tuple(across.get(part["name"], ()))
        column = -1
        if names:
            column = len(across_columns)
            total = ca.SX.zeros(n_v)
            for n in names:
                total = total + builder.terms[n]
            across_columns.append(total)
        joints.append(JointInfo(**part, driver_rows=np.array(driver_rows.get(part["name"], []),
                                                             dtype=int),
                                across=names, across_column=column))

    w, wd, wdd = laws.symbols()
    symbolic = Symbolic(q=q, v=v, w=w, wd=wd, wdd=wdd, qdot=qdot,
                        phi=ca.vertcat(*residuals) if residuals else ca.SX(0, 1), Q=Q,
                        Q_across=ca.horzcat(*across_columns) if across_columns else None)
    return Model(name=si.name, dimension=dim, bodies=bodies, joints=tuple(joints),
                 drivers=tuple(drivers), rows=tuple(rows), laws=tuple(laws.laws),
                 gravity=si.gravity, characteristic_length=_characteristic_length(si,
                                                                                  joint_points),
                 q0=q0, v0=v0, mass=mass, symbolic=symbolic,
                 force_names=tuple(si.forces), rank_tolerance=rank_tolerance)
