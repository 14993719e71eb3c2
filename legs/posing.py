"""Where a scene's bodies start: at joint angles counted from their zero (a tree, posed through
its joints' frames), or at the start of the scene's own motion, as the engine's kinematics
solves it.

A scene's written pose is the initial guess of every solve, and more: the characteristic length
of the ground-force policies (:func:`hexapod.assemble`) is measured on it. A walking scene is
therefore written at the pose its motion has at ``t = 0`` (:func:`at_start`), found by the same
Newton solve that places the legs along the motion, so that how it was first posed leaves no
trace in its results.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

import hexapod as hx
from hexapod import Scene
from hexapod.scene import GROUND
from hexapod.spatial import Placement, rotation_about_axis


def moved(scene: Scene, poses: dict[str, Placement]) -> Scene:
    """A copy of ``scene`` with each body's reference frame at ``poses[name]`` (scene units),
    its joints' frames kept on their bodies as they are at its current pose, every other
    element and setting unchanged."""
    elements = []
    for body in scene.bodies.values():
        pose = poses.get(body.name, body.pose)
        elements.append(replace(body, position=pose.position, rotation=pose.rotation))
    for joint in scene.joints.values():
        parent_frame, child_frame = scene.joint_frames(joint)
        elements.append(replace(joint, origin=None, rotation=None, parent_frame=parent_frame,
                                child_frame=child_frame))
    placed = set(scene.bodies) | set(scene.joints)
    return scene.with_elements(elements + [e for e in scene.elements if e.name not in placed])


def posed(scene: Scene, angles: dict[str, float], lift: float = 0.0) -> Scene:
    """A copy of the tree ``scene`` with its bodies moved to the pose of the revolute joints'
    ``angles`` (rad, from the joints' zero; others at zero), the bodies no joint moves raised
    by ``lift`` (scene units): the joint frames stay on the bodies as at zero, so the angles
    still count from there."""
    children = {j.child for j in scene.joints.values()}
    poses = {GROUND: Placement.identity(3)}
    raised = Placement(np.array([0.0, 0.0, lift]))
    poses.update({b: raised @ scene.pose(b) for b in scene.bodies if b not in children})
    pending = list(scene.joints.values())
    while pending:
        joint = next(j for j in pending if j.parent in poses)  # tree order
        pending.remove(joint)
        parent_frame, child_frame = scene.joint_frames(joint)
        turn = (Placement(np.zeros(3), rotation_about_axis(joint.unit_axis(3),
                                                           angles.get(joint.name, 0.0)))
                if joint.kind == "revolute" else Placement.identity(3))
        poses[joint.child] = poses[joint.parent] @ parent_frame @ turn @ child_frame.inverse()
    return moved(scene, poses)


def at_start(scene: Scene, t: float = 0.0) -> Scene:
    """A copy of ``scene`` with its bodies where its motion has them at ``t``: the engine's
    Newton solve of its constraints and drivers (its guides' first, for a guided scene) from
    the pose it is written at, as its inverse dynamics solves its first sample. Where no pose
    satisfies them (guides out of the joints' reach), ``scene`` itself: the analysis of it
    says so, naming the guides, the time and how far off they are."""
    model = hx.assemble(scene)
    try:  # the positions alone: the inverse dynamics' first sample less its dynamics
        q = hx.assemble_positions(model, model.create_data(), float(t))
    except hx.AssemblyError:
        return scene
    positions, rotations = hx.body_poses(model, q[None])
    poses = {}
    for k, info in enumerate(model.bodies):
        rotation = rotations[0, k]
        centre = positions[0, k] / scene.unit  # the model is in SI
        poses[info.name] = Placement(centre - rotation @ scene.bodies[info.name].com, rotation)
    return moved(scene, poses)
