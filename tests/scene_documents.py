"""Scene documents for the scene-file tests: where the example files are, writing a document as
a file, the state results to compare, and four mechanisms written in any length unit."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from script_loader import load_script

import hexapod

fuzz = load_script("tests/fuzz/fuzz_inputs.py")  # its TOML writer

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "data" / "scenes"
SCENE_FILES = sorted(SCENES.glob("*.toml"))


def write_scene(directory: Path, name: str, document: dict | str) -> Path:
    path = directory / f"{name}.toml"
    path.write_text(document if isinstance(document, str) else fuzz.toml_text(document),
                    encoding="utf-8")
    return path


def state_results(model: hexapod.Model, t: float) -> dict[str, np.ndarray]:
    """Positions, velocities, accelerations, joint wrenches and driver efforts at ``t`` (SI)."""
    data = model.create_data()
    q = hexapod.assemble_positions(model, data, t)
    v = hexapod.solve_velocities(model, data, t, q)
    v_dot = hexapod.forward_dynamics(model, data, t, q, v)
    wrenches = hexapod.joint_wrenches(model, data)
    return {"q": q, "v": v, "v_dot": v_dot, "force": wrenches.force,
            "torque": wrenches.torque, "effort": wrenches.effort,
            "driver_efforts": np.array(list(hexapod.driver_efforts(model, data).values())),
            "redundant": np.array(data.redundant_rows)}


def assert_close(name: str, a, b, rtol: float) -> None:
    """``a`` and ``b`` agree to ``rtol`` relative to the largest entry of ``a``."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape, name
    np.testing.assert_array_equal(np.isnan(a), np.isnan(b), err_msg=name)
    finite = np.isfinite(a)
    scale = max(float(np.max(np.abs(a[finite]), initial=0.0)), 1e-300)
    error = float(np.max(np.abs(a[finite] - b[finite]), initial=0.0))
    assert error <= rtol * scale, f"{name}: max difference {error:.3e} > {rtol:g} x {scale:.3e}"


# ------------------------------------------------------------------ mechanisms in any length unit

def crane(k: float, unit: str, gravity: bool) -> dict:
    """A spatial scene with every joint type but distance, every force element, a spline
    driver, markers and rotations of each form; lengths are those in metres times ``k``."""

    def L(*x):  # lengths, L
        return [float(v * k) for v in x] if len(x) > 1 else float(x[0] * k)

    def inertia(*x):  # kg L^2
        return [float(v * k * k) for v in x]

    hinge_rotation = {"rpy": [-math.pi / 2, 0.0, 0.0]}
    scene = {"name": "crane", "dimension": 3, "length_unit": unit,
             "characteristic_length": L(0.5)}
    if gravity:
        scene["gravity"] = L(0.0, 0.0, -9.81)
    return {
        "scene": scene,
        "body": [
            {"name": "carriage", "mass": 5.0, "inertia": inertia(0.00833, 0.02083, 0.02083),
             "position": L(0.0, 0.0, 1.0), "velocity": L(0.1, 0.0, 0.02),
             "markers": {"hinge": {"position": L(0.0, 0.0, -0.05),
                                   "rotation": hinge_rotation}}},
            {"name": "arm", "mass": 2.0,
             "inertia": inertia(0.06, 0.06, 0.002, 0.0005, 0.0, 0.0),
             "position": L(0.0, 0.0, 0.95), "com": L(0.0, 0.0, -0.3),
             "angular_velocity": [0.1, 0.7, 0.0], "markers": {"tip": L(0.0, 0.0, -0.6)}},
            {"name": "bob", "type": "particle", "mass": 1.0, "position": L(0.0, 0.0, 0.35),
             "velocity": L(0.3, 0.1, 0.0)},
            {"name": "sensor", "mass": 0.1,
             "inertia": [inertia(6.67e-6, 0.0, 0.0), inertia(0.0, 6.67e-6, 0.0),
                         inertia(0.0, 0.0, 8e-6)],
             "position": L(0.02, 0.0, 0.7),
             "rotation": {"matrix": [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]},
             "inertia_rotation": {"axis": [0.0, 0.0, 1.0], "angle": 0.3}},
        ],
        "joint": [
            {"name": "rail", "type": "prismatic", "parent": "ground", "child": "carriage",
             "origin": L(0.0, 0.0, 1.0), "axis": [1.0, 0.0, 0.0]},
            {"name": "hinge", "type": "revolute", "parent": "carriage", "child": "arm",
             "parent_frame": "hinge",
             "child_frame": {"position": L(0.0, 0.0, 0.0), "rotation": hinge_rotation}},
            {"name": "ball", "type": "spherical", "parent": "arm", "child": "bob",
             "parent_frame": "tip"},
            {"name": "mount", "type": "fixed", "parent": "arm", "child": "sensor",
             "origin": L(0.0, 0.0, 0.7), "rotation": {"quaternion": [1.0, 0.0, 0.0, 0.0]}},
        ],
        "driver": [
            {"name": "rail_drive", "joint": "rail",
             "law": {"type": "spline", "times": [0.0, 1.0, 2.0, 3.0, 4.0],
                     "values": L(0.0, 0.1, 0.2, 0.1, 0.0), "boundary": "clamped"}},
        ],
        "force": [
            {"name": "buffer", "type": "spring", "body_a": "ground",
             "point_a": L(-0.5, 0.0, 1.0), "body_b": "carriage", "point_b": L(-0.1, 0.0, 0.0),
             "stiffness": 200.0 / k, "damping": 5.0 / k, "free_length": L(0.45),
             "force": {"type": "harmonic", "sin": [2.0], "frequency": 0.5}},
            {"name": "wind", "type": "applied-force", "body": "arm", "point": "tip",
             "force": [1.0, 0.0, {"type": "harmonic", "cos": [0.5], "frequency": 0.25}]},
            {"name": "push", "type": "applied-force", "body": "carriage",
             "point": L(0.05, 0.0, 0.0), "frame": "body", "force": [0.5, 0.2, 0.0]},
            {"name": "twist", "type": "applied-torque", "body": "sensor", "frame": "body",
             "torque": L(0.0, 0.0, 0.01)},
            {"name": "turn", "type": "applied-torque", "body": "arm", "torque": L(0.02, 0.0, 0.01)},
            {"name": "hinge_motor", "type": "effort", "joint": "hinge",
             "law": {"type": "polynomial", "coefficients": L(0.01, 0.05)}},
            {"name": "rail_force", "type": "effort", "joint": "rail", "law": 3.0},
        ],
    }


def four_bar(k: float, unit: str, gravity: bool) -> dict:
    """The four-bar of data/scenes/four_bar_3d.toml (three redundant rows; default
    characteristic length) with a spring across joint C."""

    def L(*x):
        return [float(v * k) for v in x] if len(x) > 1 else float(x[0] * k)

    def bar(name, mass, length, centre, angle):
        return {"name": name, "mass": mass,
                "inertia": [mass * length**2 * k * k / 1200,
                            mass * length**2 * k * k / 12, mass * length**2 * k * k / 12],
                "position": L(*centre), "rotation": {"rpy": [0.0, 0.0, angle]}}

    def pin(name, parent, child, origin):
        return {"name": name, "type": "revolute", "parent": parent, "child": child,
                "origin": L(*origin), "axis": [0.0, 0.0, 1.0]}

    scene = {"name": "four-bar", "length_unit": unit}
    if gravity:
        scene["gravity"] = L(0.0, -9.81, 0.0)
    return {
        "scene": scene,
        "body": [bar("crank", 0.3, 0.1, (0.0, 0.05, 0.0), math.pi / 2),
                 bar("coupler", 1.0, 0.5, (0.2, 0.25, 0.0), math.atan2(0.3, 0.4)),
                 bar("rocker", 0.8, 0.4, (0.4, 0.2, 0.0), math.pi / 2)],
        "joint": [pin("A", "ground", "crank", (0.0, 0.0, 0.0)),
                  pin("B", "crank", "coupler", (0.0, 0.1, 0.0)),
                  pin("C", "coupler", "rocker", (0.4, 0.4, 0.0)),
                  pin("D", "ground", "rocker", (0.4, 0.0, 0.0))],
        "driver": [{"name": "crank_motor", "joint": "A",
                    "law": {"type": "harmonic", "sin": [0.5], "frequency": 0.5}}],
        "force": [{"name": "knee_spring", "type": "spring", "body_a": "coupler",
                   "point_a": L(0.1, 0.0, 0.0), "body_b": "rocker", "point_b": L(-0.1, 0.0, 0.0),
                   "stiffness": 50.0 / k, "free_length": L(0.05)}],
    }


def seed002(k: float, unit: str, gravity: bool) -> dict:
    """The closed-loop pendulum of Richard, Anderson and Andrews (y down) with a guessed initial
    velocity."""
    assert gravity, "gravity points along +y here: it must be given"

    def L(*x):
        return [float(v * k) for v in x]

    return {
        "scene": {"name": "closed-pendulum", "dimension": 2, "length_unit": unit,
                  "gravity": L(0.0, 9.81)},
        "body": [{"name": "m1", "type": "particle", "mass": 2.0, "position": L(0.4, 0.4),
                  "velocity": L(0.3, -0.3)},
                 {"name": "m2", "type": "particle", "mass": 1.0, "position": L(1.2, 0.5),
                  "velocity": L(0.3, -0.2)}],
        "joint": [{"name": "rod1", "type": "distance", "parent": "ground", "child": "m1",
                   "parent_frame": L(0.0, 0.0)},
                  {"name": "rod2", "type": "distance", "parent": "ground", "child": "m2",
                   "parent_frame": L(0.7, 0.0), "length": float(math.sqrt(0.5) * k)},
                  {"name": "coupler", "type": "distance", "parent": "m1", "child": "m2",
                   "parent_frame": L(0.0, 0.0), "child_frame": L(0.0, 0.0)}],
    }


def planar_mechanism(k: float, unit: str, gravity: bool) -> dict:
    """A planar double pendulum and a driven slider, with every planar force element."""

    def L(*x):
        return [float(v * k) for v in x] if len(x) > 1 else float(x[0] * k)

    scene = {"name": "planar", "dimension": 2, "length_unit": unit}
    if gravity:
        scene["gravity"] = L(0.0, -9.81)
    return {
        "scene": scene,
        "body": [
            {"name": "upper", "mass": 1.0, "inertia": 0.0833 * k * k, "position": L(0.0, 0.0),
             "com": L(0.5, 0.0), "angle": 0.2, "angular_velocity": 1.0,
             "markers": {"elbow": {"position": L(1.0, 0.0), "rotation": -0.3}}},
            {"name": "lower", "mass": 0.5, "inertia": 0.0267 * k * k,
             "position": L(math.cos(0.2), math.sin(0.2)), "angle": -0.1, "com": L(0.4, 0.0),
             "angular_velocity": -0.5},
            {"name": "slider", "mass": 2.0, "inertia": 0.001 * k * k, "position": L(0.0, -1.0)},
            {"name": "bead", "type": "particle", "mass": 0.2, "position": L(0.3, -1.0),
             "velocity": L(0.0, 0.5)},
        ],
        "joint": [
            {"name": "shoulder", "type": "revolute", "parent": "ground", "child": "upper"},
            {"name": "elbow", "type": "revolute", "parent": "upper", "child": "lower",
             "parent_frame": "elbow", "child_frame": {"position": L(0.0, 0.0), "rotation": -0.3}},
            {"name": "guide", "type": "prismatic", "parent": "ground", "child": "slider",
             "origin": L(0.0, -1.0), "rotation": 0.1, "axis": [1.0, 0.0]},
            {"name": "tether", "type": "distance", "parent": "slider", "child": "bead",
             "parent_frame": L(0.0, 0.0)},
        ],
        "driver": [{"name": "slide", "body": "slider", "coordinate": "x",
                    "law": {"type": "polynomial", "coefficients": L(0.0, 0.2, -0.05)}}],
        "force": [
            {"name": "elbow_spring", "type": "spring", "body_a": "upper", "point_a": L(0.8, 0.0),
             "body_b": "lower", "point_b": L(0.3, 0.0), "stiffness": 30.0 / k,
             "damping": 0.5 / k},
            {"name": "hand", "type": "applied-force", "body": "lower", "point": L(0.8, 0.0),
             "frame": "body", "force": [0.3, {"type": "harmonic", "sin": [1.0],
                                              "frequency": 2.0}]},
            {"name": "wrist", "type": "applied-torque", "body": "lower", "torque": [0.05 * k]},
            {"name": "shoulder_motor", "type": "effort", "joint": "shoulder",
             "law": {"type": "spline", "times": [0.0, 0.5, 1.0, 1.5],
                     "values": L(0.0, 0.1, 0.05, 0.0)}},
            {"name": "guide_force", "type": "effort", "joint": "guide", "law": 1.5},
        ],
    }
