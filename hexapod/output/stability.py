"""How close a walking robot is to tipping over, sample by sample: the static stability
margin and the margin of the centre of pressure (the ZMP on flat ground).

Both are measured in the ground's plane, the plane normal to gravity, from the **support
polygon**: the convex hull of the feet in stance (by the gait's schedule), projected along
gravity; a segment with two feet, a point with one.

* The **static stability margin** (McGhee and Frank, 1968) is the distance from the centre of
  mass's projection to the nearest edge of the support polygon, positive inside, negative
  outside (then minus the distance to the polygon). A robot whose margin stays positive would
  stand if it froze at any instant.
* The **centre of pressure** is the point of the ground where the ground's forces on the feet
  have no moment about the plane's axes: ``sum_i F_n,i p_i / sum_i F_n,i`` for point feet on
  one plane, the zero-moment point (Vukobratovic) of the motion. Its margin, measured the same
  way, is positive while every stance foot is pushed (a weighted mean of their positions); it
  says how much of the polygon the motion leaves before a foot would have to pull.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from hexapod.algorithms.inverse import InverseResult
from hexapod.algorithms.kinematics import body_poses
from hexapod.model.model import Model
from hexapod.output.summary_parts import markdown_table

if TYPE_CHECKING:
    from matplotlib.figure import Figure


#: m: a point this close to the support polygon is on its edge, not outside it. Two feet
#: support the robot on a segment, which has no inside: a centre of pressure on it (a trot's,
#: the weighted mean of the two feet) is a round-off's distance away, never more.
ON_THE_EDGE = 1e-9


@dataclass(frozen=True)
class Stability:
    """The support polygons and the two margins at every sample (see the module's
    description); plane coordinates along two horizontal axes (world x and y when gravity
    is along -z), m.

    Attributes
    ----------
    times : ndarray, shape (N,)
    axes : ndarray, shape (2, 3)
        The plane's axes, world.
    com, cop : ndarray, shape (N, 2)
        The centre of mass's projection and the centre of pressure (NaN where no foot is
        pushed).
    support : list of ndarray, shape (k, 2)
        Per sample the support polygon's corners, counter-clockwise (k = 0 in flight).
    static_margin, cop_margin : ndarray, shape (N,)
        The margins (m): positive inside the polygon, negative outside.
    """

    times: np.ndarray
    axes: np.ndarray
    com: np.ndarray
    cop: np.ndarray
    support: list
    static_margin: np.ndarray
    cop_margin: np.ndarray


def stability_margins(model: Model, result: InverseResult) -> Stability:
    """The margins of a walking robot's inverse dynamics (feet on the ground by contacts).

    Parameters
    ----------
    model : Model
        With foot contacts.
    result : InverseResult
        Its inverse dynamics (the ground forces on the feet).

    Returns
    -------
    Stability
    """
    t = result.times
    axes, normal = _plane_axes(np.asarray(model.gravity, dtype=float))
    positions, rotations = body_poses(model, result.q)
    masses = np.array([body.mass for body in model.bodies])
    com = np.einsum("b,nbi->ni", masses, positions) / masses.sum() @ axes.T
    feet = np.stack([_foot(model, contact, positions, rotations) for contact in model.contacts],
                    axis=1)  # (N, C, 3), world
    feet_plane = feet @ axes.T
    pushed = np.asarray(result.ground_force, dtype=float) @ normal  # (N, C)
    total = pushed.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cop = np.where((total > 0)[:, None],
                       np.einsum("nc,nci->ni", pushed, feet_plane) / total[:, None], np.nan)
    stance = np.array([contact.in_stance(t) for contact in model.contacts]).T  # (N, C)
    support = [_hull(feet_plane[k, stance[k]]) for k in range(t.size)]
    return Stability(t, axes, com, cop, support,
                     np.array([signed_distance(p, s) for p, s in zip(com, support, strict=True)]),
                     np.array([signed_distance(p, s) for p, s in zip(cop, support, strict=True)]))


def _plane_axes(gravity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit axes normal to gravity (world x and y when gravity is along -z, or without
    gravity) and the upward unit normal."""
    up = -gravity / np.linalg.norm(gravity) if np.any(gravity) else np.array([0.0, 0.0, 1.0])
    first = np.eye(3)[int(np.argmin(np.abs(up)))] if abs(up[2]) < 0.9 else np.eye(3)[0]
    first = first - (first @ up) * up
    first /= np.linalg.norm(first)
    return np.array([first, np.cross(up, first)]), up


def _foot(model: Model, contact, positions: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """The foot point of ``contact`` at every sample (N, 3), world: its joint's frame on the
    child (the foot's body)."""
    joint = model.joints[contact.joint]
    local = np.zeros(3)
    origin = np.asarray(joint.child_frame.position, dtype=float)
    local[:origin.size] = origin
    return positions[:, joint.child] + np.einsum("nij,j->ni", rotations[:, joint.child], local)


def _hull(points: np.ndarray) -> np.ndarray:
    """The convex hull of plane ``points``, counter-clockwise (Andrew's monotone chain):
    a segment's two ends for collinear points, a point for one."""
    unique = np.unique(np.round(points, 12), axis=0)
    if len(unique) <= 2:
        return unique

    def half(ordered):
        chain: list = []
        for p in ordered:
            while len(chain) >= 2 and _cross(chain[-2], chain[-1], p) <= 0:
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(unique), half(unique[::-1])
    return np.array(lower[:-1] + upper[:-1])


def _cross(o, a, b) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def signed_distance(point: np.ndarray, polygon: np.ndarray) -> float:
    """The distance from ``point`` to the nearest edge of the convex ``polygon``
    (counter-clockwise corners), positive inside, negative outside (minus the distance to
    the polygon; a segment or a point has no inside). NaN for a NaN point or no polygon.

    Parameters
    ----------
    point : ndarray, shape (2,)
    polygon : ndarray, shape (k, 2)

    Returns
    -------
    float
    """
    if not len(polygon) or not np.all(np.isfinite(point)):
        return np.nan
    if len(polygon) == 1:
        return -float(np.linalg.norm(point - polygon[0]))
    starts, ends = polygon, np.roll(polygon, -1, axis=0)
    if len(polygon) == 2:
        starts, ends = polygon[:1], polygon[1:]
    edges = ends - starts
    lengths = np.linalg.norm(edges, axis=1)
    along = np.clip(np.einsum("ki,ki->k", point - starts, edges) / lengths**2, 0.0, 1.0)
    nearest = np.linalg.norm(starts + along[:, None] * edges - point, axis=1).min()
    if len(polygon) == 2:
        return -float(nearest)
    outward = np.column_stack([edges[:, 1], -edges[:, 0]]) / lengths[:, None]
    beyond = np.einsum("ki,ki->k", point - starts, outward)
    return float(-beyond.max()) if np.all(beyond <= 0) else -float(nearest)


def margins_csv_columns() -> dict[str, tuple[str, str]]:
    """The columns of ``margins.csv``, each with its unit and meaning."""
    return {"t": ("s", "time"),
            "com:x": ("m", "the centre of mass projected on the ground's plane, first axis"),
            "com:y": ("m", "the same, second axis"),
            "cop:x": ("m", "the centre of pressure (ZMP), first axis; nan in flight"),
            "cop:y": ("m", "the same, second axis"),
            "margin:static": ("m", "static stability margin: distance from the centre of "
                              "mass's projection to the support polygon's nearest edge, "
                              "negative outside"),
            "margin:cop": ("m", "the same for the centre of pressure")}


def margins_csv_text(margins: Stability) -> str:
    """``margins.csv`` (:func:`margins_csv_columns`)."""
    table = np.column_stack([margins.times, margins.com, margins.cop, margins.static_margin,
                             margins.cop_margin])
    lines = [",".join(margins_csv_columns())]
    lines += [",".join(f"{x:.17g}" for x in row) for row in table]
    return "\n".join(lines) + "\n"


def stability_section(margins: Stability) -> list[str]:
    """The summary's section: each margin's smallest value and when, and how long the point
    is outside the support polygon (by more than :data:`ON_THE_EDGE`)."""
    rows = []
    for name, margin in (("static (centre of mass)", margins.static_margin),
                         ("centre of pressure (ZMP)", margins.cop_margin)):
        valid = np.isfinite(margin)
        k = int(np.flatnonzero(valid)[np.argmin(margin[valid])]) if valid.any() else 0
        outside = int(np.count_nonzero(margin[valid] < -ON_THE_EDGE))
        rows.append([name, f"{1e3 * margin[k]:.4g}", f"{margins.times[k]:.4g}",
                     f"{outside} of {margin.size}"])
    return (["", "## Stability", "",
             "Margins in the ground's plane from the support polygon of the feet in stance "
             "(their convex hull; a segment with two feet): positive inside, the distance to "
             "its nearest edge; negative outside. The static margin is the centre of mass's "
             "projection's; the centre of pressure's (the ZMP on flat ground) stays inside "
             "while every stance foot is pushed.", ""]
            + markdown_table(["margin", "smallest (mm)", "at t (s)", "samples outside"], rows))


def stability_figure(margins: Stability, title: str) -> Figure:
    """Top view: the support polygons (each change of the feet in stance, and midway
    between), the paths of the centre of mass's projection and of the centre of pressure;
    beside it both margins against time.

    Parameters
    ----------
    margins : Stability
    title : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    from hexapod.output.panel_axes import light_ticks

    figure = Figure(figsize=(10.0, 4.2))
    grid = figure.add_gridspec(1, 2, left=0.07, right=0.98, bottom=0.13, top=0.85, wspace=0.25,
                               width_ratios=[1.1, 1.0])
    top, side = figure.add_subplot(grid[0, 0]), figure.add_subplot(grid[0, 1])
    for k in _polygon_samples(margins.support):
        polygon = margins.support[k]
        if len(polygon) >= 2:
            closed = np.vstack([polygon, polygon[:1]])
            top.plot(closed[:, 0], closed[:, 1], color="0.55", linewidth=0.7)
            top.plot(*margins.com[k], "o", color="tab:blue", markersize=3)
    top.plot(margins.com[:, 0], margins.com[:, 1], color="tab:blue", label="centre of mass")
    top.plot(margins.cop[:, 0], margins.cop[:, 1], color="tab:orange", linewidth=1.0,
             label="centre of pressure")
    top.set_aspect("equal", adjustable="datalim")
    top.set_xlabel("x (m)")
    top.set_ylabel("y (m)")
    top.legend(fontsize=8, loc="upper right", frameon=False)
    top.set_title("support polygons and paths (top view)", fontsize=9)
    for values, colour, label in ((margins.static_margin, "tab:blue", "static margin"),
                                  (margins.cop_margin, "tab:orange", "centre of pressure")):
        side.plot(margins.times, 1e3 * values, color=colour, label=label)
    side.axhline(0.0, color="tab:red", linewidth=0.8)
    side.set_xlabel("t (s)")
    side.set_ylabel("margin (mm)")
    side.legend(fontsize=8, frameon=False)
    side.set_title("margins (negative: outside the support polygon)", fontsize=9)
    for ax in (top, side):
        light_ticks(ax)
    figure.suptitle(title, fontsize=11)
    return figure


def _polygon_samples(support: list) -> list[int]:
    """The samples whose polygon is drawn: where the feet in stance change, and midway
    between two changes."""
    sizes = [len(s) for s in support]
    changes = [0] + [k for k in range(1, len(support))
                     if sizes[k] != sizes[k - 1]
                     or not np.allclose(support[k], support[k - 1], atol=1e-9)] + [len(support)]
    picked = set()
    for a, b in zip(changes[:-1], changes[1:], strict=True):
        picked.update({a, (a + b - 1) // 2})
    return sorted(picked)
