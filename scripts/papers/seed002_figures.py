"""Figs. 6-10 of Richard, Anderson and Andrews (1989/90): the closed-loop pendulum of RESTRI
against its Lagrange equation.

Richard, Anderson and Andrews, "The vector-network method for the modelling of mechanical
systems" (1989/90), Section 5: two particles, m1 = 2 kg and m2 = 1 kg, each on a rigid rod
from a fixed point, joined by a rigid coupler (one degree of freedom), released at rest and
simulated for 15 s. The paper checks RESTRI's output (triangles) against the solution of the
one-degree-of-freedom Lagrange equation (solid lines) in Figs. 7-10.

Reading of the paper (as in ``data/scenes/closed_pendulum_seed002.toml``): lengths in dm; x to the
right, y pointing down (gravity along +y, g = 98.1 dm/s^2); m1 hangs from the fixed point (0, 0)
(point 4 of Fig. 5), m2 from (7, 0) (point 3); initial x1 = 4, y1 = 4, x2 = 12, y2 = 5 dm at rest;
links 5.657, 7.071 and 8.062 dm.

Figures, as the captions of the paper's OCR copy name them:

* Fig. 7: mass #1 vertical displacement (y1) against time;
* Fig. 8: mass #1 horizontal displacement (x1);
* Fig. 9: mass #2 vertical displacement (y2);
* Fig. 10: mass #2 horizontal displacement (x2).

Each is drawn as the paper draws it: the Lagrange solution
(``hexapod.benchmarks.ClosedLoopPendulum``, built here from the paper's numbers in dm, DOP853 at
1e-13) as a solid line, the absolute-coordinate engine (``hexapod.simulation.loop`` on the scene
file, default method,
rtol 1e-10) as triangles, and below it a panel of the difference engine - Lagrange at every
saved state of the engine. Fig. 6, the vector-network diagram (5 vertices, 9 elements: tree
edges solid, cotree edges dashed) is drawn from ``hexapod.algorithms.topology.vector_network``, and
its incidence, cutset and circuit matrices are written to ``seed002_matrices.md``; the script
checks ``cutset circuit^T = 0`` (with signs) and ``A = -B^T`` and stops if either fails.

    python3 scripts/papers/seed002_figures.py [--out figures/seed002] [--duration 15] [--rtol 1e-10]

``make(out_dir, ...)`` does the same from Python (for ``scripts/papers/make_figures.py``) and
returns one entry per file: ``file``, ``reproduces`` (the paper's figure), ``parameters``,
``caption``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import hexapod as hx
from hexapod import VectorNetwork, read_scene, simulate, vector_network
from hexapod.benchmarks import ClosedLoopPendulum

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "data" / "scenes" / "closed_pendulum_seed002.toml"
DM_PER_M = 10.0  # the engine's outputs are in SI (m), the paper's in dm

#: The paper's Section 5, in its units (dm, kg, s).
PAPER = {"m1": 2.0, "m2": 1.0, "anchor1": (0.0, 0.0), "anchor2": (7.0, 0.0),
         "p1": (4.0, 4.0), "p2": (12.0, 5.0), "g": 98.1}
DURATION = 15.0
CRITERION_DM = 1e-6  # the acceptance criterion: engine within 1e-6 dm of Lagrange over 15 s

#: (file, paper figure, mass, coordinate index, what the paper's caption says)
PANELS = (
    ("seed002_fig07_m1_vertical.png", "Fig. 7", "m1", 1, "mass #1 vertical displacement"),
    ("seed002_fig08_m1_horizontal.png", "Fig. 8", "m1", 0, "mass #1 horizontal displacement"),
    ("seed002_fig09_m2_vertical.png", "Fig. 9", "m2", 1, "mass #2 vertical displacement"),
    ("seed002_fig10_m2_horizontal.png", "Fig. 10", "m2", 0,
     "mass #2 horizontal displacement"),
)
GRAPH_FILE = "seed002_fig06_vector_network.png"
MATRICES_FILE = "seed002_matrices.md"

#: The paper's numbering of Fig. 6's elements, as far as the OCR copy shows it: r1-r4 (solid)
#: form the tree, r5-r9 (dashed) the cotree; the sentence naming them is garbled, and reads
#: best as r1, r2 the masses, r3, r4 the specified points 3 and 4, r5, r6 the weights,
#: r7-r9 the rigid links.
PAPER_ELEMENTS = {"m1": "r1 (mass m1)", "m2": "r2 (mass m2)",
                  "point rod2": "r3 (specified point 3)", "point rod1": "r4 (specified point 4)",
                  "weight m1": "r5 (weight of m1)", "weight m2": "r6 (weight of m2)",
                  "rod1": "r7-r9 (rigid link)", "rod2": "r7-r9 (rigid link)",
                  "coupler": "r7-r9 (rigid link, coupler)"}


# ------------------------------------------------------------------ the two solutions

def lagrange_reference() -> ClosedLoopPendulum:
    """The one-degree-of-freedom Lagrange model with the paper's numbers, in dm (the equation
    is homogeneous in length, so g in dm/s^2 gives positions in dm)."""
    return ClosedLoopPendulum(m1=PAPER["m1"], m2=PAPER["m2"], anchor1=PAPER["anchor1"],
                              anchor2=PAPER["anchor2"], p1=PAPER["p1"], p2=PAPER["p2"],
                              g=PAPER["g"])


def run(duration: float = DURATION, rtol: float = 1e-10, atol: float = 1e-12,
        max_step: float = 0.005) -> dict:
    """Simulate the scene with the engine (default method) and solve the Lagrange equation.

    Returns ``t`` (s, the engine's saved states, at most ``max_step`` apart), ``engine`` and
    ``lagrange`` (arrays (N, 2, 2): mass, coordinate, in dm), ``motion`` (the Lagrange solution
    as a function of time, giving ``p1, p2, theta`` in dm), the largest difference (dm), the
    engine's result and the time both took.
    """
    start = time.perf_counter()
    model = hx.assemble(read_scene(SCENE))
    result = simulate(model, duration, rtol=rtol, atol=atol, options={"max_step": max_step})
    if not result.success:
        raise RuntimeError(f"the engine failed: {result.message}")
    engine_seconds = time.perf_counter() - start
    slices = [model.bodies[model.body_index[name]].q for name in ("m1", "m2")]
    engine = np.stack([result.q[:, s] for s in slices], axis=1) * DM_PER_M
    start = time.perf_counter()
    motion = lagrange_reference().solve(duration, rtol=1e-13, atol=1e-13)
    p1, p2, _ = motion(result.t)
    lagrange = np.stack([p1, p2], axis=1)
    return {"t": result.t, "engine": engine, "lagrange": lagrange, "motion": motion,
            "difference": float(np.abs(engine - lagrange).max()), "result": result,
            "engine_seconds": engine_seconds,
            "lagrange_seconds": time.perf_counter() - start,
            "options": {"method": result.method, "rtol": rtol, "atol": atol,
                        "max_step": max_step}}


# ------------------------------------------------------------------ the vector network

def network() -> VectorNetwork:
    """The vector-network graph of the scene, checked against the paper's Fig. 6."""
    net = vector_network(hx.assemble(read_scene(SCENE)))
    kinds = sorted(e.kind for e in net.edges)
    expected = sorted(["inertial"] * 2 + ["specified-point"] * 2 + ["weight"] * 2
                      + ["joint"] * 3)
    if len(net.vertices) != 5 or kinds != expected:
        raise RuntimeError(f"the graph is not Fig. 6's: {len(net.vertices)} vertices, {kinds}")
    check_orthogonal(net.cutset, net.circuit, net.branches)
    return net


def check_orthogonal(cutset: np.ndarray, circuit: np.ndarray, branches: int) -> np.ndarray:
    """``cutset circuit^T`` (signed integers, the project's convention); raises unless it is
    zero and the chord part ``A`` of ``cutset = [U A]`` is ``-B^T`` of ``circuit = [B U]``."""
    product = np.asarray(cutset) @ np.asarray(circuit).T
    A, B = np.asarray(cutset)[:, branches:], np.asarray(circuit)[:, :branches]
    if np.any(product != 0) or not np.array_equal(A, -B.T):
        raise RuntimeError(f"cutset and circuit matrices are not orthogonal:\n{product}")
    return product


def _labels(net: VectorNetwork) -> list[str]:
    return [f"e{j + 1}" for j in range(len(net.edges))]


def _table(matrix: np.ndarray, rows: list[str], columns: list[str], corner: str) -> list[str]:
    lines = ["| " + corner + " | " + " | ".join(columns) + " |",
             "|---" * (len(columns) + 1) + "|"]
    for name, row in zip(rows, matrix, strict=True):
        lines.append(f"| {name} | " + " | ".join(f"{int(x):+d}" if x else "0" for x in row)
                     + " |")
    return lines


def matrices_text(net: VectorNetwork) -> str:
    """The edges and the incidence, cutset and circuit matrices as Markdown tables."""
    labels = _labels(net)
    tree = [f"{lab} ({e.name})" for lab, e in zip(labels, net.edges, strict=True) if e.tree]
    chords = [f"{lab} ({e.name})" for lab, e in zip(labels, net.edges, strict=True)
              if not e.tree]
    product = check_orthogonal(net.cutset, net.circuit, net.branches)
    lines = [
        "# Richard, Anderson and Andrews (1989/90), Fig. 6: the vector network of the closed-loop "
        "pendulum",
        "",
        f"Written by `scripts/papers/seed002_figures.py` from `{SCENE.relative_to(ROOT)}` "
        "(`hexapod.algorithms.topology.vector_network`; `hexapod info SCENE --graph` prints "
        "the same). "
        f"{len(net.vertices)} vertices, {len(net.edges)} elements: {len(tree)} tree branches "
        f"(solid in Fig. 6), {len(chords)} chords (cotree, dashed).",
        "",
        "Conventions (Richard, Anderson and Andrews, Section 2): the incidence matrix has +1 "
        "where a vertex is an "
        "element's initial vertex (tail) and -1 where it is its final vertex (head); the "
        "cutset matrix `[U A]` (one row per tree branch) comes from row reduction of the "
        "incidence matrix without its root row, the circuit matrix `[B U]` (one row per "
        "chord) from the tree paths, independently. The paper's column for the element "
        "numbers is a reading of a garbled sentence of the OCR copy (r1-r4 solid, r5-r9 "
        "dashed is certain; the order within each group is not).",
        "",
        "## Elements",
        "",
        "| edge | name | kind | tail -> head | tree / cotree | paper |",
        "|---|---|---|---|---|---|",
    ]
    for lab, e in zip(labels, net.edges, strict=True):
        lines.append(f"| {lab} | {e.name} | {e.kind} | {e.tail} -> {e.head} | "
                     f"{'tree' if e.tree else 'cotree'} | {PAPER_ELEMENTS.get(e.name, '')} |")
    lines += ["", "Vertices: " + ", ".join(f"`{v}`" for v in net.vertices)
              + " (`ground` is the root, the inertial reference frame; `ground@rod1` is the "
              "fixed point 4 at (0, 0) dm, `ground@rod2` the fixed point 3 at (7, 0) dm).", ""]
    lines += ["## Incidence matrix K (rows: vertices, columns: elements)", ""]
    lines += _table(net.incidence, list(net.vertices), labels, "vertex")
    lines += ["", "## Cutset matrix [U A] (rows: tree branches, columns: elements)", ""]
    lines += _table(net.cutset, tree, labels, "branch")
    lines += ["", "## Circuit matrix [B U] (rows: chords, columns: elements)", ""]
    lines += _table(net.circuit, chords, labels, "chord")
    lines += ["", "## Check: cutset x circuit^T (signed integers)", ""]
    lines += _table(product, tree, [c.split()[0] for c in chords], "branch \\ chord")
    lines += ["", "Every entry is zero and `A = -B^T`: the cutset and circuit matrices are "
              "orthogonal (checked by the script, which stops otherwise).", ""]
    return "\n".join(lines)


# ------------------------------------------------------------------ figures

def _save(figure, path: Path) -> None:
    figure.savefig(path, dpi=110)


def _style(ax) -> None:
    # as hexapod.output.figures's panels
    ax.grid(True, linewidth=0.4, alpha=0.6)
    ax.tick_params(labelsize=8)


def displacement_figure(data: dict, panel: tuple, duration: float):
    """One of Figs. 7-10: Lagrange (solid), engine (triangles), and their difference."""
    from matplotlib.figure import Figure

    _, paper_figure, mass, axis, quantity = panel
    k = 0 if mass == "m1" else 1
    symbol = f"{'xy'[axis]}{k + 1}"
    t, engine, lagrange = data["t"], data["engine"][:, k, axis], data["lagrange"][:, k, axis]
    fine = np.linspace(0.0, duration, max(200, int(200 * duration) + 1))
    curve = data["motion"](fine)[k][:, axis]
    # the paper's triangles: the engine's saved state nearest every 0.1 s
    marks = np.unique(np.clip(np.searchsorted(t, np.arange(0.0, duration + 1e-9, 0.1)),
                              0, t.size - 1))
    figure = Figure(figsize=(7.0, 5.2))
    top, bottom = figure.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1.2]})
    figure.subplots_adjust(left=0.12, right=0.97, top=0.9, bottom=0.1, hspace=0.12)
    top.plot(fine, curve, color="black", linewidth=1.1,
             label="Lagrange equation, 1 DOF (solid)")
    top.plot(t[marks], engine[marks], linestyle="none", marker="^", markersize=4,
             markerfacecolor="none", markeredgecolor="tab:red", markeredgewidth=0.8,
             label="hexapod engine, absolute coordinates (triangles)")
    direction = "positive down" if axis == 1 else "positive right"
    top.set_ylabel(f"{symbol} (dm, {direction})", fontsize=9)
    low, high = float(curve.min()), float(curve.max())
    top.set_ylim(low - 0.05 * (high - low), high + 0.4 * (high - low))  # room for the legend
    top.legend(fontsize=7, loc="upper right", framealpha=0.9)
    top.set_title(f"{paper_figure}: closed loop particle mass system, {quantity} vs time",
                  fontsize=9)
    difference = engine - lagrange
    worst = float(np.abs(difference).max())
    bottom.plot(t, difference, color="tab:blue", linewidth=0.8)
    bottom.set_ylabel("engine - Lagrange\n(dm)", fontsize=8)
    bottom.set_xlabel("t (s)")
    bottom.text(0.01, 0.92, f"max |difference| = {worst:.1e} dm (all saved states)",
                transform=bottom.transAxes, fontsize=7, va="top")
    bottom.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    bottom.yaxis.get_offset_text().set_fontsize(7)
    for ax in (top, bottom):
        _style(ax)
    bottom.set_xlim(0.0, duration)
    return figure, worst


def _vertex_positions(net: VectorNetwork, model) -> dict[str, np.ndarray]:
    """Where to draw each vertex (dm, y down): bodies and fixed points where they are at
    t = 0, the root (inertial frame) above the fixed points."""
    places = {"ground": np.array([5.0, -4.5])}
    for v in net.vertices:
        if v in model.body_index:
            places[v] = model.q0[model.bodies[model.body_index[v]].q] * DM_PER_M
        elif v.startswith("ground@"):
            joint = next(j for j in model.joints if j.name == v.split("@", 1)[1])
            places[v] = np.asarray(joint.parent_frame.position)[:2] * DM_PER_M
    return places


def graph_figure(net: VectorNetwork):
    """Fig. 6: the vector-network diagram (tree solid, cotree dashed), vertices where the
    points are at t = 0, y pointing down as in Fig. 5."""
    from matplotlib.figure import Figure

    model = hx.assemble(read_scene(SCENE))
    places = _vertex_positions(net, model)
    names = {"ground": "root\n(inertial frame)", "m1": "m1 (2 kg)", "m2": "m2 (1 kg)",
             "ground@rod1": "point 4\n(0, 0)", "ground@rod2": "point 3\n(7, 0)"}
    colours = {"inertial": "tab:blue", "specified-point": "tab:green", "weight": "tab:orange",
               "joint": "tab:red"}
    bend = {"inertial": 0.0, "weight": -0.28, "specified-point": 0.0, "joint": 0.0}
    figure = Figure(figsize=(8.0, 6.2))
    ax = figure.subplots()
    figure.subplots_adjust(left=0.08, right=0.98, top=0.9, bottom=0.08)
    labels = _labels(net)
    for lab, e in zip(labels, net.edges, strict=True):
        a, b = places[e.tail], places[e.head]
        d = b - a
        normal = np.array([-d[1], d[0]])
        control = (a + b) / 2 + bend[e.kind] * normal
        s = np.linspace(0.0, 1.0, 60)[:, None]
        path = (1 - s) ** 2 * a + 2 * s * (1 - s) * control + s**2 * b
        # stop short of the head vertex's marker, and put the arrowhead there
        length = np.cumsum(np.r_[0.0, np.linalg.norm(np.diff(path, axis=0), axis=1)])
        keep = length <= length[-1] - 0.45
        path = path[keep]
        style = "-" if e.tree else "--"
        ax.plot(path[:, 0], path[:, 1], style, color=colours[e.kind], linewidth=1.6)
        ax.annotate("", xy=path[-1], xytext=path[-4],
                    arrowprops={"arrowstyle": "-|>", "color": colours[e.kind], "lw": 1.4})
        middle = 0.25 * a + 0.5 * control + 0.25 * b
        ax.text(*middle, f"{lab}\n{e.name}", fontsize=7, ha="center", va="center",
                color=colours[e.kind],
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.85})
    for v, xy in places.items():
        ax.plot(*xy, "o", color="black", markersize=7, zorder=5)
        ax.annotate(names.get(v, v), xy, xytext=(8, -8), textcoords="offset points",
                    fontsize=8, ha="left", va="bottom", weight="bold")
    handles = [ax.plot([], [], "-", color="black")[0], ax.plot([], [], "--", color="black")[0]]
    handles += [ax.plot([], [], "-", color=c, linewidth=3)[0] for c in colours.values()]
    ax.legend(handles, ["tree branch (solid)", "cotree chord (dashed)", "mass (inertial)",
                        "specified point", "weight", "rigid link"], fontsize=7,
              loc="lower left")
    ax.set_xlim(-1.5, 14.5)
    ax.set_ylim(6.5, -5.5)  # y down
    ax.set_aspect("equal")
    ax.set_xlabel("x (dm)")
    ax.set_ylabel("y (dm, down)")
    _style(ax)
    ax.set_title(f"Fig. 6: vector-network diagram, {len(net.vertices)} vertices, "
                 f"{len(net.edges)} elements ({net.branches} tree, "
                 f"{len(net.edges) - net.branches} cotree)", fontsize=9)
    return figure


# ------------------------------------------------------------------ make / main

def make(out_dir="figures/seed002", duration: float = DURATION, rtol: float = 1e-10,
         atol: float = 1e-12, max_step: float = 0.005, verbose: bool = False) -> list[dict]:
    """Simulate, draw Figs. 6-10 and write the matrices into ``out_dir``; returns one entry
    per file written: ``file``, ``reproduces``, ``parameters``, ``caption``."""
    import matplotlib

    matplotlib.use("Agg")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    data = run(duration, rtol=rtol, atol=atol, max_step=max_step)
    result = data["result"]
    common = {"duration": f"{duration:g} s", "engine": f"{result.method}, rtol {rtol:g}, "
              f"atol {atol:g} m, max step {max_step:g} s",
              "saved states": int(data["t"].size),
              "reference": "Lagrange, 1 DOF, DOP853 at 1e-13",
              "max engine - Lagrange (both masses, x and y)": f"{data['difference']:.2e} dm"}
    entries = []
    for panel in PANELS:
        file, paper_figure, mass, axis, quantity = panel
        figure, worst = displacement_figure(data, panel, duration)
        _save(figure, out / file)
        symbol = f"{'xy'[axis]}{mass[1]}"
        entries.append({
            "file": file, "reproduces": f"{paper_figure} ({quantity} vs time)",
            "parameters": {**common, "quantity": f"{symbol} (dm)",
                           "max difference in this figure": f"{worst:.2e} dm"},
            "caption": (f"{paper_figure} of Richard, Anderson and Andrews ({quantity}, the "
                        f"paper's caption: here "
                        f"{symbol}, dm, y positive down) of the closed-loop pendulum over "
                        f"{duration:g} s: the one-degree-of-freedom Lagrange solution (solid "
                        f"line) and the absolute-coordinate engine (triangles, every 0.1 s), "
                        f"with their difference below (largest {worst:.1e} dm in this "
                        f"coordinate, {data['difference']:.1e} dm over all four).")})
    net = network()
    figure = graph_figure(net)
    _save(figure, out / GRAPH_FILE)
    entries.append({
        "file": GRAPH_FILE, "reproduces": "Fig. 6 (vector-network diagram)",
        "parameters": {"vertices": len(net.vertices), "elements": len(net.edges),
                       "tree": net.branches, "cotree": len(net.edges) - net.branches},
        "caption": ("Fig. 6 of Richard, Anderson and Andrews: the vector-network graph of the "
                    "closed-loop pendulum "
                    "as hexapod builds it (5 vertices; 9 elements: 2 masses and 2 specified "
                    "points in the tree, solid; 2 weights and 3 rigid links in the cotree, "
                    "dashed), vertices drawn where the points are at t = 0.")})
    (out / MATRICES_FILE).write_text(matrices_text(net))
    entries.append({
        "file": MATRICES_FILE, "reproduces": "Section 2's matrices for Fig. 6",
        "parameters": {"incidence": "5 x 9", "cutset": "4 x 9", "circuit": "5 x 9",
                       "cutset x circuit^T": "0 (checked)"},
        "caption": ("The incidence, cutset [U A] and circuit [B U] matrices of Fig. 6's graph, "
                    "with the check cutset x circuit^T = 0.")})
    if verbose:
        print(f"engine: {result.method}, {data['t'].size} saved states, "
              f"{result.counters.steps} steps, {data['engine_seconds']:.1f} s; "
              f"Lagrange {data['lagrange_seconds']:.1f} s")
        met = "met" if data["difference"] <= CRITERION_DM else "NOT met"
        print(f"largest |engine - Lagrange| over {duration:g} s (m1 and m2, x and y): "
              f"{data['difference']:.3e} dm (criterion {CRITERION_DM:g} dm: {met})")
    return entries


def main(argv=None) -> list[dict]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="figures/seed002", metavar="DIR")
    parser.add_argument("--duration", type=float, default=DURATION, metavar="S")
    parser.add_argument("--rtol", type=float, default=1e-10)
    parser.add_argument("--atol", type=float, default=1e-12)
    parser.add_argument("--max-step", type=float, default=0.005, metavar="S")
    args = parser.parse_args(argv)
    entries = make(args.out, args.duration, args.rtol, args.atol, args.max_step, verbose=True)
    for entry in entries:
        print(f"wrote {Path(args.out) / entry['file']}  ({entry['reproduces']})")
    return entries


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    main()
