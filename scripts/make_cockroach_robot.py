"""Writes the built-in walking robot as a robot description: ``data/robots/cockroach.urdf`` (its
bodies and joints, from ``legs.robot.cockroach_body``) and ``data/robots/cockroach.toml`` (its
feet, coupled joints, gait and ground, from ``legs.robot.cockroach_description``), so that
``hexapod report data/robots/cockroach.toml`` walks the cockroach through the path every robot
takes. ``tests/test_cockroach_data.py`` checks that the files are what this script writes and
that they walk to the built-in robot's figures.

    python3 scripts/make_cockroach_robot.py [--out data/robots]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import hexapod as hx
from legs.cockroach import MODEL_SCALE, STRIDE_PERIOD
from legs.robot import WALKING_DUTY, cockroach_body, cockroach_description, walking_pattern

ROOT = Path(__file__).resolve().parents[1]


def _number(x: float) -> str:
    return repr(float(x))


def _numbers(values) -> str:
    return "[" + ", ".join(_number(x) for x in values) + "]"


def description_text() -> str:
    """The TOML of the built-in robot's description (tripod, 0.5 s, 20:1)."""
    pattern = walking_pattern("tripod", WALKING_DUTY["tripod"])
    robot = cockroach_description(pattern, STRIDE_PERIOD, MODEL_SCALE, name="cockroach")
    gait = robot.gait
    lines = ["# The built-in walking robot (the cockroach of Dumitru, Marin and Margine at",
             "# 20:1) as a robot description: `hexapod report data/robots/cockroach.toml` walks",
             "# it by the path every robot takes, to the built-in robot's figures. Written by",
             "# scripts/make_cockroach_robot.py.",
             "[robot]", 'name = "cockroach"', 'urdf = "cockroach.urdf"', 'trunk = "trunk"', "",
             "[robot.coupled]                # levation, coxa rotation and tita follow the foot"]
    lines += [f'"{pattern_}" = {{ {follows} = {_number(np.degrees(amplitude))} }}'
              for pattern_, (follows, amplitude) in robot.coupled.items()]
    lines += ["", "[robot.feet]                   # the tarsus's end; the stance line's middle "
              "offset fore-aft"]
    lines += [f'{name} = {{ link = "{foot.link}", point = {_numbers(foot.point)}, '
              f"offset = {_numbers(foot.offset)} }}" for name, foot in robot.feet.items()]
    lines += ["", "[gait]", 'pattern = "tripod"', f"duty = {_number(gait.duty)}",
              f"period = {_number(gait.period)}",
              f"stride = {_number(gait.stride)}   # 13 mm of stance at 20:1, over the duty",
              f"step_height = {_number(gait.step_height)}", 'trunk = "level"',
              f"height = {_number(gait.height)}", "", "[ground]", 'policy = "min-wrench"']
    return "\n".join(lines) + "\n"


def urdf_text() -> str:
    """The URDF of the built-in robot's bodies and joints."""
    return hx.scene.urdf_text(cockroach_body(MODEL_SCALE, name="cockroach"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "data" / "robots")
    out = parser.parse_args().out
    (out / "cockroach.urdf").write_text(urdf_text())
    (out / "cockroach.toml").write_text(description_text())
    print(f"wrote {out / 'cockroach.urdf'} and {out / 'cockroach.toml'}")


if __name__ == "__main__":
    main()
