"""The walking hexapod on real ground under joint control, over strides (not a test).

The tripod gait of the free-trunk hexapod (``legs.robot.hexapod_scene(gait, trunk="free")``,
stride 0.5 s): inverse dynamics at samples chosen until each joint's effort spline is within
``--tol`` of its largest (``legs.replay.adaptive_inverse``); the robot on real ground
(``legs.replay.grounded_scene``): each joint driven by a controller (target the driver's
law, feedforward the inverse efforts, gains ``--kp`` and ``--kd``), each foot a unilateral
contact with the ground (Coulomb friction ``--mu``, plastic impacts) instead of its
scheduled rows; simulated by Moreau-Jean time-stepping at ``--step`` (or ``--method
event-driven`` at ``--rtol``) over ``--strides`` strides (the efforts of one stride repeat).
Printed: each foot's touch-downs and lift-offs against its schedule (the table for one
stride; over more, the largest lateness of each: ``legs.replay.schedule_lateness``, a foot's
first landing and last leaving around each scheduled one), the impacts with their impulses,
the grazes (a foot that touches and leaves at the same instant, with no time on the ground;
the touch-downs' lateness is given with them and without them), the slips, the largest joint
tracking error (the engine's ``err:`` columns, checked against an independent measure of the
joint angles; over several strides, per stride too), the trunk's position against the
prescribed one at the end, the CPU time per simulated second (of the time loop; the whole
run's beside it), the largest difference of the feet's normal forces from the inverse
dynamics' inside the stances, and the feet that slip inside a stance beside those the
inverse dynamics marks ``slip`` at ``--mu`` (its friction demand ``|F_t| / F_n`` above it).
With ``--figures DIR``, the simulated gait against the scheduled one (``gait.png``), the
ground forces (``contacts.png``) and the tracking errors (``tracking.png``) are written
there; nothing else is written. With ``--actuators TABLE`` each controller is limited by its
joint's motor (its torque-speed line), as a robot with those motors would be.

    python3 scripts/studies/walking_on_ground.py [--gait tripod] [--kp 200] [--kd 2]
        [--bandwidth HZ] [--mu 0.8] [--method moreau-jean] [--step 1e-3] [--rtol 1e-6]
        [--tol 3e-6] [--strides 1] [--figures DIR] [--actuators TABLE.toml]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402
from legs.cockroach import STRIDE_PERIOD  # noqa: E402
from legs.efforts import EFFORT_TOL, adaptive_inverse  # noqa: E402
from legs.replay import (  # noqa: E402
    GROUND_KD,
    GROUND_KP,
    event_times,
    grazes,
    grounded_scene,
    joint_angles,
    prescribed_angles,
    schedule_lateness,
    wrapped,
)
from legs.robot import hexapod_scene  # noqa: E402


def schedule_table(model, result, period: float) -> list[str]:
    """Per foot: the scheduled stances (of the driven ``model``) and the simulated
    touch-downs and lift-offs (ms), over the first stride."""
    lines = [f"{'foot':10} {'scheduled stances (ms)':28} {'touch-downs (ms)':22} lift-offs (ms)"]
    for contact in model.contacts:
        stances = contact.stances(0.0, period)
        times = {kind: [1e3 * e.t for e in result.events
                        if e.contact == contact.name and e.kind == kind and e.t <= period]
                 for kind in ("touch-down", "lift-off")}
        lines.append(f"{contact.name:10} "
                     f"{' '.join(f'{1e3 * a:.0f}-{1e3 * b:.0f}' for a, b in stances):28} "
                     f"{' '.join(f'{x:.1f}' for x in times['touch-down']):22} "
                     f"{' '.join(f'{x:.1f}' for x in times['lift-off'])}")
    return lines


def slips(model, inverse, result, mu: float, margin: float = 5e-3) -> list[str]:
    """The inverse dynamics' peak friction demand ``|F_t| / F_n`` per foot (over the samples
    where it carries more than a thousandth of the weight), the feet it marks ``slip`` at
    ``mu`` (a demand above it), and the feet that slip in the simulation while the schedule
    has them in stance (a slip-start more than ``margin`` s inside a stance: not the instants
    a foot is unloaded at touch-down and lift-off)."""
    force = np.asarray(inverse.ground_force, dtype=float)
    weight = float(model.total_mass * np.linalg.norm(model.gravity))
    loaded = np.linalg.norm(force, axis=-1) > 1e-3 * weight
    demand = np.where(loaded, np.hypot(force[..., 0], force[..., 1])
                      / np.maximum(force[..., 2], 1e-300), 0.0)
    names = [c.name for c in model.contacts]
    peaks = demand.max(axis=0)
    period = float(inverse.times[-1] - inverse.times[0])
    slipped = set()
    for event in result.events:
        if event.kind != "slip-start" or event.contact not in names:
            continue
        contact = model.contacts[names.index(event.contact)]
        cycle = event.t % period
        if any(a + margin < cycle < b - margin for a, b in contact.stances(0.0, period)):
            slipped.add(event.contact)
    marked = [n for n, p in zip(names, peaks, strict=True) if p > mu]
    return ["inverse dynamics, peak |F_t| / F_n per foot: "
            + ", ".join(f"{n} {p:.3f}" for n, p in zip(names, peaks, strict=True)),
            f"at mu = {mu:g} it marks slip: {', '.join(marked) or 'none'}; the simulation's "
            f"feet slipping inside a stance: {', '.join(sorted(slipped)) or 'none'}"]


def normal_force_gap(model, inverse, result, margin: float = 0.02) -> str:
    """The largest difference of each foot's simulated normal force from the inverse
    dynamics' (its samples interpolated, a stride repeating) inside the scheduled stances,
    ``margin`` s away from their touch-downs and lift-offs, in N and in body weights."""
    period = float(inverse.times[-1] - inverse.times[0])
    names = [c.name for c in model.contacts]
    order = [result.contact_names.index(n) for n in names]
    simulated = result.contact_forces[:, order, 2]
    cycle = np.mod(result.t - inverse.times[0], period) + inverse.times[0]
    worst, where = 0.0, ""
    for c, contact in enumerate(model.contacts):
        wanted = np.interp(cycle, inverse.times, inverse.ground_force[:, c, 2])
        inside = np.zeros(result.t.size, bool)
        for a, b in contact.stances(0.0, float(result.t[-1])):
            inside |= (result.t > a + margin) & (result.t < b - margin)
        if inside.any():
            gap = np.abs(simulated[inside, c] - wanted[inside])
            if gap.max() > worst:
                worst, where = float(gap.max()), contact.name
    weight = float(model.total_mass * np.linalg.norm(model.gravity))
    return (f"normal forces inside the stances ({1e3 * margin:.0f} ms from their ends) within "
            f"{worst:.3g} N of the inverse dynamics' ({worst / weight:.3g} body weights; "
            f"{where})")


def write_figures(folder: Path, model, result, t_end: float) -> None:
    """``gait.png`` (simulated against scheduled), ``contacts.png``, ``tracking.png``."""
    scheduled = [contact.stances(0.0, t_end) for contact in model.contacts]
    figures = hx.output.render_figures({**hx.output.contact_figure_builders(result, scheduled),
                                        **hx.output.tracking_figure_builders(result)})
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in figures.items():
        (folder / name).write_bytes(data)
    print(f"wrote {', '.join(figures)} in {folder}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gait", default="tripod")
    parser.add_argument("--kp", type=float, default=GROUND_KP,
                        help=f"N m/rad (default {GROUND_KP:g})")
    parser.add_argument("--kd", type=float, default=GROUND_KD,
                        help=f"N m s/rad (default {GROUND_KD:g})")
    parser.add_argument("--mu", type=float, default=0.8)
    parser.add_argument("--method", choices=("moreau-jean", "event-driven"),
                        default="moreau-jean")
    parser.add_argument("--step", type=float, default=1e-3,
                        help="s, Moreau-Jean's (default 1e-3)")
    parser.add_argument("--rtol", type=float, default=1e-6,
                        help="the event-driven scheme's relative tolerance (default 1e-6)")
    parser.add_argument("--tol", type=float, default=EFFORT_TOL)
    parser.add_argument("--bandwidth", type=float, default=None,
                        help="Hz: gains critically damped on each joint's reflected inertia "
                             "at this bandwidth, instead of --kp and --kd")
    parser.add_argument("--strides", type=int, default=1)
    parser.add_argument("--figures", type=Path, default=None, help="a folder for the figures")
    parser.add_argument("--actuators", type=Path, default=None,
                        help="an actuator table: each controller limited by its joint's motor "
                        "(e.g. data/actuators/hexapod.toml)")
    args = parser.parse_args()
    period = STRIDE_PERIOD
    scene = hexapod_scene(gait=args.gait, trunk="free", period=period)
    model = hx.assemble(scene)
    mark = time.process_time()
    inverse, _ = adaptive_inverse(model, scene, 0.0, period, tol=args.tol)
    print(f"inverse dynamics: {inverse.times.size} samples, "
          f"{time.process_time() - mark:.1f} s CPU")
    kp, kd = (args.kp, args.kd) if args.bandwidth is None else hx.simulation.critical_gains(
        model, inverse.q[0], args.bandwidth)
    if args.bandwidth is not None:
        print(f"gains at {args.bandwidth:g} Hz: kp {min(kp.values()):.3g} to "
              f"{max(kp.values()):.3g} N m/rad, kd {min(kd.values()):.3g} to "
              f"{max(kd.values()):.3g} N m s/rad")
    motors = None if args.actuators is None else hx.scene.read_actuators(args.actuators)
    grounded = hx.assemble(grounded_scene(scene, inverse, kp=kp, kd=kd, mu=args.mu,
                                          periodic=True, actuators=motors))
    t_end = args.strides * period
    mark = time.process_time()
    options = ({"step": args.step} if args.method == "moreau-jean" else {"rtol": args.rtol})
    result = hx.simulate(grounded, t_end, method=args.method, **options)
    cpu = time.process_time() - mark
    print(f"{result.method} at {next(iter(options.values())):g}: {result.status} "
          f"{result.message}")
    print(f"CPU {cpu:.1f} s for {result.t[-1]:.3f} s simulated, the laws' table and the "
          f"kernels built included; the time loop's {result.cpu_time:.1f} s: "
          f"{result.cpu_time / result.t[-1]:.1f} s per simulated second "
          f"(load {os.getloadavg()[0]:.1f})")
    print("\n".join(schedule_table(model, result, period)))
    print("\n".join(slips(model, inverse, result, args.mu)))
    print(normal_force_gap(model, inverse, result))
    reached = float(result.t[-1])
    worst = schedule_lateness(model, event_times(result.events), reached)
    landed = schedule_lateness(model, event_times(result.events, with_grazes=False), reached)
    print(f"over {reached:.3f} s: touch-downs within {1e3 * worst['touch-down']:.2f} ms "
          f"of the schedule ({1e3 * landed['touch-down']:.2f} ms without the grazes), "
          f"lift-offs within {1e3 * worst['lift-off']:.2f} ms")
    touches = grazes(result.events)
    if touches:
        print(f"{len(touches)} grazes (touched and left at once), the largest impulse "
              f"{max(np.linalg.norm(p) for *_, p in touches):.3g} N s:")
        for t, name, impulse in touches:
            print(f"  {1e3 * t:9.4f} ms {name:10} impulse {np.linalg.norm(impulse):.3g} N s")
    for event in result.events:
        if event.kind in ("impact", "slip-start", "slip-end"):
            print(f"  {1e3 * event.t:7.1f} ms {event.kind:10} {event.contact:10} "
                  + (f"impulse {np.array2string(event.impulse, precision=4)} N s"
                     if event.kind == "impact" else ""))
    joints, wanted = prescribed_angles(scene, result.t)
    error = np.abs(wrapped(joint_angles(grounded, result.q, joints) - wanted))
    k, j = np.unravel_index(int(np.argmax(error)), error.shape)
    engine = float(np.abs(result.tracking).max())
    print(f"largest joint tracking error {error[k, j]:.3g} rad ({joints[j]} at "
          f"{result.t[k]:.3f} s); the engine's err: columns say {engine:.3g} rad")
    if args.strides > 1:  # whether the errors settle or grow from stride to stride
        stride = np.minimum((result.t // period).astype(int), args.strides - 1)
        print("largest joint tracking error per stride (rad): " + ", ".join(
            f"{error[stride == n].max():.2g}" for n in range(args.strides)
            if (stride == n).any()))
    if args.figures is not None:
        write_figures(args.figures, model, result, float(result.t[-1]))
    trunk = [b.name for b in grounded.bodies].index("trunk")
    sl = grounded.bodies[trunk].q
    start, end = (inverse.q[k][model.bodies[trunk].q][:3] for k in (0, -1))
    prescribed = start + args.strides * (end - start)  # a stride's advance, repeated
    print(f"trunk at the end {np.round(result.q[-1][sl][:3], 5)} m, prescribed "
          f"{np.round(prescribed, 5)} m")


if __name__ == "__main__":
    main()
