"""The mixed model of Dumitru, Marin and Margine of the front leg against the engine over one
stride (not a test).

The mixed formulation (legs/seed001.py: centre of mass plus joint angle per element, 24
unknowns, 18 rows) and the engine's inverse dynamics are run on the same joint laws, with the
foot free and with the ground's reaction in stance; the largest differences of the joint forces
(world axes) and of the driving torques are printed relative to their largest magnitudes.

    python3 scripts/papers/seed001_check.py [--samples 501]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import hexapod as hx
from hexapod import inverse_dynamics
from legs import GAITS, front_leg_scene, leg_geometry, walking_leg_scene
from legs.cockroach import STRIDE_PERIOD
from legs.leg import JOINTS
from legs.robot import robot_weight
from legs.seed001 import MixedModel


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=501)
    args = parser.parse_args()
    t = np.linspace(0.0, STRIDE_PERIOD, args.samples)
    laws = GAITS["tripod"].joint_laws("L1", STRIDE_PERIOD)
    values = [laws[joint].evaluate(t) for joint in JOINTS]
    q, q_dot, q_ddot = (np.column_stack([v[k] for v in values]) for k in range(3))
    print(f"{'foot':8s} {'joint forces':>13s} {'torques':>10s}   (relative, {t.size} samples)")
    for loaded in (False, True):
        scene = walking_leg_scene("L1") if loaded else front_leg_scene()
        engine = inverse_dynamics(hx.assemble(scene), t, frame="world")
        foot = None
        if loaded:
            load = GAITS["tripod"].stance_load("L1", robot_weight(), STRIDE_PERIOD)
            foot = np.column_stack([law(t) for law in load])
        mixed = MixedModel(leg_geometry("front", "L"), foot_load=loaded).inverse(
            q, q_dot, q_ddot, foot)
        forces = np.abs(mixed.joint_forces - engine.force).max() / np.abs(engine.force).max()
        torques = np.abs(mixed.torques - engine.effort).max() / np.abs(engine.effort).max()
        print(f"{'loaded' if loaded else 'free':8s} {forces:13.1e} {torques:10.1e}")


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    main()
