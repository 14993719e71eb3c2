"""Reports of inverse dynamics: the liaison force report's statistics and Markdown summary
(``hexapod report``), and the comparison of inverse-dynamics tables (:func:`agreement`).

The CSV of the ``hexapod inverse`` contract is written by :mod:`hexapod.output.inverse_csv`,
whose functions this module re-exports.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from hexapod.algorithms.balance import BodyBalance
from hexapod.algorithms.inverse import InverseResult
from hexapod.model.model import GROUND_INDEX, JointInfo, Model
from hexapod.output.actuation import (
    DriverStatistics,
    driver_statistics,
    motor_checks,
    motors_csv_columns,
    motors_csv_text,
    motors_section,
    speed_unit,
)
from hexapod.output.figures import (
    effort_figure,
    friction_ratio_figure,
    gait_diagram_figure,
    ground_reaction_figure,
    leg_comparison_figure,
    render_figures,
    trajectory_figure,
    wrench_figure,
)
from hexapod.output.ground import (
    FootLoads,
    TrunkMotion,
    describe_events,
    foot_events,
    foot_loads,
    ground_csv_columns,
    ground_csv_text,
    joint_type,
    leg_groups,
    trunk_csv_columns,
    trunk_csv_text,
    trunk_motion,
)
from hexapod.output.inverse_csv import (  # noqa: F401 (re-exported: the CSV's contract)
    inverse_column_units,
    inverse_columns,
    inverse_csv_text,
    inverse_table,
    units_path,
    write_inverse_files,
)
from hexapod.output.motor_figures import envelope_figure
from hexapod.output.stability import (
    margins_csv_columns,
    margins_csv_text,
    stability_figure,
    stability_margins,
    stability_section,
)
from hexapod.output.summary_parts import Peak, count, g4, markdown_table, time_rms
from hexapod.output.walking_summary import ground_section, trunk_section
from hexapod.scene.actuators import ActuatorTable
from hexapod.simulation.results import units_json


def agreement(columns: list[str], table: np.ndarray, reference_columns: list[str],
              reference: np.ndarray) -> float:
    """Largest difference from a reference CSV, relative to the largest magnitude of the same
    quantity: for each joint, its forces (``Fx, Fy, Fz``) against the largest of them, its
    moments (``tau, Tx, Ty, Tz``) against the largest of those, over all samples. Columns of the
    table that the reference lacks (fixed joints, say) are not compared.

    Parameters
    ----------
    columns : list of str
        The table's header (:func:`inverse_columns`).
    table : ndarray, shape (N, len(columns))
        Our values (:func:`inverse_table`).
    reference_columns : list of str
        The reference's header; each must be one of ``columns``.
    reference : ndarray, shape (N, len(reference_columns))
        The reference's values at the same samples.

    Returns
    -------
    float
        The largest relative difference (0 for none).
    """
    index = {name: k for k, name in enumerate(columns)}
    groups: dict[tuple[str, str], list[int]] = {}
    for k, name in enumerate(reference_columns):
        if ":" not in name:
            continue
        component, joint = name.split(":", 1)
        kind = "force" if component.startswith(("F", "GR")) else "moment"
        groups.setdefault((joint, kind), []).append(k)
    worst = 0.0
    for members in groups.values():
        scale = max(np.abs(reference[:, members]).max(), np.finfo(float).tiny)
        ours = table[:, [index[reference_columns[k]] for k in members]]
        worst = max(worst, float(np.abs(ours - reference[:, members]).max() / scale))
    return worst


# ------------------------------------------------------------------ the liaison force report

def wrench_label(model: Model, joint: JointInfo) -> str:
    """The name Dumitru, Marin and Margine give a joint's wrench: ``F21`` is exerted by element 1 on
    element 2, with the bodies numbered from 1 in model order and the ground 0 (``F12,11`` past
    9).

    Parameters
    ----------
    model : Model
    joint : JointInfo
        One of ``model.joints``.

    Returns
    -------
    str
    """
    child = joint.child + 1
    parent = 0 if joint.parent == GROUND_INDEX else joint.parent + 1
    return f"F{child}{parent}" if max(child, parent) < 10 else f"F{child},{parent}"


def _body_name(model: Model, index: int) -> str:
    return "ground" if index == GROUND_INDEX else model.bodies[index].name


@dataclass(frozen=True)
class JointStatistics:
    """Peaks (with their times) and time-RMS of a joint's force and moment magnitudes."""

    name: str
    label: str
    parent: str
    child: str
    peak_force: Peak
    rms_force: float
    peak_torque: Peak
    rms_torque: float


def joint_statistics(model: Model, result: InverseResult) -> list[JointStatistics]:
    t = result.times
    out = []
    for k, joint in enumerate(model.joints):
        force = np.linalg.norm(result.force[:, k], axis=1)
        torque = np.linalg.norm(result.torque[:, k], axis=1)
        out.append(JointStatistics(joint.name, wrench_label(model, joint),
                                   _body_name(model, joint.parent), _body_name(model, joint.child),
                                   Peak.of(t, force), time_rms(t, force),
                                   Peak.of(t, torque), time_rms(t, torque)))
    return out


@dataclass(frozen=True)
class RunInfo:
    """How the report's numbers were obtained.

    Attributes
    ----------
    scene : str
        The scene's name.
    source : str
        Where the scene came from (a file, or a built-in scene's name).
    run_time : float
        The inverse dynamics' wall-clock time, s.
    window : str
        Why the time window is what it is (shown in the summary).
    """

    scene: str
    source: str
    run_time: float  # s, inverse dynamics alone
    window: str  # why the time window is what it is


def summary_markdown(model: Model, result: InverseResult, balance: BodyBalance,
                     run: RunInfo, drivers: list[DriverStatistics], figures: list[str],
                     loads: FootLoads | None = None,
                     trunks: list[TrunkMotion] | None = None,
                     more: list[str] = ()) -> str:
    """The report's summary: the run, the joints, the drivers (and their peaks per joint type
    for a robot), the feet's ground reactions and the trunk's motion (a walking robot:
    ``loads``, ``trunks``), ``more`` sections (the stability margins, the motors' check), the
    bodies' balance."""
    t = result.times
    frame = ("the child's joint frame" if result.frame == "joint" else "world axes")
    mass = (f", total mass {model.total_mass:.4g} kg" if loads is not None else "")
    lines = [
        f"# Liaison force report: {run.scene}",
        "",
        f"Scene `{run.source}`: {count(len(model.bodies), 'body', 'bodies')}, "
        f"{count(len(model.joints), 'joint')}, {count(len(model.drivers), 'driver')}, "
        f"{count(len(model.forces), 'force element')}{mass}.",
        f"{t.size} samples over t = {t[0]:g} ... {t[-1]:g} s ({run.window}); "
        f"{result.method} path, {run.run_time:.3g} s of inverse dynamics.",
        f"Largest constraint residual {result.max_violation:.1e} (scaled); "
        + (f"redundant rows: {', '.join(result.redundant_rows)}."
           if result.redundant_rows else "no redundant rows."),
    ]
    if loads is not None:
        lines.append(f"Ground forces shared by the policy `{loads.policy}`.")
    lines += [
        "",
        "Wrenches are exerted by the parent on the child, about the joint origin, in "
        f"{frame}; `F21` is the wrench at the joint of body 2 exerted by body 1 (bodies "
        "numbered from 1 in scene order, the ground 0). RMS over time.",
        "",
        "## Joints",
        "",
    ]
    lines += markdown_table(
        ["wrench", "joint", "parent -> child", "peak \\|F\\| (N)", "at t (s)",
         "RMS \\|F\\| (N)", "peak \\|T\\| (N m)", "at t (s)", "RMS \\|T\\| (N m)"],
        [[s.label, f"`{s.name}`", f"{s.parent} -> {s.child}", g4(s.peak_force.value),
          f"{s.peak_force.time:.4g}", g4(s.rms_force), g4(s.peak_torque.value),
          f"{s.peak_torque.time:.4g}", g4(s.rms_torque)]
         for s in joint_statistics(model, result)])
    if drivers:
        lines += ["", "## Drivers", "",
                  "The actuator's effort about (along) the joint axis, the joint's speed, and "
                  "the power it delivers, effort times joint rate; work is the net energy over "
                  "the run, positive work the energy delivered where the power is positive.", ""]
        lines += markdown_table(
            ["joint", "peak \\|effort\\|", "at t (s)", "RMS effort", "peak \\|speed\\|",
             "peak \\|power\\| (W)", "at t (s)", "RMS power (W)", "work (J)",
             "positive work (J)"],
            [[f"`{d.joint}`", f"{g4(d.peak_effort.value)} {d.unit}", f"{d.peak_effort.time:.4g}",
              f"{g4(d.rms_effort)} {d.unit}", f"{g4(d.peak_speed.value)} {speed_unit(d)}",
              g4(d.peak_power.value), f"{d.peak_power.time:.4g}", g4(d.rms_power),
              g4(d.work), g4(d.positive_work)] for d in drivers])
        lines += _effort_type_section(drivers)
    if loads is not None:
        lines += ground_section(model, result, loads)
    if trunks:
        lines += trunk_section(trunks)
    lines += more  # the stability and the motors, when the report has them
    relative = balance.relative()
    lines += ["", "## Balance of each body", "",
              "Largest residual over the samples of each body's Newton-Euler equations under "
              "the reported wrenches, gravity and the loads (the joint frames rebuilt from the "
              "bodies' poses): round-off when the report is consistent. Relative to the "
              "body's largest force or moment term.", ""]
    lines += markdown_table(
        ["body", "force residual (N)", "moment residual (N m)", "relative"],
        [[name, f"{balance.force[:, b].max():.2e}", f"{balance.moment[:, b].max():.2e}",
          f"{relative[b]:.1e}"] for b, name in enumerate(balance.bodies)])
    if figures:
        lines += ["", "## Figures", ""] + [f"![{name}]({name})" for name in figures]
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ a robot: legs and feet

@dataclass(frozen=True)
class TypePeak:
    """The largest effort of one joint type over the legs (``ctr`` of ``L1/ctr`` ... ``R3/ctr``)."""

    joint_type: str
    joint: str  # where it occurs
    unit: str
    peak: Peak


def effort_peaks_by_type(drivers: list[DriverStatistics]) -> list[TypePeak]:
    """Per joint type, the peak ``|effort|`` over the legs and where it occurs; empty unless
    the driven joints belong to two legs or more (:func:`leg_groups`)."""
    if leg_groups([d.joint for d in drivers]) is None:
        return []
    best: dict[str, DriverStatistics] = {}
    for d in drivers:
        kind = joint_type(d.joint)
        # ties to round-off (a left leg and its mirror) go to the first leg
        if kind not in best or d.peak_effort.value > best[kind].peak_effort.value * (1 + 1e-9):
            best[kind] = d
    return [TypePeak(kind, d.joint, d.unit, d.peak_effort) for kind, d in best.items()]


def _effort_type_section(drivers: list[DriverStatistics]) -> list[str]:
    peaks = effort_peaks_by_type(drivers)
    if not peaks:
        return []
    lines = ["", "## Peak effort per joint type", "",
             "The largest actuator effort of each joint over the legs, and where it occurs.", ""]
    return lines + markdown_table(
        ["joint type", "peak \\|effort\\|", "joint", "at t (s)"],
        [[f"`{p.joint_type}`", f"{g4(p.peak.value)} {p.unit}", f"`{p.joint}`",
          f"{p.peak.time:.4g}"] for p in peaks])


def walking_headlines(model: Model, result: InverseResult,
                      drivers: list[DriverStatistics] | None = None) -> list[str]:
    """The lines ``hexapod report`` prints for a model with foot contacts: the policy and the
    redundant rows, each foot's peak ground reaction in body weights (the peak of its magnitude
    ``|F|`` and, beside it, the peak of its vertical component ``Fz``, world axes), the peak
    effort per joint type, and every run of samples where a foot slips or pulls (empty without
    contacts)."""
    if not model.contacts:
        return []
    loads = foot_loads(model, result)
    drivers = driver_statistics(model, result) if drivers is None else drivers
    feet = range(len(loads.legs))
    peaks = [float(np.linalg.norm(loads.force[:, c], axis=1).max()) for c in feet]
    vertical = loads.normal.max(axis=0)  # F_n = Fz: the ground's normal is world z
    unit = "body weights" if loads.weight > 0 else "N"
    scale = loads.weight if loads.weight > 0 else 1.0
    lines = [f"ground forces by the policy {loads.policy}; "
             f"{count(len(result.redundant_rows), 'redundant row')}",
             f"peak ground reaction per foot, |F| / vertical Fz ({unit}, robot weight "
             f"{loads.weight:.4g} N): "
             + ", ".join(f"{leg} {p / scale:.3g} / {z / scale:.3g}"
                         for leg, p, z in zip(loads.legs, peaks, vertical, strict=True))]
    types = effort_peaks_by_type(drivers)
    if types:
        lines.append("peak effort per joint type: " + ", ".join(
            f"{p.joint_type} {p.peak.value:.4g} {p.unit} ({p.joint.partition('/')[0]})"
            for p in types))
    events = foot_events(loads)
    lines.append("slip or pull: " + ("none" if not events else "; ".join(describe_events(events))))
    return lines


#: Name of the markers whose paths the report draws.
FOOT_MARKER = "foot"


def _side_by_side(names: list[str], groups: dict[str, list[int]]):
    """The legs of ``groups`` (``other`` left out), a title per k-th joint of a leg (the first
    leg's, its leg's name taken off: ``L1/ctr`` -> ``ctr``), and the index (legs, panels) of
    each leg's k-th joint in ``names`` (-1 where a leg has fewer)."""
    legs = [leg for leg in groups if leg != "other"]
    count = max(len(groups[leg]) for leg in legs)
    index = np.full((len(legs), count), -1)
    for m, leg in enumerate(legs):
        index[m, :len(groups[leg])] = groups[leg]
    titles = []
    for k in range(count):
        m = int(np.flatnonzero(index[:, k] >= 0)[0])
        name = names[index[m, k]]
        titles.append(name.removeprefix(legs[m]).lstrip("/_-") or name)
    return legs, titles, index


def _sheets(groups: dict[str, list[int]], leg_figures: bool):
    """``(index, suffix, which)`` of each sheet drawn one group at a time: every joint on one
    (``groups`` of the single group ``""``), else the joints of no leg (``-other``) and, with
    ``leg_figures``, each leg's (``-L1`` ...)."""
    for leg, index in groups.items():
        if not leg:
            yield index, "", ""
        elif leg == "other":
            yield index, "-other", " other joints"
        elif leg_figures:
            yield index, f"-{leg}", f" leg {leg}"


def _gathered(values: np.ndarray, index: np.ndarray) -> np.ndarray:
    """``values`` (N, joints) arranged (N, legs, panels), NaN where ``index`` is -1."""
    out = values[:, np.maximum(index, 0)]
    out[:, index < 0] = np.nan
    return out


def _wrench_figures(model: Model, result: InverseResult, scene: str,
                    leg_figures: bool = False) -> dict:
    """``forces.png`` and ``torques.png``: every joint's force and moment. For a robot (see
    :func:`report_files`) the legs side by side (magnitudes), and with ``leg_figures`` one
    sheet of each per leg with the components (``forces-L1.png`` ...). Their builders (each
    makes its figure when called)."""
    t = result.times
    labels = [wrench_label(model, joint) for joint in model.joints]
    names = [j.name for j in model.joints]
    where = "joint frame" if result.frame == "joint" else "world axes"
    groups = leg_groups(names, model) or {"": list(range(len(names)))}
    figures = {}
    if "" not in groups:
        legs, titles, index = _side_by_side(names, groups)
        for kind, values, unit, what in (("forces", result.force, "N", "force |F|"),
                                         ("torques", result.torque, "N m", "moment |T|")):
            figures[f"{kind}.png"] = partial(
                leg_comparison_figure, t, _gathered(np.linalg.norm(values, axis=2), index),
                legs, titles, unit, f"{scene}: each joint's {what}, legs side by side")
    for index, suffix, which in _sheets(groups, leg_figures):
        figures[f"forces{suffix}.png"] = partial(
            wrench_figure, t, result.force[:, index], [f"{labels[k]}  {names[k]}" for k in index],
            "F", "N", f"{scene}{which}: joint forces, by parent on child ({where})")
        figures[f"torques{suffix}.png"] = partial(
            wrench_figure, t, result.torque[:, index],
            [f"T{labels[k][1:]}  {names[k]}" for k in index], "T", "N m",
            f"{scene}{which}: joint moments about the joint origins ({where})")
    return dict(sorted(figures.items(), key=lambda item: not item[0].startswith("forces")))


def _effort_figures(model: Model, times: np.ndarray, drivers: list[DriverStatistics],
                    scene: str, leg_figures: bool = False) -> dict:
    """``efforts.png``: each actuator's effort and power; for a robot the legs' efforts side
    by side, and with ``leg_figures`` one sheet per leg (``efforts-L1.png`` ...). Builders."""
    if not drivers:
        return {}
    joints = [d.joint for d in drivers]
    groups = leg_groups(joints, model) or {"": list(range(len(drivers)))}
    out = {}
    if "" not in groups:
        legs, titles, index = _side_by_side(joints, groups)
        efforts = np.column_stack([d.effort for d in drivers])
        units = sorted({d.unit for d in drivers})
        out["efforts.png"] = partial(
            leg_comparison_figure, times, _gathered(efforts, index), legs, titles,
            " or ".join(units), f"{scene}: actuator efforts, legs side by side")
    for index, suffix, which in _sheets(groups, leg_figures):
        out[f"efforts{suffix}.png"] = partial(
            effort_figure, times,
            [(drivers[k].joint, drivers[k].unit, drivers[k].effort, drivers[k].power)
             for k in index], f"{scene}{which}: actuator efforts (solid) and power (dashed)")
    return out


def _ground_figures(model: Model, loads: FootLoads, scene: str) -> dict:
    legs = list(loads.legs)
    t = loads.times
    return {
        "ground.png": partial(
            ground_reaction_figure, t, loads.force, legs, loads.stance, loads.weight,
            f"{scene}: the ground's force on each foot (stance shaded, infeasible hatched; "
            f"policy {loads.policy})", loads.status),
        "friction.png": partial(
            friction_ratio_figure, t, loads.ratio, loads.status, legs, loads.stance, loads.mu,
            f"{scene}: friction ratio |F_t| / (mu F_n) of each foot"),
        "gait.png": partial(gait_diagram_figure, legs, loads.stance, float(t[0]), float(t[-1]),
                            f"{scene}: gait diagram (black: stance)"),
    }


def report_files(model: Model, result: InverseResult, balance: BodyBalance, run: RunInfo,
                 feet: dict[str, np.ndarray], *, figures: bool = True,
                 workers: int = 1, leg_figures: bool = False,
                 actuators: ActuatorTable | None = None) -> dict[str, bytes]:
    """Every file of the report, in memory: ``inverse.csv``, ``units.json`` (the unit and
    meaning of every column of every CSV), ``summary.md`` and the figures
    (``forces.png``, ``torques.png``; ``efforts.png`` when there are joint drivers;
    ``foot.png`` when there are ``feet``, paths (N, 3) by body). For a robot (joints named
    ``<leg>/...`` in two legs or more, or a URDF robot's limbs) the force, moment and effort
    figures put the legs side by side, one panel per joint of a leg, and ``leg_figures`` adds
    one sheet of each per leg with the components (``forces-L1.png`` ...: three times the
    drawing). With foot contacts (a walking robot) also ``ground.csv`` and
    ``trunk.csv`` (:mod:`hexapod.output.ground`), and the figures ``ground.png`` (the
    ground's force on each foot), ``friction.png`` (the friction ratio) and ``gait.png`` (the
    gait diagram).

    Parameters
    ----------
    model : Model
    result : InverseResult
        The inverse dynamics over the report's window.
    balance : BodyBalance
        Its per-body balance (:func:`hexapod.body_balance`), summarised in ``summary.md``.
    run : RunInfo
        How the numbers were obtained.
    feet : dict of str to ndarray, shape (N, 3)
        Foot paths (world, m) by body; empty for none.
    figures : bool
        Draw the figures (3 s of CPU of the walking robot's 10,
        ``scripts/benchmarks/bench_report.py``); without them the tables and the summary are
        the same.
    workers : int
        Processes drawing the figures (:func:`hexapod.output.figures.render_figures`): more
        than one forks this process that many times, on systems that fork; the same bytes.
    leg_figures : bool
        For a robot, also one sheet per leg of its joints' forces, moments and efforts (the
        components and the power), beside the sheets that put the legs side by side.
    actuators : ActuatorTable, optional
        The driven joints' motors (:func:`hexapod.read_actuators`): adds ``motors.csv``, the
        summary's section on them and ``motors.png`` (:mod:`hexapod.output.actuation`).

    Returns
    -------
    dict of str to bytes
        The files' contents by name; nothing is written (see
        :func:`write_directory_atomically`).
    """
    t = result.times
    drivers = driver_statistics(model, result)
    files = {"inverse.csv": inverse_csv_text(model, result).encode()}
    units = {"inverse.csv": inverse_column_units(model, result.frame)}
    loads = trunks = None
    if model.contacts:
        loads = foot_loads(model, result)
        trunks = trunk_motion(model, result.q, result.v)
    drawn = figure_builders(model, result, run.scene, feet, leg_figures=leg_figures,
                            drivers=drivers, loads=loads) if figures else {}
    if loads is not None:
        files["ground.csv"] = ground_csv_text(loads).encode()
        units["ground.csv"] = ground_csv_columns(loads.legs)
        if trunks:
            files["trunk.csv"] = trunk_csv_text(t, trunks).encode()
            units["trunk.csv"] = trunk_csv_columns([m.body for m in trunks])
        margins = stability_margins(model, result)
        files["margins.csv"] = margins_csv_text(margins).encode()
        units["margins.csv"] = margins_csv_columns()
        if figures:
            drawn["margins.png"] = partial(stability_figure, margins,
                                             f"{run.scene}: stability")
    more: list[str] = []
    if actuators is not None:
        assigned = actuators.assign([d.joint for d in drivers])
        checks = motor_checks(t, drivers, assigned)
        files["motors.csv"] = motors_csv_text(checks).encode()
        units["motors.csv"] = motors_csv_columns(checks)
        more = motors_section(checks, [d.joint for d in drivers if d.joint not in
                                              assigned], actuators.source)
        if figures and checks:
            drawn["motors.png"] = partial(envelope_figure, checks, f"{run.scene}: motors")
    files["units.json"] = units_json(units).encode()
    if loads is not None:
        more = stability_section(margins) + more
    files["summary.md"] = summary_markdown(model, result, balance, run, drivers,
                                           list(drawn), loads, trunks, more).encode()
    files.update(render_figures(drawn, workers))
    return files


def figure_builders(model: Model, result: InverseResult, scene: str,
                    feet: dict[str, np.ndarray], *, leg_figures: bool = False,
                    drivers: list[DriverStatistics] | None = None,
                    loads: FootLoads | None = None) -> dict:
    """The figures of :func:`report_files`, not drawn: a builder per file name, each making
    its :class:`matplotlib.figure.Figure` when called (to draw them:
    :func:`hexapod.output.figures.render_figures`).

    Parameters
    ----------
    model : Model
    result : InverseResult
        The inverse dynamics the figures show.
    scene : str
        The scene's name, in the titles.
    feet : dict of str to ndarray
        The feet's paths (:func:`hexapod.marker_trajectories`), drawn in ``foot.png``.
    leg_figures : bool
        Also one sheet of each kind per leg.
    drivers, loads : optional
        The drivers' statistics and, with foot contacts, the feet's loads of ``result``, when
        already computed (else computed here).

    Returns
    -------
    dict of str to callable
        ``file name -> build``, ``build()`` returning the figure.
    """
    drivers = driver_statistics(model, result) if drivers is None else drivers
    drawn = _wrench_figures(model, result, scene, leg_figures)
    drawn.update(_effort_figures(model, result.times, drivers, scene, leg_figures))
    if feet:
        drawn["foot.png"] = partial(
            trajectory_figure, result.times, feet,
            f"{scene}: {'foot' if len(feet) == 1 else 'feet'} (world frame)")
    if model.contacts:
        loads = foot_loads(model, result) if loads is None else loads
        drawn.update(_ground_figures(model, loads, scene))
    return drawn
