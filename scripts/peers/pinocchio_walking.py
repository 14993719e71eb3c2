"""The walking hexapod's inverse dynamics by Pinocchio, as a robotics engineer would script it
(not a test; needs the optional `compare` extra: `pip install ".[compare]"`). The Pinocchio side
of ``scripts/benchmarks/bench_walking_inverse.py``; nothing here imports Pinocchio before it is
asked for.

The robot: the URDF hexapod writes of the built-in ``hexapod`` scene without its ground contacts,
the trunk welded to the URDF's root link (``urdf_text`` writes trees hanging from the ground),
read by ``pinocchio.buildModelFromUrdf`` on a free flyer: the root link, and with it the trunk,
becomes the floating base. A frame at each foot (the tarsus's ``foot`` marker) stands for the
foot link an engineer would add to the URDF.

The motion, computed before any timing as a trajectory generator would hand it over: the
trunk's pose, velocity and acceleration from hexapod's own ``q``, ``v``, ``v_dot`` (Pinocchio's
free-flyer convention: position and quaternion ``x, y, z, w`` of the base frame, velocity and
acceleration in the base frame, the acceleration the rate of that velocity), the 36 joint
angles, rates and accelerations from the gait's laws (the driver laws: the angles count from
the rest pose in both libraries), and each foot's load-sharing weight ``w`` (0 in swing) with
the list of the feet down at each sample (the gait's schedule).

The pipeline per sample, in Python:

1. ``pinocchio.rnea`` without contact forces: ``tau_0`` (6 free-flyer components, 36 joints);
2. ``computeJointJacobians`` and each stance foot's ``getFrameJacobian`` at the foot point
   (``LOCAL_WORLD_ALIGNED``, its three linear rows);
3. the feet's forces ``f`` from the base rows ``J_b^T f = tau_0[:6]`` (the ground forces balance
   the robot), by one of two policies:

   * ``least-norm``: the weighted least-norm solution, least ``sum_k |f_k|^2 / w_k``, the feet of
     weight zero left out (every foot down when all weigh zero, hexapod's rule): the force part
     of hexapod's policy, and a common choice where the distribution is not the point;
   * ``min-wrench``: hexapod's default policy itself, least ``sum_j |F_j|^2 + |T_j / l|^2`` over
     every joint's wrench plus ``sum_k |f_k|^2 / w_k``: each joint's wrench is ``data.f`` of step
     1 minus its foot's force carried to the joint origin (world axes: norms do not depend on
     axes), so the objective is one 3 x 3 block per foot; ``l`` is hexapod's characteristic
     length. It agrees with hexapod to round-off (so the numbers of both can be compared
     exactly), and costs reading every ``data.f`` and joint placement;

4. ``tau = tau_0[6:] - J_j^T f``; with every joint wrench, ``pinocchio.rnea`` again with the
   feet's forces as ``fext`` (each tarsus joint's local frame, about its origin), whose ``tau``
   it is, and ``data.f`` of the 36 joints read into an array (report convention: by the parent
   on the child, about the joint origin, in the child's joint frame).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

import hexapod as hx
from hexapod.scene import Contact, Fixed, urdf_text

#: Below this weight a foot carries nothing (hexapod's threshold for its policy).
NO_LOAD = 1e-12


def walking_urdf(scene: hx.Scene) -> tuple[str, hx.spatial.Placement]:
    """The URDF of a walking ``scene`` (its contacts left out, the trunk welded to the root
    link), and the trunk's pose in the root link's frame (the free flyer's frame)."""
    tree = hx.Scene(scene.name + "-tree", scene.dimension, scene.length_unit)
    tree.gravity = scene.gravity
    tree.add(*[e for e in scene.elements if not isinstance(e, Contact)])
    tree.add(Fixed("trunk_hold", "ground", "trunk"))
    return urdf_text(tree), tree.in_si().pose("trunk")


@dataclass
class Robot:
    """Pinocchio's model and workspace, with what the pipeline reads per sample."""

    model: object  # pinocchio.Model
    data: object  # pinocchio.Data
    joints: list[int]  # Pinocchio ids of the driven joints, hexapod's order
    v_index: np.ndarray  # their columns of v
    foot_joint: np.ndarray  # (C,) per foot: the Pinocchio id of its tarsus joint
    foot_frame: list[int]  # per foot: the frame at the foot point
    foot_point: np.ndarray  # (C, 3) per foot: the foot in the tarsus joint's frame (m)
    foot_placement: list  # per foot: the foot point's pinocchio.SE3 in that frame
    chain: np.ndarray  # (C, L) per foot: the leg's joints, trunk to tarsus (Pinocchio ids)
    length: float  # hexapod's characteristic length, the min-wrench policy's moment scale


def load_robot(urdf: str, joints: list[str], feet: list[tuple[str, np.ndarray]],
               length: float) -> Robot:
    """The robot from the URDF file ``urdf`` on a free flyer, its driven ``joints`` by name, and
    ``feet`` as (tarsus joint name, foot point in that joint's frame)."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
    ids = [model.getJointId(name) for name in joints]
    foot_joint, foot_frame, placements, chain = [], [], [], []
    for k, (name, point) in enumerate(feet):
        jid = model.getJointId(name)
        placements.append(pin.SE3(np.eye(3), np.asarray(point, dtype=float)))
        foot_frame.append(model.addFrame(pin.Frame(f"foot{k}", jid, placements[-1],
                                                   pin.FrameType.OP_FRAME)))
        foot_joint.append(jid)
        chain.append([j for j in model.supports[jid] if j > 1])  # universe and free flyer out
    return Robot(model, model.createData(), ids, np.array([model.idx_vs[j] for j in ids]),
                 np.array(foot_joint), foot_frame, np.array([p for _, p in feet], dtype=float),
                 placements, np.array(chain), float(length))


def pinocchio_motion(model: hx.Model, result: hx.InverseResult, robot: Robot,
                     trunk_pose: hx.spatial.Placement) -> tuple[np.ndarray, ...]:
    """Pinocchio's ``q`` (N, nq), ``v`` and ``a`` (N, nv) of hexapod's ``result``, and each
    foot's load-sharing weight (N, C); ``trunk_pose`` as :func:`walking_urdf` gives it."""
    import pinocchio as pin

    pm, n = robot.model, result.times.size
    trunk = next(b for b in model.bodies if b.name == "trunk")
    position, rotation = hx.body_poses(model, result.q)
    offset = trunk_pose.inverse()  # the free flyer's frame in the trunk's frame
    c, Rc = offset.position, offset.rotation
    q, v, a = np.zeros((n, pm.nq)), np.zeros((n, pm.nv)), np.zeros((n, pm.nv))
    for k in range(n):
        R, r = rotation[k, trunk.index], position[k, trunk.index]
        r_dot, omega = result.v[k, trunk.v][:3], result.v[k, trunk.v][3:]  # omega: body axes
        r_dd, omega_dot = result.v_dot[k, trunk.v][:3], result.v_dot[k, trunk.v][3:]
        origin_dot = r_dot + R @ np.cross(omega, c)
        origin_dd = r_dd + R @ (np.cross(omega_dot, c) + np.cross(omega, np.cross(omega, c)))
        base = R @ Rc
        v_local, w_local = base.T @ origin_dot, Rc.T @ omega
        q[k, :7] = np.concatenate([r + R @ c, pin.Quaternion(base).coeffs()])
        v[k, :6] = np.concatenate([v_local, w_local])
        a[k, :6] = np.concatenate([base.T @ origin_dd - np.cross(w_local, v_local),
                                   Rc.T @ omega_dot])
    w, wd, wdd = (np.asarray(x).reshape(model.n_w, n) for x in model.law_values(result.times))
    for driver in model.drivers:
        jid = pm.getJointId(model.joints[driver.joint].name)
        iq, iv = pm.idx_qs[jid], pm.idx_vs[jid]
        if driver.law < 0:  # a constant law, folded into its row
            q[:, iq], v[:, iv], a[:, iv] = driver.spec.evaluate(0.0)[0], 0.0, 0.0
        else:
            q[:, iq], v[:, iv], a[:, iv] = w[driver.law], wd[driver.law], wdd[driver.law]
    weights = np.array([np.asarray(c.weight(result.times), dtype=float).reshape(n)
                        for c in model.contacts]).T
    stance = np.array([np.asarray(c.in_stance(result.times), dtype=bool).reshape(n)
                       for c in model.contacts]).T
    unloaded = ~np.any(weights > NO_LOAD, axis=1)  # every foot down at its switch: equal shares
    weights[unloaded] = stance[unloaded]
    return q, v, a, weights


@dataclass
class Stance:
    """The feet down at one sample, from the gait's schedule (part of the motion, as the
    weights: computed before the timing)."""

    down: np.ndarray  # the feet carrying a load, in contact order
    loaded: set  # the same, as a set
    weights: np.ndarray  # their weights
    rows: np.ndarray  # their weights, each repeated for the three rows of its foot
    frames: list[int]  # their foot frames


def schedule(weights: np.ndarray, foot_frame: list[int]) -> list[Stance]:
    """The feet down at every sample, from their weights (N, C)."""
    out = []
    for w in weights:
        down = np.flatnonzero(w > NO_LOAD)
        out.append(Stance(down, set(down.tolist()), w[down], np.repeat(w[down], 3),
                          [foot_frame[i] for i in down.tolist()]))
    return out


def _least_norm(robot: Robot, tau0, J, stance: Stance) -> np.ndarray:
    """The least ``sum_k |f_k|^2 / w_k`` with ``J_b^T f = tau_0[:6]``."""
    Jb = J[:, :6]
    WJ = stance.rows[:, None] * Jb
    return WJ @ np.linalg.solve(Jb.T @ WJ, tau0[:6])


def _cross(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Row-wise cross products of (n, 3) arrays (``np.cross`` costs far more on small ones)."""
    return x[:, [1, 2, 0]] * y[:, [2, 0, 1]] - x[:, [2, 0, 1]] * y[:, [1, 2, 0]]


def _min_wrench(robot: Robot, tau0, J, stance: Stance) -> np.ndarray:
    """hexapod's least-wrench policy (module docstring), from ``data.f`` of the last RNEA: per
    foot ``H f - g`` of its leg's wrenches, then the balance rows by their multipliers."""
    data, scale, down = robot.data, 1.0 / robot.length**2, stance.down
    wrench = np.array([x.vector for x in data.f])  # local frames, about the joint origins
    pose = np.array([x.homogeneous for x in data.oMi])
    ids = robot.chain[down].reshape(-1)  # the stance legs' joints, foot by foot
    R, origin = pose[ids, :3, :3], pose[ids, :3, 3]
    force = np.einsum("nij,nj->ni", R, wrench[ids, :3])  # world axes
    moment = np.einsum("nij,nj->ni", R, wrench[ids, 3:])
    tarsus = pose[robot.foot_joint[down]]
    foot = np.einsum("sij,sj->si", tarsus[:, :3, :3], robot.foot_point[down]) + tarsus[:, :3, 3]
    s, links = len(down), robot.chain.shape[1]
    d = (np.repeat(foot, links, axis=0) - origin)
    g = (force + scale * _cross(moment, d)).reshape(s, links, 3).sum(axis=1)
    dd = (d[:, :, None] * d[:, None, :]).reshape(s, links, 3, 3).sum(axis=1)
    diagonal = links + 1.0 / stance.weights + scale * np.trace(dd, axis1=1, axis2=2)
    H = diagonal[:, None, None] * np.eye(3) - scale * dd
    Hinv = np.linalg.inv(H)
    Jb = J[:, :6]
    HJ = np.einsum("sij,sjk->sik", Hinv, Jb.reshape(s, 3, 6)).reshape(3 * s, 6)
    Hg = np.einsum("sij,sj->si", Hinv, g).reshape(-1)
    mu = np.linalg.solve(Jb.T @ HJ, tau0[:6] - Jb.T @ Hg)
    return Hg + HJ @ mu


@dataclass
class Run:
    """One pass of the pipeline over the samples."""

    tau: np.ndarray  # (N, J) joint torques, hexapod's joint order
    forces: np.ndarray  # (N, C, 3) the ground's force on each foot, world axes
    base: np.ndarray  # (N, 6) the free flyer's generalized force left (balance: zero)
    wrenches: np.ndarray | None  # (N, J, 6) force then moment of every joint, or None
    seconds: float  # CPU time of the sample loop (time.process_time)


def run_pipeline(robot: Robot, q, v, a, weights, policy: str = "least-norm",
                 wrenches: bool = False, forces: np.ndarray | None = None) -> Run:
    """The pipeline over every sample (module docstring); ``forces`` (N, C, 3), when given,
    replaces step 3 (hexapod's own ground forces: a check of the model and the motion)."""
    import pinocchio as pin

    pm, data = robot.model, robot.data
    share = {"least-norm": _least_norm, "min-wrench": _min_wrench}[policy]
    frame, n, feet = pin.LOCAL_WORLD_ALIGNED, q.shape[0], len(robot.foot_joint)
    tau = np.zeros((n, len(robot.joints)))
    ground, base = np.zeros((n, feet, 3)), np.zeros((n, 6))
    joint_wrenches = np.zeros((n, len(robot.joints), 6)) if wrenches else None
    fext = pin.StdVec_Force()
    fext.extend([pin.Force.Zero() for _ in range(pm.njoints)])
    nothing, zero = pin.Force.Zero(), np.zeros(3)
    feet_down = schedule(weights, robot.foot_frame)
    begun = time.process_time()
    for k in range(n):
        stance = feet_down[k]
        down = stance.down
        tau0 = pin.rnea(pm, data, q[k], v[k], a[k]).copy()
        pin.computeJointJacobians(pm, data, q[k])
        J = np.vstack([pin.getFrameJacobian(pm, data, i, frame)[:3] for i in stance.frames])
        f = share(robot, tau0, J, stance) if forces is None \
            else forces[k, down].reshape(-1)
        ground[k, down] = f.reshape(-1, 3)
        if not wrenches:
            out = tau0 - J.T @ f
        else:
            for i in range(feet):  # the foot's force at the foot, in its joint's frame
                jid = int(robot.foot_joint[i])
                fext[jid] = nothing if i not in stance.loaded else \
                    robot.foot_placement[i].act(pin.Force(data.oMi[jid].rotation.T @ ground[k, i],
                                                          zero))
            out = pin.rnea(pm, data, q[k], v[k], a[k], fext)
            joint_wrenches[k] = np.array([x.vector for x in data.f])[robot.joints]
        tau[k], base[k] = out[robot.v_index], out[:6]
    return Run(tau, ground, base, joint_wrenches, time.process_time() - begun)
