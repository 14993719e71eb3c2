"""Scene checks built in Python: each problem is found, named, and reported once."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod as hx
from hexapod.spatial import is_rotation


def _problems(scene):
    with pytest.raises(hx.ModelError) as info:
        scene.validate()
    return [str(p) for p in info.value.problems]


def test_every_problem_is_listed_once():
    scene = hx.Scene("bad", 2)
    scene.add(hx.scene.Particle("p", 1.0, position=[0.0, 1.0]))
    scene.add(hx.scene.PlanarBody("b", -1.0, 0.0, markers={"bad name": [0.0, 0.0]}))
    scene.add(hx.scene.Revolute("pin", "ground", "p"))
    scene.add(hx.scene.JointDriver("drive", "pin", 0.3))
    scene.add(hx.scene.AppliedTorque("twist", "p", [1.0]))
    scene.add(hx.scene.AppliedForce("on_ground", "ground", [1.0, 0.0]))
    problems = _problems(scene)
    expected = ["mass): must be positive", "inertia): must be positive",
                "'bad name' is not a valid marker name", "joins a particle, which has no angle",
                "a torque on it does nothing", "a load on the ground does nothing"]
    for text in expected:
        assert sum(text in p for p in problems) == 1, (text, problems)
    assert len(problems) == len(expected)


def test_rotation_tolerance_is_absolute():
    R = np.diag([1 + 4e-6, 1 / (1 + 4e-6), 1.0])  # det 1, but not orthonormal to 1e-6
    assert not is_rotation(R)
    assert is_rotation(np.round(hx.spatial.rotation_from_rpy(0.3, -0.2, 1.1), 7))
    assert not is_rotation(np.diag([1.0, 1.0, -1.0]))


def test_spline_with_times_too_close_is_reported():
    law = hx.scene.Spline([0.0, 1e-320, 2e-320, 1.0], [0.0, 1.0, 2.0, 3.0])
    assert law.problems() and "interpolated" in law.problems()[0]


@pytest.mark.parametrize("dimension", [2, 3])
def test_velocity_is_that_of_the_reference_origin(dimension):
    """Like ``position``, ``velocity`` belongs to the reference frame; the centre of mass moves
    with it plus the rotation about it."""
    com = np.array([0.3, -0.1, 0.2])[:dimension]
    if dimension == 3:
        body = hx.scene.SpatialBody("b", 1.0, [1, 1, 1], com=com, velocity=[1.0, 2.0, 3.0],
                                    angular_velocity=[0.0, 0.0, 2.0])
        arm_velocity = np.cross([0, 0, 2.0], com)
    else:
        body = hx.scene.PlanarBody("b", 1.0, 1.0, com=com, velocity=[1.0, 2.0],
                                   angular_velocity=2.0)
        arm_velocity = 2.0 * np.array([-com[1], com[0]])
    scene = hx.Scene("v", dimension)
    scene.add(body)
    model = hx.assemble(scene)
    assert np.allclose(model.v0[:dimension], body.velocity + arm_velocity)


def test_particles_need_a_position():
    with pytest.raises(TypeError):
        hx.scene.Particle("p", 1.0)  # its dimension comes from its position
