"""How well the walking hexapod walks, per gait (not a test: the tests bound these figures).

For each gait of the free-trunk hexapod (``legs.robot.hexapod_scene(gait, trunk="free")``), the
inverse dynamics over one stride at ``--samples`` samples, and printed:

* the largest stance-foot slip: the distance of a foot in stance from its foothold (m);
* the largest constraint residual (scaled, as ``InverseResult.max_violation``);
* the centroidal balance: ground reactions plus gravity against the rate of change of the
  robot's linear and angular momentum from the body motions alone, relative to the weight (and
  weight times the characteristic length);
* the peak ground reaction per foot in body weights;
* the CPU time per sample of the inverse dynamics (model built and warmed up first).

    python3 scripts/studies/walking_checks.py [--gait tripod tetrapod wave] [--samples 201]
        [--policy min-wrench]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # as the command line: small matrices

import time  # noqa: E402

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402
from legs.robot import hexapod_scene  # noqa: E402

PERIOD = 0.5


def slip(model, result) -> float:
    """The largest distance of a stance foot from its foothold (m)."""
    feet = hx.marker_trajectories(model, result.q, "foot")
    w = model.law_values(result.times)[0]
    worst = 0.0
    for contact in model.contacts:
        footholds = [k for k, law in enumerate(model.laws)
                     if law.kind == "foothold" and law.contact is contact.schedule]
        stance = np.asarray(contact.in_stance(result.times))
        foot = feet[contact.name.split("/")[0] + "/tarsus"]
        if stance.any():
            worst = max(worst, float(np.abs(foot - w[footholds].T)[stance].max()))
    return worst


def centroidal(model, result) -> tuple[float, float]:
    """Largest unbalanced force over the weight, and moment over weight times length."""
    position, rotation = hx.body_poses(model, result.q)
    feet = hx.marker_trajectories(model, result.q, "foot")
    weight = model.total_mass * float(np.linalg.norm(model.gravity))
    force_error = moment_error = 0.0
    for k in range(result.times.size):
        force, moment = np.zeros(3), np.zeros(3)
        for b in model.bodies:
            a, omega = result.v_dot[k][b.v], result.v[k][b.v][3:]
            net = b.mass * (a[:3] - model.gravity)
            force += net
            moment += (np.cross(position[k, b.index], net)
                       + rotation[k, b.index] @ (b.inertia @ a[3:]
                                                 + np.cross(omega, b.inertia @ omega)))
        for c, name in enumerate(result.contacts):
            ground = result.ground_force[k, c]
            force -= ground
            moment -= np.cross(feet[name.split("/")[0] + "/tarsus"][k], ground)
        force_error = max(force_error, float(np.abs(force).max()) / weight)
        moment_error = max(moment_error, float(np.abs(moment).max())
                           / (weight * model.characteristic_length))
    return force_error, moment_error


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gait", nargs="+", default=["tripod", "wave"],
                        choices=["tripod", "tetrapod", "wave"])
    parser.add_argument("--samples", type=int, default=201)
    parser.add_argument("--policy", default="min-wrench",
                        choices=["min-wrench", "min-effort", "friction"])
    args = parser.parse_args()
    times = np.linspace(0.0, PERIOD, args.samples)
    for gait in args.gait:
        model = hx.assemble(hexapod_scene(gait, trunk="free",
                                          ground=hx.scene.GroundForces(policy=args.policy)))
        hx.inverse_dynamics(model, times[:3])  # the CasADi functions built
        start = time.process_time()
        result = hx.inverse_dynamics(model, times)
        cost = (time.process_time() - start) / times.size
        weight = model.total_mass * float(np.linalg.norm(model.gravity))
        force, moment = centroidal(model, result)
        peaks = np.linalg.norm(result.ground_force, axis=2).max(axis=0) / weight
        print(f"{gait} ({args.policy}, {times.size} samples over {PERIOD} s):")
        print(f"  largest stance-foot slip {slip(model, result):.2g} m "
              f"(robot size {model.characteristic_length:.3g} m); "
              f"constraint residual {result.max_violation:.2g}")
        print(f"  centroidal balance: force {force:.2g} of the weight, moment {moment:.2g}")
        print("  peak ground reaction (body weights): " + ", ".join(
            f"{name.split('/')[0]} {p:.3f}" for name, p in zip(result.contacts, peaks,
                                                               strict=True)))
        print(f"  inverse dynamics: {cost * 1e3:.1f} ms of CPU per sample")


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    main()
