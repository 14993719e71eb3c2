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
  number of samples. Run with compiled code (``jit``: ``hx.executing(compiled=True)``) and,
  when ``--vm`` is given, by CasADi's virtual machine too (``vm``, the library's default).
* Pinocchio (optional extra ``compare``): in the same process, ``pinocchio.rnea`` then reading
  ``data.f`` and ``tau`` into one array per sample, the job the CSV needs; median of repeats.
  Agreement (``hexapod.output.report.agreement``): the largest difference, relative to the largest
  magnitude of the same quantity (a joint's forces, a joint's moments and tau).
* Growth exponent: slope of log(cost) against log(links) over the chains.

    python3 scripts/benchmarks/bench_inverse.py [--samples 1000] [--repeats 5]
        [--chains 10 30 100 300]

Whole commands (``--whole-command``)
------------------------------------
What a user waits for, start-up included: ``hexapod inverse MODEL.urdf --motion MOTION.csv
--out OUT.csv`` as a fresh process, against Pinocchio's equivalent whole script
(``scripts/peers/pinocchio_inverse.py``: the same files in, the same CSV out), on the front leg
and the 18-joint hexapod (``--samples`` samples, default 1000), timed in the same run:

* ``interpreted``: the default, evaluated by CasADi's virtual machine (nothing is cached:
  only compiled libraries are);
* ``compiled``: ``--compile yes`` with the cache holding the optimized library (put
  there beforehand by a compiled run), which later compiled runs then load;
* Pinocchio's script.

Each is run ``--runs`` times (default 7), interleaved, after one warm-up run of each; the table
gives the minimum and the median wall time of the processes, the minimum of their CPU time
(user and system: the steadier figure on a machine other work shares), and their ratios to
Pinocchio's.
Everything is written in a temporary folder: the models, the outputs, the caches, and Python's
bytecode of both programs (``PYTHONPYCACHEPREFIX``, so that neither recompiles its modules on
each run, whatever ``PYTHONDONTWRITEBYTECODE`` says).
POSIX only (the CPU time of child processes).

    python3 scripts/benchmarks/bench_inverse.py --whole-command [--samples 1000] [--runs 7]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from measure import (
    growth_exponent,
    log,
    median_time,
    one_blas_thread,
    ratio_range,
    run_process,
    start,
)

one_blas_thread()  # before NumPy loads

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402
from hexapod import apply_motion, inverse_dynamics, read_motion, read_urdf  # noqa: E402
from hexapod.output import agreement, inverse_columns, inverse_table  # noqa: E402
from hexapod.scene import urdf_text  # noqa: E402
from legs import front_leg_scene  # noqa: E402

#: Pinocchio's side (``inverse`` CSV by its RNEA): ``scripts/peers/pinocchio_inverse.py``
PEERS = Path(__file__).resolve().parents[1] / "peers"


def chain_scene(n: int, planar: bool = False, seed: int = 0) -> hx.Scene:
    rng = np.random.default_rng(seed)
    scene = hx.Scene(f"chain-{n}")
    for k in range(n):
        axis = [0.0, 0.0, 1.0] if planar else rng.normal(size=3)
        scene.add(hx.scene.SpatialBody(f"l{k}", 1.0, [1e-3, 1e-2, 1e-2], com=[0.05, 0, 0],
                                       position=[0.1 * k, 0, 0]))
        scene.add(hx.scene.Revolute(f"j{k}", "ground" if k == 0 else f"l{k - 1}", f"l{k}",
                                    origin=[0.1 * k, 0, 0], axis=axis))
    return scene


def hexapod_robot() -> hx.Scene:
    """Six 3-joint legs (coxa about z, femur and tibia about the leg's normal) on a trunk."""
    scene = hx.Scene("hexapod-18")
    scene.add(hx.scene.SpatialBody("trunk", 18.4, [0.218, 1.055, 1.226]))
    scene.add(hx.scene.Fixed("stand", "ground", "trunk"))
    for k, side in enumerate(("L1", "R1", "L2", "R2", "L3", "R3")):
        sign = 1.0 if side[0] == "L" else -1.0
        base = np.array([0.24 - 0.12 * (k // 2), 0.08 * sign, -0.04])
        leg = hx.Scene("leg")
        out = np.array([0.0, sign, 0.0])
        lengths, masses = (0.1, 0.15, 0.2), (0.1, 0.09, 0.03)
        point = np.zeros(3)
        parents = ("ground", "coxa", "femur")
        for i, name in enumerate(("coxa", "femur", "tibia")):
            leg.add(hx.scene.SpatialBody(name, masses[i], [1e-5, 2e-4, 2e-4],
                                         com=lengths[i] / 2 * out, position=point))
            axis = [0.0, 0.0, 1.0] if i == 0 else [sign, 0.0, 0.0]
            leg.add(hx.scene.Revolute(name, parents[i], name, origin=point, axis=axis))
            point = point + lengths[i] * out
        scene.attach(leg, side, base="trunk", placement=hx.spatial.Placement(base))
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


def time_hexapod(urdf: Path, motion: Path, repeats: int, mode: str) -> dict:
    """Build and per-sample cost, compiled (``jit``) or in CasADi's virtual machine (``vm``)."""
    with hx.executing(compiled=mode == "jit"):
        begun = time.perf_counter()
        read = read_motion(motion)
        model = hx.assemble(apply_motion(read_urdf(urdf), read))
        inverse_dynamics(model, read.times[:1])  # the build
        built = time.perf_counter() - begun
        result = inverse_dynamics(model, read.times)  # warm-up
        cost = median_time(lambda _: inverse_dynamics(model, read.times), repeats,
                           time.perf_counter)
    return {"build_s": built, "per_sample_us": 1e6 * cost / read.times.size,
            "table": (inverse_columns(model), inverse_table(model, result))}


def time_pinocchio(urdf: Path, motion: Path, repeats: int) -> dict | None:
    if str(PEERS) not in sys.path:
        sys.path.append(str(PEERS))
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
        result = time_hexapod(urdf, motion, args.repeats, mode)
        row[f"{mode}_build_s"] = result["build_s"]
        row[f"{mode}_us"] = result["per_sample_us"]
        row["table"] = result["table"]
    pin = time_pinocchio(urdf, motion, args.repeats)
    if pin is not None:
        row["pin_us"] = pin["per_sample_us"]
        row["ratio"] = row["jit_us"] / pin["per_sample_us"]
        for mode in ("vm",):
            if f"{mode}_us" in row:
                row[f"{mode}_ratio"] = row[f"{mode}_us"] / pin["per_sample_us"]
        row["agreement"] = agreement(*row["table"], *pin["table"])
    log(f"  {name}: done")
    return row


# ------------------------------------------------------------------ whole commands

WHOLE_MODELS = ("front leg", "hexapod 18 joints")
#: Fills a cache with the optimized library, as a run asked to compile does.
PRIME = """
import sys, hexapod as hx
motion = hx.read_motion(sys.argv[2])
driven = hx.apply_motion(hx.read_urdf(sys.argv[1]), motion)
with hx.executing(compiled=True, cache=sys.argv[3]):
    hx.inverse_dynamics(hx.assemble(driven), motion.times)
"""


def whole_commands(name: str, folder: Path, args) -> dict:
    """Wall times of the whole ``hexapod inverse`` process in each cache state, and of
    Pinocchio's script, on one model (see the module docstring)."""
    base = folder / name.replace(" ", "_")
    urdf, motion = base.with_suffix(".urdf"), base.with_suffix(".csv")
    urdf.write_text(urdf_text(MODELS[name]()))
    joints = [j.name for j in read_urdf(urdf).joints.values() if j.kind != "fixed"]
    write_motion(motion, joints, args.samples)
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONDONTWRITEBYTECODE", "HEXAPOD_CACHE", "HEXAPOD_CACHE_SIZE")}
    env.update(PYTHONPYCACHEPREFIX=str(folder / "bytecode"), OPENBLAS_NUM_THREADS="1")
    inverse = [sys.executable, "-m", "hexapod", "inverse", str(urdf), "--motion", str(motion),
               "--out"]
    compiled = dict(env, HEXAPOD_CACHE_DIR=str(base) + "-compiled")
    subprocess.run([sys.executable, "-c", PRIME, str(urdf), str(motion),
                    compiled["HEXAPOD_CACHE_DIR"]], env=compiled, check=True)
    commands = {
        "interpreted": lambda k: (inverse + [f"{base}-interpreted.csv"],
                                  dict(env, HEXAPOD_CACHE_DIR=f"{base}-empty-{k}")),
        "compiled": lambda k: (inverse + [f"{base}-compiled.csv", "--compile", "yes"],
                               compiled),
        "pinocchio": lambda k: ([sys.executable, str(PEERS / "pinocchio_inverse.py"),
                                 str(urdf), str(motion), f"{base}-pinocchio.csv"], env),
    }
    times: dict[str, list[tuple[float, float]]] = {mode: [] for mode in commands}
    for k in range(args.runs + 1):  # the first round warms up (bytecode)
        for mode, command in commands.items():
            argv, variables = command(k)
            measured = run_process(argv, folder, variables)
            if k:
                times[mode].append(measured)
    ours = read_csv_table(f"{base}-compiled.csv")
    theirs = read_csv_table(f"{base}-pinocchio.csv")
    row = {"model": name, "joints": len(joints), "agreement": agreement(*ours, *theirs)}
    for mode, measured in times.items():
        wall, cpu = ([m[i] for m in measured] for i in (0, 1))
        row[mode] = (min(wall), statistics.median(wall), min(cpu))
    log(f"  {name}: done")
    return row


def read_csv_table(path: str) -> tuple[list[str], np.ndarray]:
    with open(path) as stream:
        header = stream.readline().strip().split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def whole_command_study(args) -> None:
    try:
        import pinocchio  # noqa: F401
    except ImportError:
        raise SystemExit("--whole-command compares with Pinocchio: pip install '.[compare]'") \
            from None
    with tempfile.TemporaryDirectory(prefix="hexapod-whole-") as scratch:
        rows = [whole_commands(name, Path(scratch), args) for name in WHOLE_MODELS]
    modes = ("pinocchio", "interpreted", "compiled")
    print(f"whole processes, {args.samples} samples, {args.runs} runs each. Seconds: wall "
          "time min / median, CPU time min; ratios to Pinocchio's script: wall min / wall "
          "median / CPU min (CPU time is the steadier on a shared machine)")
    for row in rows:
        pin = row["pinocchio"]
        print(f"{row['model']} ({row['joints']} joints; largest difference from Pinocchio "
              f"{row['agreement']:.1e})")
        for mode in modes:
            wall_min, wall_median, cpu = row[mode]
            ratio = ("" if mode == "pinocchio" else
                     f"   ratio {wall_min / pin[0]:5.2f} / {wall_median / pin[1]:5.2f} / "
                     f"{cpu / pin[2]:5.2f}")
            print(f"  {mode:<10} {wall_min:6.3f} / {wall_median:6.3f} / {cpu:6.3f}{ratio}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--chains", type=int, nargs="*", default=[10, 30, 100, 300])
    parser.add_argument("--vm", action="store_true", help="also time the interpreted path")
    parser.add_argument("--whole-command", action="store_true", help="time whole processes "
                        "of 'hexapod inverse' (interpreted, compiled) against Pinocchio's "
                        "whole script instead (see the module docstring)")
    parser.add_argument("--runs", type=int, default=7, help="--whole-command: processes per "
                        "mode (default 7)")
    parser.add_argument("--keep", metavar="DIR", help="keep the URDFs and motions in DIR (to "
                        "time whole commands, e.g. hexapod inverse against "
                        "scripts/peers/pinocchio_inverse.py)")
    args = parser.parse_args()
    if args.whole_command:
        whole_command_study(args)
        return
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
            slope = growth_exponent([r["joints"] for r in chains],
                                    [r[f"{mode}_us"] for r in chains])
            print(f"growth exponent over the chains ({label}): {slope:.2f}")
        key = "ratio" if mode == "jit" else f"{mode}_ratio"
        ratios = [r[key] for r in rows if key in r]
        if ratios:
            print(f"time ratio hexapod ({label}) / Pinocchio: {ratio_range(ratios)}")


if __name__ == "__main__":
    start("bench_inverse")
    main()
