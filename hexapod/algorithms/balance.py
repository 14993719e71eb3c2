"""Free-body balance of reported joint wrenches: how well each body's Newton-Euler equations
close with them.

For body ``b``, with the wrenches ``W_k`` of the report (by the parent on the child, about the
joint origin) taken back to world axes and to the body's centre of mass,

    sum_{k: b is the child} W_k  -  sum_{k: b is the parent} W_k  +  loads
        =  (m a,  A (J' omega_dot' + omega' x J' omega'))

where the loads are gravity, applied forces and the springs between bodies (those acting across
a joint are part of that joint's wrench). The joint frames are rebuilt here from the bodies'
poses and the joints' frames, not taken from the solver, so a wrong rotation or moment point in
a report shows as a residual; a consistent report leaves round-off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.algorithms.kinematics import body_poses
from hexapod.model.model import GROUND_INDEX, Model


@dataclass(frozen=True)
class BodyBalance:
    """Residuals of every body's equations over the samples.

    Attributes
    ----------
    bodies : tuple of str
        The bodies' names, in model order.
    force, moment : ndarray (N, n_bodies)
        Norm of the unbalanced force (N) and moment about the centre of mass (N m).
    force_scale, moment_scale : ndarray (n_bodies,)
        The largest force and moment term of each body's equations over the samples, the scale
        the residuals are relative to.
    """

    bodies: tuple[str, ...]
    force: np.ndarray
    moment: np.ndarray
    force_scale: np.ndarray
    moment_scale: np.ndarray

    def relative(self) -> np.ndarray:
        """Worst residual of each body over the samples, relative to its scale (n_bodies,)."""
        tiny = np.finfo(float).tiny
        return np.maximum(self.force.max(axis=0) / np.maximum(self.force_scale, tiny),
                          self.moment.max(axis=0) / np.maximum(self.moment_scale, tiny))


def _embed(body_kind: str, g: np.ndarray, rotation: np.ndarray):
    """Force and moment (world, 3-D; moment about the centre of mass) of generalized forces
    ``g`` (N, dofs) of one body."""
    n = g.shape[0]
    if body_kind == "spatial":
        return g[:, :3], np.einsum("nab,nb->na", rotation, g[:, 3:])
    force, moment = np.zeros((n, 3)), np.zeros((n, 3))
    if body_kind == "planar":
        force[:, :2], moment[:, 2] = g[:, :2], g[:, 2]
    else:
        force[:, :g.shape[1]] = g
    return force, moment


def body_balance(model: Model, times: np.ndarray, q: np.ndarray, v: np.ndarray,
                 v_dot: np.ndarray, force: np.ndarray, torque: np.ndarray,
                 frame: str = "joint") -> BodyBalance:
    """Balance of every body under the joint wrenches ``force``, ``torque`` (N, n_joints, 3),
    given about the joint origins in the joint frames (``frame="joint"``) or world axes.

    Parameters
    ----------
    model : Model
    times : ndarray, shape (N,)
        s.
    q, v, v_dot : ndarray, shape (N, n_q), (N, n_v), (N, n_v)
        The motion at the samples.
    force, torque : ndarray, shape (N, n_joints, 3)
        The joint wrenches (N, N m), e.g. an :class:`InverseResult`'s.
    frame : {"joint", "world"}
        Their axes.

    Returns
    -------
    BodyBalance
    """
    w = model.law_values(np.asarray(times, dtype=float))[0].T
    inertial = v_dot @ model.mass.dense().T
    loads = model.call_samples("Q", q=q, v=v, w=w)
    if model.Q_across is not None:
        loads = loads - model.call_samples("Q_across", q=q, v=v, w=w).sum(axis=2)
    position, rotation = body_poses(model, q)
    n, n_b = q.shape[0], len(model.bodies)
    force_sum, moment_sum = np.zeros((n, n_b, 3)), np.zeros((n, n_b, 3))
    force_scale, moment_scale = np.zeros(n_b), np.zeros(n_b)

    def add(b, f, m, *parts):  # a term of body b's equations: f (N, 3), m about its centre
        # (N, 3), the sum of ``parts`` when given: they, not their sum, set the moment's scale
        # (a joint's torque and its force's moment may cancel: an arm turning steadily)
        if model.bodies[b].kind == "particle":  # no moment equation (only round-off there)
            m, parts = np.zeros_like(m), ()
        force_sum[:, b] += f
        moment_sum[:, b] += m
        force_scale[b] = max(force_scale[b], np.linalg.norm(f, axis=1).max(initial=0.0))
        for part in parts or (m,):
            moment_scale[b] = max(moment_scale[b],
                                  np.linalg.norm(part, axis=1).max(initial=0.0))

    for b, body in enumerate(model.bodies):
        f, m = _embed(body.kind, inertial[:, body.v], rotation[:, b])
        add(b, -f, -m)
        f, m = _embed(body.kind, loads[:, body.v], rotation[:, b])
        add(b, f, m)
    for k, joint in enumerate(model.joints):
        frame_position = joint.child_frame.position
        frame_position = np.concatenate([frame_position, np.zeros(3 - frame_position.size)])
        frame_rotation = np.eye(3)
        frame_rotation[:joint.child_frame.rotation.shape[0], :joint.child_frame.rotation.shape[1]] \
            = joint.child_frame.rotation
        if joint.child == GROUND_INDEX:
            origin = np.tile(frame_position, (n, 1))
            R = np.tile(frame_rotation, (n, 1, 1))
        else:
            origin = position[:, joint.child] + rotation[:, joint.child] @ frame_position
            R = rotation[:, joint.child] @ frame_rotation
        f, t = force[:, k], torque[:, k]
        if frame == "joint":
            f, t = np.einsum("nab,nb->na", R, f), np.einsum("nab,nb->na", R, t)
        for body, sign in ((joint.child, 1.0), (joint.parent, -1.0)):
            if body != GROUND_INDEX:
                arm = origin - position[:, body]
                lever = np.cross(arm, f)
                add(body, sign * f, sign * (t + lever), t, lever)
    return BodyBalance(tuple(b.name for b in model.bodies),
                       np.linalg.norm(force_sum, axis=2), np.linalg.norm(moment_sum, axis=2),
                       force_scale, moment_scale)
