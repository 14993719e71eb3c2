"""Per-sample cost of the walking robot's inverse dynamics, against a robotics engineer's
Pinocchio pipeline for the same robot and motion.

Protocol
--------
* Robot and motion: the built-in ``hexapod`` (a free trunk, 36 driven joints, the feet in stance
  held by contacts, ground forces by the ``min-wrench`` policy), one stride of 0.5 s at
  ``--samples`` samples (default 501, the report's, and 5001).
* hexapod: ``hx.inverse_dynamics(model, times)`` (the phase path), interpreted (CasADi's
  virtual machine, the default) and compiled (``hx.executing(compiled=True, cache=...)``).
  Builds apart: the interpreted path's first call; the compiled path's first call on an empty
  cache (CasADi's C code compiled by gcc: wall time, and CPU time with the compiler's), then the
  first call of a fresh model on that warm cache (what the next run pays). Per sample: the
  median of ``--repeats`` later calls' ``time.process_time``, after a warm-up call, each on the
  times moved by a picosecond (the gait laws keep their last samples), over the samples.
  The interpreted path twice: a model's first calls, then the same model after
  ``SETTLE_CALLS`` more calls of the count (``settled``: each of its plans has evaluated more
  than ``hexapod.algorithms.phase_plan.EXPAND_AFTER`` samples, and evaluates its samples apart,
  32 at a time, by CasADi's MX virtual machine; what a sweep or a long run pays).
* The gait laws' share: ``law_values(times)`` the same way (moved the other way) of the
  guides' kinematics (``model.guidance.kinematics``: the foot paths, the trunk's motion, the
  gates; the guided joints' own laws would solve that kinematics), which the inverse dynamics
  evaluates once per sample.
* Pinocchio (``scripts/peers/pinocchio_walking.py``; the ``compare`` extra): the same robot from
  the URDF hexapod writes, on a free flyer, with the same motion (hexapod's trunk motion and the
  gait's joint laws, converted to Pinocchio's convention before timing: a trajectory generator's
  output); per sample in Python: RNEA, the stance feet's Jacobians, the feet's forces from the
  base rows, the torques; with every joint wrench, RNEA again with the feet's forces and
  ``data.f`` read out. Two force distributions: ``least-norm`` (least ``sum |f_k|^2 / w_k``, the
  engineer's pipeline, which the ratios are taken against) and ``min-wrench`` (hexapod's policy
  reproduced, the check of agreement). Per sample: the median of ``--repeats`` passes over the
  samples after a warm-up pass, ``time.process_time`` of the loop.
* Targets: hexapod, which always returns every joint wrench, at most 2 times the
  Pinocchio pipeline that also returns every joint wrench, compiled (moonshot: 1 time), at most
  5 times interpreted; the gait laws at most 20 us a sample. Both ratios are printed, against
  the torques-only pipeline as well.
* Agreement, on the first sample count: Pinocchio's RNEA with hexapod's ground forces gives
  hexapod's efforts (the model and the motion are the same), its ``min-wrench`` reproduces
  hexapod's torques, ground forces and joint wrenches, and any policy's total ground force
  matches hexapod's (fixed by the motion): each to 1e-8 (of the largest torque, the weight, the
  largest force or moment); a failed check ends the run with status 1.

Everything but ``--out`` goes to temporary folders. Timings are noisy on a shared machine:
compare the ratios of one run; the load average is printed at the start and the end.

    python3 scripts/benchmarks/bench_walking_inverse.py [--samples 501 5001] [--repeats 3]
        [--out bench-walking-inverse] [--cache DIR] [--quick]

``--quick``: 501 samples, 2 repeats, and the compiled path only with ``--cache`` (a folder of an
earlier run's compiled code: compiling takes minutes).
"""

from __future__ import annotations

import argparse
import io
import json
import sys
import tempfile
import time
from pathlib import Path

from measure import cpu_seconds, load_average, log, machine, median_time, one_blas_thread, start

one_blas_thread()  # before NumPy loads

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402

PEERS = Path(__file__).resolve().parents[1] / "peers"
SCENE, STRIDE = "hexapod", 0.5  # the built-in walking robot, one stride (s)
TARGETS = {"compiled": 2.0, "moonshot": 1.0, "interpreted": 5.0, "laws_us": 20.0}
#: Calls of a sample count before its settled timing: a plan given a tenth of a stride's
#: samples (the built-in gait's shortest contact phase) evaluates EXPAND_AFTER of them after
#: twenty at 501 samples.
SETTLE_CALLS = 20
TOLERANCE = 1e-8  # agreement with Pinocchio (relative, see the module docstring)
VARIANTS = (("least-norm", False), ("least-norm", True), ("min-wrench", False),
            ("min-wrench", True))


def variant_name(policy: str, wrenches: bool) -> str:
    return f"pinocchio {policy}{', every joint wrench' if wrenches else ', torques'}"


def per_sample(call, times: np.ndarray, repeats: int, sign: float = 1.0) -> float:
    """Microseconds of CPU per sample of ``call(times moved by k picoseconds)`` (median)."""
    return 1e6 * median_time(lambda k: call(times + sign * (k + 1) * 1e-12),
                             repeats) / times.size


def first_call(model: hx.Model, times: np.ndarray) -> tuple[float, float, hx.InverseResult]:
    """Wall and CPU seconds (the compiler's included) of a call, and its result."""
    wall, cpu = time.perf_counter(), cpu_seconds()
    result = hx.inverse_dynamics(model, times)
    return time.perf_counter() - wall, cpu_seconds() - cpu, result


def hexapod_interpreted(counts: list[int], repeats: int) -> tuple[dict, dict]:
    """Per-sample costs of the interpreted path and the gait laws, the first call, and the
    results (per sample count, for Pinocchio's motion)."""
    model = hx.assemble(hx.load_scene(SCENE))
    # the gait's laws: a guided robot's guides' (its guided joints' own laws solve the guides'
    # kinematics, which the run does once for all its samples)
    gait = model if model.guidance is None else model.guidance.kinematics
    out, results = {"build": {}, "us": {}, "laws_us": {}}, {}
    for n in counts:
        times = np.linspace(0.0, STRIDE, n)
        wall, cpu, results[n] = first_call(model, times)  # the warm-up
        out["build"].setdefault("first_call_wall_s", wall)
        out["build"].setdefault("first_call_cpu_s", cpu)
        out["us"][n] = per_sample(lambda t: hx.inverse_dynamics(model, t), times, repeats)
        out["laws_us"][n] = per_sample(gait.law_values, times, repeats, sign=-1.0)
        log(f"  hexapod interpreted, {n} samples: {out['us'][n]:.0f} us a sample")
    # the same model again, settled: SETTLE_CALLS more calls of each count first (the plans of
    # a count's contact phases are not always those of another's: a rank decision taken at
    # another sample may keep other rows)
    out["settled_us"] = {}
    for n in counts:
        times = np.linspace(0.0, STRIDE, n)
        log(f"  settling the interpreted path at {n} samples ({SETTLE_CALLS} calls)")
        for k in range(SETTLE_CALLS):
            hx.inverse_dynamics(model, times - (k + 1) * 1e-12)
        out["settled_us"][n] = per_sample(lambda t: hx.inverse_dynamics(model, t), times,
                                          repeats)
        log(f"  hexapod interpreted, settled, {n} samples: {out['settled_us'][n]:.0f} us a "
            "sample")
    return out, results


def hexapod_compiled(counts: list[int], repeats: int, cache: Path,
                     results: dict) -> dict:
    """Per-sample costs of the compiled path, its builds (an empty or given cache, then a fresh
    model on the warm cache), and its largest effort difference from the interpreted path."""
    empty = not any(cache.iterdir())
    out = {"build": {"cache_was_empty": empty}, "us": {}, "vs_interpreted": 0.0}
    with hx.executing(compiled=True, cache=str(cache)):
        times = np.linspace(0.0, STRIDE, counts[0])
        log("  hexapod compiled: building (gcc; minutes on an empty cache)")
        wall, cpu, _ = first_call(hx.assemble(hx.load_scene(SCENE)), times)
        out["build"].update(first_call_wall_s=wall, first_call_cpu_s=cpu)
        model = hx.assemble(hx.load_scene(SCENE))
        wall, cpu, _ = first_call(model, times)
        out["build"].update(warm_cache_wall_s=wall, warm_cache_cpu_s=cpu)
        for n in counts:
            times = np.linspace(0.0, STRIDE, n)
            result = hx.inverse_dynamics(model, times)  # the warm-up
            reference = results[n].effort
            out["vs_interpreted"] = max(out["vs_interpreted"], float(
                np.nanmax(np.abs(result.effort - reference)) / np.nanmax(np.abs(reference))))
            out["us"][n] = per_sample(lambda t: hx.inverse_dynamics(model, t), times, repeats)
            log(f"  hexapod compiled, {n} samples: {out['us'][n]:.0f} us a sample")
    return out


def load_peer():
    """The Pinocchio side's module, or None without Pinocchio."""
    try:
        import pinocchio  # noqa: F401
    except ImportError:
        return None
    if str(PEERS) not in sys.path:
        sys.path.append(str(PEERS))
    import pinocchio_walking

    return pinocchio_walking


def pinocchio_robot(peer, model: hx.Model, folder: Path):
    """Pinocchio's robot from the URDF of the scene, and the trunk's pose in its root frame."""
    text, trunk_pose = peer.walking_urdf(hx.load_scene(SCENE))
    urdf = folder / "hexapod.urdf"
    urdf.write_text(text)
    driven = [j for j in model.joints if j.kind == "revolute"]
    feet = []
    for contact in model.contacts:
        tarsus = model.joints[contact.joint].child
        joint = next(j for j in driven if j.child == tarsus)  # its frame is the URDF link's
        foot = model.bodies[tarsus].markers["foot"].position
        feet.append((joint.name, joint.child_frame.inverse().transform_point(foot)))
    robot = peer.load_robot(str(urdf), [j.name for j in driven], feet,
                            model.characteristic_length)
    return robot, trunk_pose, [j.index for j in driven]


def pinocchio_costs(peer, counts: list[int], repeats: int, results: dict, folder: Path
                    ) -> tuple[dict, dict]:
    """Per-sample costs of every variant, and the agreement on the first sample count."""
    model = hx.assemble(hx.load_scene(SCENE))
    robot, trunk_pose, driven = pinocchio_robot(peer, model, folder)
    costs: dict = {variant_name(*v): {} for v in VARIANTS}
    agreement = {}
    for n in counts:
        motion = peer.pinocchio_motion(model, results[n], robot, trunk_pose)
        for policy, wrenches in VARIANTS:
            runs = [peer.run_pipeline(robot, *motion, policy=policy, wrenches=wrenches)
                    for _ in range(repeats + 1)]  # the first warms up
            costs[variant_name(policy, wrenches)][n] = \
                1e6 * float(np.median([r.seconds for r in runs[1:]])) / n
            if n == counts[0]:
                agreement.update(compare(model, results[n], driven, runs[0], policy, wrenches))
        if n == counts[0]:
            given = peer.run_pipeline(robot, *motion, forces=results[n].ground_force)
            agreement.update(compare(model, results[n], driven, given, "hexapod forces", False))
        log(f"  pinocchio, {n} samples: done")
    return costs, agreement


def compare(model: hx.Model, result: hx.InverseResult, driven: list[int], run, policy: str,
            wrenches: bool) -> dict:
    """The largest differences of one Pinocchio pass from hexapod's result (relative: to the
    largest torque, to the weight, to the largest joint force or moment)."""
    weight = model.total_mass * float(np.linalg.norm(model.gravity))
    effort = result.effort[:, driven]
    out = {f"{policy}: torques": np.abs(run.tau - effort).max() / np.abs(effort).max(),
           f"{policy}: free-flyer residual force / weight": np.abs(run.base[:, :3]).max()
           / weight}
    if policy != "hexapod forces":
        total = run.forces.sum(axis=1) - result.ground_force.sum(axis=1)
        out[f"{policy}: total ground force / weight"] = np.abs(total).max() / weight
        out[f"{policy}: total vertical ground force / weight"] = np.abs(total[:, 2]).max() \
            / weight
        out[f"{policy}: feet's forces / weight"] = \
            np.abs(run.forces - result.ground_force).max() / weight
    if wrenches:
        for part, name, cut in (("force", "joint forces", slice(0, 3)),
                                ("torque", "joint moments", slice(3, 6))):
            ours = getattr(result, part)[:, driven]
            out[f"{policy}: {name}"] = np.abs(run.wrenches[..., cut] - ours).max() \
                / np.abs(ours).max()
    return {key: float(value) for key, value in out.items()}


def must_agree(key: str) -> bool:
    """The differences that must be within :data:`TOLERANCE` (the least-norm policy's own
    torques and forces differ from hexapod's by design)."""
    return not key.startswith("least-norm") or "total" in key or "residual" in key


# ------------------------------------------------------------------ the table and the figure

def rows(figures: dict) -> list[dict]:
    """One row per path and sample count: cost, ratios to Pinocchio's least-norm pipeline
    (torques only; every joint wrench), target and verdict."""
    out = []
    peer = figures.get("pinocchio") or {}
    torques = peer.get(variant_name("least-norm", False), {})
    wrenches = peer.get(variant_name("least-norm", True), {})
    for n in figures["samples"]:
        paths = [("hexapod interpreted, a model's first calls", figures["interpreted"]["us"][n],
                  "interpreted"),
                 ("hexapod interpreted, settled (every plan past EXPAND_AFTER samples)",
                  figures["interpreted"].get("settled_us", {}).get(n), "interpreted"),
                 ("hexapod compiled", figures.get("compiled", {}).get("us", {}).get(n),
                  "compiled"),
                 ("gait laws (the guides' law_values)", figures["interpreted"]["laws_us"][n],
                  "laws")]
        paths += [(name, costs[n], None) for name, costs in peer.items()]
        for name, us, kind in paths:
            if us is None:
                continue
            row = {"path": name, "samples": n, "us": us, "target": "", "met": ""}
            if n in torques and kind != "laws":  # the laws are a share of hexapod's cost
                row["x_torques"], row["x_wrenches"] = us / torques[n], us / wrenches[n]
            if kind == "laws":
                row["target"] = f"<= {TARGETS['laws_us']:g} us"
                row["met"] = "yes" if us <= TARGETS["laws_us"] else "no"
            elif kind and "x_wrenches" in row:
                limit = TARGETS[kind]
                row["target"] = f"<= {limit:g} x (wrenches)"
                row["met"] = "yes" if row["x_wrenches"] <= limit else "no"
                if kind == "compiled":
                    moon = TARGETS["moonshot"]
                    row["target"] += f"; moonshot {moon:g} x"
                    row["met"] += f"; {'yes' if row['x_wrenches'] <= moon else 'no'}"
            out.append(row)
    return out


def without_laws(figures: dict) -> list[str]:
    """Per sample count: hexapod's costs less the gait laws', and their ratios."""
    wrenches = figures["pinocchio"][variant_name("least-norm", True)]
    out = []
    for n in figures["samples"]:
        laws = figures["interpreted"]["laws_us"][n]
        parts = [f"{mode} {figures[mode]['us'][n] - laws:.1f} us "
                 f"({(figures[mode]['us'][n] - laws) / wrenches[n]:.2f} x)"
                 for mode in ("interpreted", "compiled") if mode in figures]
        out.append(f"{n} samples: " + ", ".join(parts))
    return out


def markdown(figures: dict) -> str:
    """The Markdown table of the run, with its builds, agreement and load averages."""
    lines = [f"Walking robot (`{SCENE}`), inverse dynamics over one stride of {STRIDE} s: CPU "
             f"time per sample (median of {figures['repeats']}), microseconds. Ratios to "
             "Pinocchio's least-norm pipeline in the same run, torques only and with every "
             "joint wrench; the targets are against the latter (hexapod returns every joint "
             "wrench).", "",
             "| path | samples | us / sample | x Pinocchio (torques) | x Pinocchio (wrenches) "
             "| target | met |", "| --- | ---: | ---: | ---: | ---: | --- | --- |"]
    for row in rows(figures):
        ratio = [f"{row[k]:.2f}" if k in row else "-" for k in ("x_torques", "x_wrenches")]
        lines.append(f"| {row['path']} | {row['samples']} | {row['us']:.1f} | {ratio[0]} | "
                     f"{ratio[1]} | {row['target']} | {row['met']} |")
    if not figures.get("pinocchio"):
        lines += ["", "Pinocchio not installed (`pip install '.[compare]'`): no ratios."]
    else:
        lines += ["", "Without the gait laws (Pinocchio's motion comes with its joint angles, "
                  "computed before its timing), hexapod against Pinocchio with every joint "
                  "wrench:"] + [f"- {line}" for line in without_laws(figures)]
    builds = [("interpreted", figures["interpreted"]["build"])]
    if "compiled" in figures:
        builds.append(("compiled", figures["compiled"]["build"]))
    lines += ["", "Builds (first call, seconds, wall / CPU with the compiler's):"]
    for name, build in builds:
        line = (f"- {name}: {build['first_call_wall_s']:.1f} / {build['first_call_cpu_s']:.1f}")
        if "warm_cache_wall_s" in build:
            state = "an empty cache" if build["cache_was_empty"] else "the given cache"
            line += (f" on {state}; a fresh model on the warm cache "
                     f"{build['warm_cache_wall_s']:.1f} / {build['warm_cache_cpu_s']:.1f}")
        lines.append(line)
    if "compiled" in figures:
        lines.append(f"- compiled against interpreted efforts: largest difference "
                     f"{figures['compiled']['vs_interpreted']:.1e} of the largest")
    if figures.get("agreement"):
        lines += ["", f"Agreement with hexapod at {figures['samples'][0]} samples (relative; "
                  f"checked to {TOLERANCE:g} where marked):", ""]
        for key, value in figures["agreement"].items():
            mark = (" (ok)" if value <= TOLERANCE else " (FAILED)") if must_agree(key) \
                else " (a different policy)"
            lines.append(f"- {key}: {value:.1e}{mark}")
    lines += ["", f"Load average at the start: {figures['load_start']}; at the end: "
              f"{figures['load_end']}."]
    return "\n".join(lines) + "\n"


def figure(figures: dict) -> bytes:
    """A bar chart of the costs per sample, one panel per sample count, with the targets."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    counts = figures["samples"]
    fig = Figure(figsize=(10, 1.0 + 0.3 * len(rows(figures)) + 0.6 * len(counts)))
    axes = np.atleast_1d(fig.subplots(len(counts), 1, sharex=True, squeeze=False)[:, 0])
    for ax, n in zip(axes, counts, strict=True):
        data = [r for r in rows(figures) if r["samples"] == n]
        names = [r["path"] for r in data]
        colours = ["C0" if r["path"].startswith("hexapod") else "C2" if "laws" in r["path"]
                   else "C1" for r in data]
        ax.barh(np.arange(len(data)), [r["us"] for r in data], color=colours)
        for k, r in enumerate(data):
            ax.text(r["us"] * 1.05, k, f"{r['us']:.0f}", va="center", fontsize=7)
        ax.set_yticks(np.arange(len(data)), names, fontsize=8)
        ax.invert_yaxis()
        ax.set_xscale("log")
        wrenches = (figures.get("pinocchio") or {}).get(variant_name("least-norm", True), {})
        if n in wrenches:
            for key, style in (("compiled", "--"), ("interpreted", ":")):
                ax.axvline(TARGETS[key] * wrenches[n], color="k", linestyle=style,
                           linewidth=0.8, label=f"{TARGETS[key]:g} x Pinocchio with wrenches")
        ax.axvline(TARGETS["laws_us"], color="C2", linestyle="-.", linewidth=0.8,
                   label=f"gait laws target {TARGETS['laws_us']:g} us")
        ax.set_title(f"{n} samples over one stride", fontsize=9)
        ax.grid(True, axis="x", which="both", linewidth=0.4, alpha=0.6)
    every = [r["us"] for r in rows(figures)] + [TARGETS["laws_us"]]
    axes[0].set_xlim(0.5 * min(every), 2.0 * max(every))  # room for the labels
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=7, loc="lower center", ncol=len(labels))  # off the bars
    axes[-1].set_xlabel("CPU time per sample (us, log scale)")
    fig.tight_layout(rect=(0.0, 0.04, 1.0, 1.0))
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=120)
    return buffer.getvalue()


# ------------------------------------------------------------------ the run

def measure_all(args, scratch: Path) -> dict:
    figures = {"scene": SCENE, "stride_s": STRIDE, "samples": args.samples,
               "repeats": args.repeats, "machine": machine(), "load_start": load_average(),
               "targets": TARGETS, "tolerance": TOLERANCE}
    figures["interpreted"], results = hexapod_interpreted(args.samples, args.repeats)
    if args.cache or not args.quick:
        cache = Path(args.cache) if args.cache else scratch / "cache"
        cache.mkdir(parents=True, exist_ok=True)
        figures["compiled"] = hexapod_compiled(args.samples, args.repeats, cache, results)
    peer = load_peer()
    if peer is None:
        log("Pinocchio not installed: pip install '.[compare]'")
        figures["pinocchio"] = None
    else:
        figures["pinocchio"], figures["agreement"] = pinocchio_costs(
            peer, args.samples, args.repeats, results, scratch)
    figures["load_end"] = load_average()
    figures["rows"] = rows(figures)
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, nargs="+", default=None,
                        help="sample counts over one stride (default 501 5001)")
    parser.add_argument("--repeats", type=int, default=None, help="timed calls (default 3)")
    parser.add_argument("--out", default="bench-walking-inverse",
                        help="folder for figures.json, table.md and costs.png")
    parser.add_argument("--cache", metavar="DIR", help="keep the compiled code in DIR (a "
                        "later run loads it instead of compiling)")
    parser.add_argument("--quick", action="store_true", help="501 samples, 2 repeats, the "
                        "compiled path only with --cache")
    args = parser.parse_args()
    args.samples = args.samples or ([501] if args.quick else [501, 5001])
    args.repeats = args.repeats or (2 if args.quick else 3)
    with tempfile.TemporaryDirectory(prefix="hexapod-walking-bench-") as scratch:
        figures = measure_all(args, Path(scratch))
    text = markdown(figures)
    print(text)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text(text)
    (out / "figures.json").write_text(json.dumps(figures, indent=1, default=float) + "\n")
    (out / "costs.png").write_bytes(figure(figures))
    log(f"wrote {out}/table.md, figures.json and costs.png")
    failed = [k for k, v in (figures.get("agreement") or {}).items()
              if must_agree(k) and not v <= TOLERANCE]
    if failed:
        raise SystemExit(f"disagreement with Pinocchio beyond {TOLERANCE:g}: {', '.join(failed)}")


if __name__ == "__main__":
    start("bench_walking_inverse")
    main()
