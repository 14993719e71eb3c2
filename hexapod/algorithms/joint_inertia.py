"""The inertia a joint's actuator sees: the **reflected inertia** of each drivable joint at a
pose, the bodies beyond the joint turning (or sliding) about its axis as one rigid body, the
other joints locked and the parent side held still. It is the diagonal entry of the
joint-space mass matrix of a tree, and what a gain rule tunes a servo on
(``kp = I w^2``, ``kd = 2 I w``: critically damped at the bandwidth ``w``).

About a revolute joint with world axis ``a`` through ``p``: ``I = sum_b a . J_b a + m_b |a x
(r_b - p)|^2`` over the bodies ``b`` beyond it (``J_b`` the inertia about the centre of mass
``r_b``, world axes); along a prismatic joint, ``sum_b m_b``. "Beyond" is the child's side
when the joint is cut; a joint inside a closed loop has no such side and no reflected inertia
of its own. A walking robot's scheduled feet (contact joints) are left out: the inertia is the
one a joint sees with its foot in the air, as servos are tuned.
"""

from __future__ import annotations

import numpy as np

from hexapod.errors import HexapodError
from hexapod.model.model import Model


def reflected_inertias(model: Model, q: np.ndarray) -> dict[str, float]:
    """Each drivable joint's reflected inertia at the positions ``q``.

    Parameters
    ----------
    model : Model
    q : ndarray, shape (n_q,)

    Returns
    -------
    dict of str to float
        Joint name to its inertia (kg m^2 about a revolute joint's axis, kg along a prismatic
        one's), in the model's order.

    Raises
    ------
    HexapodError
        A drivable joint lies in a closed loop (cutting it leaves its child connected to its
        parent).
    """
    poses = [model.body_pose(q, body.index) for body in model.bodies]
    out = {}
    for joint in model.joints:
        if not joint.type.drivable or (joint.axis is None and model.dimension == 3):
            continue
        beyond = _beyond(model, joint)
        if joint.type.coordinate_unit != "angle":
            out[joint.name] = float(sum(model.bodies[b].mass for b in beyond))
            continue
        child = poses[joint.child]
        frame = child.rotation @ joint.child_frame.rotation
        origin = child.position + child.rotation @ joint.child_frame.position
        axis = frame @ np.asarray(joint.axis, dtype=float) if model.dimension == 3 else None
        total = 0.0
        for b in beyond:
            body, pose = model.bodies[b], poses[b]
            arm = pose.position - origin
            if model.dimension == 2:  # about the plane's normal
                spin = float(body.inertia[0, 0]) if body.inertia.size else 0.0
                total += spin + body.mass * float(arm @ arm)
            else:
                J = (pose.rotation @ body.inertia @ pose.rotation.T if body.inertia.size
                     else np.zeros((3, 3)))
                total += float(axis @ J @ axis) + body.mass * float(
                    np.sum(np.cross(axis, arm) ** 2))
        out[joint.name] = total
    return out


def _beyond(model: Model, joint) -> list[int]:
    """The bodies on the child's side of ``joint`` once it is cut (the child included)."""
    neighbours: dict[int, list[int]] = {}
    for other in model.joints:
        if other.index != joint.index and other.kind != "contact":
            neighbours.setdefault(other.parent, []).append(other.child)
            neighbours.setdefault(other.child, []).append(other.parent)
    seen, stack = {joint.child}, [joint.child]
    while stack:
        for b in neighbours.get(stack.pop(), []):
            if b == joint.parent or b < 0:  # back to the parent, or held by the ground
                raise HexapodError(f"joint '{joint.name}' closes a loop: the bodies beyond "
                                   "it are not its child's alone, and it has no reflected "
                                   "inertia of its own")
            if b not in seen:
                seen.add(b)
                stack.append(b)
    return sorted(seen)


def critical_gains(model: Model, q: np.ndarray, bandwidth: float) -> tuple[dict, dict]:
    """Servo gains by the rule "critically damped on each joint's reflected inertia":
    ``kp = I w^2`` and ``kd = 2 I w`` at ``w = 2 pi bandwidth``, ``I`` the joint's reflected
    inertia at the positions ``q`` (:func:`reflected_inertias`): each joint alone would follow
    a step of its target as ``1 - (1 + w t) e^(-w t)``.

    Parameters
    ----------
    model : Model
    q : ndarray, shape (n_q,)
    bandwidth : float
        Hz, positive.

    Returns
    -------
    tuple of dict
        ``(kp, kd)``: joint name to N m/rad and N m s/rad (N and N s/m along a prismatic
        joint), SI.
    """
    if not (np.isfinite(bandwidth) and bandwidth > 0):
        raise HexapodError(f"a bandwidth must be a positive number of Hz, got {bandwidth}")
    w = 2 * np.pi * float(bandwidth)
    inertia = reflected_inertias(model, q)
    return ({j: i * w**2 for j, i in inertia.items()}, {j: 2 * i * w for j, i in inertia.items()})
