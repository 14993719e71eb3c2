"""The walking robot and the built-in scenes the tests read, each assembled once per test
process (one worker of the run); the robots of data/robots walking their fixtures' samples, and
the checks every walk of theirs passes.

A model is frozen, and what it builds as it is used (the phase plans of the inverse dynamics,
its evaluated functions) is kept with it: the tests that only read the same robot pay for its
assembly and those builds once, where each module used to pay for them again (the walking
robot's assembly and first inverse dynamics take one to three seconds). Each test still makes
its own workspace (``model.create_data()``, as every run does). A test about building itself (in
threads, into the cache, a fresh model's first call) assembles its own model.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np

import hexapod as hx
from hexapod.spatial import rotation_from_euler_parameters
from legs.robot import hexapod_scene

ROBOTS = Path(__file__).resolve().parents[1] / "data" / "robots"
FIXTURES = Path(__file__).resolve().parent / "data"


@cache
def builtin_model(name: str) -> hx.Model:
    """The built-in scene ``name`` (``hexapod scenes``) assembled."""
    return hx.assemble(hx.load_scene(name))


def walking_robot(gait: str = "tripod", references: tuple = (), **ground) -> hx.Model:
    """The walking robot with a free trunk, its ``gait`` and ground settings (keywords of
    :class:`hexapod.scene.GroundForces`; ``references``: pairs of joint name and reference
    effort). A setting given its default value is the same robot: ``walking_robot()`` and
    ``walking_robot(policy="min-wrench")`` are the built-in ``hexapod``."""
    defaults = hx.scene.GroundForces()
    changed = tuple(sorted((k, v) for k, v in ground.items() if v != getattr(defaults, k)))
    if gait == "tripod" and not references and not changed:
        return builtin_model("hexapod")
    return _walking_robot(gait, references, changed)


@cache
def _walking_robot(gait: str, references: tuple, ground: tuple) -> hx.Model:
    settings = hx.scene.GroundForces(**dict(ground), reference_efforts=dict(references))
    return hx.assemble(hexapod_scene(gait, trunk="free", ground=settings))


def stored_rnea(name: str) -> dict:
    """Pinocchio's torques for a robot of data/robots (tests/data/make_walking_fixture.py
    --NAME; CI has no Pinocchio)."""
    with np.load(FIXTURES / f"{name}_rnea.npz", allow_pickle=False) as data:
        return {key: data[key] for key in data.files}


@cache
def described_walk(name: str) -> tuple:
    """``data/robots/NAME.toml`` walked at its fixture's samples: the scene, the model, the
    inverse dynamics and the fixture."""
    stored = stored_rnea(name)
    scene = hx.load_scene(ROBOTS / f"{name}.toml")
    model = hx.assemble(scene)
    return scene, model, hx.inverse_dynamics(model, stored["times"]), stored


def rest_feet(name: str) -> dict[str, np.ndarray]:
    """Where each foot of ``data/robots/<name>.toml`` is (world, m) with the robot in its rest
    posture, its trunk's frame over the origin at its walking height: where the walk's
    footholds are measured from (the scene itself is written at the motion's start)."""
    import tomllib

    from legs.description import read_robot, rest_angles
    from legs.posing import posed

    path = ROBOTS / f"{name}.toml"
    description = read_robot(tomllib.loads(path.read_text()), path)
    urdf = hx.read_urdf(description.urdf, base="free")
    scene = posed(urdf, rest_angles(description, urdf.joints))
    feet = {foot: scene.pose(f.link).transform_point(f.point)
            for foot, f in description.feet.items()}
    height = -np.mean([p[2] for p in feet.values()])
    return {foot: p + [0.0, 0.0, height] for foot, p in feet.items()}


def foot_on_ground(scene, model, result, contact) -> tuple:
    """A contact's foot world position, its foothold on a straight walk (``foothold + k
    advance``) and whether it is in stance, per sample."""
    body = scene.bodies[contact.child]
    point = contact.child_frame.position - np.asarray(body.com, dtype=float)
    info = model.bodies[model.body_index[body.name]]
    position = np.array([q[info.q][:3] + rotation_from_euler_parameters(q[info.q][3:])
                         @ point for q in result.q])
    k = np.floor(result.times / contact.period - contact.lift_off) + 1.0
    foothold = contact.foothold + k[:, None] * contact.advance
    return position, foothold, hx.scene.contacts.in_stance(contact, result.times)


def momentum_gap(model, result) -> float:
    """The largest residual of ``sum F_ground + M g = sum m a_com``, over the weight."""
    rate = sum(b.mass * result.v_dot[:, b.v][:, :3] for b in model.bodies)
    gravity = model.total_mass * np.asarray(model.gravity)
    gap = result.ground_force.sum(axis=1) + gravity - rate
    return float(np.abs(gap).max() / (model.total_mass * 9.81))


def check_pinocchio(model, result, stored) -> None:
    """The efforts equal Pinocchio's floating-base RNEA with the reported ground reactions at
    the feet (the fixture always: 1e-8 of the largest; live when Pinocchio is installed)."""
    index = {name: k for k, name in enumerate(result.joints)}
    efforts = result.effort[:, [index[str(name)] for name in stored["joints"]]]
    scale = np.abs(stored["pinocchio"]).max()
    assert np.abs(efforts - stored["pinocchio"]).max() < 1e-8 * scale
    assert np.abs(stored["base"]).max() < 1e-8 * scale
    try:
        import pinocchio  # noqa: F401
    except ImportError:
        return
    from script_loader import load_script

    script = load_script("tests/data/make_walking_fixture.py")
    comparison = script.pinocchio_rnea(hx.simulation.motion_model(model, result), result)
    assert comparison.placement_gap < 1e-12 and comparison.motion_gap < 1e-10
    assert comparison.difference < 1e-8
