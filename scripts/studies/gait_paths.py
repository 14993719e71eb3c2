"""How closely the feet of the hexapod follow their designed paths, gait by gait (not a test).

For each gait the six-legged robot (trunk held, 20:1) is driven by its joint laws; the engine's
feet (the ``foot`` markers, from the inverse-dynamics positions) are compared, at SAMPLES times
over one stride, with the paths the laws were designed for (``legs.stepping``): the largest
distance to the path, the largest height above the ground in stance, the stance velocity's
largest deviation from the walking speed (central differences of the engine's positions,
h = 1e-6 s, relative), and the lift reached in swing. Also the solved joints' ranges and the
time to design one leg's laws (the engine's kinematics over a cycle and the fit, natural scale).

    python3 scripts/studies/gait_paths.py [--samples 1001] [--plot FIGURE.png]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import hexapod as hx
from hexapod import inverse_dynamics, marker_trajectories
from legs.cockroach import FOOT_LIFT_MM, GROUND_Z_MM, MODEL_SCALE, STRIDE_PERIOD
from legs.gait import GAITS, LEG_NAMES
from legs.robot import hexapod_scene
from legs.stepping import SOLVED_JOINTS, stepping_harmonics


def measure(gait: str, samples: int) -> tuple[list[list], dict]:
    pattern = GAITS[gait]
    model = hx.assemble(hexapod_scene(gait))
    t = np.linspace(0.0, STRIDE_PERIOD, samples)
    h = 1e-6
    feet = {}
    for offset in (0.0, -h, h):
        feet[offset] = marker_trajectories(model, inverse_dynamics(model, t + offset).q, "foot")
    targets = pattern.foot_targets(t)
    speed = pattern.walking_speed()
    ground = GROUND_Z_MM * 1e-3 * MODEL_SCALE
    rows = []
    for leg in LEG_NAMES:
        foot = feet[0.0][f"{leg}/tarsus"]
        stance = pattern.in_stance(leg, t)
        velocity = (feet[h][f"{leg}/tarsus"] - feet[-h][f"{leg}/tarsus"]) / (2 * h)
        rows.append([gait, leg, np.linalg.norm(foot - targets[leg], axis=1).max(),
                     np.abs(foot[stance, 2] - ground).max(),
                     np.abs(velocity[stance] - [-speed, 0, 0]).max() / speed,
                     (foot[:, 2] - ground).max() / (FOOT_LIFT_MM * 1e-3 * MODEL_SCALE)])
    return rows, {leg: feet[0.0][f"{leg}/tarsus"] for leg in LEG_NAMES}


def joint_ranges(duty: float) -> list[str]:
    out = []
    for position in ("front", "middle", "hind"):
        stepping_harmonics.cache_clear()
        started = time.perf_counter()
        harmonics = stepping_harmonics(position, duty)
        elapsed = time.perf_counter() - started
        tau = np.linspace(0.0, 1.0, 2001)
        ranges = []
        for joint in SOLVED_JOINTS:
            offset, cos, sin = harmonics[joint]
            law = hx.scene.Harmonic(offset, cos, sin, frequency=1.0)
            angles = np.degrees(law(tau))
            ranges.append(f"{joint} {angles.min():+.0f}..{angles.max():+.0f}")
        out.append(f"  {position:6s} ({elapsed:.2f} s to design): " + ", ".join(ranges)
                   + " deg")
    return out


def plot(paths: dict, path: str) -> None:
    from matplotlib.figure import Figure

    figure = Figure(figsize=(12.0, 3.4 * len(paths)), layout="constrained")
    axes = figure.subplots(len(paths), 2, squeeze=False)
    for row, (gait, feet) in enumerate(paths.items()):
        for leg, foot in feet.items():
            axes[row, 0].plot(foot[:, 0], foot[:, 2], label=leg)
            axes[row, 1].plot(foot[:, 0], foot[:, 1], label=leg)
        axes[row, 0].set_title(f"{gait}: side view (trunk frame)", fontsize=9)
        axes[row, 1].set_title(f"{gait}: top view", fontsize=9)
        for ax, label in zip(axes[row], ("z (m)", "y (m)"), strict=True):
            ax.set_xlabel("x (m)")
            ax.set_ylabel(label)
            ax.grid(True, linewidth=0.4, alpha=0.6)
        axes[row, 1].set_aspect("equal", adjustable="datalim")
    axes[0, 1].legend(fontsize=7, ncols=2)
    figure.savefig(path, dpi=110)
    print(f"wrote {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1001)
    parser.add_argument("--plot", metavar="FIGURE.png", help="draw the feet's paths")
    args = parser.parse_args()
    print(f"{'gait':9s} {'leg':4s} {'path error m':>13s} {'stance height m':>16s} "
          f"{'speed error':>12s} {'lift / design':>14s}")
    paths = {}
    for gait in GAITS:
        rows, paths[gait] = measure(gait, args.samples)
        for g, leg, miss, height, speed, lift in rows:
            print(f"{g:9s} {leg:4s} {miss:13.1e} {height:16.1e} {speed:12.1e} {lift:14.6f}")
    for gait, pattern in GAITS.items():
        print(f"solved joints, {gait} (duty {pattern.duty:.3g}):")
        print("\n".join(joint_ranges(pattern.duty)))
    if args.plot:
        plot(paths, args.plot)


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    main()
