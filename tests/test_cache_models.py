"""Assembled models kept in the cache (hexapod.model.stored): a model read back is the assembled
one to the last bit, with the laws of the scene at hand; a damaged entry is assembled again."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod._support import cache
from hexapod.algorithms.inverse import inverse_dynamics
from hexapod.model import stored
from legs import front_leg_scene

from mechanisms import random_tree

ROOT = Path(__file__).resolve().parents[1]
FIXTURE = ROOT / "tests" / "data" / "pinocchio" / "tree-7"


@pytest.fixture
def folder(tmp_path, monkeypatch) -> Path:
    path = tmp_path / "cache"
    monkeypatch.setenv("HEXAPOD_CACHE_DIR", str(path))
    monkeypatch.delenv("HEXAPOD_CACHE", raising=False)
    return path


def loaded_scene_with_forces() -> hx.Scene:
    """A tree with every kind of law slot: drivers, a spring's force law, an applied force's
    and torque's components, an actuator effort and a torsion spring's torque."""
    scene = random_tree(4, 5)
    joints = list(scene.joints.values())
    scene.add(hx.SpringDamper("spring", "b0", "b2", stiffness=30.0, damping=0.5,
                              force=hx.Harmonic(sin=[0.3], frequency=1.0)))
    scene.add(hx.AppliedForce("push", "b1", [hx.Harmonic(sin=[1.0]), 0.0, 2.0]))
    scene.add(hx.AppliedTorque("twist", "b3", [0.0, hx.Harmonic(cos=[0.2]), 0.1]))
    drivable = [j for j in joints if j.kind in ("revolute", "prismatic")]
    scene.add(hx.JointEffort("motor", drivable[0].name, hx.Harmonic(sin=[0.5])))
    revolute = next(j for j in joints if j.kind == "revolute")
    scene.add(hx.RotationalSpringDamper("torsion", revolute.name, stiffness=2.0,
                                        torque=hx.Harmonic(sin=[0.1])))
    return scene


SCENES = {
    "front-leg": front_leg_scene,
    "walking hexapod": lambda: hx.load_scene("hexapod"),
    "urdf and motion": lambda: hx.apply_motion(hx.read_urdf(FIXTURE / "model.urdf"),
                                               hx.read_motion(FIXTURE / "motion.csv")),
    "forces of every kind": loaded_scene_with_forces,
    "planar": lambda: hx.read_scene(ROOT / "data" / "scenes" / "double_pendulum_planar.toml"),
}


def same(a, b) -> bool:
    """Equal to the last bit: numbers, arrays, dataclasses, tuples."""
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        return type(a) is type(b) and all(same(getattr(a, f.name), getattr(b, f.name))
                                          for f in dataclasses.fields(a))
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(a, b)
    return a is b or a == b


@pytest.mark.parametrize("name", SCENES)
def test_a_model_read_back_is_the_assembled_one(folder, name):
    assembled = hx.assemble(SCENES[name]())
    scene = SCENES[name]()
    restored = stored.restore(scene.in_si(), assembled.digest)
    assert restored is not None
    for field in ("bodies", "joints", "rows", "forces", "gravity", "q0", "v0", "dimension",
                  "characteristic_length", "working_elements", "rank_tolerance", "name",
                  "digest"):
        assert same(getattr(restored, field), getattr(assembled, field)), field
    assert same(restored.mass.dense(), assembled.mass.dense())
    for a, b in zip(restored.drivers, assembled.drivers, strict=True):
        assert same(dataclasses.replace(a, spec=None), dataclasses.replace(b, spec=None))
        assert type(a.spec) is type(b.spec)
    assert [c.name for c in restored.contacts] == [c.name for c in assembled.contacts]
    assert [type(law) for law in restored.laws] == [type(law) for law in assembled.laws]
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 1.0, 7)
    for x, y in zip(restored.law_values(t), assembled.law_values(t), strict=True):
        assert np.array_equal(x, y)
    values = {"q": assembled.normalize(assembled.q0 + 0.1 * rng.normal(size=assembled.n_q)),
              "v": rng.normal(size=assembled.n_v), "w": rng.normal(size=assembled.n_w),
              "wd": rng.normal(size=assembled.n_w), "wdd": rng.normal(size=assembled.n_w),
              "lam": rng.normal(size=assembled.n_c)}
    functions = ["phi", "Phi_q", "Phi_v", "nu", "gamma", "Q", "qdot", "dynamics_terms",
                 "energy", "tangent_matrices"] + (["Q_across"] if assembled.Q_across else [])
    for function in functions:
        mine, theirs = getattr(restored, function), getattr(assembled, function)
        args = [values[n] for n in theirs.name_in()]
        for x, y in zip(mine.call(args), theirs.call(args), strict=True):
            assert np.array_equal(np.asarray(x), np.asarray(y)), function


def test_the_second_assembly_is_read_back_with_the_laws_of_its_scene(folder, tmp_path):
    """Another motion of the same robot: the same entry, the new motion's laws, and inverse
    dynamics equal to the last bit to that of a model assembled without a cache."""
    first = hx.assemble(SCENES["urdf and motion"]())
    motion = hx.read_motion(FIXTURE / "motion.csv")
    times = motion.times[::3]
    rows = np.column_stack([times] + [0.2 * np.cos(3 * times + k)
                                      for k in range(len(motion.joints))])
    other = tmp_path / "other.csv"
    np.savetxt(other, rows, delimiter=",", header=",".join(["t", *motion.joints]),
               comments="")
    with pytest.warns(hx.MotionWarning):
        scene = hx.apply_motion(hx.read_urdf(FIXTURE / "model.urdf"), hx.read_motion(other))
    entries = len(cache.entries())
    second = hx.assemble(scene)
    assert len(cache.entries()) == entries and second.digest == first.digest
    assert second.laws[0] is not first.laws[0]  # the scene's own laws
    cache.clean()
    fresh = hx.assemble(scene)  # assembled: nothing in the cache
    assert len(cache.entries()) == entries
    x, y = (inverse_dynamics(m, times, compile=False) for m in (second, fresh))
    for key in ("force", "torque", "effort", "q", "v", "v_dot"):
        assert np.array_equal(getattr(x, key), getattr(y, key), equal_nan=True), key


def test_a_damaged_model_entry_is_assembled_again(folder):
    model = hx.assemble(front_leg_scene())
    (entry,) = cache.entries()
    (entry.path / stored.DESCRIPTION).write_bytes(b"not a pickle")
    meta = entry.path / cache.META
    import hashlib
    import json

    listed = json.loads(meta.read_text())  # consistent checksums: only reading it fails
    listed["files"][stored.DESCRIPTION] = hashlib.sha256(b"not a pickle").hexdigest()
    meta.write_text(json.dumps(listed))
    assert stored.restore(front_leg_scene().in_si(), model.digest) is None
    assert cache.entries() == []  # removed
    again = hx.assemble(front_leg_scene())
    assert again.digest == model.digest and len(cache.entries()) == 1


def test_without_a_cache_nothing_is_kept(tmp_path, monkeypatch):
    monkeypatch.setenv("HEXAPOD_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("HEXAPOD_CACHE", "0")
    hx.assemble(front_leg_scene())
    assert not (tmp_path / "cache").exists()


def test_every_law_slot_is_found_in_the_scene():
    scene = loaded_scene_with_forces().in_si()
    for where, kind in ((("force", "push", "force", 0), hx.Harmonic),
                        (("force", "spring", "force", None), hx.Harmonic),
                        (("force", "motor", "law", None), hx.Harmonic)):
        assert isinstance(stored.find_law(scene, where), kind)
    with pytest.raises(ValueError, match="no law where"):
        stored.find_law(scene, ("elsewhere", "x"))
