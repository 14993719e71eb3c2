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
  of ``--repeats`` runs. Target: at most 5 times one run. Also printed: the step height's
  alone, and once the robot's 18 segment lengths' (parameters that move the motion).
* Agreement: at ``--points`` random parameter points (every parameter multiplied by a factor
  drawn in [0.7, 1.3], seeded), for the walking robot, the front leg and the quadruped
  (``data/robots/quadruped.toml``, its friction policy: its masses moved, its shanks' lengths
  ``joint.*_knee.parent_frame.position.2`` checked, one at least at each point), the
  derivatives of every effort, joint wrench, ground force and figure of merit against central
  differences of whole runs on the scene re-read with one parameter moved by ``--step`` of its
  value, or by 1e-6 m for a joint's position (the ``ctr``, ``fti`` and ``tita`` origins of the
  front leg on its joint laws, ``legs.front_leg_scene``, and of the built-in leg, whose joints
  follow its foot's guides; the walking robot's coxa, femur and tibia lengths,
  ``joint.*/ctr|fti|tita.parent_frame.position.0``; the last two checked at the points but not
  moved there); ``--checked`` parameters drawn per point; the forces are linear in masses and
  inertias, so those differences are exact but for round-off); and the walking robot's builder
  arguments ``period`` (drawn in [0.35, 0.7] s, derived at fixed phase), ``step_height``
  (drawn in [0.03, 0.07] m, derived through the motion: the feet's paths move the legs),
  ``scale`` (drawn in [15, 25], against ``geometric_scale``, relative to the robot built) and
  ``payload`` (drawn in [0.5, 5] kg), and its description's ``gait.duty`` (drawn in [0.55,
  0.65], its stride and period kept: a longer stance leaves the legs' reach) and
  ``gait.stride`` (drawn in [0.40, 0.46] m, its period and duty kept), the robot built by
  ``legs.hexapod_walking`` (or its description walked) at the value drawn with its masses
  moved as at the other points (not the scale's: its masses follow the scale), against the
  robot built again with the value moved by ``--step`` of it (sampled at the same fractions of
  the stride for the period; the duty's differences of fourth order; the duty's and stride's
  characteristic length held, as derived). The error is ``p |exact - difference|`` over the
  largest value of the array (or the metric's value): the change of the output per unit
  relative change of the parameter, relative. Target: 1e-6. A figure of merit is smooth but
  for kinks (a sample's power changing sign in the positive work, the peak moving to another
  sample): one that misses it is checked again at a tenth, a hundredth and a thousandth of the
  step, and the count of those that then agree (a kink within the step) is printed. A failed
  check ends with status 1.

Everything goes to temporary folders; nothing is written.

    python3 scripts/benchmarks/bench_sensitivity.py [--samples 501] [--points 10]
        [--rebuilt gait.duty payload] [--no-scenes | --scenes hexapod ...]

``--points 0``: the cost alone.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import measure

measure.one_blas_thread()

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402

FAMILIES = ("peak_effort", "rms_effort", "peak_force", "peak_moment", "peak_ground", "energy",
            "cost_of_transport")
ROBOT_PARAMETERS = ["body.trunk.mass", "body.trunk.inertia", "body.*/femur.mass",
                    "body.*/tibia.mass", "body.*/coxa.mass"]
#: the walking robot's segment lengths (coxa, femur, tibia: the joints' frames on their
#: parents), checked at its random points (not moved: a leg moved 30 % may not reach its path)
ROBOT_LENGTHS = ["joint.*/ctr.parent_frame.position.0", "joint.*/fti.parent_frame.position.0",
                 "joint.*/tita.parent_frame.position.0"]
LEG_PARAMETERS = ["body.*.mass", "body.*.inertia"]
#: the built-in front leg's joints' origins, checked at its points (its joints follow the
#: foot's guides: through the phase path's step)
LEG_ORIGINS = ["joint.ctr.origin", "joint.fti.origin", "joint.tita.origin"]
#: the front leg on its joint laws also moves its joints: derivatives through the motion
LAW_LEG_PARAMETERS = LEG_PARAMETERS + ["joint.ctr.origin", "joint.fti.origin",
                                       "joint.tita.origin"]
TOLERANCE = 1e-6
#: the quadruped's shank lengths (its knees' frames on the thighs), derived through the
#: friction policy's QP on its active set (its scene's default policy)
QUADRUPED_LENGTHS = ["joint.*_knee.parent_frame.position.2"]


def derivatives(model, result, changes, scene=None):
    moved = None if scene is None else hx.sweeps.moved_model(scene, model, changes)
    sensitivity = hx.inverse_sensitivities(model, result, changes, moved=moved)
    return sensitivity, hx.sweeps.metric_sensitivities(model, result, sensitivity, FAMILIES)


def cost(samples: int, count: int, repeats: int) -> float:
    scene = hx.load_scene("hexapod")
    model = hx.assemble(scene)
    times = np.linspace(0.0, model.time_window()[0], samples)
    changes = hx.sweeps.inertia_parameters(scene, ROBOT_PARAMETERS)[:count]
    height = hx.sweeps.inertia_parameters(scene, ["step_height"])
    gait = hx.sweeps.inertia_parameters(scene, ["gait.step_height", "gait.duty"])
    result = hx.inverse_dynamics(model, times)  # the warm-up: the phase plans built
    derivatives(model, result, changes)
    derivatives(model, result, height)
    run, gradients, lifted = [], [], []
    for _ in range(repeats):
        began = time.process_time()
        result = hx.inverse_dynamics(model, times)
        run.append(time.process_time() - began)
        began = time.process_time()
        derivatives(model, result, changes)
        gradients.append(time.process_time() - began)
        began = time.process_time()
        derivatives(model, result, height)
        lifted.append(time.process_time() - began)
    ratio = statistics.median(gradients) / statistics.median(run)
    print(f"walking robot, {samples} samples, {len(changes)} parameters, {len(FAMILIES)} "
          f"families: inverse dynamics {statistics.median(run):.3f} s CPU, every figure of "
          f"merit's gradient {statistics.median(gradients):.3f} s: {ratio:.2f} x "
          "(target: at most 5)")
    print(f"  the step height alone (the motion moves: the phase step differentiated): "
          f"{statistics.median(lifted):.3f} s, "
          f"{statistics.median(lifted) / statistics.median(run):.2f} x")
    began = time.process_time()
    derivatives(model, result, gait)
    spent = time.process_time() - began
    print(f"  the step height and the duty factor together (one forward sweep, two "
          f"directions): {spent:.3f} s, {spent / statistics.median(run):.2f} x")
    lengths = hx.sweeps.inertia_parameters(scene, ROBOT_LENGTHS)
    began = time.process_time()  # once, the moved model's assembly and plans included
    derivatives(model, result, lengths, scene)
    spent = time.process_time() - began
    print(f"  its {len(lengths)} segment lengths (the same, on the scene assembled again with "
          f"the joints' frames shifted by symbols): {spent:.3f} s, "
          f"{spent / statistics.median(run):.2f} x")
    return ratio


def outputs(model, result):
    out = {name: getattr(result, name) for name in ("effort", "force", "torque")}
    if model.contacts:
        out["ground_force"] = result.ground_force
    return out


def random_point(scene, patterns, rng) -> dict:
    """The scene keys of a random point: one factor in [0.7, 1.3] per body's mass and one per
    body's inertia (a slender rod's moments, moved apart, would break the triangle inequality
    the scene reader checks)."""
    factors: dict[str, float] = {}
    moved = {}
    for change in hx.sweeps.inertia_parameters(scene, patterns):
        kind = change.name.rpartition(".mass")[0] or change.name.split(".inertia")[0] + "/J"
        factor = factors.setdefault(kind, rng.uniform(0.7, 1.3))
        moved[change.name] = change.value / change.scene_scale * factor
    return moved


def point_errors(scene, patterns, lengths, samples, checked, step, rng
                 ) -> tuple[float, str, int]:
    """The worst error at one random point of the parameters ``patterns`` (``lengths``
    checked there, not moved: one of them at least), where it is, and how many figures of
    merit agreed only at a smaller step (a kink straddled)."""
    scene = hx.sweeps.with_scene_keys(scene, random_point(scene, patterns, rng))
    changes = hx.sweeps.inertia_parameters(scene, patterns + lengths)
    model = hx.assemble(scene)
    times = np.linspace(0.0, model.time_window()[0], samples)
    run = Run(model, hx.inverse_dynamics(model, times), changes, scene)
    worst, where, kinks = 0.0, "", 0
    chosen = rng.choice(len(changes), checked, replace=False)
    moved = len(hx.sweeps.inertia_parameters(scene, patterns)) if patterns else 0
    if lengths and chosen.max() < moved:  # a length among them at every point
        chosen[-1] = rng.integers(moved, len(changes))
    for p in chosen:
        change = changes[p]
        # a relative step for the masses and inertias (the forces are linear in them), 1e-6 m
        # for a joint's position (they are not: truncation then stays below round-off)
        h = step * abs(change.value) if change.unit != "m" else 1e-6
        found = run.errors(p, h, lambda h, change=change: moved_runs(scene, change, h, times))
        worst, where = max((worst, where), found[:2])
        kinks += found[2]
    return worst, where, kinks


#: The walking robot's parameters checked by rebuilding it: name -> (the range the value is
#: drawn in, whether the samples stay at the same fractions of the stride, the parameter
#: derived: the builder's own, or the geometric scale relative to the robot built). The duty
#: factor is its description's (``gait.duty``: stride and period kept), rebuilt with its
#: characteristic length held, as derived, and differenced to fourth order (a foot's weight
#: ramps up as a cubic over 6 % of its stance: second-order differences of touch-down samples
#: are 1e-4 off at the step).
REBUILT = {"period": ((0.35, 0.7), True, None), "step_height": ((0.03, 0.07), False, None),
           "scale": ((15.0, 25.0), False, "geometric_scale"), "payload": ((0.5, 5.0), False, None),
           "gait.duty": ((0.55, 0.65), False, None), "gait.stride": ((0.40, 0.46), False, None)}


def walking_robot(argument: str, value: float, length: float | None = None):
    """The built-in walking robot with ``argument`` at ``value``: its builder's, or for
    ``gait.duty`` and ``gait.stride`` its description's gait (its characteristic length
    ``length`` when given)."""
    from dataclasses import replace

    from legs.robot import cockroach_description, hexapod_walking, walking_pattern
    from legs.walker import robot_scene

    if not argument.startswith("gait."):
        return hexapod_walking(**{argument: value})
    description = cockroach_description(walking_pattern("tripod", None), 0.5)
    gait = replace(description.gait, **{argument.split(".")[1]: value})
    scene = robot_scene(replace(description, gait=gait))
    scene.characteristic_length = length
    return scene


def rebuilt_errors(argument, samples, step, rng) -> tuple[float, str, int]:
    """A parameter of the walking robot at one random point (:data:`REBUILT`): the robot
    built at a value drawn in its range, its masses and inertias moved as at the other points,
    derived (the period at fixed phase, the step height and the duty through the motion),
    against central differences of the robot built again with the value moved by ``step`` of
    it; over a stride, sampled at the same fractions of it for the period."""
    (low, high), with_phase, relative = REBUILT[argument]
    value = rng.uniform(low, high)
    # the masses moved as at the other points: scene keys, fixed values, which the builder's
    # scale would no longer scale (the scale's point keeps the built robot's masses)
    moved = random_point(hx.load_scene("hexapod"), ROBOT_PARAMETERS, rng) \
        if not relative else {}
    if argument == "payload":  # on the trunk's mass, which the point keeps
        moved.pop("body.trunk.mass", None)
    scene = hx.sweeps.with_scene_keys(walking_robot(argument, value), moved)
    model = hx.assemble(scene)
    held = model.characteristic_length if argument.startswith("gait.") else None

    def built(x):
        return hx.sweeps.with_scene_keys(walking_robot(argument, x, held), moved)

    period = model.cycle_time()
    phases = np.linspace(0.0, 1.0, samples)

    def times(x):
        return phases * (x if with_phase else period)

    changes = hx.sweeps.inertia_parameters(scene, [relative or argument])
    run = Run(model, hx.inverse_dynamics(model, times(value)), changes, scene)

    def at(x):
        moved_model = hx.assemble(built(x))
        result = hx.inverse_dynamics(moved_model, times(x))
        return outputs(moved_model, result), inverse_metrics(moved_model, result)

    def ends(h):  # h in the parameter's units (relative for the geometric scale)
        if relative:
            return [at(value * (1 + h)), at(value * (1 - h))]
        if argument != "gait.duty":
            return [at(value + h), at(value - h)]
        # fourth order: ends whose central difference is (8 (f(h) - f(-h)) - f(2h) + f(-2h))
        # / 12 h
        near, far = (at(value + h), at(value - h)), (at(value + 2 * h), at(value - 2 * h))
        return [tuple({k: (8 * n[i][k] - f[i][k]) / 6 for k in n[i]} for i in range(2))
                for n, f in zip(near, far, strict=True)]

    # the duty's fourth-order difference at a tenth of the step: its truncation at a
    # touch-down sample (the weight's quartic term one-sided) falls as the step cubed
    return run.errors(0, step * changes[0].value * (0.1 if argument == "gait.duty" else 1.0),
                      ends)


class Run:
    """A run at a point, its derivatives and figures of merit, and their errors against the
    central differences of runs with one parameter moved."""

    def __init__(self, model, result, changes, scene=None):
        self.model, self.result, self.changes = model, result, changes
        self.sensitivity, self.metric_derivatives = derivatives(model, result, changes, scene)
        self.metrics = inverse_metrics(model, result)

    def errors(self, p: int, h: float, runs) -> tuple[float, str, int]:
        """The worst error of parameter ``p``'s derivatives against the differences of
        ``runs(h)`` (the outputs and figures of merit at ``+h`` and ``-h``), where it is, and
        whether a figure of merit agreed only at a smaller step."""
        change, worst, where, kinks = self.changes[p], 0.0, "", 0
        ends = runs(h)
        for name, value in outputs(self.model, self.result).items():
            difference = (ends[0][0][name] - ends[1][0][name]) / (2 * h)
            exact = getattr(self.sensitivity, name)[..., p]
            finite = np.isfinite(value)
            error = change.value * np.abs(exact[finite] - difference[finite]).max()
            error /= np.abs(value[finite]).max()
            if error > worst:
                worst, where = error, f"{change.name}, {name}"
        for column, exact in self.metric_derivatives.items():
            if not np.isfinite(self.metrics[column]):
                continue
            weight = abs(change.value) / (abs(self.metrics[column]) or 1.0)  # relative
            error = metric_error(ends, h, column, exact[p], weight)
            # a figure of merit is smooth but for kinks (a sample's power changing sign in the
            # positive work, the peak moving to another sample): a kink within the step moves
            # the difference, not the derivative. Smaller steps then agree, where a wrong
            # derivative would not.
            smaller = h
            while error > TOLERANCE and smaller > h / 1000:
                smaller /= 10
                error = metric_error(runs(smaller), smaller, column, exact[p], weight)
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
    """``(name, scene, parameter patterns moved and checked, patterns checked)`` of the
    agreement check: the built-in front leg with its joints' origins (its joints follow the
    foot's guides: through the phase path's step differentiated), the front leg on its
    harmonic joint laws, its foot loaded as the built-in leg's (``legs.front_leg_scene``),
    with its joints' positions (the tree path), and the walking robot with its segment
    lengths (its joints' frames on their parents: the phase path's step), and the quadruped
    (``data/robots/quadruped.toml``) with its masses and its shanks' lengths through its
    friction policy."""
    from legs import front_leg_scene

    on_laws = front_leg_scene()
    on_laws.add(hx.load_scene("front-leg").forces["ground_reaction"])
    quadruped = hx.load_scene(str(Path(__file__).resolve().parents[2] / "data" / "robots"
                                  / "quadruped.toml"))
    return [("front-leg", hx.load_scene("front-leg"), LEG_PARAMETERS, LEG_ORIGINS),
            ("front leg on its joint laws", on_laws, LAW_LEG_PARAMETERS, []),
            ("hexapod", hx.load_scene("hexapod"), ROBOT_PARAMETERS, ROBOT_LENGTHS),
            ("quadruped, friction policy", quadruped, ["body.*.mass"], QUADRUPED_LENGTHS)]


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
    parser.add_argument("--rebuilt", nargs="*", choices=list(REBUILT), default=list(REBUILT),
                        help="the walking robot's parameters checked against the robot built "
                        "again (default: all)")
    parser.add_argument("--no-scenes", action="store_true",
                        help="skip the scenes' random points (masses, inertias, lengths)")
    parser.add_argument("--scenes", nargs="*", default=None, metavar="NAME",
                        help="the scenes whose random points are checked (default: all: "
                        "front-leg, 'front leg on its joint laws', hexapod, 'quadruped, "
                        "friction policy')")
    args = parser.parse_args()
    measure.start("bench_sensitivity")
    ratio = cost(args.samples, args.parameters, args.repeats)
    rng = np.random.default_rng(args.seed)
    failed = ratio > 5.0
    scenes = [entry for entry in checked_scenes() if args.scenes is None
              or entry[0] in args.scenes] if args.points > 0 and not args.no_scenes else ()
    for name, scene, patterns, lengths in scenes:
        errors = []
        for point in range(args.points):
            measure.log(f"{name}: point {point + 1} of {args.points}")
            errors.append(point_errors(scene, patterns, lengths, args.check_samples,
                                       args.checked, args.step, rng))
        failed |= report(f"{name}: {args.points} random points, {args.checked} parameters "
                         f"each", errors, args.step)
    for argument in args.rebuilt if args.points > 0 else ():
        errors = []
        for point in range(args.points):
            measure.log(f"hexapod, its {argument}: point {point + 1} of {args.points}")
            errors.append(rebuilt_errors(argument, args.check_samples, args.step, rng))
        failed |= report(f"hexapod, its {argument} (the robot built again): {args.points} "
                         "random points", errors, args.step)
    return 1 if failed else 0


def report(what: str, errors: list, step: float) -> bool:
    """Print the worst of ``errors`` (``point_errors``'s); whether it fails the target."""
    worst, where, _ = max(errors)
    kinks = sum(e[2] for e in errors)
    print(f"{what}, step {step:g}: worst error {worst:.2e} ({where}; target {TOLERANCE:g})"
          + (f"; {kinks} figures of merit agreed at a tenth to a thousandth of the step "
             "(a kink within it)" if kinks else ""))
    return worst > TOLERANCE


if __name__ == "__main__":
    sys.exit(main())
