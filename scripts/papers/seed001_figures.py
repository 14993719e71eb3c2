"""Fig. 7 of Dumitru, Marin and Margine redrawn: the liaison force F21 of the left front leg over
0-0.5 s.

Dumitru, Marin and Margine plot, as their Fig. 7 "Liaison force variation F21", the components Fx,
Fy, Fz of the force element 1 exerts on element 2 of the left anterior leg and its magnitude |F|, in
N, against time from 0 to 0.5 s. No numbers of theirs survive: only that layout (the OCR keeps the
legend "Fx Fy Fz |F|", the unit "(N)", "time (s)", the ticks 0.1 ... 0.5 and the caption). This
script computes the same quantity as ``hexapod report`` does on its default scene, and draws it in
that layout:

* the scene is the built-in ``front-leg`` (the L1 leg of ``legs``, trunk held, six revolute
  joints driven by the walking robot's tripod laws, the foot loaded by the ground's reaction the
  walking robot gives it), loaded
  by name exactly as the command line loads it;
* the window is the command's default, one cycle of the scene's periodic laws (the 0.5 s
  stride), with 501 samples including both ends;
* the wrenches follow the report convention (docs/report.md): exerted by the parent on the
  child, about the joint origin, in the child's joint frame (z along the joint axis), so
  ``F21`` is the force at ``thc_levation`` exerted by element 1 (``thc_link_1``) on element 2
  (``thc_link_2``).

It writes ``fig7_F21.png`` (the paper's figure) and ``fig7_<joint>.png``, the same figure for
each of the leg's six joints (``F10`` ... ``F65``; element 0 is the held trunk), and prints a
caption per file.

    python3 scripts/papers/seed001_figures.py [--out figures/seed001] [--samples 501]
"""

from __future__ import annotations

import os

# One OpenBLAS thread, as the command line has (hexapod sets it, but only if NumPy is not loaded
# yet): the numbers then equal those of `hexapod report`'s inverse.csv to the last bit.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import sys  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402
from hexapod import (  # noqa: E402
    InverseResult,
    Model,
    inverse_dynamics,
    load_scene,
)
from hexapod.output import (  # noqa: E402
    COMPONENT_COLOURS,
    png_bytes,
    wrench_label,
)
from hexapod.scene import DEFAULT_SCENE  # noqa: E402

SCENE = DEFAULT_SCENE  # "front-leg": what `hexapod report` runs without a SCENE
GAIT = "tripod"  # the built-in leg scenes are driven by the tripod gait (legs/front_leg.py)
LEG = "L1"  # the left anterior leg of Dumitru, Marin and Margine
SAMPLES = 501  # `hexapod report`'s default
FRAME = "joint"  # `hexapod report`'s default: the child's joint frame
PAPER_WRENCH = "F21"
PAPER_FIGURE = "Dumitru, Marin and Margine, Fig. 7 (Liaison force variation F21)"
#: The same figure named inside a sentence (the captions of the other joints' figures).
PAPER_FIGURE_IN_TEXT = "Fig. 7 of Dumitru, Marin and Margine (Liaison force variation F21)"
PAPER_LAYOUT = ("what survives of the paper's figure (OCR): the legend Fx, Fy, Fz, |F|, the "
                "unit (N), the abscissa time (s) with ticks 0.1 ... 0.5, the caption "
                "'Fig.7 Liaison force variation F21'; no numbers, no curve styles, no y-range")
CHOSEN_LAYOUT = ("chosen: the four curves on one axes (the OCR has one legend, one unit and one "
                 "time axis for all four), 0 to 0.5 s ticked every 0.1 s, the components thin "
                 "in red, green, blue and |F| thick black as in `hexapod report`'s forces.png")


@dataclass(frozen=True)
class Run:
    """The inverse dynamics behind the figures."""

    scene: str
    model: Model
    times: np.ndarray
    result: InverseResult
    window: str  # why the window is what it is


def liaison_forces(samples: int = SAMPLES, scene: str = SCENE) -> Run:
    """Inverse dynamics of ``scene`` over its default window, as ``hexapod report`` runs it:
    the joint wrenches in the child's joint frame at ``samples`` times, both ends included."""
    if samples < 2:
        raise ValueError(f"samples must be at least 2, got {samples}")
    model = hx.assemble(load_scene(scene))
    duration, why = model.time_window()
    times = np.linspace(0.0, duration, samples)
    result = inverse_dynamics(model, times, frame=FRAME)
    return Run(scene, model, times, result, f"{why}, {duration:g} s")


def _element(model: Model, name: str) -> tuple[int, str]:
    """The number Dumitru, Marin and Margine give a body (from 1 in scene order, the ground 0) and
    its name."""
    if name == hx.scene.GROUND:
        return 0, "trunk, held: the ground"
    return model.body_index[name] + 1, name


def joint_description(model: Model, k: int) -> dict:
    """The wrench's label and which element exerts it on which."""
    joint = model.joints[k]
    parent, parent_name = _element(model, joint.type.parent)
    child, child_name = _element(model, joint.type.child)
    return {"joint": joint.name, "wrench": wrench_label(model, joint),
            "by_element": parent, "by_body": parent_name,
            "on_element": child, "on_body": child_name,
            "exerted": (f"exerted by element {parent} ({parent_name}) on element {child} "
                        f"({child_name})")}


def fig7_figure(times: np.ndarray, force: np.ndarray, subtitle: str, caption: str):
    """The layout of Fig. 7 of Dumitru, Marin and Margine: ``force`` (N, 3) components and magnitude
    against time on one axes, a caption under it as in the paper. Drawn on a bare matplotlib Figure
    (Agg canvas, no pyplot, no display)."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(7.6, 4.6))
    figure.subplots_adjust(left=0.1, right=0.97, top=0.87, bottom=0.19)
    ax = figure.add_subplot()
    for c, colour in enumerate(COMPONENT_COLOURS):
        ax.plot(times, force[:, c], color=colour, linewidth=1.1, label=f"F{'xyz'[c]}")
    magnitude = np.linalg.norm(force, axis=1)
    ax.plot(times, magnitude, color="black", linewidth=1.8, label="|F|")
    peak = int(np.argmax(magnitude))
    ax.scatter([times[peak]], [magnitude[peak]], s=16, color="black", zorder=3,
               label=f"peak |F| {magnitude[peak]:.4g} N at {times[peak]:.4g} s")
    ax.set_xlim(times[0], times[-1])
    step = 0.1
    ax.set_xticks(np.arange(np.ceil(times[0] / step), np.floor(times[-1] / step + 1e-9) + 1)
                  * step)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("(N)")
    ax.grid(True, linewidth=0.4, alpha=0.6)
    ax.tick_params(labelsize=8)
    ax.axhline(0.0, color="0.5", linewidth=0.6, zorder=0)
    ax.legend(fontsize=8, ncols=5, loc="upper left", columnspacing=1.2)
    ax.set_title(subtitle, fontsize=9)
    figure.text(0.5, 0.025, caption, ha="center", va="bottom", fontsize=11)
    return figure


def parameters(run: Run) -> dict:
    """How the curves were computed (the same for every figure)."""
    return {"scene": run.scene, "gait": GAIT, "leg": LEG,
            "start": float(run.times[0]), "duration": float(run.times[-1] - run.times[0]),
            "samples": int(run.times.size), "method": run.result.method,
            "frame": ("the child's joint frame, z along the joint axis (report convention: "
                      "exerted by the parent on the child, about the joint origin)")}


def figures(run: Run) -> list[tuple[dict, object]]:
    """(entry, Figure) for ``fig7_F21.png`` and then one ``fig7_<joint>.png`` per joint. Each
    entry: ``file``, ``reproduces`` (the paper's figure), ``parameters`` (scene, gait, leg,
    window, samples, frame), ``caption``, the joint and its wrench's label, which element
    exerts it on which, and the peak of ``|F|`` with its time."""
    model, t, force = run.model, run.times, run.result.force
    joints = [joint_description(model, k) for k in range(len(model.joints))]
    out = []
    paper = next(k for k, j in enumerate(joints) if j["wrench"] == PAPER_WRENCH)
    for k in [paper] + list(range(len(joints))):
        j = joints[k]
        magnitude = np.linalg.norm(force[:, k], axis=1)
        peak = int(np.argmax(magnitude))
        is_paper = not out
        name = f"fig7_{j['wrench']}.png" if is_paper else f"fig7_{j['joint']}.png"
        subtitle = (f"{j['wrench']} at {j['joint']}, {j['exerted']}\n"
                    f"{run.scene} scene, {GAIT} gait; in element {j['on_element']}'s joint "
                    "frame, z along the joint axis")
        caption = (f"{j['wrench']}: the force {j['exerted']} at joint {j['joint']} of the "
                   f"{LEG} leg ({run.scene} scene, {GAIT} gait, "
                   f"{t[0]:g}-{t[-1]:g} s, {t.size} samples), in element {j['on_element']}'s "
                   f"joint frame; peak |F| {magnitude[peak]:.4g} N at {t[peak]:.4g} s")
        if is_paper:
            caption += f". Layout: {PAPER_LAYOUT}; {CHOSEN_LAYOUT}."
        else:
            caption += (f"; the layout of {PAPER_FIGURE_IN_TEXT}"
                        + (", same curves as fig7_F21.png" if k == paper else "") + ".")
        entry = {"file": name,
                 "reproduces": PAPER_FIGURE if is_paper
                 else f"{PAPER_FIGURE}, layout applied to joint {j['joint']}",
                 "parameters": parameters(run), **j,
                 "peak_force": float(magnitude[peak]), "peak_time": float(t[peak]),
                 "caption": caption}
        under = (f"Fig. 7  Liaison force variation {j['wrench']}" if is_paper
                 else f"Liaison force variation {j['wrench']} (the layout of Fig. 7 of Dumitru, "
                       "Marin and Margine)")
        out.append((entry, fig7_figure(t, force[:, k], subtitle, under)))
    return out


def make(out_dir, samples: int = SAMPLES) -> list[dict]:
    """Compute and write the figures into ``out_dir`` (created if needed); one entry per file
    written: its name, the paper figure it reproduces, the parameters, a caption."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    entries = []
    for entry, figure in figures(liaison_forces(samples)):
        (out / entry["file"]).write_bytes(png_bytes(figure))
        entries.append(entry)
    return entries


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="figures/seed001", help="output directory")
    parser.add_argument("--samples", type=int, default=SAMPLES,
                        help="samples over the window, both ends included (501)")
    args = parser.parse_args(argv)
    if args.samples < 2:
        parser.error("--samples must be at least 2")
    entries = make(args.out, args.samples)
    for entry in entries:
        print(f"{args.out}/{entry['file']}: {entry['caption']}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    sys.exit(main())
