"""Whether a robot's feet can carry its trunk: the trunk planned with the whole robot, with
the lumped model alone, and level (not a test).

For a robot description (default the project's quadruped, ``data/robots/quadruped.toml``;
``--slope`` sets its ground's slope, degrees) the walk is run over one stride at ``--samples``
samples three times: its trunk swaying as planned with the whole robot's centre of pressure
(``whole-body``, ``legs.balance``), as planned by the lumped model alone (``planned``,
``legs.trunk_path``) and level at constant speed, with the description's ground-force policy:
the samples where a foot would pull or slip (the ground cannot give the forces), the smallest
normal force of a foot in stance, and the CPU time of building the scene (the plan).

    python3 scripts/studies/trunk_planning.py [ROBOT.toml] [--samples 201] [--slope DEG]
"""

from __future__ import annotations

import argparse
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

import hexapod as hx
from legs.description import read_robot
from legs.walker import robot_scene

ROBOT = Path(__file__).resolve().parents[2] / "data" / "robots" / "quadruped.toml"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", nargs="?", type=Path, default=ROBOT)
    parser.add_argument("--samples", type=int, default=201)
    parser.add_argument("--slope", type=float, default=None)
    args = parser.parse_args()
    document = tomllib.loads(args.robot.read_text())
    if args.slope is not None:
        document.setdefault("ground", {})["slope"] = args.slope
    description = read_robot(document, args.robot)
    times = np.linspace(0.0, description.gait.period, args.samples)
    print(f"{description.name}: {description.gait.pattern or 'phases'}, duty "
          f"{description.gait.duty}, period {description.gait.period} s, stride "
          f"{description.gait.stride} m, {args.samples} samples, ground policy "
          f"{description.ground.get('policy', 'min-wrench')}, slope "
          f"{description.ground.get('slope', 0.0)} degrees")
    print("| trunk | samples a foot would pull or slip | least normal force in stance (N) "
          "| plan (CPU s) |")
    print("| --- | ---: | ---: | ---: |")
    for trunk in ("whole-body", "planned", "level"):
        description.gait.trunk = trunk
        tic = time.process_time()
        scene = robot_scene(description)
        planning = time.process_time() - tic
        result = hx.inverse_dynamics(hx.assemble(scene), times)
        stance = np.asarray(result.ground_status) != "swing"
        print(f"| {trunk} | {int(result.infeasible.sum())} of {times.size} | "
              f"{result.ground_force[:, :, 2][stance].min():.2f} | {planning:.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
