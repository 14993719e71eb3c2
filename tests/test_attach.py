"""Sub-models attached with a name prefix (six legs from one leg builder)."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod as hx
from legs import front_leg_scene

from mechanisms import solve_state


def arm(unit="m", world_joint=False):
    """A two-link arm whose first joint is on the sub-model's ground."""
    k = hx.scene.LENGTH_UNITS[unit]
    scene = hx.Scene("arm", 3, unit)
    scene.add(hx.scene.SpatialBody("upper", 0.4, np.array([1e-3, 4e-3, 4e-3]) / k**2,
                                   com=[0.1 / k, 0, 0]))
    scene.add(hx.scene.SpatialBody("lower", 0.3, np.array([1e-3, 3e-3, 3e-3]) / k**2,
                                   com=[0.1 / k, 0, 0],
                                   position=[0.2 / k, 0, 0]))
    if world_joint:
        scene.add(hx.scene.Revolute("shoulder", "ground", "upper", origin=[0, 0, 0],
                                    axis=[0, 1, 0]))
    else:
        scene.add(hx.scene.Revolute("shoulder", "ground", "upper",
                                    parent_frame=hx.spatial.Placement(np.zeros(3)), axis=[0, 1, 0]))
    scene.add(hx.scene.Revolute("elbow", "upper", "lower", origin=[0.2 / k, 0, 0], axis=[0, 1, 0]))
    scene.add(hx.scene.JointDriver("drive", "elbow", hx.scene.Harmonic(sin=[0.4], frequency=1.0)))
    scene.add(hx.scene.SpringDamper("tendon", "ground", "lower", point_a=[0.0, 0.0, 0.05 / k],
                                    point_b=[0.1 / k, 0, 0], stiffness=20.0 * k))
    return scene


def trunk_scene():
    scene = hx.Scene("robot")
    scene.add(hx.scene.SpatialBody("trunk", 5.0, [0.1, 0.2, 0.25], position=[0.0, 0.0, 0.5],
                                   rotation=hx.spatial.rotation_about_axis([0, 0, 1], 0.3)))
    scene.add(hx.scene.Fixed("weld", "ground", "trunk"))
    return scene


PLACEMENTS = {
    "L": hx.spatial.Placement([0.2, 0.1, 0.0], hx.spatial.rotation_about_axis([0, 0, 1], 1.2)),
    "R": hx.spatial.Placement([0.2, -0.1, 0.0], hx.spatial.rotation_about_axis([0, 0, 1], -1.2)),
}


def direct_scene():
    """The same robot written by hand: what attach must produce."""
    scene = trunk_scene()
    trunk = scene.bodies["trunk"].pose
    for prefix, placement in PLACEMENTS.items():
        T = trunk @ placement
        sub = arm()
        for name in ("upper", "lower"):
            b = sub.bodies[name]
            scene.add(hx.scene.SpatialBody(f"{prefix}/{name}", b.mass, b.inertia, com=b.com,
                                           position=T.transform_point(b.position),
                                           rotation=T.rotation @ b.rotation))
        scene.add(hx.scene.Revolute(f"{prefix}/shoulder", "trunk", f"{prefix}/upper",
                                    parent_frame=placement, axis=[0, 1, 0]))
        scene.add(hx.scene.Revolute(f"{prefix}/elbow", f"{prefix}/upper", f"{prefix}/lower",
                                    origin=T.transform_point([0.2, 0, 0]), rotation=T.rotation,
                                    axis=[0, 1, 0]))
        scene.add(hx.scene.JointDriver(f"{prefix}/drive", f"{prefix}/elbow",
                                       hx.scene.Harmonic(sin=[0.4], frequency=1.0)))
        scene.add(hx.scene.SpringDamper(f"{prefix}/tendon", "trunk", f"{prefix}/lower",
                                        point_a=placement.transform_point([0, 0, 0.05]),
                                        point_b=[0.1, 0, 0], stiffness=20.0))
    return scene


def _results(scene, t=0.4):
    model, q, _, v_dot, data = solve_state(scene, t)
    w = hx.joint_wrenches(model, data)
    return model, q, v_dot, w


@pytest.mark.parametrize("unit", ["m", "mm"])
@pytest.mark.parametrize("world_joint", [False, True])
def test_attached_arms_equal_the_same_robot_written_by_hand(unit, world_joint):
    scene = trunk_scene()
    for prefix, placement in PLACEMENTS.items():
        scene.attach(arm(unit, world_joint), prefix, base="trunk", placement=placement)
    assert list(scene.bodies) == ["trunk", "L/upper", "L/lower", "R/upper", "R/lower"]
    assert "R/elbow" in scene.joints and scene.joints["R/shoulder"].parent == "trunk"
    attached = _results(scene)
    direct = _results(direct_scene())
    assert attached[0].row_index == direct[0].row_index
    for a, b in zip(attached[1:3], direct[1:3], strict=True):
        assert np.allclose(a, b, rtol=1e-10, atol=1e-12)
    assert np.allclose(attached[3].force, direct[3].force, rtol=1e-10, atol=1e-10)
    assert np.allclose(attached[3].torque, direct[3].torque, rtol=1e-10, atol=1e-10)


def test_six_legs_from_one_builder():
    scene = hx.Scene("hexapod")
    scene.add(hx.scene.SpatialBody("trunk", 18.4, [0.218, 1.055, 1.226]))
    scene.add(hx.scene.Fixed("stand", "ground", "trunk"))
    for k, (prefix, y) in enumerate((("L1", 0.08), ("R1", -0.08), ("L2", 0.09), ("R2", -0.09),
                                     ("L3", 0.09), ("R3", -0.09))):
        leg = front_leg_scene(phase=0.0 if prefix in ("L1", "R2", "L3") else np.pi)
        placement = hx.spatial.Placement(
            [0.24 - 0.12 * (k // 2), y, -0.04],
            np.diag([1.0, 1.0 if y > 0 else -1.0, 1.0 if y > 0 else -1.0]))
        scene.attach(leg, prefix, base="trunk", placement=placement)
    model = hx.assemble(scene)
    assert len(model.bodies) == 37 and len(model.joints) == 37 and len(model.drivers) == 36
    data = model.create_data()
    q = hx.assemble_positions(model, data, 0.1)
    mobility = hx.degrees_of_freedom(model, data, 0.1, q)
    assert mobility["dof_with_drivers"] == 0 and mobility["redundant_rows"] == []


def test_attach_rejects_mismatches():
    scene = trunk_scene()
    with pytest.raises(hx.ModelError, match="2-D"):
        scene.attach(hx.Scene("flat", 2), "P")
    with pytest.raises(hx.ModelError, match="base body 'nobody'"):
        scene.attach(arm(), "P", base="nobody")
    with pytest.raises(hx.ModelError, match="prefix"):
        scene.attach(arm(), "bad prefix")
