"""The numbers a sweep keeps per case, from an inverse-dynamics or a simulation result.

A metric is a family (``peak_effort``) and, for families with one value per joint or per foot,
an element: the column ``peak_effort:L1/tita``. Definitions (``docs/sweeps.md``):

=====================  ======  ================================================================
family                 unit    value
=====================  ======  ================================================================
peak_effort:J          N m, N  largest ``|tau|`` of driven joint J over the samples
rms_effort:J           N m, N  root mean square of ``tau`` over time (trapezoidal)
peak_force:J           N       largest ``|F|`` of joint J's wrench (report convention)
peak_moment:J          N m     largest ``|T|`` of joint J's wrench, about the joint origin
peak_ground:LEG        N       largest ``|F|`` of the ground's force on the foot
friction_ratio:LEG             largest ``|F_t| / (mu F_n)`` of a loaded foot (above 1: outside
                               the friction cone; infinite: the ground would pull)
slip_samples           1       samples where a foot slips or is pulled, whatever the policy
static_margin          m       smallest static stability margin (the centre of mass's
                               projection to the support polygon's nearest edge; negative
                               outside)
cop_margin             m       smallest margin of the centre of pressure (the ZMP)
energy                 J       the actuators' positive work per stride, ``int sum max(tau w, 0)``
cost_of_transport      1       that work over ``m g d``, ``d`` the horizontal distance the
                               centre of mass travels in the stride (NaN when it stays put)
max_violation          1       largest scaled constraint residual
energy_drift           1       simulate: the run's energy drift (NaN when energy is not
                               conserved)
max_position_violation 1       simulate: largest scaled ``|phi|`` over the steps
t_reached              s       simulate: the time the run reached
steps                  1       simulate: accepted steps
=====================  ======  ================================================================
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from hexapod.output.summary_parts import time_integral, time_rms

if TYPE_CHECKING:
    from hexapod.algorithms.inverse import InverseResult
    from hexapod.model.model import Model

#: The metric families of each job kind, in the table's column order.
FAMILIES = {
    "inverse": ("peak_effort", "rms_effort", "peak_force", "peak_moment", "peak_ground",
                "friction_ratio", "slip_samples", "static_margin", "cop_margin", "energy",
                "cost_of_transport", "max_violation"),
    "simulate": ("peak_effort", "rms_effort", "peak_force", "peak_moment", "energy_drift",
                 "max_position_violation", "max_velocity_violation", "t_reached", "steps"),
}
_UNITS = {"peak_force": "N", "peak_moment": "N m", "peak_ground": "N", "energy": "J",
          "static_margin": "m", "cop_margin": "m",
          "t_reached": "s", "max_velocity_violation": "1/s"}


def metric_unit(model, column: str) -> str:
    """The unit of a metric column ("" for a pure number)."""
    family, _, element = column.partition(":")
    if family in ("peak_effort", "rms_effort"):
        return model.joints[model.joint_index[element]].type.effort_unit or ""
    return _UNITS.get(family, "")


def inverse_metrics(model: Model, result: InverseResult, families: Sequence[str],
                    strides: float, masses: np.ndarray | None = None) -> dict[str, float]:
    """The metrics of an inverse-dynamics ``result`` over ``strides`` strides.

    Parameters
    ----------
    model : Model
        The model ``result`` was computed with.
    result : InverseResult
    families : sequence of str
        The families kept (:data:`FAMILIES` ``["inverse"]``).
    strides : float
        The window in strides (the energy is per stride).
    masses : ndarray, optional
        The bodies' masses, kg (default the model's): the cost of transport's weight and
        centre of mass when ``result`` holds the forces of other masses (a design's).

    Returns
    -------
    dict
        Metric column (``family`` or ``family:element``) -> value, in the units of
        :func:`metric_unit`.
    """
    out: dict[str, float] = {}
    t = result.times
    driven = [j for j in model.joints if j.driver_rows.size and j.type.drivable]
    _wrench_metrics(out, model, t, result.effort, result.force, result.torque, driven, families)
    if model.contacts and result.ground_force is not None:
        from hexapod.output.ground import foot_loads

        loads = foot_loads(model, result)
        for c, leg in enumerate(loads.legs):
            if "peak_ground" in families:
                out[f"peak_ground:{leg}"] = float(np.max(np.linalg.norm(loads.force[:, c],
                                                                        axis=-1)))
            if "friction_ratio" in families:
                ratio = loads.ratio[:, c]
                out[f"friction_ratio:{leg}"] = (float(np.nanmax(ratio))
                                                if np.any(np.isfinite(ratio) | np.isinf(ratio))
                                                else float("nan"))
        if "slip_samples" in families:
            out["slip_samples"] = float(np.sum(loads.infeasible.any(axis=1)))
        if {"static_margin", "cop_margin"} & set(families):
            from hexapod.output.stability import stability_margins

            margins = stability_margins(model, result)
            for name in ("static_margin", "cop_margin"):
                if name in families:
                    out[name] = float(np.nanmin(getattr(margins, name)))
    if {"energy", "cost_of_transport"} & set(families):
        work = positive_work(model, t, result.effort, driven)
        if "energy" in families:
            out["energy"] = work / strides
        if "cost_of_transport" in families:
            out["cost_of_transport"] = cost_of_transport(model, result.q, work, masses)
    if "max_violation" in families:
        out["max_violation"] = float(result.max_violation)
    return out


def simulation_metrics(model, result, families) -> dict[str, float]:
    """The metrics of a simulation ``result`` (wrench metrics when it computed forces)."""
    out: dict[str, float] = {}
    if result.force is not None:
        driven = [j for j in model.joints if j.driver_rows.size and j.type.drivable]
        _wrench_metrics(out, model, result.t, result.effort, result.force, result.torque,
                        driven, families)
    scalars = {"energy_drift": result.energy_drift,
               "max_position_violation": result.max_position_violation,
               "max_velocity_violation": result.max_velocity_violation,
               "t_reached": float(result.t[-1]),
               "steps": float(result.counters.as_dict().get("steps", np.nan))}
    for name, value in scalars.items():
        if name in families:
            out[name] = float("nan") if value is None else float(value)
    return out


def _wrench_metrics(out: dict, model, t, effort, force, torque, driven, families) -> None:
    for joint in driven:
        tau = effort[:, joint.index]
        if "peak_effort" in families:
            out[f"peak_effort:{joint.name}"] = float(np.max(np.abs(tau)))
        if "rms_effort" in families:
            out[f"rms_effort:{joint.name}"] = time_rms(t, tau)
    feet = {c.joint for c in model.contacts}
    for joint in model.joints:
        if joint.index in feet:
            continue
        if "peak_force" in families:
            out[f"peak_force:{joint.name}"] = float(np.max(np.linalg.norm(force[:, joint.index],
                                                                          axis=-1)))
        if "peak_moment" in families:
            out[f"peak_moment:{joint.name}"] = float(np.max(np.linalg.norm(
                torque[:, joint.index], axis=-1)))


def joint_rates(model, t, joints) -> np.ndarray:
    """The rates of the driven joints' coordinates at ``t`` (N, len(joints)): their drivers'
    law derivatives (zero for a constant law)."""
    _, wd, _ = model.law_values(t)
    return by_driver_law(model, np.asarray(wd).reshape(model.n_w, -1), joints).T


def by_driver_law(model, values: np.ndarray, joints) -> np.ndarray:
    """Each of ``joints``' entry of ``values`` (laws first: n_w x ...), that of its driver's
    law, zero for a constant law: (len(joints), ...)."""
    out = np.zeros((len(joints),) + values.shape[1:])
    for k, joint in enumerate(joints):
        for row in joint.driver_rows:
            driver = next(d for d in model.drivers if d.row == row)
            if driver.law >= 0:
                out[k] = values[driver.law]
    return out


def positive_work(model, t, effort, joints) -> float:
    """``int sum_j max(tau_j w_j, 0) dt`` over the samples (J): what the actuators spend when
    braking recovers nothing."""
    if len(t) < 2 or not joints:
        return 0.0
    power = effort[:, [j.index for j in joints]] * joint_rates(model, t, joints)
    return time_integral(t, np.maximum(power, 0.0).sum(axis=1))


def cost_of_transport(model, q: np.ndarray, work: float, masses=None) -> float:
    """``work / (m g d)``, ``d`` the horizontal displacement of the model's centre of mass
    between the first and last samples; NaN when it does not move or there is no gravity.
    ``masses``: the bodies' (default the model's)."""
    g = float(np.linalg.norm(model.gravity))
    masses = body_masses(model, masses)
    mass = float(masses.sum())
    if g == 0.0 or mass == 0.0:
        return float("nan")
    dim = model.dimension
    centre = sum(m * q[:, b.q][:, :dim] for m, b in zip(masses, model.bodies, strict=True)) \
        / mass
    shift = centre[-1] - centre[0]
    down = np.asarray(model.gravity, dtype=float) / g
    distance = float(np.linalg.norm(shift - (shift @ down) * down))
    scale = model.characteristic_length or 1.0
    if distance <= 1e-9 * scale:
        return float("nan")
    return work / (mass * g * distance)


def body_masses(model, masses=None) -> np.ndarray:
    """The bodies' masses in model order: ``masses`` when given, else the model's."""
    if masses is None:
        return np.array([b.mass for b in model.bodies], dtype=float)
    return np.asarray(masses, dtype=float).reshape(len(model.bodies))
