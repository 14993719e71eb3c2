"""Forward dynamics against Exudyn: cost per step, CPU time to an accuracy, growth with size.

Protocol
--------
* Problems, every body released at rest under gravity (9.81 m/s^2), no driver, no other force:

  - ``front-leg``: the left front leg of ``legs`` (``front_leg_scene(gait=False)``: 6 spatial
    bodies, 6 revolute joints, the trunk fixed) falling from its initial pose, 0.5 s;
  - ``four-bar``: the four-bar of ``data/scenes/four_bar_3d.toml`` (crank 0.1 m 0.3 kg,
    coupler 0.5 m 1 kg, rocker 0.4 m 0.8 kg, slender bars, ground 0.4 m) built in the plane,
    the crank turned to +x (the file's pose is an equilibrium): pivots A (0, 0), B (0.1, 0),
    C (0.4, 0.4), D (0.4, 0) m; 3 planar bodies, 4 revolute joints, the rocker's ground pivot
    closing the loop, 1 degree of freedom, gravity along -y, 2 s;
  - ``chain-N``: the serial chains of ``bench_inverse.py`` (N spatial bodies of 1 kg, 0.1 m
    apart along x, revolute joints with random axes, seed 0) hanging from the ground, released
    from that horizontal pose, 0.5 s; N in ``--sizes`` (default 10 30 100 300).

* Error of a run: ``e = max_k max_i |r_i(t_k) - r_i_ref(t_k)| / max_k,i |r_i_ref(t_k)|``, with
  ``r_i`` the centre of mass of body i (the bodies' position coordinates in both libraries,
  Euclidean norm), ``t_k`` the end of every step the run returns, and the reference
  interpolated at ``t_k`` by quintic Hermite interpolation from its ``r, r_dot, r_ddot``.
* Reference: the same model integrated by hexapod's ``--reference-method`` (default
  ``dop853-projection``) at ``rtol = atol = 1e-12`` with steps of at most 2.5 ms,
  cached in ``OUT/references/`` and reused while the problem, the settings and hexapod's version
  are the same. Checked twice: its interpolation error (every other sample left out and
  interpolated from the rest; the real spacing is half that, so the figure is pessimistic) and,
  with Exudyn, against Exudyn's own tight solution (its index-2 trapezoidal rule at
  ``h = t_end / 8000`` and ``t_end / 16000`` with Newton's relative tolerance 1e-12,
  Richardson-extrapolated: the rule is symmetric, its error even in h), which must agree to
  about 1e-8 (measured: 1e-13 to 1e-9).
* Methods: every integrator in hexapod's registry (``--methods`` to choose). Adaptive ones on
  the ladder ``rtol = atol = 1e-3, 1e-4, ..., 1e-11`` (SI units: atol applies to metres,
  radians, Euler parameters and their rates alike), fixed-step ones on ``h = 4 ms / 2^k``.
  Exudyn (optional extra ``compare``), when ``import exudyn`` works: the same model built from
  hexapod's assembled model (``ObjectRigidBody`` on ``NodeRigidBodyEP``, Euler parameters with
  their normalisation as an algebraic equation; ``ObjectRigidBody2D`` in the plane; joints by
  ``CreateRevoluteJoint`` (``ObjectJointRevoluteZ``, 5 equations) or ``ObjectJointRevolute2D``,
  all with Lagrange multipliers), solved by its generalized-alpha at index 3 (spectral radius
  0.9, as hexapod's) and by its trapezoidal rule at index 2 (Newmark 1/4, 1/2 with velocity
  constraints), each with its default modified Newton method (the Jacobian is kept over steps
  while Newton converges fast enough), on the same step ladder, with Eigen's sparse LU (faster
  than its dense default at every size measured here, 10 to 300 bodies). Its explicit solvers
  (DOPRI5, RK67, ...) do not solve joint constraints: they refuse Euler-parameter nodes (an
  algebraic equation per node), and with rotation-vector nodes they either drop the joint
  equations (a warning; the bodies fall freely) or refuse them; the script tries DOPRI5 and
  RK67 once per problem and reports what they say.
* Same mechanism: Exudyn's initial accelerations (its solver's initialisation) against
  hexapod's saddle-point solve, relative to the largest, printed; must be ~1e-8 or better.
* (a) Cost per step: CPU time of the run at the representative setting (``rtol = 1e-6``; ``h =
  1 ms``) divided by its accepted steps. (b) CPU time to reach ``e = 1e-6``: the ladder is
  walked from the representative setting, tighter while ``e > 1e-6`` or looser while
  ``e <= 1e-6``, and the CPU time interpolated log-log between the two rungs that bracket
  1e-6; ``<=`` when the loosest rung run is already below (or its looser neighbour failed),
  ``>`` when no rung within the budget reaches it. (c) Growth exponent: least-squares slope of
  log(CPU per step) against log(bodies) over the chains.
* Timing: ``time.process_time`` around the integrator's start (hexapod: the consistent initial
  state; Exudyn: its solver's initialisation, initial accelerations included) and its steps;
  best of ``--repeat`` runs (a run of more than 10 s is not repeated). Not timed: the model's
  assembly, the construction of CasADi's Functions (a warm-up run of every method before any
  timing, reported as ``warm-up s``), Exudyn's ``mbs.Assemble()``, writing. Both libraries
  record the centre-of-mass positions after every step during the timed runs (hexapod: a copy;
  Exudyn: internal sensors, measured at under 1 % of a step). Exudyn's output files, renderer
  and console output are switched off; it runs on one thread, and so does BLAS
  (``OPENBLAS_NUM_THREADS=1`` unless set otherwise).
* Budget: a hexapod run is stopped when its CPU time passes ``--budget`` seconds (then it
  counts as not reaching the target, its steps still give the cost per step, and the ladder is
  walked looser); a rung whose predicted time (from the previous rung) exceeds the budget is
  not run.

Outputs in ``--out`` (default ``bench-forward/``): the Markdown table on stdout,
``bench_forward.json`` (every rung of every method; rewritten after each problem, with
``"complete": false`` until the end), ``bench_forward.png`` (CPU per step against
bodies over the chains with the fitted exponents, and CPU time to 1e-6 per problem) and the
references, each written atomically; progress on stderr.

    python3 scripts/benchmarks/bench_forward.py [--sizes 10 30 100 300] [--repeat 3]
        [--budget 900]
    python3 scripts/benchmarks/bench_forward.py --quick   # chains of 10 and 30, one run per rung
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from measure import log, machine, one_blas_thread, start

one_blas_thread()  # before NumPy loads; Exudyn runs on one thread too

import numpy as np  # noqa: E402
from bench_forward_exudyn import bench_exudyn, exudyn_available  # noqa: E402
from bench_forward_problems import Problem, problems, reference, write_bytes_atomically  # noqa: E402
from bench_forward_report import figure, finite, growth_exponents, markdown, ratios  # noqa: E402
from bench_forward_runs import (  # noqa: E402
    REPRESENTATIVE_RTOL,
    REPRESENTATIVE_STEP,
    RTOL_LADDER,
    STEP_LADDER,
    TARGET,
    Run,
    best_of,
    run_hexapod,
    time_to_target,
    walk,
)

import hexapod as hx  # noqa: E402
from hexapod import INTEGRATORS, get_integrator  # noqa: E402
from hexapod.output import write_atomically  # noqa: E402

# ------------------------------------------------------------------ one problem

def bench_problem(problem: Problem, methods: list[str], args, exudyn_ok: bool,
                  keep: dict | None = None) -> dict:
    """hexapod's (and Exudyn's) runs on ``problem``; ``keep``: given, it receives the model and
    the reference the runs were measured on (``"model"``, ``"reference"``), to run again."""
    log(f"{problem.key}: {problem.title}, {problem.t_end} s")
    tic = time.process_time()
    model = hx.assemble(problem.build())
    data = model.create_data()
    q, v = hx.consistent_state(model, data)
    v_dot = hx.forward_dynamics(model, data, 0.0, q, v)
    assembled = time.process_time() - tic
    tic = time.process_time()
    for method in methods:  # warm-up: CasADi builds its Functions on first use
        cls = get_integrator(method)
        integrator = cls(model, 0.0, problem.t_end, **(
            {"rtol": 1e-3, "atol": 1e-3} if cls.adaptive else {"step": problem.t_end / 100}))
        for _ in range(2):
            if integrator.status == "running":
                integrator.step()
    warm = time.process_time() - tic
    log(f"  {model!r}: assembled in {assembled:.2f} s, warm-up {warm:.2f} s")
    ref = reference(problem, model, args.reference_method, Path(args.out) / "references")
    result = {"problem": problem.spec(), "bodies": len(model.bodies), "n_q": model.n_q,
              "n_v": model.n_v, "n_c": model.n_c, "assemble_s": assembled, "warm_up_s": warm,
              "reference": {**ref.meta, "samples": int(ref.t.size), "scale_m": ref.scale,
                            "interpolation_check": ref.interpolation_check()},
              "methods": {}, "exudyn": None}
    log(f"  reference interpolation check: {result['reference']['interpolation_check']:.1e}")
    if keep is not None:
        keep.update(model=model, reference=ref)

    def ladder_of(fixed: bool) -> tuple[list[float], int]:
        if fixed:
            return STEP_LADDER, STEP_LADDER.index(REPRESENTATIVE_STEP)
        return RTOL_LADDER, RTOL_LADDER.index(REPRESENTATIVE_RTOL)

    def record(library: str, method: str, fixed: bool, runs: dict[int, Run],
               description: str = ""):
        ladder, start = ladder_of(fixed)
        value, qualifier = time_to_target(runs)
        representative = runs[start]
        result["methods"][method] = {
            "library": library, "adaptive": not fixed, "description": description,
            "representative": representative.as_dict(),
            # a run stopped by the budget still measured the cost of its steps
            "cpu_per_step_ms": (representative.per_step_ms
                                if representative.status in ("finished", "budget")
                                else float("nan")),
            "time_to_target_s": value, "time_to_target_qualifier": qualifier,
            "rungs": [r.as_dict() for _, r in sorted(runs.items())]}

    for method in methods:
        cls = get_integrator(method)
        fixed = not cls.adaptive
        ladder, start = ladder_of(fixed)

        def one(setting, method=method, fixed=fixed):
            run = best_of(args.repeat, lambda: run_hexapod(model, method, setting, problem.t_end,
                                                           ref, args.budget))
            log(f"  {method} {'h' if fixed else 'rtol'} = {setting:.3g}: {run.status}, "
                f"{run.steps} steps, {run.cpu:.3g} s, error {run.error:.2e}")
            return run
        # steps grow like tol^(-1/order) for adaptive methods, like 1/h for fixed ones
        growth = 2.0 if fixed else 10.0 ** (1.0 / max(cls.order, 1))
        record("hexapod", method, fixed, walk(ladder, start, one, growth, args.budget),
               cls.describe().get("description", ""))

    if exudyn_ok:
        result["exudyn"] = bench_exudyn(problem, model, q, v, v_dot, ref, args, record)
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=None,
                        help="bodies of the serial chains (default 10 30 100 300)")
    parser.add_argument("--repeat", type=int, default=None, help="best of (default 3)")
    parser.add_argument("--budget", type=float, default=900.0,
                        help="largest CPU time of one run, s (default 900)")
    parser.add_argument("--methods", nargs="*", default=None,
                        help="hexapod methods (default: the whole registry)")
    parser.add_argument("--problems", nargs="*", default=None,
                        help="problem keys to run (default: all)")
    parser.add_argument("--reference-method", default="dop853-projection")
    parser.add_argument("--no-exudyn", action="store_true", help="hexapod alone")
    parser.add_argument("--quick", action="store_true",
                        help="chains of 10 and 30, one run per rung, budget 120 s")
    parser.add_argument("--out", default="bench-forward")
    args = parser.parse_args()
    if args.quick:
        args.sizes = args.sizes if args.sizes is not None else [10, 30]
        args.repeat = args.repeat or 1
        args.budget = min(args.budget, 120.0)
    args.sizes = args.sizes if args.sizes is not None else [10, 30, 100, 300]
    args.repeat = args.repeat or 3
    methods = args.methods or list(INTEGRATORS)
    for method in methods + [args.reference_method]:
        get_integrator(method)  # an unknown name fails here, before any work
    exudyn_ok, exudyn_version = (False, "not asked") if args.no_exudyn else exudyn_available()
    if not exudyn_ok:
        print(f"Exudyn is not available ({exudyn_version}): hexapod alone. "
              "(pip install \".[compare]\" for the comparison.)\n")
    todo = [p for p in problems(args.sizes) if not args.problems or p.key in args.problems]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()

    def report(results: list[dict], complete: bool) -> dict:
        exponents = growth_exponents(results)
        return {"complete": complete, "protocol": __doc__, "target": TARGET,
                "repeat": args.repeat, "budget_s": args.budget, "sizes": args.sizes,
                "methods": methods, "hexapod": hx.__version__,
                "exudyn": exudyn_version if exudyn_ok else None,
                **machine(), "numpy": np.__version__,
                "wall_time_s": time.perf_counter() - started,
                "growth_exponents": exponents, "problems": results,
                "ratios": {r["problem"]["key"]: ratios(r) for r in results},
                "table": markdown(results, exponents, args)}

    results = []
    for k, problem in enumerate(todo):
        results.append(bench_problem(problem, methods, args, exudyn_ok))
        if k + 1 < len(todo):  # what is done survives an interrupted run
            write_atomically(out / "bench_forward.json",
                             json.dumps(finite(report(results, False)), indent=1))
    final = report(results, True)
    print(final["table"])
    write_atomically(out / "bench_forward.json", json.dumps(finite(final), indent=1))
    write_bytes_atomically(out / "bench_forward.png",
                           figure(results, final["growth_exponents"]))
    log(f"wrote {out / 'bench_forward.json'} and {out / 'bench_forward.png'}")


if __name__ == "__main__":
    start("bench_forward")
    main()
