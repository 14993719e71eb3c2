"""The content hash of a model (hexapod.model.digest): the same in every process and whatever
order dictionaries were filled in, the same for another motion of the same robot, and different
for any change of what the model's Functions are built from."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms.inverse import tree_plan
from hexapod.model.digest import describe, scene_digest
from hexapod.scene.builtin import builtin_scenes
from legs import front_leg_scene

from mechanisms import random_tree

ROOT = Path(__file__).resolve().parents[1]
FIXTURE = ROOT / "tests" / "data" / "pinocchio-fixtures" / "tree-7"


def digest(scene: hx.Scene, rank_tolerance: float = 1e-9) -> str:
    return scene_digest(scene.in_si(), rank_tolerance)


def driven_urdf(motion_path: Path = FIXTURE / "motion.csv") -> hx.Scene:
    return hx.apply_motion(hx.read_urdf(FIXTURE / "model.urdf"), hx.read_motion(motion_path))


def test_assemble_gives_the_model_its_digest():
    scene = front_leg_scene()
    model = hx.assemble(scene)
    assert model.digest == digest(scene) and len(model.digest) == 64


def test_the_digest_is_the_same_in_another_process():
    code = ("import hexapod as hx; from legs import front_leg_scene; "
            "from pathlib import Path; f = Path('tests/data/pinocchio-fixtures/tree-7'); "
            "print(hx.assemble(front_leg_scene()).digest); print(hx.assemble(hx.apply_motion("
            "hx.read_urdf(f / 'model.urdf'), hx.read_motion(f / 'motion.csv'))).digest)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout.split()
    assert out == [hx.assemble(front_leg_scene()).digest, hx.assemble(driven_urdf()).digest]


def test_another_motion_of_the_same_robot_has_the_same_digest(tmp_path):
    """Time laws are inputs of the Functions: other samples, other law types (positions only,
    splines instead of Hermite interpolants) change nothing."""
    motion = hx.read_motion(FIXTURE / "motion.csv")
    joints = list(motion.joints)
    times = np.linspace(0.0, 2.0, 40)
    rows = np.column_stack([times] + [0.3 * np.sin(times + k) for k in range(len(joints))])
    other = tmp_path / "other.csv"
    np.savetxt(other, rows, delimiter=",", header=",".join(["t", *joints]), comments="")
    with pytest.warns(hx.scene.MotionWarning):
        assert digest(driven_urdf(other)) == digest(driven_urdf())


def test_dictionary_order_names_of_files_and_the_scene_name_do_not_count():
    def leg(order, name, source):
        scene = front_leg_scene(name=name)
        scene.source = source
        body = next(iter(scene.bodies.values()))
        markers = {"tip": hx.spatial.Placement([0.1, 0.0, 0.0]),
                   "base": hx.spatial.Placement([0.0, 0.0, 0.0])}
        body.markers = dict(sorted(markers.items(), reverse=order))
        body.source = source
        return scene

    assert digest(leg(True, "a", "a.toml")) == digest(leg(False, "b", "elsewhere/b.toml"))


def _changed(change) -> str:
    scene = random_tree(3, 5)
    change(scene)
    return digest(scene)


def _first(scene, family):
    return next(iter(getattr(scene, family).values()))


CHANGES = {
    "a mass": lambda s: setattr(_first(s, "bodies"), "mass", _first(s, "bodies").mass * 1.001),
    "an inertia": lambda s: setattr(_first(s, "bodies"), "inertia",
                                    _first(s, "bodies").inertia * (1 + 1e-12)),
    "a centre of mass": lambda s: setattr(_first(s, "bodies"), "com",
                                          _first(s, "bodies").com + [0, 0, 1e-9]),
    "a joint axis": lambda s: setattr(_first(s, "joints"), "axis", [0.0, 0.6, 0.8]),
    "a joint origin": lambda s: setattr(_first(s, "joints"), "origin",
                                        np.asarray(_first(s, "joints").origin) + 1e-6),
    "a body's name": lambda s: setattr(_first(s, "bodies"), "name", "renamed"),
    "gravity": lambda s: setattr(s, "gravity", [0.0, 0.0, -9.80665]),
    "a constant law": lambda s: setattr(_first(s, "drivers"), "law", hx.scene.Constant(0.25)),
    "a force element": lambda s: s.add(hx.scene.AppliedForce("push", "b1", [1.0, 0.0, 0.0])),
    "the order of elements": lambda s: s._elements.reverse(),
    "the length unit": lambda s: setattr(s, "length_unit", "cm"),
}


@pytest.mark.parametrize("change", CHANGES, ids=list(CHANGES))
def test_a_change_of_what_the_functions_are_built_from_changes_the_digest(change):
    assert _changed(CHANGES[change]) != _changed(lambda s: None)


def test_a_constant_laws_value_counts_and_the_rank_tolerance_too():
    def constant(value):
        scene = random_tree(3, 5)
        driver = _first(scene, "drivers")
        driver.law = hx.scene.Constant(value)
        return digest(scene)

    assert constant(0.25) == constant(0.25) != constant(0.2500000001)
    scene = random_tree(3, 5)
    assert digest(scene, 1e-9) != digest(scene, 1e-8)


@pytest.mark.parametrize("name", sorted(builtin_scenes()))
def test_every_builtin_scene_is_described(name):
    scene = hx.load_scene(name)
    assert len(digest(scene)) == 64
    for law in {id(e.law): e.law for e in scene.elements if hasattr(e, "law")}.values():
        describe(law, time_laws=True)  # a kernel that compiles laws in can key on them


def test_a_scene_holding_a_value_of_an_unknown_kind_has_no_digest_and_is_not_cached():
    scene = random_tree(3, 5)
    _first(scene, "bodies").mesh = object()  # no description: no digest, nothing cached
    model = hx.assemble(scene)
    assert model.digest == "" and tree_plan(model).key is None
    assert np.isfinite(hx.inverse_dynamics(model, np.linspace(0, 0.1, 3)).effort).all()


def test_a_value_of_an_unknown_kind_is_an_error_not_an_unstable_description():
    with pytest.raises(TypeError, match="cannot describe a object"):
        describe(object())
    assert describe({"b": 1.5, "a": [np.float64(2.0), None]}) == {"b": 1.5, "a": [2.0, None]}
    assert describe(float("nan")) == "nan" and describe(hx.scene.Harmonic(offset=1.0)) == "time law"
