"""Design sensitivities: their cost against one inverse-dynamics run, and their agreement with
central differences at random parameter points.

Protocol
--------
* Cost: the built-in ``hexapod`` (walking robot, 36 driven joints, min-wrench), one stride at
  ``--samples`` samples (default 501, the report's). One inverse-dynamics run
  (``hx.inverse_dynamics``, after a warm-up run) against the derivatives of every figure of
  merit with respect to ``--parameters`` parameters (default 20: the trunk's mass and inertia,
  the femurs', tibias' and coxas' masses): ``hx.inverse_sensitivities`` and
  ``hx.sweeps.metric_sensitivities`` on that run. CPU time (``time.process_time``), the median
  of ``--repeats`` runs. Target: at most 5 times one run.
* Agreement: at ``--points`` random parameter points (every parameter multiplied by a factor
  drawn in [0.7, 1.3], seeded), for the walking robot and the front leg, the derivatives of
  every effort, joint wrench, ground force and figure of merit against central differences of
  whole runs on the scene re-read with one parameter moved by ``--step`` of its value, or by
  1e-6 m for a joint's position (the ``ctr``, ``fti`` and ``tita`` origins of the front leg on
  its joint laws, ``legs.front_leg_scene``: the built-in leg's joints follow its foot's guides,
  whose derivatives through the kinematics are not computed;
  ``--checked`` parameters drawn per point; the forces are linear in masses and inertias, so
  those differences are exact but for round-off). The error is ``p |exact - difference|`` over
  the largest value of the array (or the metric's value): the change of the output per unit
  relative change of the parameter, relative. Target: 1e-6. A figure of merit is smooth but
  for kinks (a sample's power changing sign in the positive work, the peak moving to another
  sample): one that misses it is checked again at a tenth, a hundredth and a thousandth of the
  step, and the count of those that then agree (a kink within the step) is printed. A failed
  check ends with status 1.

Everything goes to temporary folders; nothing is written.

    python3 scripts/benchmarks/bench_sensitivity.py [--samples 501] [--points 10]

``--points 0``: the cost alone.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

import measure

measure.one_blas_thread()

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402

FAMILIES = ("peak_effort", "rms_effort", "peak_force", "peak_moment", "peak_ground", "energy",
            "cost_of_transport")
ROBOT_PARAMETERS = ["body.trunk.mass", "body.trunk.inertia", "body.*/femur.mass",
                    "body.*/tibia.mass", "body.*/coxa.mass"]
LEG_PARAMETERS = ["body.*.mass", "body.*.inertia"]
#: the front leg on its joint laws also moves its joints: derivatives through the motion
LAW_LEG_PARAMETERS = LEG_PARAMETERS + ["joint.ctr.origin", "joint.fti.origin",
                                       "joint.tita.origin"]
TOLERANCE = 1e-6


def derivatives(model, result, changes):
    sensitivity = hx.inverse_sensitivities(model, result, changes)
    return sensitivity, hx.sweeps.metric_sensitivities(model, result, sensitivity, FAMILIES)


def cost(samples: int, count: int, repeats: int) -> float:
    scene = hx.load_scene("hexapod")
    model = hx.assemble(scene)
    times = np.linspace(0.0, model.time_window()[0], samples)
    changes = hx.sweeps.inertia_parameters(scene, ROBOT_PARAMETERS)[:count]
    result = hx.inverse_dynamics(model, times)  # the warm-up: the phase plans built
    derivatives(model, result, changes)
    run, gradients = [], []
    for _ in range(repeats):
        began = time.process_time()
        result = hx.inverse_dynamics(model, times)
        run.append(time.process_time() - began)
        began = time.process_time()
        derivatives(model, result, changes)
        gradients.append(time.process_time() - began)
    ratio = statistics.median(gradients) / statistics.median(run)
    print(f"walking robot, {samples} samples, {len(changes)} parameters, {len(FAMILIES)} "
          f"families: inverse dynamics {statistics.median(run):.3f} s CPU, every figure of "
          f"merit's gradient {statistics.median(gradients):.3f} s: {ratio:.2f} x "
          "(target: at most 5)")
    return ratio


def outputs(model, result):
    out = {name: getattr(result, name) for name in ("effort", "force", "torque")}
    if model.contacts:
        out["ground_force"] = result.ground_force
    return out


def point_errors(scene, patterns, samples, checked, step, rng) -> tuple[float, str, int]:
    """The worst error at one random point of the parameters, where it is, and how many
    figures of merit agreed only at a smaller step (a kink straddled)."""
    base = hx.sweeps.inertia_parameters(scene, patterns)
    # one factor per body's mass and one per body's inertia (a slender rod's moments, moved
    # apart, would break the triangle inequality the scene reader checks)
    factors: dict[str, float] = {}
    moved = {}
    for change in base:
        kind = change.name.rpartition(".mass")[0] or change.name.split(".inertia")[0] + "/J"
        factor = factors.setdefault(kind, rng.uniform(0.7, 1.3))
        moved[change.name] = change.value / change.scene_scale * factor
    scene = hx.sweeps.with_scene_keys(scene, moved)
    changes = hx.sweeps.inertia_parameters(scene, patterns)
    model = hx.assemble(scene)
    times = np.linspace(0.0, model.time_window()[0], samples)
    result = hx.inverse_dynamics(model, times)
    sensitivity, metric_derivatives = derivatives(model, result, changes)
    metrics = inverse_metrics(model, result)
    worst, where, kinks = 0.0, "", 0
    for p in rng.choice(len(changes), checked, replace=False):
        change = changes[p]
        # a relative step for the masses and inertias (the forces are linear in them), 1e-6 m
        # for a joint's position (they are not: truncation then stays below round-off)
        h = step * abs(change.value) if change.unit != "m" else 1e-6
        ends = moved_runs(scene, change, h, times)
        for name, value in outputs(model, result).items():
            difference = (ends[0][0][name] - ends[1][0][name]) / (2 * h)
            exact = getattr(sensitivity, name)[..., p]
            finite = np.isfinite(value)
            error = change.value * np.abs(exact[finite] - difference[finite]).max()
            error /= np.abs(value[finite]).max()
            if error > worst:
                worst, where = error, f"{change.name}, {name}"
        for column, exact in metric_derivatives.items():
            if not np.isfinite(metrics[column]):
                continue
            weight = abs(change.value) / (abs(metrics[column]) or 1.0)  # relative
            error = metric_error(ends, h, column, exact[p], weight)
            # a figure of merit is smooth but for kinks (a sample's power changing sign in the
            # positive work, the peak moving to another sample): a kink within the step moves
            # the difference, not the derivative. Smaller steps then agree, where a wrong
            # derivative would not.
            smaller = h
            while error > TOLERANCE and smaller > h / 1000:
                smaller /= 10
                error = metric_error(moved_runs(scene, change, smaller, times), smaller, column,
                                     exact[p], weight)
            kinks += smaller < h and error <= TOLERANCE
            if error > worst:
                worst, where = error, f"{change.name}, {column}"
    return worst, where, kinks


def metric_error(ends, h, column, exact, weight) -> float:
    """``|exact - central difference|`` of a figure of merit, times ``weight``."""
    return weight * abs(exact - (ends[0][1][column] - ends[1][1][column]) / (2 * h))


def moved_runs(scene, change, h, times):
    """The outputs and figures of merit of the runs with ``change`` moved by ``+h`` and
    ``-h``."""
    ends = []
    for sign in (1.0, -1.0):
        value = (change.value + sign * h) / change.scene_scale  # the scene's units
        moved = hx.assemble(hx.sweeps.with_scene_keys(scene, {change.name: value}))
        run = hx.inverse_dynamics(moved, times)
        ends.append((outputs(moved, run), inverse_metrics(moved, run)))
    return ends


def inverse_metrics(model, result):
    return hx.sweeps.inverse_metrics(model, result, FAMILIES, 1.0)  # the sweeps' definitions


def checked_scenes():
    """``(name, scene, parameter patterns)`` of the agreement check: the built-in front leg and
    walking robot (their guided joints follow the guides' kinematics, whose derivatives are not
    computed: masses and inertias), and the front leg on its harmonic joint laws, its foot
    loaded as the built-in leg's (``legs.front_leg_scene``), with its joints' positions."""
    from legs import front_leg_scene

    on_laws = front_leg_scene()
    on_laws.add(hx.load_scene("front-leg").forces["ground_reaction"])
    return [("front-leg", hx.load_scene("front-leg"), LEG_PARAMETERS),
            ("front leg on its joint laws", on_laws, LAW_LEG_PARAMETERS),
            ("hexapod", hx.load_scene("hexapod"), ROBOT_PARAMETERS)]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=int, default=501)
    parser.add_argument("--parameters", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--points", type=int, default=10)
    parser.add_argument("--checked", type=int, default=3,
                        help="parameters checked by differences at each point")
    parser.add_argument("--check-samples", type=int, default=101)
    parser.add_argument("--step", type=float, default=1e-4)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    measure.start("bench_sensitivity")
    ratio = cost(args.samples, args.parameters, args.repeats)
    rng = np.random.default_rng(args.seed)
    failed = ratio > 5.0
    for name, scene, patterns in checked_scenes() if args.points > 0 else ():
        errors = []
        for point in range(args.points):
            measure.log(f"{name}: point {point + 1} of {args.points}")
            errors.append(point_errors(scene, patterns, args.check_samples, args.checked,
                                       args.step, rng))
        worst, where, _ = max(errors)
        kinks = sum(e[2] for e in errors)
        print(f"{name}: {args.points} random points, {args.checked} parameters each, step "
              f"{args.step:g}: worst error {worst:.2e} ({where}; target {TOLERANCE:g})"
              + (f"; {kinks} figures of merit agreed at a tenth to a thousandth of the step "
                 "(a kink within it)" if kinks else ""))
        failed |= worst > TOLERANCE
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
