"""Write ``data/scenes/andrews.toml``: Andrews' squeezing mechanism as seven planar bodies.

The bodies, points and joints are those of the absolute-coordinate description in
``data/benchmarks/README.md`` (checked there against the test set's mass matrix); the numbers
come from ``data/benchmarks/andrews.json``. Each body's reference frame sits at its pivot, so
every joint is placed by markers in body coordinates, exactly as the description gives them;
the initial poses are those of the published q(0).

    python3 data/scenes/make_andrews_scene.py
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]


def _f(x: float) -> str:
    return repr(float(x))


def _v(*xs: float) -> str:
    return "[" + ", ".join(_f(x) for x in xs) + "]"


def scene_text(p: dict, q0: list[float]) -> str:
    beta, theta, gamma, phi, delta, omega, epsilon = q0[:7]
    angles = {1: beta, 2: beta + theta, 3: gamma, 4: phi + delta, 5: delta, 6: omega + epsilon,
              7: epsilon}

    def rot(a, x, y):
        return np.array([np.cos(a) * x - np.sin(a) * y, np.sin(a) * x + np.cos(a) * y])

    A, B, O = np.array([p["xa"], p["ya"]]), np.array([p["xb"], p["yb"]]), np.zeros(2)
    F = O + rot(angles[1], p["rr"], 0.0)
    G = A + rot(angles[5], p["zt"], 0.0)
    H = A + rot(angles[7], 0.0, -p["u"])
    origins = {1: O, 2: F, 3: B, 4: G, 5: A, 6: H, 7: A}
    # body: (name, mass, inertia, centre of mass, markers) in the body frame at its pivot
    bodies = {
        1: ("crank", "m1", "i1", (p["ra"], 0.0), {"F": (p["rr"], 0.0)}),
        2: ("rod2", "m2", "i2", (-p["da"], 0.0), {"E": (-p["d"], 0.0)}),
        3: ("triangle", "m3", "i3", (p["sb"], -p["sa"]),
            {"E": (0.0, -p["ss"]), "D": (p["sd"], -p["sc"])}),
        4: ("rod4", "m4", "i4", (0.0, -(p["e"] - p["ea"])), {"E": (0.0, -p["e"])}),
        5: ("link5", "m5", "i5", (p["ta"], p["tb"]), {"G": (p["zt"], 0.0)}),
        6: ("rod6", "m6", "i6", (p["zf"] - p["fa"], 0.0), {"E": (p["zf"], 0.0)}),
        7: ("link7", "m7", "i7", (p["ua"], p["ub"]), {"H": (0.0, -p["u"])}),
    }
    out = [
        "# Andrews' squeezing mechanism: seven planar bodies, ten revolute joints, 1 DOF.",
        "# Written by data/scenes/make_andrews_scene.py from data/benchmarks/andrews.json",
        "# (Test Set for IVP Solvers, problem 'andrews'); bodies and points as",
        "# data/benchmarks/README.md gives them. Reference frames at the pivots; initial poses",
        "# from the published q(0).",
        "# The forces that rod2 exerts at E on the triangle, rod4 and rod6 (joints E3, E4, E6,",
        "# world axes) are the published multipliers lambda1..6.",
        "[scene]", 'name = "andrews"', "dimension = 2", 'length_unit = "m"',
        "gravity = [0.0, 0.0]", "",
    ]
    for k, (name, m, i, com, markers) in bodies.items():
        marks = ", ".join(f"{key} = {_v(*xy)}" for key, xy in markers.items())
        out += ["[[body]]", f'name = "{name}"', f"mass = {_f(p[m])}", f"inertia = {_f(p[i])}",
                f"com = {_v(*com)}", f"position = {_v(*origins[k])}",
                f"angle = {_f(angles[k])}", f"markers = {{ {marks} }}", ""]
    joints = [  # name, parent, parent point, child, child point
        ("O", "ground", _v(0.0, 0.0), "crank", None),
        ("F", "crank", '"F"', "rod2", None),
        ("B", "ground", _v(p["xb"], p["yb"]), "triangle", None),
        ("A5", "ground", _v(p["xa"], p["ya"]), "link5", None),
        ("A7", "ground", _v(p["xa"], p["ya"]), "link7", None),
        ("G", "link5", '"G"', "rod4", None),
        ("H", "link7", '"H"', "rod6", None),
        ("E3", "rod2", '"E"', "triangle", '"E"'),
        ("E4", "rod2", '"E"', "rod4", '"E"'),
        ("E6", "rod2", '"E"', "rod6", '"E"'),
    ]
    for name, parent, on_parent, child, on_child in joints:
        out += ["[[joint]]", f'name = "{name}"', 'type = "revolute"', f'parent = "{parent}"',
                f"parent_frame = {on_parent}", f'child = "{child}"']
        if on_child is not None:
            out.append(f"child_frame = {on_child}")
        out.append("")
    out += ["[[force]]", 'name = "spring"', 'type = "spring"', 'body_a = "triangle"',
            'point_a = "D"', 'body_b = "ground"', f"point_b = {_v(p['xc'], p['yc'])}",
            f"stiffness = {_f(p['c0'])}", f"free_length = {_f(p['l0'])}", "",
            "[[force]]", 'name = "motor"', 'type = "applied-torque"', 'body = "crank"',
            f"torque = {_f(p['mom'])}", ""]
    return "\n".join(out)


def main() -> None:
    data = json.loads((ROOT / "data/benchmarks/andrews.json").read_text())
    target = ROOT / "data/scenes/andrews.toml"
    target.write_text(scene_text(data["parameters"], data["initial"]["y"]))
    print(f"wrote {target.relative_to(ROOT)}")


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT / "scripts"))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    main()
