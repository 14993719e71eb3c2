"""The trunk planned with the whole robot (legs/balance.py): the zero-moment point it reads
from every body's momentum against the centre of pressure of the ground forces that balance
them (written out here), the guides' laws swapped into a built kinematics against a fresh
assembly, and the plan it gives carrying a walk the lumped plan alone does not."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from robots import ROBOTS, described_walk

import hexapod as hx
from legs.balance import zero_moment_point

TIMES = np.linspace(0.0, 1.2, 9)


@pytest.fixture(scope="module")
def quadruped():
    scene = hx.load_scene(ROBOTS / "quadruped.toml")
    model = hx.assemble(scene)
    return scene, model, hx.inverse_dynamics(model, TIMES)


def _centre_of_pressure(model, result, normal) -> np.ndarray:
    """The feet's positions weighted by their ground forces' normal components (N, 2)."""
    positions, rotations = hx.body_poses(model, result.q)
    feet = []
    for name in result.contacts:
        joint = model.joints[model.joint_index[name]]
        feet.append(positions[:, joint.child]
                    + rotations[:, joint.child] @ joint.child_frame.position)
    pushed = result.ground_force @ normal
    return ((pushed[..., None] * np.stack(feet, axis=1)).sum(axis=1)
            / pushed.sum(axis=1)[:, None])[:, :2]


def test_the_zero_moment_point_is_the_centre_of_pressure_of_the_ground_forces(quadruped):
    """Whatever the policy shares among the feet, the ground forces balance every body's
    motion: their centre of pressure is the robot's zero-moment point (1e-9 m), flat and on a
    slope's plane (its axes), where the feet's forces along its normal weigh them."""
    _, model, result = quadruped
    flat = zero_moment_point(model, result, np.eye(3))
    assert np.abs(flat - _centre_of_pressure(model, result, [0.0, 0.0, 1.0])).max() < 1e-9
    sloped = hx.assemble(hx.load_scene(ROBOTS / "quadruped-slope.toml"))
    walk = hx.inverse_dynamics(sloped, TIMES)
    axes = sloped.ground.terrain.axes()
    found = zero_moment_point(sloped, walk, axes)
    assert np.abs(found - _centre_of_pressure(sloped, walk, axes[2])).max() < 1e-9


def test_a_guide_s_law_swapped_into_built_kinematics_gives_a_fresh_assembly_s_motion(
        quadruped):
    """The trunk's sway changed (its harmonics scaled by 1.05) and swapped into the guides'
    kinematics already built (``with_laws``, sharing its builds) moves every body as the
    scene assembled afresh with it does (1e-12 m)."""
    scene, model, before = quadruped
    kinematics = model.guidance.kinematics
    law = scene.drivers["trunk/x"].law
    swayed = dataclasses.replace(law, cos=tuple(1.05 * c for c in law.cos),
                                 sin=tuple(1.05 * c for c in law.sin))
    index = next(d.law for d in kinematics.drivers if d.name == "trunk/x")
    laws = list(kinematics.laws)
    laws[index] = swayed
    swapped = kinematics.with_laws(tuple(laws), "swayed", share_built=True)
    scene.drivers["trunk/x"].law = swayed
    fresh = hx.inverse_dynamics(hx.assemble(scene), TIMES)
    moved = hx.inverse_dynamics(swapped, TIMES)
    assert np.abs(fresh.q - before.q).max() > 1e-4  # the trunk moves otherwise
    assert np.abs(moved.q - fresh.q).max() < 1e-12
    assert np.abs(moved.v_dot - fresh.v_dot).max() < 1e-9 * np.abs(fresh.v_dot).max()


def test_the_whole_body_plan_carries_the_ankled_quadruped():
    """data/robots/quadruped-ankles.toml plans its trunk with the whole robot: the friction
    policy carries its stride at every sample (the lumped plan alone leaves a fore foot
    pulling after the fore feet touch down: scripts/studies/trunk_planning.py)."""
    _, _, result, _ = described_walk("quadruped-ankles")
    assert result.feasible
