"""Contact joints and the [ground] table in scene files: written and read back unchanged, and
every malformed value reported with the file and its key."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import hexapod as hx
from hexapod.scene.reader import read_scene
from hexapod.scene.writer import scene_text, write_scene


def _leg(ground: hx.scene.GroundForces | None = None) -> hx.Scene:
    """A thigh and a shank hanging from the ground, the shank's foot in contact with it by a
    walking schedule."""
    scene = hx.Scene("stepping-leg", ground=ground)
    scene.add(hx.scene.SpatialBody("thigh", 1.0, [0.01, 0.01, 0.001], position=[0.0, 0.0, -0.25],
                                   markers={"knee": [0.0, 0.0, -0.25]}))
    scene.add(hx.scene.SpatialBody("shank", 0.5, [0.005, 0.005, 0.0005], position=[0.0, 0.0, -0.75],
                                   markers={"foot": [0.0, 0.0, -0.25]}))
    scene.add(hx.scene.Revolute("hip", "ground", "thigh", origin=[0.0, 0.0, 0.0],
                                axis=[0.0, 1.0, 0.0]))
    scene.add(hx.scene.Revolute("knee", "thigh", "shank", parent_frame="knee",
                                child_frame=hx.spatial.Placement([0.0, 0.0, 0.25]),
                                axis=[0.0, 1.0, 0.0]))
    scene.add(hx.scene.Contact("toe", "ground", "shank", child_frame="foot", period=1.2, duty=0.7,
                               lift_off=0.25, foothold=[0.0, 0.0, -1.0], advance=[0.1, 0.0, 0.0],
                               ramp=0.15))
    scene.add(hx.scene.JointDriver("hip_drive", "hip",
                                   hx.scene.Harmonic(sin=(0.1,), frequency=0.5)))
    scene.add(hx.scene.JointDriver("knee_drive", "knee",
                                   hx.scene.Harmonic(sin=(0.2,), frequency=0.5)))
    return scene


GROUND = hx.scene.GroundForces(policy="friction", mu=0.6, faces=0, min_normal=0.5,
                               default_reference=2.0, reference_efforts={"hip": 3.0, "knee": 1.5})


def _ground_settings(ground: hx.scene.GroundForces) -> dict:
    """Every setting but where it was written."""
    return {k: v for k, v in dataclasses.asdict(ground).items() if k != "source"}


def test_contact_and_ground_round_trip(tmp_path):
    scene = _leg(GROUND)
    path = write_scene(scene, tmp_path / "leg.toml")
    text = path.read_text()
    assert 'type = "contact"' in text and "\n[ground]\n" in text
    assert "\n[ground.reference_efforts]\n" in text
    copy = read_scene(path)
    assert _ground_settings(copy.ground) == _ground_settings(GROUND)
    assert copy.ground.source == f"{path}, ground"
    toe = copy.joints["toe"]
    assert isinstance(toe, hx.scene.Contact) and toe.child_frame == "foot"
    assert (toe.period, toe.duty, toe.lift_off, toe.ramp) == (1.2, 0.7, 0.25, 0.15)
    np.testing.assert_array_equal(toe.foothold, [0.0, 0.0, -1.0])
    np.testing.assert_array_equal(toe.advance, [0.1, 0.0, 0.0])
    assert scene_text(copy) == scene_text(scene)  # every written value came back
    # the same model: rows, initial pose, and the stance gate and footholds over two cycles
    a, b = hx.assemble(scene), hx.assemble(copy)
    assert [r.name for r in a.rows] == [r.name for r in b.rows]
    np.testing.assert_allclose(a.q0, b.q0, rtol=0, atol=1e-12)
    for t in np.linspace(-1.0, 2.4, 35):
        np.testing.assert_array_equal(a.law_values(t)[0], b.law_values(t)[0])


def test_default_ground_writes_no_table(tmp_path):
    scene = _leg()
    assert "[ground" not in scene_text(scene)
    copy = read_scene(write_scene(scene, tmp_path / "leg.toml"))
    assert _ground_settings(copy.ground) == _ground_settings(hx.scene.GroundForces())


def test_reference_efforts_of_prefixed_joints_are_quoted(tmp_path):
    """Attached legs have names with '/', which TOML keys must quote."""
    ground = hx.scene.GroundForces(policy="min-effort", reference_efforts={"L1/hip": 0.5})
    scene = hx.Scene("legs", ground=ground)
    scene.attach(_leg(), "L1")
    copy = read_scene(write_scene(scene, tmp_path / "legs.toml"))
    assert copy.ground.reference_efforts == {"L1/hip": 0.5}
    assert copy.joints["L1/toe"].parent == "ground"


def test_a_reference_effort_of_no_driven_joint_is_a_problem():
    scene = _leg(hx.scene.GroundForces(policy="min-effort", reference_efforts={"hipp": 0.5}))
    with pytest.raises(hx.ModelError, match="no driven joint .hipp."):
        scene.validate()


# ------------------------------------------------------------------ malformed files

_BASE = """\
[scene]
name = "leg"

[ground]
{ground}

[[body]]
name = "thigh"
mass = 1.0
inertia = [0.01, 0.01, 0.001]
position = [0.0, 0.0, -0.25]

[[body]]
name = "shank"
mass = 0.5
inertia = [0.005, 0.005, 0.0005]
position = [0.0, 0.0, -0.75]
markers = {{ foot = [0.0, 0.0, -0.25] }}

[[joint]]
name = "hip"
type = "revolute"
parent = "ground"
child = "thigh"
origin = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]

[[joint]]
name = "knee"
type = "revolute"
parent = "thigh"
child = "shank"
origin = [0.0, 0.0, -0.5]
axis = [0.0, 1.0, 0.0]

[[joint]]
name = "toe"
type = "contact"
parent = "{parent}"
child = "shank"
child_frame = "foot"
period = 1.0
foothold = [0.0, 0.0, -1.0]
{contact}
"""


def _document(ground: str = 'policy = "friction"', parent: str = "ground",
              contact: str = "") -> str:
    return _BASE.format(ground=ground, parent=parent, contact=contact)


def test_the_base_document_is_valid(tmp_path):
    path = tmp_path / "leg.toml"
    path.write_text(_document())
    scene = read_scene(path)
    assert scene.ground.policy == "friction"
    hx.assemble(scene)


@pytest.mark.parametrize("changes, key, fragment", [
    (dict(ground='policy = "cheapest"'), "ground.policy", "must be one of"),
    (dict(ground="mu = -0.5"), "ground.mu", "must be positive"),
    (dict(ground="faces = 2"), "ground.faces", "0 (the exact cone) or at least 3"),
    (dict(ground="faces = 8.0"), "ground.faces", "must be an integer"),
    (dict(ground="min_normal = -1.0"), "ground.min_normal", "must not be negative"),
    (dict(ground="colour = 'grey'"), "ground.colour", "unknown key 'colour'"),
    (dict(ground="reference_efforts = { hip = 'strong' }"), "ground.reference_efforts.hip",
     "must be a number"),
    (dict(ground="reference_efforts = { hip = 0.0 }"), "ground.reference_efforts.hip",
     "must be positive"),
    (dict(parent="thigh"), "joint[2].parent", "a contact's parent is the ground"),
    (dict(contact="duty = 0.0"), "joint[2].duty", "must be in (0, 1]"),
    (dict(contact="lift_off = 1.0"), "joint[2].lift_off", "must be in [0, 1)"),
    (dict(contact="ramp = 0.6"), "joint[2].ramp", "must be in (0, 0.5]"),
    (dict(contact="advance = [0.1, 0.0]"), "joint[2].advance", "must be a list of 3 numbers"),
    (dict(contact="stride = 0.1"), "joint[2].stride", "unknown key 'stride'"),
])
def test_malformed_contact_or_ground_names_the_file_and_key(tmp_path, changes, key, fragment):
    path = tmp_path / "leg.toml"
    path.write_text(_document(**changes))
    with pytest.raises(hx.ModelError) as info:
        read_scene(path)
    where = f"{path}, {key}"
    assert [p for p in info.value.problems if p.where == where and fragment in p.message], \
        info.value
    assert where in str(info.value)


def test_ground_written_as_an_array_of_tables(tmp_path):
    path = tmp_path / "leg.toml"
    path.write_text("[[ground]]\nmu = 0.5\n")
    with pytest.raises(hx.ModelError) as info:
        read_scene(path)
    (problem,) = info.value.problems
    assert problem.where == f"{path}, ground" and "[ground]" in problem.message
