"""The built-in cockroach's figures, kept to check that the robot and its legs, rebuilt, still
give them: writes ``cockroach_reference.npz`` (``tests/test_cockroach_data.py``).

For each built-in scene of the cockroach (``front-leg``, ``middle-leg``, ``hind-leg``,
``hexapod``, ``hexapod-held``, ``hexapod-standing``) and two design variants of the walking robot
(the tetrapod gait; femurs 1.1 times longer), the inverse dynamics over one stride (0.5 s, 51
samples): every joint's force and moment (joint frame), every driven joint's effort and, for the
walking robot, the ground's force on each foot. The file committed was written by the
cockroach's own inverse kinematics (a product of exponentials solved by Newton's method, before
the engine's kinematics replaced it); run again, this script records what the code of the day
gives; with ``--compare`` it writes nothing and prints, case by case, how far the code of the
day is from the committed figures (the largest difference over the largest value of each
quantity, joints and contacts matched by name).

    python3 tests/data/make_cockroach_reference.py [--compare]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import hexapod as hx

OUT = Path(__file__).resolve().parent / "cockroach_reference.npz"
TIMES = np.linspace(0.0, 0.5, 51)


def cases() -> dict:
    """Case name -> a function building its scene."""
    from legs.robot import hexapod_walking

    out = {name: (lambda name=name: hx.load_scene(name))
           for name in ("front-leg", "middle-leg", "hind-leg", "hexapod", "hexapod-held",
                        "hexapod-standing")}
    out["hexapod-tetrapod"] = lambda: hexapod_walking(gait="tetrapod")
    out["hexapod-femur-1.1"] = lambda: hexapod_walking(femur_length=1.1)
    return out


def figures(scene: hx.Scene) -> dict[str, np.ndarray]:
    """The inverse dynamics' joints, contacts, forces, moments, efforts and ground forces."""
    result = hx.inverse_dynamics(hx.assemble(scene), TIMES)
    out = {"joints": np.array(result.joints), "force": result.force,
           "torque": result.torque, "effort": result.effort}
    if result.contacts:
        out.update(contacts=np.array(result.contacts), ground_force=result.ground_force)
    return out


def compare() -> None:
    """Print the largest relative difference of each quantity from the committed file."""
    reference = np.load(OUT)
    for name, build in cases().items():
        now, row = figures(build()), []
        for key in ("effort", "force", "torque", "ground_force"):
            if key not in now:
                continue
            names = "contacts" if key == "ground_force" else "joints"
            after = list(now[names])
            order = [after.index(n) for n in reference[f"{name}:{names}"]]
            before = reference[f"{name}:{key}"]
            difference = np.nanmax(np.abs(now[key][:, order] - before))
            row.append(f"{key} {difference / np.nanmax(np.abs(before)):.1e}")
        print(f"{name}: " + ", ".join(row), flush=True)


def main() -> None:
    if "--compare" in sys.argv[1:]:
        compare()
        return
    arrays = {"times": TIMES}
    for name, build in cases().items():
        print(name, flush=True)
        arrays.update({f"{name}:{key}": value for key, value in figures(build()).items()})
    np.savez_compressed(OUT, **arrays)
    print(f"wrote {OUT.name}")


if __name__ == "__main__":
    main()
