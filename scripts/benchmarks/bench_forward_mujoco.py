"""Forward dynamics against MuJoCo at robot sizes: CPU time to an accuracy, against its RK4.

The project's aim (issue 36, item 3): on chains of 10 and 30 links and on the 18-joint robot
on a fixed trunk, hexapod's CPU time to reach a relative error of 1e-6 over 1 s should be at
most 2 times MuJoCo's RK4. This script measures where it stands; it does not assume the aim
is met, and says for each problem whether it is.

Protocol (that of ``bench_forward.py``, whose functions it reuses, against MuJoCo)
-----------------------------------------------------------------------------------
* Problems, every body released at rest under gravity (9.81 m/s^2 along -z), no driver, no
  other force, over 1 s (``bench_forward.py`` runs its chains over 0.5 s; the aim says 1 s):

  - ``chain-10``, ``chain-30``: the serial chains of ``bench_inverse.py`` (N spatial bodies of
    1 kg, 0.1 m apart along x, revolute joints with random axes, seed 0) hanging from the
    ground, released from that horizontal pose;
  - ``hexapod-18``: the 18-joint hexapod of ``bench_inverse.py`` (six 3-joint legs, coxa about
    z, femur and tibia about the leg's normal) with its trunk welded to the ground, every joint
    free: the legs fall from their outstretched pose.

* The same mechanism in MuJoCo (optional extra ``compare``; without it the script says "MuJoCo
  not installed" and runs hexapod alone): the URDF hexapod writes (``hexapod.scene.urdf_text``,
  as ``bench_inverse.py`` gives Pinocchio) read by ``mujoco.MjModel.from_xml_string`` with a
  ``<mujoco><compiler balanceinertia="false" discardvisual="true" fusestatic="false"
  inertiafromgeom="false"/></mujoco>`` block (the inertias as written, every link a body);
  contact and joint limits disabled, no damping, armature, friction loss or stiffness
  (checked), gravity hexapod's. Checked before any timing, each relative to the largest value:
  the initial centres of mass (``xipos``) against hexapod's, and their accelerations and the
  bodies' angular accelerations, world frame (``mj_objectAcceleration`` after
  ``mj_rnePostConstraint``, gravity added back), against hexapod's saddle-point solve: they
  agree to round-off (measured: 1e-15 to 1e-12).
* Error of a run, as ``bench_forward.py``: ``e = max_k max_i |r_i(t_k) - r_i_ref(t_k)| /
  max_k,i |r_i_ref(t_k)|`` over the bodies' centres of mass (MuJoCo: ``data.xipos`` after every
  step) at the end of every step; the reference is hexapod's ``--reference-method`` (default
  ``dop853-projection``) at ``rtol = atol = 1e-12``, interpolated by quintic Hermite, cached in
  ``OUT/references/``. Checked against MuJoCo: its RK4 at ``h = --check-step`` (default
  31.25 us), a different formulation (joint coordinates) and method, must agree to about 1e-10.
* Methods: hexapod's ``--methods`` (default ``dop853-projection dopri5-projection
  rk4-baumgarte``), adaptive ones on ``rtol = atol = 1e-3 ... 1e-11``, fixed-step ones on
  ``h = 4 ms / 2^k``; MuJoCo's RK4 (``mjINT_RK4``) on the same step ladder, and its default
  semi-implicit Euler (``mjINT_EULER``) for information (first order: it does not reach 1e-6
  on the ladder).
* (a) CPU per step at the representative setting (``rtol = 1e-6``; ``h = 1 ms``). (b) CPU
  time to ``e = 1e-6``: the ladder walked from the representative setting, tighter while
  ``e > 1e-6``, looser while ``e <= 1e-6``, log-log interpolation between the two rungs that
  bracket 1e-6 (``<=``: the loosest rung run is below; ``>``: not reached within the budget).
  (c) The ratio hexapod's fastest method / MuJoCo's RK4 for (b), against the aim of 2.
* Timing: ``time.process_time``, best of ``--repeat`` runs (a run over 10 s is not repeated).
  Then the rungs (c) is read from (hexapod's fastest method's and MuJoCo's RK4's, the one or
  two that bracket 1e-6) are timed ``--confirm`` times more (default 5), the two libraries
  alternately, each rung's time the least of all its runs: a burst of load on the machine
  during one library's ladder no longer decides the ratio (every time is in the JSON,
  ``confirmation``; a run again must take the same steps to the same error).
  hexapod as ``bench_forward.py`` (the integrator's start and its steps, positions copied after
  every step; not timed: assembly, CasADi's Functions, built in a warm-up run). MuJoCo: its own
  loop in C, ``mj_step(m, d, nstep)`` from ``qpos0`` at rest, is the time compared (the fastest
  way MuJoCo runs; the aim's figure); the same steps are then run one ``mj_step`` at a time
  from Python with ``xipos`` copied after each, for the error, and that loop's time is shown
  too (in brackets); both loops must end in the same state, bit for bit. One BLAS thread.
* Budget (``--budget`` s of CPU, default 900): a hexapod run is stopped when it passes it; a
  rung predicted (from the previous one) to exceed it is not run.

Outputs in ``--out`` (default ``bench-forward-mujoco/``): the Markdown table on stdout,
``bench_forward_mujoco.json`` (every rung; rewritten after each problem with ``"complete":
false`` until the end), ``bench_forward_mujoco.png`` (CPU time against error, both libraries,
a panel per problem) and the references; progress and the load average on stderr.

    python3 scripts/benchmarks/bench_forward_mujoco.py [--repeat 3] [--budget 900]
    python3 scripts/benchmarks/bench_forward_mujoco.py --quick   # one run per rung, budget
        # 120 s, MuJoCo's Euler at h = 1 ms only
    python3 scripts/benchmarks/bench_forward_mujoco.py --quick --compile   # hexapod's kernels
        # compiled to C (the LU written out), compiled during the warm-up
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

from measure import log, machine, one_blas_thread, start

one_blas_thread()  # before NumPy loads

import numpy as np  # noqa: E402
from bench_forward import bench_problem  # noqa: E402
from bench_forward_mujoco_side import (  # noqa: E402
    MUJOCO_METHODS,
    MujocoModel,
    fastest,
    figure,
    markdown,
    mujoco_available,
    ratio_to_rk4,
)
from bench_forward_problems import Problem, reference, write_bytes_atomically  # noqa: E402
from bench_forward_report import finite  # noqa: E402
from bench_forward_runs import (  # noqa: E402
    REPRESENTATIVE_STEP,
    RTOL_LADDER,
    STEP_LADDER,
    Run,
    best_of,
    bracket,
    run_hexapod,
    runs_of,
    time_to_target,
    walk,
)
from bench_inverse import chain_scene, hexapod_robot  # noqa: E402

import hexapod as hx  # noqa: E402
from hexapod import get_integrator  # noqa: E402
from hexapod.output import write_atomically  # noqa: E402

SPAN = 1.0  # s, the aim's span
DEFAULT_METHODS = ["dop853-projection", "dopri5-projection", "rk4-baumgarte"]


def robot_problems() -> list[Problem]:
    return [*(Problem(f"chain-{n}", f"chain of {n}, hanging", lambda n=n: chain_scene(n), SPAN,
                      chain=n) for n in (10, 30)),
            Problem("hexapod-18", "18-joint hexapod, trunk fixed, legs falling", hexapod_robot,
                    SPAN)]


# ------------------------------------------------------------------ MuJoCo's side of a problem

def mujoco_entry(runs: dict[int, Run], description: str) -> dict:
    """A method's entry in the results, as ``bench_forward.py`` records one, with the time to
    the target of the Python loop too."""
    representative = runs.get(STEP_LADDER.index(REPRESENTATIVE_STEP))
    value, qualifier = time_to_target(runs)
    recorded = {i: dataclasses.replace(r, cpu=r.counters.get("cpu_recorded_s", float("inf")))
                for i, r in runs.items()}
    value_recorded, _ = time_to_target(recorded)
    return {"library": "mujoco", "adaptive": False, "description": description,
            "representative": representative.as_dict(),
            "cpu_per_step_ms": representative.per_step_ms if representative.ok
            else float("nan"),
            "time_to_target_s": value, "time_to_target_qualifier": qualifier,
            "time_to_target_recorded_s": value_recorded,
            "rungs": [r.as_dict() for _, r in sorted(runs.items())]}


def bench_mujoco(problem: Problem, args, result: dict, keep: dict) -> dict:
    """MuJoCo's runs on ``problem``, added to ``result["methods"]``; the checks returned;
    ``keep`` receives the model they ran and their reference (``"mujoco"``)."""
    scene = problem.build()
    model = hx.assemble(scene)
    q, v = hx.consistent_state(model, model.create_data())
    v_dot = hx.forward_dynamics(model, model.create_data(), 0.0, q, v)
    ref = reference(problem, model, args.reference_method, Path(args.out) / "references")
    try:
        mm = MujocoModel(scene, model)
    except NotImplementedError as error:
        log(f"  MuJoCo: not the same model ({error})")
        return {"translated": False, "why": str(error)}
    keep["mujoco"] = (mm, ref)
    agreement = mm.agreement(q, v_dot)
    log("  MuJoCo against hexapod at the start: centres of mass {positions:.1e}, their "
        "accelerations {com_accelerations:.1e}, angular accelerations "
        "{angular_accelerations:.1e} (relative)".format(**agreement))
    check = mm.run("mujoco-rk4", args.check_step, problem.t_end, ref)
    log(f"  reference against MuJoCo's RK4 at h = {args.check_step:.3g} s: {check.error:.1e}")
    start = STEP_LADDER.index(REPRESENTATIVE_STEP)
    for method, (_, description) in MUJOCO_METHODS.items():
        def one(step, method=method):
            run = best_of(args.repeat, lambda: mm.run(method, step, problem.t_end, ref))
            log(f"  {method} h = {step:.3g}: {run.status}, {run.steps} steps, {run.cpu:.3g} s "
                f"({run.counters.get('cpu_recorded_s', float('nan')):.3g} s from Python), "
                f"error {run.error:.2e}")
            return run
        if args.quick and method != "mujoco-rk4":  # for information: its cost per step only
            runs = {start: one(STEP_LADDER[start])}
        else:
            runs = walk(STEP_LADDER, start, one, 2.0, args.budget)
        result["methods"][method] = mujoco_entry(runs, description)
    return {"translated": True, "model": mm.describe(), "agreement": agreement,
            "check_step_s": args.check_step, "check_error": check.error}


def confirm(problem: Problem, result: dict, keep: dict, args) -> None:
    """The rungs the ratio is read from (:func:`bench_forward_runs.bracket` of hexapod's
    fastest method and of MuJoCo's RK4) timed ``args.confirm`` times more, the libraries
    alternately (each round the other first), each rung's time the least of all its runs; the
    entries' times to the target read again from them, every time kept (``confirmation``)."""
    _, method = fastest(result, "hexapod")
    if args.confirm <= 0 or not method or "mujoco-rk4" not in result["methods"]:
        return
    mm, mujoco_reference = keep["mujoco"]
    adaptive = get_integrator(method).adaptive
    again = {method: (RTOL_LADDER if adaptive else STEP_LADDER, lambda setting: run_hexapod(
                 keep["model"], method, setting, problem.t_end, keep["reference"], args.budget)),
             "mujoco-rk4": (STEP_LADDER, lambda setting: mm.run(
                 "mujoco-rk4", setting, problem.t_end, mujoco_reference))}
    runs = {name: runs_of(result["methods"][name], ladder) for name, (ladder, _) in again.items()}
    times = {name: {i: [runs[name][i].cpu] for i in bracket(runs[name])} for name in again}
    for round_ in range(args.confirm):
        for name in list(again)[::1 if round_ % 2 == 0 else -1]:
            ladder, run = again[name]
            for i in times[name]:
                repeat, first = run(ladder[i]), runs[name][i]
                if repeat.steps != first.steps or not np.isclose(repeat.error, first.error,
                                                                 rtol=1e-12, atol=0.0):
                    log(f"  {name} at {ladder[i]:.3g}: not the same run again ({repeat.steps} "
                        f"steps, error {repeat.error:.3e}; first {first.steps}, "
                        f"{first.error:.3e}): its time not taken")
                    continue
                times[name][i].append(repeat.cpu)
                first.cpu = min(first.cpu, repeat.cpu)
    for name, (ladder, _) in again.items():
        entry, kept = result["methods"][name], runs[name]
        before = entry["time_to_target_s"]
        entry["time_to_target_s"], entry["time_to_target_qualifier"] = time_to_target(kept)
        entry["rungs"] = [r.as_dict() for _, r in sorted(kept.items())]
        representative = ladder.index(entry["representative"]["setting"])
        if representative in times[name]:
            entry["representative"] = kept[representative].as_dict()
            entry["cpu_per_step_ms"] = kept[representative].per_step_ms
        entry["confirmation"] = {"rounds": args.confirm, "cpu_s": {
            f"{ladder[i]:.6g}": t for i, t in times[name].items()}}
        log(f"  {name}: time to 1e-6 {before:.4g} s -> {entry['time_to_target_s']:.4g} s after "
            f"{args.confirm} rounds alternated")


def summary_lines(results: list[dict]) -> list[str]:
    """One line per problem: where hexapod stands against the aim."""
    lines = []
    for r in results:
        rt = ratio_to_rk4(r)
        key = r["problem"]["key"]
        if not rt:
            lines.append(f"{key}: no ratio (MuJoCo absent, or a side did not reach 1e-6)")
            continue
        verdict = ("cannot tell (bounds only)" if rt["meets_aim"] is None
                   else "meets the aim" if rt["meets_aim"] else "does not meet the aim")
        lines.append(f"{key}: hexapod's best ({rt['hexapod']}) takes {rt['bound']}"
                     f"{rt['ratio']:.3g} times MuJoCo's RK4 to reach 1e-6 over "
                     f"{r['problem']['t_end']:g} s; the aim is at most {rt['aim']:g}: {verdict}."
                     + (f" A step of RK4 at h = 1 ms costs {rt['rk4_per_step']:.3g} times "
                        "MuJoCo's." if np.isfinite(rt["rk4_per_step"]) else ""))
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=None, help="best of (default 3)")
    parser.add_argument("--confirm", type=int, default=5,
                        help="rounds re-timing the rungs the ratio is read from, the libraries "
                        "alternately (default 5; 0: none)")
    parser.add_argument("--budget", type=float, default=900.0,
                        help="largest CPU time of one run, s (default 900)")
    parser.add_argument("--methods", nargs="*", default=None,
                        help=f"hexapod methods (default {' '.join(DEFAULT_METHODS)})")
    parser.add_argument("--problems", nargs="*", default=None,
                        help="problem keys (default: chain-10 chain-30 hexapod-18)")
    parser.add_argument("--reference-method", default="dop853-projection")
    parser.add_argument("--check-step", type=float, default=STEP_LADDER[7],
                        help="MuJoCo RK4's step for the check of the reference, s")
    parser.add_argument("--no-mujoco", action="store_true", help="hexapod alone")
    parser.add_argument("--quick", action="store_true", help="one run per rung, budget 120 s, "
                        "MuJoCo's Euler at h = 1 ms only")
    parser.add_argument("--compile", action="store_true",
                        help="hexapod's kernels compiled to C (kept in OUT/kernels; compiling "
                        "is part of the warm-up, not of the times compared)")
    parser.add_argument("--out", default="bench-forward-mujoco")
    args = parser.parse_args()
    with hx.executing(compiled=args.compile,
                      cache=Path(args.out) / "kernels" if args.compile else None):
        run(args)


def run(args) -> None:
    if args.quick:
        args.repeat = args.repeat or 1
        args.budget = min(args.budget, 120.0)
    args.repeat = args.repeat or 3
    methods = args.methods or DEFAULT_METHODS
    for method in methods + [args.reference_method]:
        get_integrator(method)  # an unknown name fails here, before any work
    mujoco_ok, mujoco_version = (False, "not asked") if args.no_mujoco else mujoco_available()
    if not mujoco_ok:
        print(f"MuJoCo not installed ({mujoco_version}): hexapod alone. "
              "(pip install \".[compare]\" for the comparison.)\n")
    todo = [p for p in robot_problems() if not args.problems or p.key in args.problems]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()

    def report(results: list[dict], complete: bool) -> dict:
        return {"complete": complete, "protocol": __doc__, "repeat": args.repeat,
                "confirm": args.confirm,
                "compiled": args.compile,
                "budget_s": args.budget, "methods": methods, "hexapod": hx.__version__,
                "mujoco": mujoco_version if mujoco_ok else None, **machine(),
                "numpy": np.__version__, "wall_time_s": time.perf_counter() - started,
                "problems": results, "ratios": {r["problem"]["key"]: ratio_to_rk4(r)
                                                for r in results},
                "table": markdown(results, args, mujoco_version if mujoco_ok else None),
                "summary": summary_lines(results)}

    results = []
    for k, problem in enumerate(todo):
        keep: dict = {}
        result = bench_problem(problem, methods, args, exudyn_ok=False, keep=keep)
        result.pop("exudyn")
        result["mujoco"] = bench_mujoco(problem, args, result, keep) if mujoco_ok else None
        if mujoco_ok and result["mujoco"]["translated"]:
            confirm(problem, result, keep, args)
        results.append(result)
        if k + 1 < len(todo):  # what is done survives an interrupted run
            write_atomically(out / "bench_forward_mujoco.json",
                             json.dumps(finite(report(results, False)), indent=1))
    final = report(results, True)
    print(final["table"])
    print("\n".join(final["summary"]))
    write_atomically(out / "bench_forward_mujoco.json", json.dumps(finite(final), indent=1))
    write_bytes_atomically(out / "bench_forward_mujoco.png", figure(results))
    log(f"wrote {out / 'bench_forward_mujoco.json'} and {out / 'bench_forward_mujoco.png'}")


if __name__ == "__main__":
    start("bench_forward_mujoco")
    main()
