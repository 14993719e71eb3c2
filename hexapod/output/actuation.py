"""The actuators of a report: each driven joint's effort, speed, power and work, and, with an
actuator table (:mod:`hexapod.scene.actuators`), its motor's check: whether the joint stays
inside its motor's torque-speed envelope (which joint leaves it, when, by how much), the
motor's current and electrical power (``R I^2`` plus the mechanical power) and energy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.algorithms.inverse import InverseResult
from hexapod.algorithms.liaison import wrenches_from_multipliers
from hexapod.model.model import Model
from hexapod.output.summary_parts import (
    Peak,
    g4,
    markdown_table,
    time_integral,
    time_rms,
    true_runs,
)
from hexapod.scene.actuators import Actuator, ActuatorTable, effort_limits


@dataclass(frozen=True)
class DriverStatistics:
    """A driven joint's actuator: its effort (N m or N), the joint's rate (rad/s or m/s), the
    power it delivers (W)."""

    joint: str
    unit: str
    effort: np.ndarray
    rate: np.ndarray
    power: np.ndarray
    peak_effort: Peak
    rms_effort: float
    peak_speed: Peak
    peak_power: Peak
    rms_power: float
    work: float  # net energy delivered over the run (J)
    positive_work: float  # the energy delivered where the power is positive (J)


def driver_efforts_over_time(model: Model, result: InverseResult) -> dict[str, np.ndarray]:
    """The effort of each joint driver at every sample, by joint: the joint's axial effort less
    the springs and efforts acting across it (those are in parallel with the actuator)."""
    driven = {d.joint: d for d in model.drivers if d.kind == "joint"}
    efforts = {model.joints[j].name: result.effort[:, j].copy() for j in driven}
    across = [j for j in driven if model.joints[j].across_column >= 0]
    if across and model.Q_across is not None:
        w = model.law_values(result.times)[0].T
        zero_lam, zero_rows = np.zeros(model.n_c), np.zeros((model.n_c, model.n_v))
        data = model.create_data()
        for i in range(result.times.size):
            q_across = model.call("Q_across", data, q=result.q[i], v=result.v[i], w=w[i])
            passive = wrenches_from_multipliers(model, result.q[i], zero_lam, zero_rows,
                                                q_across, data=data).effort
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
        out.append(DriverStatistics(
            joint.name, joint.type.effort_unit, effort, rate, power, Peak.of(t, effort),
            time_rms(t, effort), Peak.of(t, rate), Peak.of(t, power), time_rms(t, power),
            time_integral(t, power), time_integral(t, np.maximum(power, 0.0))))
    return out


def speed_unit(driver: DriverStatistics) -> str:
    """The unit of the driver's joint speed."""
    return "rad/s" if driver.unit == "N m" else "m/s"


# ------------------------------------------------------------------ the motors' check

@dataclass(frozen=True)
class Excursion:
    """A time the joint spends outside its motor's envelope: from ``start`` to ``end`` (s,
    where the envelope use crosses 1, interpolated between samples), the largest use
    ``peak_use`` at ``at`` (s), and there the effort beyond the envelope ``effort_excess``
    (N m or N) and the speed beyond it ``speed_excess`` (rad/s or m/s; 0 for a DC motor's
    envelope, whose line bounds the effort)."""

    start: float
    end: float
    peak_use: float
    at: float
    effort_excess: float
    speed_excess: float


@dataclass(frozen=True)
class MotorCheck:
    """A driven joint against its actuator (:mod:`hexapod.scene.actuators`), per sample and
    summed up.

    Attributes
    ----------
    times : ndarray, shape (N,)
        The samples' times (s).
    driver : DriverStatistics
        The joint's effort, speed and power.
    actuator : Actuator
    use : ndarray, shape (N,)
        The envelope's use: 1 on its boundary, above 1 outside. For a DC motor the voltage it
        needs over its supply's, ``|tau_m / tau_s + w_m / w_0|``; for a rated envelope the
        larger of ``|tau_m| / tau_r`` and ``|w_m| / w_r``.
    excursions : tuple of Excursion
        Where the joint leaves the envelope.
    current, electrical_power : ndarray or None
        The motor's current (A) and electrical power ``tau w + R I^2`` (W), with a torque
        constant and a resistance.
    energy, net_energy, heat : float or None
        Over the run (J): the electrical energy drawn where the power is positive (none
        recovered), the net electrical energy (all recovered), the winding's heat.
    """

    times: np.ndarray
    driver: DriverStatistics
    actuator: Actuator
    use: np.ndarray
    excursions: tuple[Excursion, ...]
    current: np.ndarray | None
    electrical_power: np.ndarray | None
    energy: float | None
    net_energy: float | None
    heat: float | None

    @property
    def peak_use(self) -> Peak:
        """The largest use of the envelope and when."""
        return Peak.of(self.times, self.use)

    @property
    def peak_electrical(self) -> Peak | None:
        """The largest electrical power (W) and when; None without a torque constant."""
        return None if self.electrical_power is None else Peak.of(self.times,
                                                                   self.electrical_power)


def motor_checks(times: np.ndarray, drivers: list[DriverStatistics],
                 assigned: dict[str, Actuator]) -> list[MotorCheck]:
    """Each driven joint that has an actuator against it (see :class:`MotorCheck`).

    Parameters
    ----------
    times : ndarray, shape (N,)
        The samples' times (s).
    drivers : list of DriverStatistics
        The driven joints (:func:`driver_statistics`).
    assigned : dict of str to Actuator
        The actuator of each joint (:func:`hexapod.scene.actuators.assign`); joints without
        one are not checked.

    Returns
    -------
    list of MotorCheck
        In the drivers' order.
    """
    out = []
    for driver in drivers:
        actuator = assigned.get(driver.joint)
        if actuator is None:
            continue
        effort, rate = driver.effort, driver.rate
        max_effort, no_load, rated_speed = actuator.joint_limits()
        lower, upper = effort_limits(max_effort, no_load, rate)
        effort_excess = np.maximum(np.maximum(effort - upper, lower - effort), 0.0)
        if no_load is not None:
            use = np.abs(effort / max_effort + rate / no_load)
            speed_excess = np.zeros_like(rate)
        else:
            use = np.maximum(np.abs(effort) / max_effort, np.abs(rate) / rated_speed)
            speed_excess = np.maximum(np.abs(rate) - rated_speed, 0.0)
        current = power = None
        energy = net = heat = None
        if actuator.electrical:
            current = effort / (actuator.gear_ratio * actuator.torque_constant)
            losses = actuator.resistance * current**2
            power = driver.power + losses
            energy = time_integral(times, np.maximum(power, 0.0))
            net, heat = time_integral(times, power), time_integral(times, losses)
        out.append(MotorCheck(times, driver, actuator, use,
                              _excursions(times, use, effort_excess, speed_excess),
                              current, power, energy, net, heat))
    return out


def _excursions(times, use, effort_excess, speed_excess) -> tuple[Excursion, ...]:
    """The runs of samples outside the envelope (``use > 1``), their ends interpolated
    linearly to where the use crosses 1."""
    out = []
    for a, b in true_runs(use > 1.0):
        start = times[a] if a == 0 else _crossing(times, use, a - 1, a)
        end = times[b] if b == times.size - 1 else _crossing(times, use, b, b + 1)
        k = a + int(np.argmax(use[a:b + 1]))
        out.append(Excursion(float(start), float(end), float(use[k]), float(times[k]),
                             float(effort_excess[k]), float(speed_excess[k])))
    return tuple(out)


def _crossing(times, use, i, j) -> float:
    """Where the use crosses 1 between samples ``i`` and ``j`` (linearly)."""
    return times[i] + (1.0 - use[i]) / (use[j] - use[i]) * (times[j] - times[i])


def motors_csv_columns(checks: list[MotorCheck]) -> dict[str, tuple[str, str]]:
    """The columns of ``motors.csv`` in order, each with its unit and meaning."""
    columns = {"t": ("s", "time")}
    for check in checks:
        joint = check.driver.joint
        columns[f"use:{joint}"] = ("1", f"use of {joint}'s motor envelope (1 on it)")
        if check.current is not None:
            columns[f"I:{joint}"] = ("A", f"current of {joint}'s motor")
            columns[f"P_el:{joint}"] = ("W", f"electrical power of {joint}'s motor")
    return columns


def motors_csv_text(checks: list[MotorCheck]) -> str:
    """``motors.csv``: ``t``, then per checked joint ``use:<joint>`` and, with a torque
    constant and a resistance, ``I:<joint>`` (A) and ``P_el:<joint>`` (W)."""
    columns = [checks[0].times] if checks else []
    for check in checks:
        columns.append(check.use)
        if check.current is not None:
            columns += [check.current, check.electrical_power]
    lines = [",".join(motors_csv_columns(checks))]
    lines += [",".join(f"{x:.17g}" for x in row) for row in np.column_stack(columns)]
    return "\n".join(lines) + "\n"


def motors_section(checks: list[MotorCheck], unchecked: list[str], source: str) -> list[str]:
    """The summary's section on the motors: per checked joint its envelope's use, where it
    leaves the envelope, and its electrical figures; the driven joints without an actuator."""
    lines = ["", "## Motors", "",
             f"Each driven joint against its motor (actuator table `{source}`; the motor's "
             "torque and speed are the joint's divided and multiplied by the gear ratio). Use "
             "of the envelope: 1 on it; for a DC motor the voltage it needs over its supply's. "
             "Electrical power: `R I^2` plus the mechanical power; energy drawn where it is "
             "positive (none recovered), net (all recovered), and the winding's heat.", ""]
    rows = []
    for check in checks:
        d, peak, electric = check.driver, check.peak_use, check.peak_electrical
        rows.append([f"`{d.joint}`", check.actuator.name, f"{peak.value:.3f}",
                     f"{peak.time:.4g}", _outside(check) or "never",
                     "" if check.current is None else g4(float(np.abs(check.current).max())),
                     "" if electric is None else g4(electric.value),
                     *("" if x is None else g4(x)
                       for x in (check.energy, check.net_energy, check.heat))])
    lines += markdown_table(
        ["joint", "motor", "peak use", "at t (s)", "outside the envelope", "peak \\|I\\| (A)",
         "peak \\|P_el\\| (W)", "energy drawn (J)", "net energy (J)", "heat (J)"], rows)
    if unchecked:
        lines += ["", "Not checked (no actuator in the table): "
                  + ", ".join(f"`{j}`" for j in unchecked) + "."]
    return lines


def _outside(check: MotorCheck) -> str:
    """Where a joint leaves its envelope, e.g. ``0.1-0.18 s (4.2 N m beyond at 0.14 s)``."""
    d = check.driver
    parts = []
    for e in check.excursions:
        beyond = (f"{e.effort_excess:.3g} {d.unit}" if e.effort_excess > 0 else
                  f"{e.speed_excess:.3g} {speed_unit(d)}")
        parts.append(f"{e.start:.4g}-{e.end:.4g} s ({beyond} beyond at {e.at:.4g} s)")
    return "; ".join(parts)


def check_motors(model: Model, result: InverseResult, table: ActuatorTable) -> list[MotorCheck]:
    """Each driven joint of ``model`` over the inverse dynamics ``result`` against its motor
    in ``table`` (what ``hexapod report --actuators`` writes; see :class:`MotorCheck`).

    Parameters
    ----------
    model : Model
    result : InverseResult
        The inverse dynamics (the joints' efforts, speeds from the drivers' laws).
    table : ActuatorTable
        The motors (:func:`hexapod.scene.read_actuators`).

    Returns
    -------
    list of MotorCheck
        The joints that have a motor in the table, in the drivers' order.

    Raises
    ------
    InputFileError
        An entry of the table names no driven joint, or two name the same joint.
    """
    drivers = driver_statistics(model, result)
    return motor_checks(result.times, drivers, table.assign([d.joint for d in drivers]))
