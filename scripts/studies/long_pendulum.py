"""The pendulum of data/scenes/pendulum.toml over many periods, every integrator against the exact
(elliptic-function) solution: error, energy drift, constraint drift and CPU time.

    python scripts/studies/long_pendulum.py                    # 1000 periods (about half an hour)
    python scripts/studies/long_pendulum.py --periods 20       # a quick look

The rod (1 m, 1 kg, about its end) is released horizontal: a large swing (psi0 = 90 deg) whose
period, 1.933 s, depends on the amplitude, so a phase error shows. Writes OUT/long_pendulum.csv
(one row per method) and OUT/long_pendulum.png (the error against time, and the largest error
against CPU time). The largest error is the one to read: at whole periods the rod is at rest at
its turning point, where a phase error barely moves it, so the final error flatters.
"""

from __future__ import annotations

import argparse
import csv
import io
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
G, ARM, INERTIA_O = 9.81, 0.5, 0.0833 + 0.25
OMEGA0 = np.sqrt(G * ARM / INERTIA_O)
PSI0 = np.pi / 2

#: The settings of each method: its step as a fraction of the period, or its tolerances.
SETTINGS = {
    "rk4-baumgarte": {"steps_per_period": 100},
    "dopri5-projection": {"rtol": 1e-9, "atol": 1e-9},
    "dop853-projection": {"rtol": 1e-11, "atol": 1e-11},
    "generalized-alpha": {"steps_per_period": 400},
}


def exact_centre(t: np.ndarray) -> np.ndarray:
    from hexapod.benchmarks import pendulum_exact

    psi, _ = pendulum_exact(t, PSI0, OMEGA0)
    return np.column_stack([ARM * np.sin(psi), np.zeros_like(psi), -ARM * np.cos(psi)])


def run(model, method: str, periods: int, period: float) -> dict:
    from hexapod import simulate

    settings = dict(SETTINGS.get(method, {}))
    per_period = settings.pop("steps_per_period", None)
    if per_period is not None:
        settings["step"] = period / per_period
    t_end = periods * period
    last = [0.0]

    def progress(t: float, t_end: float) -> None:
        now = time.perf_counter()
        if now - last[0] > 1.0:
            last[0] = now
            print(f"\r  {method}: {100 * t / t_end:5.1f} %", end="", file=sys.stderr, flush=True)

    # about 20 saved states per period: enough to see the error envelope
    steps_guess = per_period or 40
    result = simulate(model, t_end, method=method, every=max(1, steps_guess // 20),
                      progress=progress, **settings)
    print("\r" + " " * 40 + "\r", end="", file=sys.stderr)
    error = np.linalg.norm(result.q[:, :3] - exact_centre(result.t), axis=1)
    return {"method": method, "settings": settings, "status": result.status,
            "message": result.message, "t": result.t, "error": error,
            "steps": result.counters.steps, "rhs": result.counters.rhs,
            "cpu_s": result.cpu_time, "max_error_m": float(error.max()),
            "final_error_m": float(error[-1]), "energy_drift": result.energy_drift,
            "max_phi": result.max_position_violation}


def main(argv: list[str] | None = None) -> int:
    import hexapod as hx
    from hexapod import INTEGRATORS, read_scene
    from hexapod.benchmarks import pendulum_period
    from hexapod.output import write_directory_atomically

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--periods", type=int, default=1000)
    parser.add_argument("--methods", nargs="+", default=list(INTEGRATORS),
                        choices=list(INTEGRATORS))
    parser.add_argument("--out", default="long-pendulum", help="output directory")
    args = parser.parse_args(argv)

    model = hx.assemble(read_scene(ROOT / "data" / "scenes" / "pendulum.toml"))
    period = pendulum_period(PSI0, OMEGA0)
    print(f"pendulum released at 90 deg, period {period:.6f} s, {args.periods} periods "
          f"({args.periods * period:.1f} s)")
    runs = [run(model, method, args.periods, period) for method in args.methods]

    header = ["method", "settings", "status", "steps", "rhs", "cpu_s", "max_error_m",
              "final_error_m", "energy_drift", "max_phi"]
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(header)
    print(f"{'method':20s} {'settings':28s} {'steps':>9s} {'rhs':>9s} {'cpu s':>8s} "
          f"{'max err m':>10s} {'final m':>10s} {'E drift':>9s} {'max|phi|':>9s}")
    for r in runs:
        settings = " ".join(f"{k}={v:.3g}" for k, v in r["settings"].items())
        drift = "-" if r["energy_drift"] is None else f"{r['energy_drift']:.2e}"
        writer.writerow([r["method"], settings, r["status"], r["steps"], r["rhs"],
                         f"{r['cpu_s']:.4g}", f"{r['max_error_m']:.3e}",
                         f"{r['final_error_m']:.3e}", drift, f"{r['max_phi']:.2e}"])
        print(f"{r['method']:20s} {settings:28s} {r['steps']:9d} {r['rhs']:9d} "
              f"{r['cpu_s']:8.2f} {r['max_error_m']:10.2e} {r['final_error_m']:10.2e} "
              f"{drift:>9s} {r['max_phi']:9.1e}" + ("" if r["status"] == "finished"
                                                     else f"  {r['message']}"))
    files = {"long_pendulum.csv": text.getvalue().encode(),
             "long_pendulum.png": figure(runs, period, args.periods)}
    write_directory_atomically(args.out, files)
    print(f"wrote {args.out}/: {', '.join(files)}")
    return 0


def figure(runs: list[dict], period: float, periods: int) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for r in runs:
        line, = left.loglog(r["t"][1:] / period, np.maximum(r["error"][1:], 1e-17),
                            label=r["method"], lw=0.8)
        right.loglog(r["cpu_s"], max(r["max_error_m"], 1e-17), "o", color=line.get_color(),
                     label=r["method"])
    left.set_xlabel("periods")
    left.set_ylabel("error of the centre of mass (m)")
    left.set_title(f"error against time over {periods} periods")
    left.grid(True, which="both", alpha=0.3)
    left.legend(fontsize=8)
    right.set_xlabel("CPU time (s)")
    right.set_ylabel("largest error over the run (m)")
    right.set_title("error against run time")
    right.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=120)
    plt.close(fig)
    return buffer.getvalue()


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    sys.exit(main())
