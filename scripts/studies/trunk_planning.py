"""Whether a robot's feet can carry its trunk: a planned trunk against a level one (not a test).

For a robot description (default the project's quadruped, ``data/robots/quadruped.toml``) the
walk is run twice over one stride at ``--samples`` samples, its trunk swaying as planned
(``legs.trunk_path``) and level at constant speed, with the description's ground-force policy:
the samples where a foot would pull or slip (the ground cannot give the forces) and the smallest
normal force of a foot in stance.

    python3 scripts/studies/trunk_planning.py [ROBOT.toml] [--samples 201]
"""

from __future__ import annotations

import argparse
import sys
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
    args = parser.parse_args()
    document = tomllib.loads(args.robot.read_text())
    description = read_robot(document, args.robot)
    times = np.linspace(0.0, description.gait.period, args.samples)
    print(f"{description.name}: {description.gait.pattern or 'phases'}, duty "
          f"{description.gait.duty}, period {description.gait.period} s, stride "
          f"{description.gait.stride} m, {args.samples} samples, ground policy "
          f"{description.ground.get('policy', 'min-wrench')}")
    print("| trunk | samples a foot would pull or slip | least normal force in stance (N) |")
    print("| --- | ---: | ---: |")
    for trunk in ("planned", "level"):
        description.gait.trunk = trunk
        result = hx.inverse_dynamics(hx.assemble(robot_scene(description)), times)
        stance = np.asarray(result.ground_status) != "swing"
        print(f"| {trunk} | {int(result.infeasible.sum())} of {times.size} | "
              f"{result.ground_force[:, :, 2][stance].min():.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
