"""Per-sample cost of inverse dynamics, against Pinocchio on the same URDF and motion.

Protocol
--------
* Models, all written as URDF by hexapod and read back by both libraries: the front leg
  (6 joints), a 3-link planar chain (parallel axes), an 18-joint hexapod (six 3-joint legs on a
  fixed trunk), and serial chains of 10, 30, 100 and 300 links with random axes.
* Motion: ``--samples`` samples (default 1000) of a harmonic motion of every joint, with exact
  derivatives (q, qd, qdd columns).
* hexapod: ``inverse_dynamics`` on the model driven by the motion (the tree-ordered path). The
  build (reading, assembly, the CasADi Function and its compilation) is reported apart; one
  call warms up; the per-sample cost is the median of ``--repeats`` calls divided by the
  number of samples. Run with compiled code (``jit``), and interpreted by CasADi's virtual
  machine too (``vm``) when ``--vm`` is given.
* Pinocchio (optional extra ``compare``): in the same process, ``pinocchio.rnea`` then reading
  ``data.f`` and ``tau`` into one array per sample, the job the CSV needs; median of repeats.
  Agreement (``hexapod.output.report.agreement``): the largest difference, relative to the largest
  magnitude of the same quantity (a joint's forces, a joint's moments and tau).
* Growth exponent: slope of log(cost) against log(links) over the chains.

    python3 scripts/bench_inverse.py [--samples 1000] [--repeats 5] [--chains 10 30 100 300]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import hexapod as hx
from hexapod import (
    agreement,
    apply_motion,
    inverse_columns,
    inverse_dynamics,
    inverse_table,
    read_motion,
    read_urdf,
    urdf_text,
)
from legs import front_leg_scene

sys.path.insert(0, str(Path(__file__).resolve().parent))


def chain_scene(n: int, planar: bool = False, seed: int = 0) -> hx.Scene:
    rng = np.random.default_rng(seed)
    scene = hx.Scene(f"chain-{n}")
    for k in range(n):
        axis = [0.0, 0.0, 1.0] if planar else rng.normal(size=3)
        scene.add(hx.SpatialBody(f"l{k}", 1.0, [1e-3, 1e-2, 1e-2], com=[0.05, 0, 0],
                                 position=[0.1 * k, 0, 0]))
        scene.add(hx.Revolute(f"j{k}", "ground" if k == 0 else f"l{k - 1}", f"l{k}",
                              origin=[0.1 * k, 0, 0], axis=axis))
    return scene


def hexapod_robot() -> hx.Scene:
    """Six 3-joint legs (coxa about z, femur and tibia about the leg's normal) on a trunk."""
    scene = hx.Scene("hexapod-18")
    scene.add(hx.SpatialBody("trunk", 18.4, [0.218, 1.055, 1.226]))
    scene.add(hx.Fixed("stand", "ground", "trunk"))
    for k, side in enumerate(("L1", "R1", "L2", "R2", "L3", "R3")):
        sign = 1.0 if side[0] == "L" else -1.0
        base = np.array([0.24 - 0.12 * (k // 2), 0.08 * sign, -0.04])
        leg = hx.Scene("leg")
        out = np.array([0.0, sign, 0.0])
        lengths, masses = (0.1, 0.15, 0.2), (0.1, 0.09, 0.03)
        point = np.zeros(3)
        parents = ("ground", "coxa", "femur")
        for i, name in enumerate(("coxa", "femur", "tibia")):
            leg.add(hx.SpatialBody(name, masses[i], [1e-5, 2e-4, 2e-4], com=lengths[i] / 2 * out,
                                   position=point))
            axis = [0.0, 0.0, 1.0] if i == 0 else [sign, 0.0, 0.0]
            leg.add(hx.Revolute(name, parents[i], name, origin=point, axis=axis))
            point = point + lengths[i] * out
        scene.attach(leg, side, base="trunk", placement=hx.Placement(base))
    return scene


MODELS = {"front leg": lambda: front_leg_scene(gait=False),
          "planar 3-link": lambda: chain_scene(3, planar=True),
          "hexapod 18 joints": hexapod_robot}


def write_motion(path: Path, joints: list[str], samples: int) -> None:
    t = np.linspace(0.0, 1.0, samples)
    k = np.arange(len(joints))[:, None]
    w = 2 * np.pi * (1 + 0.1 * k)
    q, qd, qdd = 0.4 * np.sin(w * t + k), 0.4 * w * np.cos(w * t + k), -0.4 * w**2 * np.sin(
        w * t + k)
    header = ["t"] + joints + [f"qd:{j}" for j in joints] + [f"qdd:{j}" for j in joints]
    np.savetxt(path, np.column_stack([t, q.T, qd.T, qdd.T]), delimiter=",",
               header=",".join(header), comments="", fmt="%.17g")


def time_hexapod(urdf: Path, motion: Path, repeats: int, compiled: bool) -> dict:
    start = time.perf_counter()
    read = read_motion(motion)
    model = hx.assemble(apply_motion(read_urdf(urdf), read))
    inverse_dynamics(model, read.times[:1], compile=compiled)  # builds the tree function
    built = time.perf_counter() - start
    inverse_dynamics(model, read.times, compile=compiled)  # warm-up: maps over the samples
    costs = []
    for _ in range(repeats):
        tic = time.perf_counter()
        result = inverse_dynamics(model, read.times, compile=compiled)
        costs.append(time.perf_counter() - tic)
    return {"build_s": built, "per_sample_us": 1e6 * statistics.median(costs) / read.times.size,
            "table": (inverse_columns(model), inverse_table(model, result))}


def time_pinocchio(urdf: Path, motion: Path, repeats: int) -> dict | None:
    try:
        from pinocchio_inverse import pinocchio_table
    except ImportError:
        return None
    try:
        import pinocchio  # noqa: F401
    except ImportError:
        return None
    costs, table = [], None
    for _ in range(repeats + 1):
        header, rows, seconds = pinocchio_table(str(urdf), str(motion))
        costs.append(seconds)
        table = (header, rows)
    samples = table[1].shape[0]
    return {"per_sample_us": 1e6 * statistics.median(costs[1:]) / samples, "table": table}


def run(name: str, scene: hx.Scene, folder: Path, args) -> dict:
    urdf = folder / f"{name.replace(' ', '_')}.urdf"
    urdf.write_text(urdf_text(scene))
    joints = [j.name for j in read_urdf(urdf).joints.values() if j.kind != "fixed"]
    motion = folder / f"{name.replace(' ', '_')}.csv"
    write_motion(motion, joints, args.samples)
    row = {"model": name, "joints": len(joints)}
    modes = ["jit", "vm"] if args.vm else ["jit"]
    for mode in modes:
        result = time_hexapod(urdf, motion, args.repeats, compiled=mode == "jit")
        row[f"{mode}_build_s"] = result["build_s"]
        row[f"{mode}_us"] = result["per_sample_us"]
        row["table"] = result["table"]
    pin = time_pinocchio(urdf, motion, args.repeats)
    if pin is not None:
        row["pin_us"] = pin["per_sample_us"]
        row["ratio"] = row["jit_us"] / pin["per_sample_us"]
        if "vm_us" in row:
            row["vm_ratio"] = row["vm_us"] / pin["per_sample_us"]
        row["agreement"] = agreement(*row["table"], *pin["table"])
    print(f"  {name}: done", file=sys.stderr, flush=True)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--chains", type=int, nargs="*", default=[10, 30, 100, 300])
    parser.add_argument("--vm", action="store_true", help="also time the interpreted path")
    parser.add_argument("--keep", metavar="DIR", help="keep the URDFs and motions in DIR (to "
                        "time whole commands, e.g. hexapod inverse against "
                        "scripts/pinocchio_inverse.py)")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(args.keep or scratch)
        folder.mkdir(parents=True, exist_ok=True)
        for name, build in MODELS.items():
            rows.append(run(name, build(), folder, args))
        for n in args.chains:
            rows.append(run(f"chain {n}", chain_scene(n), folder, args))
    columns = [("model", "{:<18}"), ("joints", "{:>6}"), ("jit_build_s", "{:>9.2f}"),
               ("jit_us", "{:>9.2f}"), ("vm_build_s", "{:>9.2f}"), ("vm_us", "{:>9.2f}"),
               ("pin_us", "{:>9.2f}"), ("ratio", "{:>7.2f}"), ("vm_ratio", "{:>8.2f}"),
               ("agreement", "{:>10.1e}")]
    print(f"samples per call: {args.samples}; costs in microseconds per sample (median of "
          f"{args.repeats}); build in seconds")
    print(" ".join(f"{name:>{len(fmt.format(0)) if 'model' not in name else 18}}"
                   if name != "model" else f"{name:<18}" for name, fmt in columns))
    for row in rows:
        cells = []
        for name, fmt in columns:
            width = len(fmt.format(0)) if name != "model" else 18
            cells.append(fmt.format(row[name]) if name in row else f"{'-':>{width}}")
        print(" ".join(cells))
    chains = [r for r in rows if r["model"].startswith("chain")]
    for mode, label in (("jit", "compiled"), ("vm", "interpreted")):
        if len(chains) >= 2 and f"{mode}_us" in chains[0]:
            slope = np.polyfit(np.log([r["joints"] for r in chains]),
                               np.log([r[f"{mode}_us"] for r in chains]), 1)[0]
            print(f"growth exponent over the chains ({label}): {slope:.2f}")
        key = "ratio" if mode == "jit" else "vm_ratio"
        ratios = [r[key] for r in rows if key in r]
        if ratios:
            print(f"time ratio hexapod ({label}) / Pinocchio: {min(ratios):.2f} to "
                  f"{max(ratios):.2f}")


if __name__ == "__main__":
    main()
