"""Scene files: the example files, the examples of docs/scene-format.md, conventions and length
units. Damaged files and error reporting: test_scene_files_errors.py."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scene_documents import (
    ROOT,
    SCENE_FILES,
    SCENES,
    assert_close,
    crane,
    four_bar,
    planar_mechanism,
    seed002,
    state_results,
    write_scene,
)

import hexapod
from hexapod.scene.reader import read_scene

DOC = ROOT / "docs" / "scene-format.md"


def doc_examples() -> list[str]:
    return re.findall(r"^```toml\n(.*?)^```", DOC.read_text(encoding="utf-8"), re.S | re.M)


# ------------------------------------------------------------------ the example files

def test_example_files_are_there():
    names = {p.name for p in SCENE_FILES}
    assert {"pendulum.toml", "double_pendulum_planar.toml", "four_bar_3d.toml",
            "closed_pendulum_seed002.toml"} <= names


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: p.name)
def test_scene_file_loads_validates_and_assembles(path):
    scene = read_scene(path)
    scene.validate()
    model = hexapod.assemble(scene)
    if any(f.contact is not None for f in model.forces):
        # unilateral contacts: no analysis at an instant (their forces are a contact
        # scheme's), said so; a few steps of the scheme instead
        with pytest.raises(hexapod.HexapodError, match="unilateral contacts"):
            state_results(model, 0.0)
        result = hexapod.simulate(model, 0.01, step=1e-3)
        assert result.success and np.all(np.isfinite(result.contact_forces))
        return
    results = state_results(model, 0.0)
    assert np.all(np.isfinite(results["v_dot"]))
    assert np.all(np.isfinite(results["force"])) and np.all(np.isfinite(results["torque"]))


def test_doc_has_examples():
    assert len(doc_examples()) >= 5


@pytest.mark.parametrize("index", range(len(doc_examples())))
def test_doc_example_loads_and_assembles(index, tmp_path):
    path = write_scene(tmp_path, f"example{index}", doc_examples()[index])
    model = hexapod.assemble(read_scene(path))
    results = state_results(model, 0.0)
    assert np.all(np.isfinite(results["v_dot"]))


def test_pendulum_closed_form():
    """theta_dd = m g l cos(theta) / I_O about +y, and the pivot pushes the rod up."""
    model = hexapod.assemble(read_scene(SCENES / "pendulum.toml"))
    r = state_results(model, 0.0)
    m, g, l, inertia = 1.0, 9.81, 0.5, 0.0833 + 0.25
    theta_dd = m * g * l / inertia
    assert r["v_dot"][4] == pytest.approx(theta_dd, rel=1e-12)  # omega'_y
    np.testing.assert_allclose(r["force"][0], [0.0, 0.0, m * (g - l * theta_dd)], atol=1e-12)


def test_double_pendulum_planar():
    scene = read_scene(SCENES / "double_pendulum_planar.toml")
    assert scene.dimension == 2
    assert [type(b) for b in scene.bodies.values()] == [hexapod.scene.PlanarBody] * 2
    model = hexapod.assemble(scene)
    data = model.create_data()
    q = hexapod.assemble_positions(model, data)
    assert hexapod.degrees_of_freedom(model, data, 0.0, q)["dof"] == 2


def test_four_bar_3d_has_three_redundant_rows():
    scene = read_scene(SCENES / "four_bar_3d.toml")
    joints = list(scene.joints.values())
    assert [j.kind for j in joints] == ["revolute"] * 4
    assert all(np.allclose(j.axis, [0.0, 0.0, 1.0]) and j.rotation is None for j in joints)
    assert set(scene.drivers) == {"crank_motor"}
    assert isinstance(scene.drivers["crank_motor"].law, hexapod.scene.Harmonic)
    model = hexapod.assemble(scene)
    data = model.create_data()
    q = hexapod.assemble_positions(model, data)
    mobility = hexapod.degrees_of_freedom(model, data, 0.0, q)
    assert mobility["dof"] == 1 and mobility["dof_with_drivers"] == 0
    assert len(mobility["redundant_rows"]) == 3
    # the redundant rows belong to the loop-closing joint, the last one
    assert all(name.startswith("D/") for name in mobility["redundant_rows"])
    # links of plausible size: crank 0.1 m, coupler 0.5 m, rocker 0.4 m, frame 0.4 m
    pivots = {j.name: j.origin for j in joints}
    lengths = [np.linalg.norm(pivots[a] - pivots[b]) for a, b in ("AB", "BC", "DC", "AD")]
    np.testing.assert_allclose(lengths, [0.1, 0.5, 0.4, 0.4], atol=1e-12)


def test_closed_pendulum_seed002():
    scene = read_scene(SCENES / "closed_pendulum_seed002.toml")
    assert scene.length_unit == "dm" and scene.dimension == 2
    np.testing.assert_allclose(scene.gravity, [0.0, 98.1])
    bodies = scene.bodies
    assert {n: type(b) for n, b in bodies.items()} == {"m1": hexapod.scene.Particle,
                                                       "m2": hexapod.scene.Particle}
    assert bodies["m1"].mass == 2.0 and bodies["m2"].mass == 1.0
    np.testing.assert_array_equal(bodies["m1"].position, [4.0, 4.0])
    np.testing.assert_array_equal(bodies["m2"].position, [12.0, 5.0])
    # the rigid links: distance joints whose lengths are the initial distances (dm)
    lengths = {}
    for joint in scene.joints.values():
        assert joint.kind == "distance"
        parent = scene.pose(joint.parent).transform_point(
            scene.frame(joint.parent, joint.parent_frame).position)
        child = scene.pose(joint.child).transform_point(
            scene.frame(joint.child, joint.child_frame).position)
        lengths[joint.name] = np.linalg.norm(child - parent)
    assert lengths == pytest.approx({"rod1": 5.657, "rod2": 7.071, "coupler": 8.062}, abs=5e-4)
    anchors = {j.name: tuple(j.parent_frame.position) for j in scene.joints.values()
               if j.parent == hexapod.scene.GROUND}
    assert anchors == {"rod1": (0.0, 0.0), "rod2": (7.0, 0.0)}

    model = hexapod.assemble(scene)
    np.testing.assert_allclose(model.gravity, [0.0, 9.81], rtol=1e-15)  # SI
    np.testing.assert_allclose(model.call("phi", q=model.q0), 0.0, atol=1e-15)
    data = model.create_data()
    q = hexapod.assemble_positions(model, data)
    assert hexapod.degrees_of_freedom(model, data, 0.0, q)["dof"] == 1
    # released at rest with both rods at 45 degrees: each mass starts as a free pendulum
    # (a1 = a2 = g/2 (-1, 1), so the coupler carries no force) with rod tension m g cos 45
    r = state_results(model, 0.0)
    np.testing.assert_allclose(r["v_dot"], 9.81 / 2 * np.array([-1.0, 1.0, -1.0, 1.0]),
                               atol=1e-12)
    tension = np.linalg.norm(r["force"], axis=1)
    np.testing.assert_allclose(tension, [2 * 9.81 / np.sqrt(2), 9.81 / np.sqrt(2), 0.0],
                               atol=1e-12)


# ------------------------------------------------------------------ conventions

def test_rotation_forms_and_conventions(tmp_path):
    roll, pitch, yaw = 0.3, -0.4, 1.1

    def rot(axis, a):
        return hexapod.spatial.rotation_about_axis(np.eye(3)[axis], a)

    expected = rot(2, yaw) @ rot(1, pitch) @ rot(0, roll)  # URDF: Rz(yaw) Ry(pitch) Rx(roll)
    p = hexapod.spatial.euler_parameters_from_rotation(expected)
    assert p[0] > 0  # scalar first
    body = {"mass": 1.0, "inertia": [1.0, 1.0, 1.0]}
    document = {"body": [
        {"name": "rpy", **body, "rotation": {"rpy": [roll, pitch, yaw]}},
        {"name": "quaternion", **body, "rotation": {"quaternion": list(2.0 * p)}},  # normalised
        {"name": "matrix", **body, "rotation": {"matrix": expected.tolist()}},
        {"name": "z_quarter_q", **body, "rotation": {"quaternion": [math.cos(0.25 * math.pi), 0,
                                                                    0, math.sin(0.25 * math.pi)]}},
        {"name": "z_quarter_a", **body, "rotation": {"axis": [0, 0, 2.0], "angle": math.pi / 2}},
    ]}
    scene = read_scene(write_scene(tmp_path, "rotations", document))
    for name in ("rpy", "quaternion", "matrix"):
        np.testing.assert_allclose(scene.bodies[name].rotation, expected, atol=1e-14)
    quarter = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    for name in ("z_quarter_q", "z_quarter_a"):
        np.testing.assert_allclose(scene.bodies[name].rotation, quarter, atol=1e-15)


def test_default_gravity_is_converted_to_the_length_unit(tmp_path):
    body = {"name": "b", "mass": 1.0, "inertia": 1.0}
    for unit, factor in (("m", 1.0), ("dm", 10.0), ("cm", 100.0), ("mm", 1000.0)):
        scene = read_scene(write_scene(tmp_path, unit, {
            "scene": {"dimension": 2, "length_unit": unit}, "body": [body]}))
        np.testing.assert_allclose(scene.gravity, [0.0, -9.81 * factor], rtol=1e-15)
        np.testing.assert_allclose(hexapod.assemble(scene).gravity, [0.0, -9.81], rtol=1e-14)


# ------------------------------------------------------------------ length units

@pytest.mark.parametrize("builder, gravity", [
    (crane, True), (crane, False), (four_bar, True), (four_bar, False), (seed002, True),
    (planar_mechanism, True), (planar_mechanism, False),
], ids=lambda x: x.__name__ if callable(x) else ("g-given" if x else "g-default"))
@pytest.mark.parametrize("t", [0.0, 0.3])
def test_metres_and_decimetres_give_the_same_si_results(tmp_path, builder, gravity, t):
    results = {}
    for unit, k in (("m", 1.0), ("dm", 10.0)):
        path = write_scene(tmp_path, f"{builder.__name__}-{unit}", builder(k, unit, gravity))
        scene = read_scene(path)
        assert scene.length_unit == unit
        results[unit] = state_results(hexapod.assemble(scene), t)
    m, dm = results["m"], results["dm"]
    np.testing.assert_array_equal(m["redundant"], dm["redundant"])
    for key in ("q", "v", "v_dot", "force", "torque", "effort", "driver_efforts"):
        assert_close(key, m[key], dm[key], rtol=1e-12)
    # joints' wrenches, one by one (a small wrench is not hidden by a large one)
    for k in range(m["force"].shape[0]):
        wrench_m = np.concatenate([m["force"][k], m["torque"][k]])
        wrench_dm = np.concatenate([dm["force"][k], dm["torque"][k]])
        assert_close(f"wrench {k}", wrench_m, wrench_dm, rtol=1e-11)


def test_four_bar_reports_three_redundant_rows_in_both_units(tmp_path):
    for unit, k in (("m", 1.0), ("dm", 10.0)):
        model = hexapod.assemble(read_scene(write_scene(tmp_path, unit,
                                                        four_bar(k, unit, True))))
        assert len(state_results(model, 0.3)["redundant"]) == 3


def test_seed002_file_matches_the_same_scene_in_metres(tmp_path):
    in_dm = hexapod.assemble(read_scene(SCENES / "closed_pendulum_seed002.toml"))
    document = seed002(1.0, "m", True)
    for body in document["body"]:
        body.pop("velocity")  # the file starts at rest
    document["joint"][1].pop("length")
    in_m = hexapod.assemble(read_scene(write_scene(tmp_path, "seed002-m", document)))
    for t in (0.0, 0.2):
        a, b = state_results(in_m, t), state_results(in_dm, t)
        for key in ("q", "v_dot", "force"):
            assert_close(key, a[key], b[key], rtol=1e-12)
