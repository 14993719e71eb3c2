"""Reports of inverse dynamics: the CSV of the ``hexapod inverse`` contract, and the liaison
force report's statistics and Markdown summary (``hexapod report``).

Columns: ``t``, then for every joint in model order ``tau:<joint>`` (revolute and prismatic
joints: N m or N), ``Fx:<joint>``, ``Fy:<joint>``, ``Fz:<joint>``, ``Tx:<joint>``,
``Ty:<joint>``, ``Tz:<joint>`` (N, N m): the wrench exerted by the parent on the child, about
the joint origin, in the child's joint frame (or world axes on request). Fixed joints and the
other joints without an axis have the force and moment columns without ``tau``. Numbers are
written with 17 significant digits, so they read back exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.algorithms.balance import BodyBalance
from hexapod.algorithms.inverse import InverseResult
from hexapod.algorithms.liaison import wrenches_from_multipliers
from hexapod.model.model import GROUND_INDEX, JointInfo, Model
from hexapod.output.figures import effort_figure, png_bytes, trajectory_figure, wrench_figure

COMPONENTS = ("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")


def inverse_columns(model: Model) -> list[str]:
    """The header of the inverse-dynamics CSV."""
    names = ["t"]
    for joint in model.joints:
        if joint.kind in ("revolute", "prismatic"):
            names.append(f"tau:{joint.name}")
        names += [f"{c}:{joint.name}" for c in COMPONENTS]
    return names


def inverse_table(model: Model, result: InverseResult) -> np.ndarray:
    """The rows of the CSV: one per sample, columns as :func:`inverse_columns`."""
    columns = [result.times[:, None]]
    for k, joint in enumerate(model.joints):
        if joint.kind in ("revolute", "prismatic"):
            columns.append(result.effort[:, k, None])
        columns += [result.force[:, k], result.torque[:, k]]
    return np.hstack(columns)


def inverse_csv_text(model: Model, result: InverseResult) -> str:
    """The CSV of ``hexapod inverse``: a header of :func:`inverse_columns` (``t``, then per joint
    ``tau`` where it has one and ``Fx .. Tz``; N, N m) and one row per sample, every number
    written to round-trip (17 significant digits)."""
    rows = inverse_table(model, result)
    line = ",".join(["%.17g"] * rows.shape[1])
    return ",".join(inverse_columns(model)) + "\n" + "".join(
        line % tuple(row) + "\n" for row in rows)


def agreement(columns: list[str], table: np.ndarray, reference_columns: list[str],
              reference: np.ndarray) -> float:
    """Largest difference from a reference CSV, relative to the largest magnitude of the same
    quantity: for each joint, its forces (``Fx, Fy, Fz``) against the largest of them, its
    moments (``tau, Tx, Ty, Tz``) against the largest of those, over all samples. Columns of the
    table that the reference lacks (fixed joints, say) are not compared."""
    index = {name: k for k, name in enumerate(columns)}
    groups: dict[tuple[str, str], list[int]] = {}
    for k, name in enumerate(reference_columns):
        if ":" not in name:
            continue
        component, joint = name.split(":", 1)
        kind = "force" if component.startswith("F") else "moment"
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
    9)."""
    child = joint.child + 1
    parent = 0 if joint.parent == GROUND_INDEX else joint.parent + 1
    return f"F{child}{parent}" if max(child, parent) < 10 else f"F{child},{parent}"


def _body_name(model: Model, index: int) -> str:
    return "ground" if index == GROUND_INDEX else model.bodies[index].name


def time_integral(times: np.ndarray, x: np.ndarray) -> float:
    """Integral over the samples' span by the trapezoidal rule (0 for one sample)."""
    return float(np.sum((x[1:] + x[:-1]) * np.diff(times)) / 2)


def time_rms(times: np.ndarray, x: np.ndarray) -> float:
    """Root mean square over time (trapezoidal rule; the value itself for one sample)."""
    if times.size < 2:
        return float(np.abs(x).max(initial=0.0))
    return float(np.sqrt(time_integral(times, x**2) / (times[-1] - times[0])))


@dataclass(frozen=True)
class Peak:
    value: float
    time: float

    @classmethod
    def of(cls, times: np.ndarray, x: np.ndarray) -> Peak:
        k = int(np.argmax(np.abs(x)))
        return cls(float(np.abs(x[k])), float(times[k]))


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


@dataclass(frozen=True)
class DriverStatistics:
    """A driven joint's actuator: its effort (N m or N), the power it delivers (W)."""

    joint: str
    unit: str
    effort: np.ndarray
    power: np.ndarray
    peak_effort: Peak
    rms_effort: float
    peak_power: Peak
    rms_power: float
    work: float  # net energy delivered over the run (J)


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


def driver_efforts_over_time(model: Model, result: InverseResult) -> dict[str, np.ndarray]:
    """The effort of each joint driver at every sample, by joint: the joint's axial effort less
    the springs and efforts acting across it (those are in parallel with the actuator)."""
    driven = {d.joint: d for d in model.drivers if d.kind == "joint"}
    efforts = {model.joints[j].name: result.effort[:, j].copy() for j in driven}
    across = [j for j in driven if model.joints[j].across_column >= 0]
    if across and model.Q_across is not None:
        w = model.law_values(result.times)[0].T
        zero_lam, zero_rows = np.zeros(model.n_c), np.zeros((model.n_c, model.n_v))
        for i in range(result.times.size):
            q_across = model.call("Q_across", q=result.q[i], v=result.v[i], w=w[i])
            passive = wrenches_from_multipliers(model, result.q[i], zero_lam, zero_rows,
                                                q_across).effort
            for j in across:
                efforts[model.joints[j].name][i] -= passive[j]
    return efforts


def driver_statistics(model: Model, result: InverseResult) -> list[DriverStatistics]:
    t = result.times
    _, wd, _ = model.law_values(t)
    efforts = driver_efforts_over_time(model, result)
    out = []
    for driver in model.drivers:
        if driver.kind != "joint":
            continue
        joint = model.joints[driver.joint]
        effort = efforts[joint.name]
        rate = wd[driver.law] if driver.law >= 0 else np.zeros_like(t)
        power = effort * rate
        work = time_integral(t, power)
        out.append(DriverStatistics(joint.name, "N" if joint.kind == "prismatic" else "N m",
                                    effort, power, Peak.of(t, effort), time_rms(t, effort),
                                    Peak.of(t, power), time_rms(t, power), work))
    return out


@dataclass(frozen=True)
class RunInfo:
    """How the report's numbers were obtained."""

    scene: str
    source: str
    run_time: float  # s, inverse dynamics alone
    window: str  # why the time window is what it is


def _count(n: int, noun: str, plural: str | None = None) -> str:
    return f"{n} {noun if n == 1 else plural or noun + 's'}"


def _g(x: float) -> str:
    return f"{x:.4g}"


def _markdown_table(header: list[str], rows: list[list[str]]) -> list[str]:
    return ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"] + [
        "| " + " | ".join(row) + " |" for row in rows]


def summary_markdown(model: Model, result: InverseResult, balance: BodyBalance,
                     run: RunInfo, drivers: list[DriverStatistics], figures: list[str]) -> str:
    """The report's summary: the run, the joints, the drivers, the bodies' balance."""
    t = result.times
    frame = ("the child's joint frame" if result.frame == "joint" else "world axes")
    lines = [
        f"# Liaison force report: {run.scene}",
        "",
        f"Scene `{run.source}`: {_count(len(model.bodies), 'body', 'bodies')}, "
        f"{_count(len(model.joints), 'joint')}, {_count(len(model.drivers), 'driver')}, "
        f"{_count(len(model.forces), 'force element')}.",
        f"{t.size} samples over t = {t[0]:g} ... {t[-1]:g} s ({run.window}); "
        f"{result.method} path, {run.run_time:.3g} s of inverse dynamics.",
        f"Largest constraint residual {result.max_violation:.1e} (scaled); "
        + (f"redundant rows: {', '.join(result.redundant_rows)}."
           if result.redundant_rows else "no redundant rows."),
        "",
        "Wrenches are exerted by the parent on the child, about the joint origin, in "
        f"{frame}; `F21` is the wrench at the joint of body 2 exerted by body 1 (bodies "
        "numbered from 1 in scene order, the ground 0). RMS over time.",
        "",
        "## Joints",
        "",
    ]
    lines += _markdown_table(
        ["wrench", "joint", "parent -> child", "peak \\|F\\| (N)", "at t (s)",
         "RMS \\|F\\| (N)", "peak \\|T\\| (N m)", "at t (s)", "RMS \\|T\\| (N m)"],
        [[s.label, f"`{s.name}`", f"{s.parent} -> {s.child}", _g(s.peak_force.value),
          f"{s.peak_force.time:.4g}", _g(s.rms_force), _g(s.peak_torque.value),
          f"{s.peak_torque.time:.4g}", _g(s.rms_torque)]
         for s in joint_statistics(model, result)])
    if drivers:
        lines += ["", "## Drivers", "",
                  "The actuator's effort about (along) the joint axis, and the power it "
                  "delivers, effort times joint rate; work is the net energy over the run.", ""]
        lines += _markdown_table(
            ["joint", "peak \\|effort\\|", "at t (s)", "RMS effort", "peak \\|power\\| (W)",
             "at t (s)", "RMS power (W)", "work (J)"],
            [[f"`{d.joint}`", f"{_g(d.peak_effort.value)} {d.unit}", f"{d.peak_effort.time:.4g}",
              f"{_g(d.rms_effort)} {d.unit}", _g(d.peak_power.value),
              f"{d.peak_power.time:.4g}", _g(d.rms_power), _g(d.work)] for d in drivers])
    relative = balance.relative()
    lines += ["", "## Balance of each body", "",
              "Largest residual over the samples of each body's Newton-Euler equations under "
              "the reported wrenches, gravity and the loads (the joint frames rebuilt from the "
              "bodies' poses): round-off when the report is consistent. Relative to the "
              "body's largest force or moment term.", ""]
    lines += _markdown_table(
        ["body", "force residual (N)", "moment residual (N m)", "relative"],
        [[name, f"{balance.force[:, b].max():.2e}", f"{balance.moment[:, b].max():.2e}",
          f"{relative[b]:.1e}"] for b, name in enumerate(balance.bodies)])
    if figures:
        lines += ["", "## Figures", ""] + [f"![{name}]({name})" for name in figures]
    return "\n".join(lines) + "\n"


#: Name of the markers whose paths the report draws.
FOOT_MARKER = "foot"


def report_files(model: Model, result: InverseResult, balance: BodyBalance, run: RunInfo,
                 feet: dict[str, np.ndarray]) -> dict[str, bytes]:
    """Every file of the report, in memory: ``inverse.csv``, ``summary.md`` and the figures
    (``forces.png``, ``torques.png``; ``efforts.png`` when there are joint drivers;
    ``foot.png`` when there are ``feet``, paths (N, 3) by body)."""
    t = result.times
    labels = [wrench_label(model, joint) for joint in model.joints]
    where = "joint frame" if result.frame == "joint" else "world axes"
    figures = {
        "forces.png": wrench_figure(
            t, result.force, [f"{label}  {j.name}" for label, j in zip(labels, model.joints,
                                                                      strict=True)],
            "F", "N", f"{run.scene}: joint forces, by parent on child ({where})"),
        "torques.png": wrench_figure(
            t, result.torque, [f"T{label[1:]}  {j.name}" for label, j in zip(labels, model.joints,
                                                                           strict=True)],
            "T", "N m", f"{run.scene}: joint moments about the joint origins ({where})"),
    }
    drivers = driver_statistics(model, result)
    if drivers:
        figures["efforts.png"] = effort_figure(
            t, [(d.joint, d.unit, d.effort, d.power) for d in drivers],
            f"{run.scene}: actuator efforts (solid) and power (dashed)")
    if feet:
        figures["foot.png"] = trajectory_figure(
            t, feet, f"{run.scene}: {'foot' if len(feet) == 1 else 'feet'} (world frame)")
    files = {"inverse.csv": inverse_csv_text(model, result).encode()}
    files["summary.md"] = summary_markdown(model, result, balance, run, drivers,
                                           list(figures)).encode()
    for name, figure in figures.items():
        files[name] = png_bytes(figure)
    return files
