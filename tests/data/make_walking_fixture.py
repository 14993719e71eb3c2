"""The walking hexapod against Pinocchio's floating-base RNEA: writes the fixture of
``tests/test_walking_pinocchio.py`` (needs `pin`).

The robot of ``legs.robot.hexapod_scene(trunk="free")`` is rebuilt in Pinocchio from the
assembled hexapod model itself (``model.bodies`` and ``model.joints``, not the leg data), so both
describe the same mechanism: the trunk on a ``JointModelFreeFlyer`` whose frame is the trunk's
centre-of-mass frame, and each leg a chain of revolute joints whose Pinocchio frames are the
hexapod joint frames (origin at the joint point, fixed to the child), with the same axes,
placements, masses, centres of mass and inertias. The hexapod inverse dynamics of one stride of
the tripod gait gives the state and the ground's force on each foot; the state is converted
(base pose with the quaternion scalar last, base velocity and acceleration in Pinocchio's local
convention, joint angles, rates and accelerations from the driver laws), the ground reactions are
applied at the feet as external forces (``fext``, in each joint's local frame, about its
origin), and ``pinocchio.rnea`` gives the joint torques. The free flyer's six components must
vanish: the reported ground reactions balance the robot. The conversion is checked on the way:
Pinocchio's placements, velocities and accelerations of every body frame against the hexapod's
(from ``q``, ``v`` and ``v_dot``), and each joint angle from ``q`` against its driver law.

    pip install ".[compare]" && python3 tests/data/make_walking_fixture.py [--quadruped]
    python3 tests/data/make_walking_fixture.py --hexapod3
    python3 tests/data/make_walking_fixture.py --quadruped-slope
    python3 tests/data/make_walking_fixture.py --hexapod3-steps
    python3 tests/data/make_walking_fixture.py --quadruped-turn
    python3 tests/data/make_walking_fixture.py --quadruped-ankles
    python3 tests/data/make_walking_fixture.py --quadruped-trot

``--quadruped`` writes ``quadruped_rnea.npz`` for the project's quadruped instead
(``data/robots/quadruped.toml``: a URDF robot whose joints follow its guides, 24 samples of a
stride), ``--hexapod3`` ``hexapod3_rnea.npz`` for its hexapod of three joints a leg
(``data/robots/hexapod3.toml``, a tripod: 20 samples of a stride); ``--quadruped-slope``
and ``--hexapod3-steps`` the same robots up a 10-degree slope (24 samples of a stride) and up
two 3 cm steps (90 samples over 9 s); ``--quadruped-turn`` the quadruped turning left at 10
degrees a second, ``--quadruped-ankles`` the quadruped with four joints a leg (24 samples of a
stride each); ``--quadruped-trot`` the quadruped trotting (30 samples of a stride: two feet
down at 24 of them).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import hexapod as hx

ROOT = Path(__file__).resolve().parents[2]
OUT = Path(__file__).resolve().parent / "walking_rnea.npz"  # beside this file
PERIOD = 0.5  # the stride of the built-in walking robot (s)
SAMPLES = 20


def walking_model() -> hx.Model:
    """The built-in walking robot (tripod gait, free trunk, min-wrench ground forces)."""
    from legs.robot import hexapod_scene

    return hx.assemble(hexapod_scene(trunk="free"))


def sample_times(samples: int = SAMPLES, period: float = PERIOD) -> np.ndarray:
    """``samples`` instants over one stride, the stride's end excluded (it repeats its start)."""
    return np.linspace(0.0, period, samples, endpoint=False)


@dataclass
class PinocchioRobot:
    """The Pinocchio model and how it maps onto the hexapod model."""

    model: object  # pinocchio.Model
    joint_id: dict[int, int]  # hexapod joint index -> Pinocchio joint id
    body_joint: dict[int, int]  # hexapod body index -> Pinocchio joint id carrying it
    body_frame: dict[int, hx.spatial.Placement]  # Pinocchio frame of the body in its com frame
    free_flyer: int  # Pinocchio joint id of the trunk
    trunk: int  # hexapod body index of the trunk


def _se3(placement: hx.spatial.Placement):
    import pinocchio as pin

    return pin.SE3(np.array(placement.rotation, dtype=float),
                   np.array(placement.position, dtype=float))


def pinocchio_robot(model: hx.Model) -> PinocchioRobot:
    """The hexapod ``model`` (one free body, the others reached from it by revolute joints;
    contacts left out) as a Pinocchio model."""
    import pinocchio as pin

    revolute = [j for j in model.joints if j.kind == "revolute"]
    fixed = [j for j in model.joints if j.kind == "fixed"]  # a foot link on its leg
    children = {j.child for j in revolute + fixed}
    free = [b.index for b in model.bodies if b.index not in children]
    if len(free) != 1:
        raise ValueError(f"expected one free body, found {[model.bodies[b].name for b in free]}")
    trunk = free[0]
    pm = pin.Model()
    pm.name = model.name
    pm.gravity = pin.Motion(np.concatenate([model.gravity, np.zeros(3)]))

    def inertia(body_index: int, frame: hx.spatial.Placement):
        """The body's inertia in the Pinocchio frame ``frame`` (given in its com frame)."""
        body = model.bodies[body_index]
        R = frame.rotation
        com = -R.T @ frame.position  # the centre of mass in the Pinocchio frame
        return pin.Inertia(body.mass, com, R.T @ body.inertia @ R)

    identity = hx.spatial.Placement(np.zeros(3))
    flyer = pm.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(),
                        model.bodies[trunk].name)
    pm.appendBodyToJoint(flyer, inertia(trunk, identity), pin.SE3.Identity())
    joint_id, body_joint, body_frame = {}, {trunk: flyer}, {trunk: identity}
    pending = list(revolute + fixed)
    while pending:  # tree order: a joint after the joint carrying its parent
        ready = [j for j in pending if j.parent in body_joint]
        if not ready:
            raise ValueError("the revolute joints do not form a tree on the free body")
        for j in ready:
            pending.remove(j)
            if j.kind == "fixed":  # the child rides on its parent's Pinocchio joint
                frame = j.child_frame @ j.parent_frame.inverse() @ body_frame[j.parent]
                body_joint[j.child], body_frame[j.child] = body_joint[j.parent], frame
                pm.appendBodyToJoint(body_joint[j.parent], inertia(j.child, frame),
                                     pin.SE3.Identity())
                continue
            axis = np.asarray(j.axis, dtype=float)
            if np.allclose(axis, [0.0, 0.0, 1.0], rtol=0.0, atol=1e-15):
                kind = pin.JointModelRZ()
            else:
                kind = pin.JointModelRevoluteUnaligned(axis / np.linalg.norm(axis))
            placement = body_frame[j.parent].inverse() @ j.parent_frame
            jid = pm.addJoint(body_joint[j.parent], kind, _se3(placement), j.name)
            pm.appendBodyToJoint(jid, inertia(j.child, j.child_frame), pin.SE3.Identity())
            joint_id[j.index], body_joint[j.child] = jid, jid
            body_frame[j.child] = j.child_frame
    return PinocchioRobot(pm, joint_id, body_joint, body_frame, flyer, trunk)


def joint_laws(model: hx.Model, times) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Angles, rates and accelerations (N, J) of every driven joint from its driver's law
    (NaN for joints without one)."""
    times = np.atleast_1d(np.asarray(times, dtype=float))
    w, wd, wdd = (np.asarray(x).reshape(model.n_w, times.size) for x in model.law_values(times))
    out = np.full((3, times.size, len(model.joints)), np.nan)
    for d in model.drivers:
        if d.kind != "joint":
            continue
        if d.law < 0:  # a constant law, folded into the row
            out[0, :, d.joint], out[1:, :, d.joint] = d.spec.evaluate(0.0)[0], 0.0
        else:
            out[:, :, d.joint] = w[d.law], wd[d.law], wdd[d.law]
    return out[0], out[1], out[2]


def _angle_from_q(joint, position, rotation) -> float:
    """Rotation (rad) of the child's joint frame from the parent's about the joint axis."""
    parent = np.eye(3) if joint.parent < 0 else rotation[joint.parent]
    relative = (parent @ joint.parent_frame.rotation).T @ rotation[joint.child] \
        @ joint.child_frame.rotation
    axis = np.asarray(joint.axis, dtype=float) / np.linalg.norm(joint.axis)
    skew = relative - relative.T
    sine = 0.5 * axis @ np.array([skew[2, 1], skew[0, 2], skew[1, 0]])
    cosine = 0.5 * (np.trace(relative) - 1.0)
    return float(np.arctan2(sine, cosine))


def pinocchio_state(model: hx.Model, robot: PinocchioRobot, result: hx.InverseResult):
    """Pinocchio's ``q`` (N, nq), ``v`` and ``a`` (N, nv) of the hexapod ``result``, and the
    largest difference between the driver laws' joint angles and those measured in ``q``."""
    pm, n = robot.model, result.times.size
    trunk = model.bodies[robot.trunk]
    angle, rate, acceleration = joint_laws(model, result.times)
    position, rotation = hx.body_poses(model, result.q)
    q, v, a = np.zeros((n, pm.nq)), np.zeros((n, pm.nv)), np.zeros((n, pm.nv))
    worst_angle = 0.0
    iq, iv = pm.idx_qs[robot.free_flyer], pm.idx_vs[robot.free_flyer]
    for k in range(n):
        e = result.q[k, trunk.q][3:]
        R = rotation[k, trunk.index]
        r_dot, omega = result.v[k, trunk.v][:3], result.v[k, trunk.v][3:]
        r_dd, omega_dot = result.v_dot[k, trunk.v][:3], result.v_dot[k, trunk.v][3:]
        q[k, iq:iq + 7] = np.concatenate([position[k, trunk.index], e[1:], e[:1]])
        v_local = R.T @ r_dot  # the trunk frame is its centre-of-mass frame
        v[k, iv:iv + 6] = np.concatenate([v_local, omega])
        # Pinocchio's a is the rate of its v: the local spatial acceleration
        a[k, iv:iv + 6] = np.concatenate([R.T @ r_dd - np.cross(omega, v_local), omega_dot])
        for j, jid in robot.joint_id.items():
            joint = model.joints[j]
            measured = _angle_from_q(joint, position[k], rotation[k])
            gap = np.angle(np.exp(1j * (measured - angle[k, j])))
            worst_angle = max(worst_angle, abs(float(gap)))
            q[k, pm.idx_qs[jid]] = angle[k, j]
            v[k, pm.idx_vs[jid]] = rate[k, j]
            a[k, pm.idx_vs[jid]] = acceleration[k, j]
    return q, v, a, worst_angle


def _frame_checks(model, robot, result, k, data, position, rotation) -> tuple[float, float]:
    """Largest differences (placement, then velocity and acceleration relative to their
    sample's largest) between Pinocchio's body frames and the hexapod's at sample ``k``."""
    place, motion = 0.0, []
    for b, jid in robot.body_joint.items():
        body = model.bodies[b]
        frame = robot.body_frame[b]
        A, r = rotation[k, b], position[k, b]
        R = A @ frame.rotation
        origin = r + A @ frame.position
        place = max(place, np.abs(data.oMi[jid].rotation - R).max(),
                    np.abs(data.oMi[jid].translation - origin).max())
        vel, acc = result.v[k, body.v], result.v_dot[k, body.v]
        w, w_dot = vel[3:], acc[3:]
        p = frame.position
        origin_dot = vel[:3] + A @ np.cross(w, p)
        origin_dd = acc[:3] + A @ (np.cross(w_dot, p) + np.cross(w, np.cross(w, p)))
        v_local = R.T @ origin_dot
        w_local = frame.rotation.T @ w
        expected_v = np.concatenate([v_local, w_local])
        expected_a = np.concatenate([R.T @ origin_dd - np.cross(w_local, v_local),
                                     frame.rotation.T @ w_dot])
        motion.append((np.abs(data.v[jid].vector - expected_v).max(), np.abs(expected_v).max(),
                       np.abs(data.a[jid].vector - expected_a).max(), np.abs(expected_a).max()))
    motion = np.array(motion)
    return place, max(motion[:, 0].max() / motion[:, 1].max(),
                      motion[:, 2].max() / motion[:, 3].max())


@dataclass
class Comparison:
    """Pinocchio's RNEA on the hexapod's motion and ground reactions."""

    joints: tuple[str, ...]  # the driven (revolute) joints, hexapod order
    hexapod: np.ndarray  # (N, J) hexapod efforts
    pinocchio: np.ndarray  # (N, J) Pinocchio's torques
    base: np.ndarray  # (N, 6) the free flyer's generalized force (local frame: force, moment)
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    angle_gap: float  # driver laws against the angles measured in q (rad)
    placement_gap: float  # Pinocchio's body frames against the hexapod's (m, and rotation)
    motion_gap: float  # velocities and accelerations of the body frames (relative)

    @property
    def difference(self) -> float:
        """Largest torque difference relative to the largest torque."""
        return float(np.abs(self.hexapod - self.pinocchio).max() / np.abs(self.pinocchio).max())


def pinocchio_rnea(model: hx.Model, result: hx.InverseResult) -> Comparison:
    """Pinocchio's joint torques for the hexapod ``result`` with its ground reactions applied
    at the feet."""
    import pinocchio as pin

    robot = pinocchio_robot(model)
    pm = robot.model
    data = pm.createData()
    q, v, a, angle_gap = pinocchio_state(model, robot, result)
    position, rotation = hx.body_poses(model, result.q)
    feet = []  # (contact number, Pinocchio joint id, the foot in that joint's frame)
    for c, name in enumerate(result.contacts):
        joint = model.joints[model.joint_index[name]]
        foot = joint.child_frame.position  # the foot point, in its body's centre-of-mass frame
        feet.append((c, robot.body_joint[joint.child],
                     robot.body_frame[joint.child].inverse() @ hx.spatial.Placement(foot)))
    revolute = [j for j in model.joints if j.kind == "revolute"]
    n = result.times.size
    tau = np.zeros((n, len(revolute)))
    base = np.zeros((n, 6))
    placement_gap = motion_gap = 0.0
    for k in range(n):
        pin.forwardKinematics(pm, data, q[k], v[k], a[k])
        place, motion = _frame_checks(model, robot, result, k, data, position, rotation)
        placement_gap, motion_gap = max(placement_gap, place), max(motion_gap, motion)
        fext = [pin.Force.Zero() for _ in range(pm.njoints)]
        for c, jid, foot in feet:
            force = data.oMi[jid].rotation.T @ result.ground_force[k, c]
            fext[jid] = fext[jid] + pin.Force(force, np.cross(foot.position, force))
        out = pin.rnea(pm, data, q[k], v[k], a[k], fext)
        iv = pm.idx_vs[robot.free_flyer]
        base[k] = out[iv:iv + 6]
        tau[k] = [out[pm.idx_vs[robot.joint_id[j.index]]] for j in revolute]
    columns = [j.index for j in revolute]
    return Comparison(tuple(j.name for j in revolute), result.effort[:, columns], tau, base,
                      q, v, a, angle_gap, placement_gap, motion_gap)


#: The robot descriptions of data/robots with a fixture: the option, the description, the
#: samples over the window (its end left out) and the window (s; None: one stride).
DESCRIBED = {"--quadruped": ("quadruped", 24, None), "--hexapod3": ("hexapod3", 20, None),
             "--quadruped-slope": ("quadruped-slope", 24, None),
             "--hexapod3-steps": ("hexapod3-steps", 90, 9.0),
             "--quadruped-turn": ("quadruped-turn", 24, None),
             "--quadruped-ankles": ("quadruped-ankles", 24, None),
             "--quadruped-trot": ("quadruped-trot", 30, None)}


def described(name: str, samples: int, window: float | None = None
              ) -> tuple[hx.Model, np.ndarray]:
    """A robot of data/robots (``data/robots/NAME.toml``: its joints follow guides) and
    ``samples`` instants over ``window`` (s; default one stride of its gait)."""
    scene = hx.load_scene(ROOT / "data" / "robots" / f"{name}.toml")
    period = scene.joints[next(j for j in scene.joints if j.endswith("/ground"))].period
    return hx.assemble(scene), np.linspace(0.0, window or period, samples, endpoint=False)


def main() -> None:
    import pinocchio as pin

    option = next((a for a in sys.argv[1:] if a in DESCRIBED), None)
    if option is not None:
        name, samples, window = DESCRIBED[option]
        model, times = described(name, samples, window)
        out = OUT.with_name(f"{name}_rnea.npz")
    else:
        model, times, out = walking_model(), sample_times(), OUT
    result = hx.inverse_dynamics(model, times)
    # a guided robot's laws: the motion its run found
    comparison = pinocchio_rnea(hx.simulation.motion_model(model, result), result)
    weight = sum(b.mass for b in model.bodies) * float(np.linalg.norm(model.gravity))
    size = model.characteristic_length
    residual = max(np.abs(comparison.base[:, :3]).max() / weight,
                   np.abs(comparison.base[:, 3:]).max() / (weight * size))
    out.parent.mkdir(parents=True, exist_ok=True)
    note = (f"Pinocchio {pin.__version__} rnea with fext (tests/data/make_walking_fixture.py) on "
            f"the hexapod inverse dynamics of {model.name}, policy "
            f"{result.policy}; torques in joint order, base = free-flyer force then moment "
            f"(local trunk frame)")
    np.savez_compressed(
        out, times=times, joints=np.array(comparison.joints), hexapod=comparison.hexapod,
        pinocchio=comparison.pinocchio, base=comparison.base, contacts=np.array(result.contacts),
        ground_force=result.ground_force, q=comparison.q, v=comparison.v, a=comparison.a,
        pinocchio_version=np.array(pin.__version__), policy=np.array(result.policy),
        note=np.array(note))
    print(f"wrote {out.relative_to(ROOT)} ({out.stat().st_size} bytes): {times.size} samples, "
          f"{len(comparison.joints)} joints, Pinocchio {pin.__version__}")
    print(f"state conversion: joint angles (laws vs q) {comparison.angle_gap:.2e} rad, body "
          f"frames {comparison.placement_gap:.2e}, velocities and accelerations "
          f"{comparison.motion_gap:.2e} (relative)")
    print(f"largest torque {np.abs(comparison.pinocchio).max():.6g} N m; largest difference "
          f"relative to it: {comparison.difference:.3e}")
    print(f"free-flyer residual: force {np.abs(comparison.base[:, :3]).max():.3e} N, moment "
          f"{np.abs(comparison.base[:, 3:]).max():.3e} N m; relative to the weight "
          f"({weight:.4g} N) and weight x size ({size:.3g} m): {residual:.3e}")


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT / "scripts"))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    main()
