"""The embedded Runge-Kutta pairs' step controller: the right-hand sides it takes to reach a
relative position error of 1e-6, against its safety factor (a study, not a test).

For each method (``dop853-projection``, ``dopri5-projection``), problem and safety factor, the
method runs the tolerance ladder ``rtol = atol = 1e-4 ... 1e-8`` from the problem's rest state;
the error of a run is the forward benchmarks' (the bodies' centres of mass against a reference
run of DOP853 at 1e-12, relative); the right-hand sides and the CPU time to reach ``e = 1e-6``
are interpolated log-log between the two rungs that bracket it, as the benchmarks interpolate
CPU time. The right-hand sides are a count: the same on every machine, so that settings compare
without the timing noise (CPU: the best of three runs, one BLAS thread). Problems: the front leg
and the planar four-bar of ``scripts/benchmarks/bench_forward.py``, the chains of 10 and 30 links
and the 18-joint robot of ``scripts/benchmarks/bench_forward_mujoco.py``.

Outputs in ``--out`` (default ``step-controller/``): ``table.md`` (also printed), the figure
``step_controller.png`` (right-hand sides to 1e-6, a bar per safety factor) and the references
(computed on the first run, reused after).

    python3 scripts/studies/step_controller.py [--safety 0.9 0.8] [--methods ...]
        [--problems ...] [--compile] [--out step-controller]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before NumPy loads: one BLAS thread
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import numpy as np  # noqa: E402
from bench_forward_mujoco import robot_problems  # noqa: E402
from bench_forward_problems import problems as forward_problems  # noqa: E402
from bench_forward_problems import reference  # noqa: E402
from bench_forward_runs import TARGET, run_hexapod  # noqa: E402

import hexapod as hx  # noqa: E402
from hexapod import get_integrator  # noqa: E402
from hexapod.output import write_atomically  # noqa: E402

LADDER = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
REPEATS = 3


def at_target(runs: list, value) -> float:
    """``value(run)`` interpolated log-log at the error TARGET between the two runs that bracket
    it (NaN where none do)."""
    ordered = sorted((r for r in runs if r.ok), key=lambda r: r.error)
    for low, high in zip(ordered, ordered[1:], strict=False):
        if low.error <= TARGET <= high.error:
            share = np.log(TARGET / low.error) / np.log(high.error / low.error)
            return float(np.exp(np.log(value(low)) + share * np.log(value(high) / value(low))))
    return float("nan")


def study(method: str, problem, model, ref, safety: float) -> dict:
    cls = get_integrator(method)
    kept = cls.safety
    cls.safety = safety  # the class's setting, for this study's runs only
    try:
        run_hexapod(model, method, LADDER[0], problem.t_end, ref, 60.0)  # warm-up
        runs = [min((run_hexapod(model, method, rtol, problem.t_end, ref, 60.0)
                     for _ in range(REPEATS)), key=lambda r: r.cpu) for rtol in LADDER]
    finally:
        cls.safety = kept
    return {"method": method, "problem": problem.key, "safety": safety,
            "rhs": at_target(runs, lambda r: r.counters["rhs"]),
            "cpu_ms": 1e3 * at_target(runs, lambda r: r.cpu),
            "rungs": [(r.setting, r.counters.get("rhs"), r.counters.get("rejected"), r.error)
                      for r in runs]}


def table(rows: list[dict], safeties: list[float]) -> str:
    base = safeties[0]
    head = ("| method | problem | " + " | ".join(f"rhs to 1e-6, safety {s}" for s in safeties)
            + " | " + " | ".join(f"change at {s}" for s in safeties[1:]) + " |")
    lines = [head, "| --- | --- |" + " ---: |" * (2 * len(safeties) - 1)]
    keys = dict.fromkeys((r["method"], r["problem"]) for r in rows)
    for method, problem in keys:
        found = {r["safety"]: r for r in rows if (r["method"], r["problem"]) == (method, problem)}
        counts = [found[s]["rhs"] for s in safeties]
        changes = [f"{100 * (c / counts[0] - 1):+.0f} %" for c in counts[1:]]
        lines.append(f"| {method} | {problem} | " + " | ".join(f"{c:.0f}" for c in counts)
                     + " | " + " | ".join(changes) + " |")
    return "\n".join(lines) + f"\n\n(changes against safety {base})"


def figure(rows: list[dict], safeties: list[float], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = list(dict.fromkeys((r["method"], r["problem"]) for r in rows))
    fig, ax = plt.subplots(figsize=(max(6.0, 1.1 * len(keys)), 4.0))
    width = 0.8 / len(safeties)
    for k, s in enumerate(safeties):
        counts = [next(r["rhs"] for r in rows if (r["method"], r["problem"]) == key
                       and r["safety"] == s) for key in keys]
        ax.bar(np.arange(len(keys)) + (k - (len(safeties) - 1) / 2) * width, counts, width,
               label=f"safety {s}")
    ax.set_xticks(np.arange(len(keys)),
                  [f"{p}\n{m.split('-')[0]}" for m, p in keys], fontsize=8)
    ax.set_ylabel("right-hand sides to reach e = 1e-6")
    ax.set_title("Embedded pairs' step controller: work to a position error of 1e-6")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--safety", type=float, nargs="+", default=[0.9, 0.8])
    parser.add_argument("--methods", nargs="+",
                        default=["dop853-projection", "dopri5-projection"])
    parser.add_argument("--problems", nargs="*", default=None, help="problem keys (default: "
                        "front-leg four-bar chain-10 chain-30 hexapod-18)")
    parser.add_argument("--compile", action="store_true",
                        help="kernels compiled to C (kept in OUT/kernels)")
    parser.add_argument("--out", default="step-controller")
    args = parser.parse_args()
    known = forward_problems([]) + robot_problems()
    unknown = sorted(set(args.problems or ()) - {p.key for p in known})
    if unknown:
        parser.error(f"unknown problem {unknown[0]!r}: choose among "
                     + ", ".join(p.key for p in known))
    if not all(0.0 < s <= 1.0 for s in args.safety):
        parser.error("--safety: each factor must be in (0, 1]")
    if any(m not in ("dop853-projection", "dopri5-projection") for m in args.methods):
        parser.error("--methods: the embedded pairs only (dop853-projection, dopri5-projection)")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    todo = [p for p in known if args.problems is None or p.key in args.problems]
    rows = []
    settings = {"compiled": True, "cache": out / "kernels"} if args.compile else {}
    with hx.executing(**settings):
        for problem in todo:
            model = hx.assemble(problem.build())
            ref = reference(problem, model, "dop853-projection", out / "references")
            for method in args.methods:
                for safety in args.safety:
                    rows.append(study(method, problem, model, ref, safety))
                    row = rows[-1]
                    print(f"{method} {problem.key} safety {safety}: {row['rhs']:.0f} "
                          f"right-hand sides, {row['cpu_ms']:.1f} ms to 1e-6", file=sys.stderr,
                          flush=True)
    text = table(rows, args.safety)
    print(text)
    write_atomically(out / "table.md", text + "\n")
    figure(rows, args.safety, out / "step_controller.png")
    print(f"wrote {out / 'table.md'} and {out / 'step_controller.png'}", file=sys.stderr)


if __name__ == "__main__":
    main()
