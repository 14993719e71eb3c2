"""Figures of a design sweep, drawn from its result table (matplotlib, imported when first drawn).

The table is passed as plain arrays, one value per case: the varied ``parameters`` (numbers, or
strings for a categorical parameter such as a gait), the ``metrics`` (columns named
``family:element``, e.g. ``peak_effort:L1/tita``, or ``family`` alone for a scalar such as
``energy``; NaN where a case failed or the metric does not apply), the ``units`` of every column
and each case's ``status``.

Each metric family is drawn against each varied parameter (one line per element; when other
parameters vary too, the value at a parameter value is the maximum over the cases that share it,
the envelope) and, when exactly two numeric parameters vary, as a map of the family's maximum
over its elements: a heat map on a full grid, a coloured scatter otherwise. The lines are drawn
from the cases whose status is ``"ok"``; the others are marked with a cross (red: failed,
orange: infeasible, the ground unable to give the feet's forces) and counted in the title. The
maps draw an infeasible case's value too, in a cell hatched orange and labelled so, so that a
peak is never read from such a case without the mark.

Figures are drawn on :class:`matplotlib.figure.Figure` directly (no pyplot, no global state);
:func:`hexapod.output.figures.png_bytes` turns one into PNG bytes.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: Elements drawn in colour (and named in the legend) when a family has many; the rest are grey.
LARGEST_SHOWN = 6
#: A family with at most this many elements has every element in colour.
ALL_SHOWN = 8
#: A heat map writes the element attaining the maximum in each cell up to this many cells.
ANNOTATED_CELLS = 40
#: The status of a case whose metrics are drawn.
OK = "ok"
#: A case computed whose robot the ground cannot hold (drawn in maps, marked).
INFEASIBLE = "infeasible"
INFEASIBLE_COLOUR = "tab:orange"
LINE_SIZE = (8.0, 4.4)  # inches
MAP_SIZE = (6.8, 5.2)
OTHERS_COLOUR = "0.65"
FAILED_COLOUR = "tab:red"
MISSING_SHADE = "0.82"


# ------------------------------------------------------------------ the table

def metric_families(metric_names: Iterable[str]) -> dict[str, list[str]]:
    """Group metric columns by family, the part of the name before ``':'``.

    Parameters
    ----------
    metric_names : iterable of str
        Column names, ``family:element`` or ``family`` for a scalar.

    Returns
    -------
    dict of str to list of str
        Family -> its columns (full names), families and columns in their first order.

    Examples
    --------
    >>> metric_families(["peak_effort:L1/tita", "energy", "peak_effort:R1/tita"])
    {'peak_effort': ['peak_effort:L1/tita', 'peak_effort:R1/tita'], 'energy': ['energy']}
    """
    families: dict[str, list[str]] = {}
    for name in metric_names:
        families.setdefault(name.partition(":")[0], []).append(name)
    return families


def _element(column: str) -> str:
    """The element of a column (``L1/tita`` of ``peak_effort:L1/tita``); a scalar's family."""
    family, colon, element = column.partition(":")
    return element if colon else family


def _label(name: str, unit: str) -> str:
    """``name [unit]``, or ``name`` when the unit is empty."""
    return f"{name} [{unit}]" if unit else name


def _family_unit(columns: list[str], units: Mapping[str, str]) -> str:
    """The unit of a family's columns (distinct units joined by ', ', in order)."""
    return ", ".join(dict.fromkeys(u for u in (units.get(c, "") for c in columns) if u))


def _safe(text: str) -> str:
    """``text`` with anything but ``[A-Za-z0-9_.-]`` replaced by ``-``."""
    return re.sub(r"[^A-Za-z0-9_.-]", "-", text)


def _numeric(values: np.ndarray) -> bool:
    return values.dtype.kind in "iuf"


def _levels(values: np.ndarray) -> tuple[list, np.ndarray]:
    """The distinct values of a parameter (numbers sorted, categories in their first order) and
    each case's index among them."""
    if _numeric(values):
        levels, index = np.unique(values.astype(float), return_inverse=True)
        return list(levels), index.ravel()
    text = values.astype(str)
    levels = list(dict.fromkeys(text.tolist()))
    where = {level: k for k, level in enumerate(levels)}
    return levels, np.array([where[t] for t in text], dtype=int)


def _envelope(values: np.ndarray, index: np.ndarray, count: int) -> np.ndarray:
    """Per level ``0 .. count - 1``, the maximum of ``values`` over the cases with that index,
    NaN ignored (NaN where every such value is NaN)."""
    out = np.full(count, np.nan)
    np.fmax.at(out, index, values)
    return out


def _element_matrix(columns: list[str], metrics: Mapping[str, np.ndarray],
                    good: np.ndarray) -> np.ndarray:
    """(cases, elements) values of a family's columns, NaN for cases that are not ok."""
    matrix = np.column_stack([np.asarray(metrics[c], dtype=float) for c in columns])
    matrix[~good] = np.nan
    return matrix


def _family_max(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per case, the maximum over the elements (NaN ignored; NaN when all are) and the index of
    the element attaining it (-1 when none)."""
    largest = np.fmax.reduce(matrix, axis=1)
    which = np.where(np.isnan(matrix), -np.inf, matrix).argmax(axis=1)
    return largest, np.where(np.isnan(largest), -1, which)


def _failure_note(status: np.ndarray) -> str:
    """``"; 2 of 12 cases failed"`` (every status but ok counted by name), or ``""``."""
    bad = status[status != OK]
    if not bad.size:
        return ""
    kinds = dict.fromkeys(bad.tolist())
    detail = "" if list(kinds) == ["failed"] else " (" + ", ".join(
        f"{kind} {int(np.sum(bad == kind))}" for kind in kinds) + ")"
    return f"; {bad.size} of {status.size} cases not ok{detail}"


def _unique_names(names: list[str]) -> list[str]:
    """File names made distinct (``a.png``, ``a-2.png``) should two sanitise alike."""
    seen: set[str] = set()
    out = []
    for name in names:
        stem, candidate, k = name[:-4], name, 1
        while candidate in seen:
            k += 1
            candidate = f"{stem}-{k}.png"
        seen.add(candidate)
        out.append(candidate)
    return out


# ------------------------------------------------------------------ a family against a parameter

def _axes(title: str, size: tuple[float, float], margins: tuple[float, float, float, float],
          grid: bool = False):
    """One panel of ``size`` (inches) with fixed ``margins`` (left, right, bottom, top; inches:
    fixed margins are fast to draw and leave room for a legend or a colour bar)."""
    from matplotlib.figure import Figure

    width, height = size
    left, right, bottom, top = margins
    figure = Figure(figsize=size)
    ax = figure.subplots()
    figure.subplots_adjust(left=left / width, right=1 - right / width, bottom=bottom / height,
                           top=1 - top / height)
    figure.suptitle(title, fontsize=10)
    if grid:
        ax.grid(True, linewidth=0.4, alpha=0.6)
    ax.tick_params(labelsize=8)
    return figure, ax


def _line_axes(title: str):
    """A family against a parameter: a right margin for the legend, a grid."""
    return _axes(title, LINE_SIZE, (0.9, 1.9, 0.65, 0.75), grid=True)


def _ranked(envelopes: np.ndarray) -> list[int]:
    """Element indices by their largest envelope value, largest first (all-NaN ones last)."""
    peaks = np.fmax.reduce(envelopes, axis=1)
    return sorted(range(len(peaks)), key=lambda k: (np.isnan(peaks[k]), -np.nan_to_num(peaks[k])))


def _draw_elements(ax, x: np.ndarray, envelopes: np.ndarray, names: list[str],
                   categorical: bool) -> None:
    """One line (markers only on a categorical axis) per element: every element in colour when
    there are few, else the :data:`LARGEST_SHOWN` largest in colour (legend, largest first) and
    the others as thin grey lines under one legend entry."""
    order = _ranked(envelopes)
    shown = order if len(order) <= ALL_SHOWN else order[:LARGEST_SHOWN]
    style = {"linestyle": "none"} if categorical else {"linewidth": 1.3}
    for rank, k in enumerate(shown):
        ax.plot(x, envelopes[k], marker="o", markersize=4, color=f"C{rank % 10}",
                label=names[k], zorder=3, gid=names[k], **style)
    rest = [k for k in order if k not in shown]
    for n, k in enumerate(rest):
        ax.plot(x, envelopes[k], marker=".", markersize=3, color=OTHERS_COLOUR,
                linewidth=0.8, zorder=2, gid=names[k],
                label=f"{len(rest)} others" if n == 0 else "_nolegend_",
                **({"linestyle": "none"} if categorical else {}))


def _mark_failed(ax, x: np.ndarray, status: np.ndarray) -> None:
    """A cross on the bottom axis at each case not ok: red for a failed case, orange for an
    infeasible one."""
    for kind, colour, label in ((INFEASIBLE, INFEASIBLE_COLOUR, "infeasible"),
                                (None, FAILED_COLOUR, "failed")):
        marked = status == kind if kind else (status != OK) & (status != INFEASIBLE)
        if marked.any():
            ax.plot(x[marked], np.zeros(int(marked.sum())), "x", color=colour,
                    markersize=8, markeredgewidth=1.6, clip_on=False, zorder=4,
                    transform=ax.get_xaxis_transform(), label=f"{label} ({int(marked.sum())})",
                    gid=label)


def _against(parameter: str, others: list[str], columns: list[str],
             parameters: Mapping[str, np.ndarray], metrics: Mapping[str, np.ndarray],
             units: Mapping[str, str], status: np.ndarray, title: str) -> Figure:
    """A family against one parameter: per element, its envelope over the other parameters."""
    family = columns[0].partition(":")[0]
    values = np.asarray(parameters[parameter])
    levels, index = _levels(values)
    categorical = not _numeric(values)
    x = np.arange(len(levels), dtype=float) if categorical else np.asarray(levels, dtype=float)
    good = status == OK
    matrix = _element_matrix(columns, metrics, good)
    envelopes = np.array([_envelope(matrix[:, k], index, len(levels))
                          for k in range(matrix.shape[1])])
    repeated = len(levels) < values.size
    over = (f" (max over {', '.join(others)})" if others
            else " (max over repeated cases)" if repeated else "")
    figure, ax = _line_axes(f"{title}\n{family} against {parameter}{over}"
                            f"{_failure_note(status)}")
    _draw_elements(ax, x, envelopes, [_element(c) for c in columns], categorical)
    _mark_failed(ax, x[index], status)
    if categorical:
        ax.set_xticks(x, [str(level) for level in levels])
        ax.set_xlim(-0.5, len(levels) - 0.5)
    ax.set_xlabel(_label(parameter, units.get(parameter, "")))
    ax.set_ylabel(_label(family, _family_unit(columns, units)) + (", max over " + ", ".join(
        others) if others else ""), fontsize=9)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
              frameon=False)
    return figure


# ------------------------------------------------------------------ maps of two parameters

def _is_grid(first: np.ndarray, second: np.ndarray) -> bool:
    """Whether every combination of the two parameters' distinct values is among the cases."""
    a, b = np.unique(first), np.unique(second)
    if a.size < 2 or b.size < 2:
        return False
    present = set(zip(first.tolist(), second.tolist(), strict=True))
    return len(present) == a.size * b.size


def _grid_cells(first: np.ndarray, second: np.ndarray, largest: np.ndarray, which: np.ndarray,
                failed: np.ndarray):
    """Levels of both parameters and, per cell (rows: second parameter, columns: first), the
    maximum over the cell's cases, the element attaining it (-1: none) and whether any of the
    cell's cases failed."""
    xs, i = np.unique(first.astype(float), return_inverse=True)
    ys, j = np.unique(second.astype(float), return_inverse=True)
    i, j = i.ravel(), j.ravel()
    cell = np.full((ys.size, xs.size), np.nan)
    element = np.full(cell.shape, -1)
    anyfailed = np.zeros(cell.shape, dtype=bool)
    for case in range(first.size):
        anyfailed[j[case], i[case]] |= failed[case]
        value = largest[case]
        if not np.isnan(value) and not value <= cell[j[case], i[case]]:
            cell[j[case], i[case]] = value
            element[j[case], i[case]] = which[case]
    return xs, ys, cell, element, anyfailed


def _map_axes(title: str):
    """A map of two parameters: a right margin for the colour bar."""
    return _axes(title, MAP_SIZE, (0.95, 0.75, 0.7, 0.8))


def _colour_map():
    import matplotlib

    return matplotlib.colormaps["viridis"].with_extremes(bad=MISSING_SHADE)


def _limits(values: np.ndarray) -> tuple[float, float]:
    finite = values[np.isfinite(values)]
    if not finite.size:
        return 0.0, 1.0
    low, high = float(finite.min()), float(finite.max())
    return (low - 0.5, high + 0.5) if low == high else (low, high)


def _level_ticks(axis, levels: np.ndarray) -> None:
    """Cell centres labelled by the parameter's values (at most about 12 labels)."""
    step = max(1, int(np.ceil(levels.size / 12)))
    positions = np.arange(0, levels.size, step)
    axis.set_ticks(positions, [f"{levels[k]:g}" for k in positions])


def _annotate_cells(ax, image, cell, element, anyfailed, names: list[str],
                    infeasible: np.ndarray) -> None:
    """Each cell's element attaining the maximum (and the value, marked when a case of the
    cell is infeasible), or why it is empty."""
    many = len(names) > 1
    for (r, c), value in np.ndenumerate(cell):
        if np.isnan(value):
            text, colour = ("failed" if anyfailed[r, c] else "n/a"), "black"
        else:
            text = (f"{names[element[r, c]]}\n" if many else "") + f"{value:.3g}"
            if infeasible[r, c]:
                text = "INFEASIBLE\n" + text
            red, green, blue, _ = image.cmap(image.norm(value))
            colour = "black" if 0.299 * red + 0.587 * green + 0.114 * blue > 0.5 else "white"
        ax.text(c, r, text, ha="center", va="center", fontsize=6.5, color=colour)


def _heat_map(first: str, second: str, columns: list[str], parameters, metrics, units,
              status: np.ndarray, title: str) -> Figure:
    """The family's maximum over its elements on the grid of the two parameters; NaN cells
    grey and hatched; the element attaining the maximum written in each cell when few."""
    from matplotlib.patches import Rectangle

    family = columns[0].partition(":")[0]
    unit = _family_unit(columns, units)
    drawn = (status == OK) | (status == INFEASIBLE)
    largest, which = _family_max(_element_matrix(columns, metrics, drawn))
    first_values, second_values = np.asarray(parameters[first]), np.asarray(parameters[second])
    xs, ys, cell, element, anyfailed = _grid_cells(first_values, second_values, largest, which,
                                                   ~drawn)
    infeasible = _grid_cells(first_values, second_values, largest, which,
                             status == INFEASIBLE)[4]
    over = "maximum over elements" if len(columns) > 1 else "value"
    figure, ax = _map_axes(f"{title}\n{family}: {over} per case{_failure_note(status)}")
    low, high = _limits(cell)
    image = ax.imshow(cell, origin="lower", aspect="auto", cmap=_colour_map(), vmin=low,
                      vmax=high, interpolation="nearest")
    for r, c in zip(*np.nonzero(np.isnan(cell)), strict=True):
        ax.add_patch(Rectangle((c - 0.5, r - 0.5), 1.0, 1.0, fill=False, hatch="///",
                               edgecolor="0.55", linewidth=0.0))
    for r, c in zip(*np.nonzero(infeasible & ~np.isnan(cell)), strict=True):
        ax.add_patch(Rectangle((c - 0.5, r - 0.5), 1.0, 1.0, fill=False, hatch="xx",
                               edgecolor=INFEASIBLE_COLOUR, linewidth=1.5))
    if cell.size <= ANNOTATED_CELLS:
        _annotate_cells(ax, image, cell, element, anyfailed, [_element(c) for c in columns],
                        infeasible)
    _level_ticks(ax.xaxis, xs)
    _level_ticks(ax.yaxis, ys)
    ax.set_xlabel(_label(first, units.get(first, "")))
    ax.set_ylabel(_label(second, units.get(second, "")))
    bar = figure.colorbar(image, ax=ax, fraction=0.06, pad=0.03)
    bar.set_label(_label(f"max {family}" if len(columns) > 1 else family, unit), fontsize=9)
    bar.ax.tick_params(labelsize=8)
    return figure


def _scatter_map(first: str, second: str, columns: list[str], parameters, metrics, units,
                 status: np.ndarray, title: str) -> Figure:
    """The family's maximum over its elements at each sampled case, as coloured points; cases
    with no value hollow grey, failed cases red crosses."""
    family = columns[0].partition(":")[0]
    good = status == OK
    largest, _ = _family_max(_element_matrix(columns, metrics, good))
    bad_ground = status == INFEASIBLE
    x = np.asarray(parameters[first], dtype=float)
    y = np.asarray(parameters[second], dtype=float)
    over = "maximum over elements" if len(columns) > 1 else "value"
    figure, ax = _map_axes(f"{title}\n{family}: {over} per case{_failure_note(status)}")
    ax.grid(True, linewidth=0.4, alpha=0.6)
    has = np.isfinite(largest)
    low, high = _limits(largest)
    points = ax.scatter(x[has], y[has], c=largest[has], cmap=_colour_map(), vmin=low, vmax=high,
                        s=36, edgecolors="0.2", linewidths=0.4, zorder=3)
    empty = good & ~has
    if empty.any():
        ax.scatter(x[empty], y[empty], facecolors="none", edgecolors="0.5", s=36, zorder=3,
                   label=f"no value ({int(empty.sum())})")
    failed = ~good & ~bad_ground
    if failed.any():
        ax.plot(x[failed], y[failed], "x", color=FAILED_COLOUR, markersize=7,
                markeredgewidth=1.5, linestyle="none", zorder=4,
                label=f"failed ({int(failed.sum())})")
    if bad_ground.any():
        ax.plot(x[bad_ground], y[bad_ground], "x", color=INFEASIBLE_COLOUR, markersize=7,
                markeredgewidth=1.5, linestyle="none", zorder=4,
                label=f"infeasible ({int(bad_ground.sum())})")
    if empty.any() or (~good).any():
        ax.legend(fontsize=7, loc="best")
    ax.set_xlabel(_label(first, units.get(first, "")))
    ax.set_ylabel(_label(second, units.get(second, "")))
    bar = figure.colorbar(points, ax=ax, fraction=0.06, pad=0.03)
    bar.set_label(_label(f"max {family}" if len(columns) > 1 else family,
                         _family_unit(columns, units)), fontsize=9)
    bar.ax.tick_params(labelsize=8)
    return figure


# ------------------------------------------------------------------ the figures of a sweep

def sweep_figures(parameters: Mapping[str, np.ndarray], metrics: Mapping[str, np.ndarray],
                  units: Mapping[str, str], status: np.ndarray | list[str],
                  title: str) -> list[tuple[str, Figure]]:
    """The figures of a design sweep, with their file names.

    Per metric family, in the families' order: the family against each varied parameter
    (``<family>-vs-<parameter>.png``), then, when exactly two numeric parameters vary, its map
    (``<family>-map.png``): a heat map of the family's maximum over its elements when the cases
    cover the full grid of the two parameters' values (rows: the second parameter; the element
    attaining the maximum written in each cell up to :data:`ANNOTATED_CELLS` cells), a scatter
    coloured by that maximum otherwise.

    Parameters
    ----------
    parameters : mapping of str to ndarray
        The varied parameters in the study's order, one value per case: floats, or strings for
        a categorical parameter (drawn at category positions in their first order).
    metrics : mapping of str to ndarray
        Columns ``family:element`` or ``family``, floats, NaN where a case failed or the metric
        does not apply.
    units : mapping of str to str
        Unit of each parameter and metric column (``""`` for none; missing means none).
    status : array_like of str
        Each case's status: ``"ok"`` drawn; ``"infeasible"`` (computed, but the ground cannot
        give the feet's forces) marked with an orange cross, and drawn in a heat map's cell
        hatched and labelled ``INFEASIBLE``; any other marked with a red cross; all not ok
        counted in the titles.
    title : str
        First line of every figure's title (e.g. the study's name).

    Returns
    -------
    list of (str, matplotlib.figure.Figure)
        File names (characters other than ``[A-Za-z0-9_.-]`` replaced by ``-``, distinct) and
        figures. Empty when no parameter varies or there are no cases.

    Notes
    -----
    When other parameters vary too, the value drawn at a parameter value is the maximum over
    the cases sharing it (the envelope), and the axis label says so (``max over duty``). A
    family with more than :data:`ALL_SHOWN` elements (18 joints) has its
    :data:`LARGEST_SHOWN` largest elements in colour, named in the legend largest first, the
    others as thin grey lines.
    """
    status = np.asarray(status).astype(str)
    names = list(parameters)
    if not names or not status.size:
        return []
    grid_ready = len(names) == 2 and all(_numeric(np.asarray(parameters[n])) for n in names)
    is_grid = grid_ready and _is_grid(*(np.asarray(parameters[n]) for n in names))
    out: list[tuple[str, Figure]] = []
    for family, columns in metric_families(metrics).items():
        for name in names:
            others = [n for n in names if n != name]
            out.append((f"{_safe(family)}-vs-{_safe(name)}.png",
                        _against(name, others, columns, parameters, metrics, units, status,
                                 title)))
        if grid_ready:
            draw = _heat_map if is_grid else _scatter_map
            out.append((f"{_safe(family)}-map.png",
                        draw(*names, columns, parameters, metrics, units, status, title)))
    return list(zip(_unique_names([n for n, _ in out]), [f for _, f in out], strict=True))
