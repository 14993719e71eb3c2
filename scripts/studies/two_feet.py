"""Gaits with two feet down, carried: a robot trotting, pacing and bounding, flat and up a slope
(not a test).

For a robot description of four feet (default the project's trotting quadruped,
``data/robots/quadruped-trot.toml``) each of ``--gaits`` is walked over one stride at
``--samples`` samples on flat ground and up each of ``--slopes`` (degrees): the samples with two
feet down, those where a foot would pull or slip (the ground cannot give the forces), the
largest correction of the trunk's sway that lets two feet carry it (``legs.carried``), the
largest departure of the trunk's accelerations from its planned motion where two feet leave it
free to tip (the dynamics decides it there), and the CPU time of building the scene (the plans)
and of the inverse dynamics.

    python3 scripts/studies/two_feet.py [ROBOT.toml] [--gaits trot pace bound]
                                        [--slopes 10] [--samples 201]
"""

from __future__ import annotations

import argparse
import sys
import time
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np

import hexapod as hx
from legs.description import read_robot
from legs.walker import robot_scene

ROBOT = Path(__file__).resolve().parents[2] / "data" / "robots" / "quadruped-trot.toml"


def _row(description, pattern: str, slope: float, samples: int) -> str:
    """One gait on one ground: the table's row."""
    description.gait.pattern = pattern
    description.gait.phases = {}
    description.ground["slope"] = slope
    tic = time.process_time()
    try:
        scene = robot_scene(description)
    except hx.HexapodError as error:  # no motion two feet can carry was found
        return f"| {pattern} | {slope:g} | {error} | | | | | |"
    planning = time.process_time() - tic
    model = hx.assemble(scene)
    times = np.linspace(0.0, description.gait.period, samples)
    tic = time.process_time()
    result = hx.inverse_dynamics(model, times)
    inverse = time.process_time() - tic
    two = (np.asarray(result.ground_status) != "swing").sum(axis=1) == 2
    trunk = model.bodies[model.body_index[description.trunk]]
    correction, departure = 0.0, 0.0
    for k, axis in enumerate("xy"):
        law = scene.drivers[f"trunk/{axis}"].law
        plain = replace(law, bounds=(), values=())
        correction = max(correction, float(np.abs(law(times) - plain(times)).max()))
        acceleration = law.evaluate(times)[2]
        departure = max(departure, float(np.abs(result.v_dot[two][:, trunk.v][:, k]
                                                 - acceleration[two]).max(initial=0.0)))
    return (f"| {pattern} | {slope:g} | {int(two.sum())} | {int(result.infeasible.sum())} | "
            f"{correction * 1e3:.2f} | {departure:.1e} | {planning:.1f} | {inverse:.1f} |")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", nargs="?", type=Path, default=ROBOT)
    parser.add_argument("--gaits", nargs="+", default=["trot", "pace", "bound"])
    parser.add_argument("--slopes", nargs="*", type=float, default=[10.0])
    parser.add_argument("--samples", type=int, default=201)
    args = parser.parse_args()
    description = read_robot(tomllib.loads(args.robot.read_text()), args.robot)
    gait = description.gait
    print(f"{description.name}: duty {gait.duty}, period {gait.period} s, stride {gait.stride} "
          f"m, trunk {gait.trunk}, {args.samples} samples of a stride, ground policy "
          f"{description.ground.get('policy', 'min-wrench')}")
    print("| gait | slope (deg) | two feet down | a foot would pull or slip | correction (mm) "
          "| trunk's departure (m/s^2) | scene (CPU s) | inverse (CPU s) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for pattern in args.gaits:
        for slope in [0.0, *args.slopes]:
            print(_row(description, pattern, slope, args.samples), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
