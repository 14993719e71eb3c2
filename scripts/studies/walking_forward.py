"""Inverse and forward agree on the walking hexapod, over one stride of each gait (not a test).

For the tripod and the wave gait of the free-trunk hexapod (``legs.robot.hexapod_scene(gait,
trunk="free")``, stride 0.5 s): inverse dynamics at samples chosen until each joint's effort
spline is within ``--tol`` of its largest effort (``legs.replay.adaptive_inverse``); the forward
twin, its 36 joint drivers replaced by those efforts (``legs.replay.replay_scene``); its
replay by ``hexapod.simulate`` (default method and tolerances) in windows of ``--window`` s,
each from the prescribed state at its start, restarted inside at every touch-down and
lift-off (``legs.replay.replay``: the twin is unstable, see that module). Printed per gait: the
samples, the largest joint-angle error over the stride against the joint drivers' laws (and
where), the trunk's position error at the end of the stride (its centre of mass against the
inverse result's, accumulated over the last window, from the prescribed state 10 ms before),
and the run times.

``--unbroken T`` also replays without windows, one run from t = 0 to T, and prints how its
error grows (the instability); ``--one-call`` replays the tripod across a touch-down and a
lift-off in single calls of ``hexapod.simulate`` (what ``legs.replay`` avoids). Nothing is
written.

    python3 scripts/studies/walking_forward.py [--gait tripod wave] [--tol 3e-6] [--window 0.01]
        [--method dopri5-projection] [--rtol 1e-6] [--atol 1e-8] [--unbroken 0.15]
        [--one-call]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

# One OpenBLAS thread, as the command line and the tests have: on this robot's small matrices
# threads only cost (the inverse dynamics of a stride took 100 s with two, 12 s with one).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import time  # noqa: E402

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402
from legs.efforts import EFFORT_TOL  # noqa: E402
from legs.replay import (  # noqa: E402
    WINDOW,
    agreement,
    joint_angles,
    prescribed_angles,
    replay,
    replay_gait,
    wrapped,
)


def stride(gait: str, args) -> dict:
    out = replay_gait(gait, tol=args.tol, window=args.window, method=args.method,
                      rtol=args.rtol, atol=args.atol)
    run, agree, sampling = out["run"], out["agreement"], out["sampling"]
    print(f"\n{gait}: {out['result'].times.size} samples of inverse dynamics (rounds "
          f"{' -> '.join(map(str, sampling.samples))}, splines within {args.tol:g} of each "
          f"joint's largest effort{'' if sampling.converged else ', NOT converged'})")
    print(f"  replay: {run.status}{' ' + run.message if run.message else ''}; "
          f"{run.starts.size - 1} windows of {args.window:g} s, {run.steps} steps "
          f"({run.rejected} rejected), {run.method} rtol {run.rtol:g} atol {run.atol:g}")
    print(f"  largest joint-angle error   {agree.angle_error:.3g} rad  ({agree.worst_joint}, "
          f"t = {agree.worst_time:.4f} s)")
    print(f"  trunk position error at the end of the stride   {agree.trunk_error:.3g} m")
    print(f"  angle measure on the inverse's own positions    {agree.reference_error:.2g} rad")
    print(f"  time: inverse dynamics {out['inverse_time']:.1f} s, assembly "
          f"{out['assemble_time']:.1f} s, replay {out['run_time']:.1f} s, total "
          f"{out['total_time']:.1f} s")
    return out


def unbroken(out: dict, end: float, args) -> None:
    """One run from t = 0 without windows, and its error against time."""
    started = time.perf_counter()
    run = replay(out["twin_model"], out["result"], window=None, method=args.method,
                 rtol=args.rtol, atol=args.atol, every=1, until=end)
    errors = agreement(out["scene"], out["twin_model"], run, out["result"]).errors
    message = f" {run.message[:160]}" if run.message else ""
    print(f"  unbroken run from 0 to {end:g} s: {run.status}{message} "
          f"({time.perf_counter() - started:.1f} s)")
    marks = np.arange(0.0, run.t[-1] + 1e-9, 0.025)
    cells = [f"{run.t[k]:.3f} s {errors[k]:.1e}"
             for k in sorted({int(np.abs(run.t - m).argmin()) for m in marks})]
    print("    error: " + ", ".join(cells))
    early = (run.t > 0.01) & (errors > 1e-12) & (errors < 1e-3)
    if early.sum() > 2:
        rate = np.polyfit(run.t[early], np.log(errors[early]), 1)[0]
        print(f"    grows as exp({rate:.0f} t) (fit where 1e-12 < error < 1e-3)")


def one_call(out: dict, args) -> None:
    """The tripod across a touch-down (0.2 s) and a lift-off (0.25 s), each in one call of
    hexapod.simulate from the prescribed state, against legs.replay's restarts."""
    model, result, scene = out["twin_model"], out["result"], out["scene"]
    print("\ntripod, single calls of hexapod.simulate across a switch (legs.replay restarts "
          "there):")
    for start, end, what in ((0.195, 0.205, "touch-down at 0.2 s"),
                             (0.245, 0.255, "lift-off at 0.25 s")):
        k = int(np.abs(result.times - start).argmin())
        run = hx.simulate(model, end, t0=result.times[k], q0=result.q[k], v0=result.v[k],
                          method=args.method, rtol=args.rtol, atol=args.atol, forces=False)
        joints, wanted = prescribed_angles(scene, run.t)
        error = np.abs(wrapped(joint_angles(model, run.q, joints) - wanted)).max()
        print(f"  {what}: from {result.times[k]:.4f} s to {end} s in one call: {run.status}, "
              f"largest joint-angle error {error:.2g} rad")
    errors = out["agreement"].errors
    window = (out["run"].t > 0.194) & (out["run"].t < 0.256)
    print(f"  the same span in legs.replay's windows: largest error {errors[window].max():.2g} "
          "rad")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gait", nargs="+", default=["tripod", "wave"],
                        choices=["tripod", "tetrapod", "wave"])
    parser.add_argument("--tol", type=float, default=EFFORT_TOL,
                        help="accuracy of the effort splines, of each joint's largest effort")
    parser.add_argument("--window", type=float, default=WINDOW, help="replay window (s)")
    parser.add_argument("--method", default=hx.simulation.DEFAULT_METHOD,
                        choices=list(hx.INTEGRATORS))
    parser.add_argument("--rtol", type=float, default=hx.simulation.DEFAULT_RTOL)
    parser.add_argument("--atol", type=float, default=hx.simulation.DEFAULT_ATOL)
    parser.add_argument("--unbroken", type=float, default=None, metavar="T",
                        help="also replay without windows from 0 to T s")
    parser.add_argument("--one-call", action="store_true",
                        help="also replay the tripod across switches in single calls")
    args = parser.parse_args()
    started = time.perf_counter()
    outputs = {}
    for gait in args.gait:
        outputs[gait] = stride(gait, args)
        if args.unbroken:
            unbroken(outputs[gait], args.unbroken, args)
    if args.one_call:
        one_call(outputs.get("tripod") or stride("tripod", args), args)
    print(f"\ntotal {time.perf_counter() - started:.1f} s")


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    main()
