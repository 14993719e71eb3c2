"""Efficiency of the three methods of Vukobratović and Potkonjak (1979): basic theorems, Lagrange,
Gibbs-Appell.

Protocol
--------
* Chains: ``n`` spatial bodies in series, every joint revolute, with random axes, joint offsets,
  centres of mass and rotated full inertia tensors (seeded: general geometry, so no structural
  zero of the geometry helps a method), gravity along -z.
* Operation counts: one forming of ``W`` and ``V`` by each method of
  ``hexapod.minimal.forming``, run on ``Counted`` scalars (numpy object arrays of a float
  that counts its multiplications and additions); products of constants of the model are
  precomputed and not counted, sines and cosines are counted apart. Counted for every ``n`` of
  ``--count-sizes`` (default 1..30).
* CPU time (``time.process_time``): one forming of ``W`` and ``V`` by each method in floats
  (the same code), the vectorised basic-theorem form of ``ChainModel.matrices``, and one
  ``hexapod.forward_dynamics`` of the absolute-coordinate engine on the same chain (assembled
  once, its CasADi Functions built by a first call not timed); median of ``--repeats`` runs
  after a warm-up, for ``n`` of ``--time-sizes``.
* Output in ``--out`` (default ``figures/seed000``): ``seed000_efficiency.csv`` (long form:
  ``n, method, mul, add, fun, cpu_ms``), ``seed000_operations.png`` (multiplications and
  additions against ``n``, one line per method) and ``seed000_cpu_time.png``.

    python3 scripts/papers/seed000_efficiency.py [--out figures/seed000] [--count-sizes 1 2 ... 30]
                                          [--time-sizes 1 2 5 10 20 30] [--repeats 5]

``make(out_dir, ...)`` does the same from Python (for ``scripts/papers/make_figures.py``).
"""

from __future__ import annotations

import argparse
import csv
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import hexapod as hx
from hexapod.minimal import METHODS, ChainModel, count_operations, form

COUNT_SIZES = tuple(range(1, 31))
TIME_SIZES = (1, 2, 3, 5, 7, 10, 15, 20, 25, 30)
LABELS = {"basic": "basic theorems", "lagrange": "Lagrange", "gibbs-appell": "Gibbs-Appell",
          "basic-vectorised": "basic theorems (vectorised, ChainModel)",
          "engine": "absolute coordinates (hx.forward_dynamics)"}


def chain_scene(n: int, seed: int = 0) -> hx.Scene:
    """A serial chain of ``n`` spatial bodies and revolute joints of general geometry."""
    rng = np.random.default_rng(seed)
    scene = hx.Scene(f"seed000-chain-{n}")
    parent, point = "ground", np.zeros(3)
    for k in range(n):
        name = f"l{k}"
        moments = np.sort(rng.uniform(0.02, 0.1, size=3))
        moments[2] = min(moments[2], moments[0] + moments[1])
        scene.add(hx.scene.SpatialBody(name, rng.uniform(0.5, 2.0), moments,
                                       com=rng.normal(size=3) * 0.05, position=point,
                                       rotation=hx.spatial.rotation_about_axis(
                                           rng.normal(size=3), rng.uniform(0, np.pi)),
                                       inertia_rotation=hx.spatial.rotation_about_axis(
                                           rng.normal(size=3), rng.uniform(0, 3))))
        scene.add(hx.scene.Revolute(f"j{k}", parent, name, origin=point, axis=rng.normal(size=3)))
        parent, point = name, point + np.array([0.1, 0.0, 0.0]) + rng.normal(size=3) * 0.02
    return scene


def _cpu_ms(call, repeats: int) -> float:
    call()  # warm-up
    times = []
    for _ in range(repeats):
        tic = time.process_time()
        call()
        times.append(time.process_time() - tic)
    return 1e3 * statistics.median(times)


def count_rows(sizes) -> list[dict]:
    rows = []
    for n in sizes:
        chain = ChainModel.from_model(hx.assemble(chain_scene(n)))
        for method in METHODS:
            tally = count_operations(chain.layout, method)
            rows.append({"n": n, "method": method, **tally.as_dict(), "cpu_ms": ""})
    return rows


def _time_chain(n: int, repeats: int) -> list[dict]:
    model = hx.assemble(chain_scene(n))
    chain = ChainModel.from_model(model)
    rng = np.random.default_rng(n)
    q, q_d = rng.normal(size=n), rng.normal(size=n)
    rows = [{"n": n, "method": method, "cpu_ms": _cpu_ms(
        lambda m=method: form(chain.layout, q, q_d, m), repeats)} for method in METHODS]
    rows.append({"n": n, "method": "basic-vectorised",
                 "cpu_ms": _cpu_ms(lambda: chain.matrices(q, q_d), repeats)})
    data = model.create_data()
    x = hx.assemble_positions(model, data, 0.0)
    v = hx.solve_velocities(model, data, 0.0, x)
    rows.append({"n": n, "method": "engine", "cpu_ms": _cpu_ms(
        lambda: hx.forward_dynamics(model, data, 0.0, x, v), repeats)})
    return rows


def time_rows(sizes, repeats: int) -> list[dict]:
    return [row for n in sizes for row in _time_chain(n, repeats)]


def _plot(counts: list[dict], times: list[dict], out: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, key, title in zip(axes, ("mul", "add"), ("multiplications", "additions"),
                                 strict=True):
        for method in METHODS:
            rows = [r for r in counts if r["method"] == method]
            ax.loglog([r["n"] for r in rows], [r[key] for r in rows], "o-", ms=3,
                      label=LABELS[method])
        ax.set_xlabel("links n")
        ax.set_title(f"{title} to form W and V (counted)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("operations")
    axes[0].legend()
    fig.tight_layout()
    paths = [out / "seed000_operations.png"]
    fig.savefig(paths[0], dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6, 4.2))
    for method in (*METHODS, "basic-vectorised", "engine"):
        rows = [r for r in times if r["method"] == method]
        ax.loglog([r["n"] for r in rows], [r["cpu_ms"] for r in rows],
                  "s--" if method == "engine" else "o-", ms=3, label=LABELS[method])
    ax.set_xlabel("links n")
    ax.set_ylabel("CPU time, ms")
    ax.set_title("forming W and V (joint coordinates) / one engine solve")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    paths.append(out / "seed000_cpu_time.png")
    fig.savefig(paths[1], dpi=120)
    plt.close(fig)
    return paths


def make(out_dir="figures/seed000", count_sizes=COUNT_SIZES, time_sizes=TIME_SIZES,
         repeats: int = 5, plot: bool = True) -> dict:
    """Count, time, write the CSV (and the figures); returns ``{"counts", "times", "files"}``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    counts = count_rows(count_sizes)
    times = time_rows(time_sizes, repeats)
    merged: dict = {}
    for r in counts + times:
        row = merged.setdefault((r["n"], r["method"]), {"n": r["n"], "method": r["method"],
                                                        "mul": "", "add": "", "fun": "",
                                                        "cpu_ms": ""})
        row.update({k: v for k, v in r.items() if v != ""})
    path = out / "seed000_efficiency.csv"
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, ["n", "method", "mul", "add", "fun", "cpu_ms"])
        writer.writeheader()
        for key in sorted(merged, key=lambda k: (k[0], k[1])):
            row = dict(merged[key])
            if row["cpu_ms"] != "":
                row["cpu_ms"] = f"{row['cpu_ms']:.4g}"
            writer.writerow(row)
    files = [path] + (_plot(counts, times, out) if plot else [])
    return {"counts": counts, "times": times, "files": files}


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="figures/seed000")
    parser.add_argument("--count-sizes", type=int, nargs="+", default=list(COUNT_SIZES))
    parser.add_argument("--time-sizes", type=int, nargs="+", default=list(TIME_SIZES))
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    result = make(args.out, args.count_sizes, args.time_sizes, args.repeats)
    counts = {(r["n"], r["method"]): r for r in result["counts"]}
    times = {(r["n"], r["method"]): r["cpu_ms"] for r in result["times"]}
    sizes = sorted({n for n, _ in counts} | {n for n, _ in times})
    print(f"{'n':>3} {'method':<18}{'mul':>10}{'add':>10}{'cpu ms':>10}")
    for n in sizes:
        for method in (*METHODS, "basic-vectorised", "engine"):
            c = counts.get((n, method))
            t = times.get((n, method))
            if c is None and t is None:
                continue
            mul = f"{c['mul']:>10}" if c else f"{'':>10}"
            add = f"{c['add']:>10}" if c else f"{'':>10}"
            cpu = f"{t:>10.3f}" if t is not None else f"{'':>10}"
            print(f"{n:>3} {method:<18}{mul}{add}{cpu}")
    print("wrote " + ", ".join(str(p) for p in result["files"]))
    return result


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    main()
