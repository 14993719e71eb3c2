"""Derivatives of a case's figures of merit (:mod:`hexapod.sweeps.metrics`) from the derivatives
of its forces (:func:`hexapod.algorithms.sensitivity.inverse_sensitivities`).

Each family's derivative follows its definition in ``metrics``:

=====================  ==========================================================================
family                 derivative
=====================  ==========================================================================
peak_effort:J          at the peak sample: ``sign(tau) dtau/dp`` (the first sample of the largest
                       ``|tau|``; a peak shared by two samples has two one-sided derivatives)
rms_effort:J           ``int tau dtau/dp dt / (T rms)`` (trapezoidal, as the value)
peak_force:J,          at the peak sample: ``F . dF/dp / |F|``
peak_moment:J,
peak_ground:LEG
energy                 ``int sum [tau w > 0] (w dtau/dp + tau dw/dp) dt`` per stride (the joint
                       rates ``w`` change with the parameters that change the laws only)
cost_of_transport      ``E / (m g d)``: the energy's derivative, and the mass's and the distance's
                       (the centre of mass's path moves with the masses and the joints)
=====================  ==========================================================================
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from hexapod.output.summary_parts import time_integral
from hexapod.sweeps.metrics import (
    body_masses,
    by_driver_law,
    cost_of_transport,
    joint_rates,
    metric_unit,
    positive_work,
)

if TYPE_CHECKING:
    from hexapod.algorithms.inverse import InverseResult
    from hexapod.algorithms.sensitivity import InverseSensitivity
    from hexapod.model.model import Model

#: The families with a derivative, in the table's order.
SENSITIVE_FAMILIES = ("peak_effort", "rms_effort", "peak_force", "peak_moment", "peak_ground",
                      "energy", "cost_of_transport")


def _peak(values: np.ndarray, derivatives: np.ndarray) -> np.ndarray:
    """``d max|x|`` at the first sample of the peak: ``values`` (N,) or (N, 3), their
    derivatives (N, P) or (N, 3, P)."""
    if values.ndim == 1:
        k = int(np.argmax(np.abs(values)))
        return np.sign(values[k]) * derivatives[k]
    size = np.linalg.norm(values, axis=-1)
    k = int(np.argmax(size))
    if size[k] == 0.0:
        return np.zeros(derivatives.shape[-1])
    return values[k] @ derivatives[k] / size[k]


def metric_sensitivities(model: Model, result: InverseResult, sensitivity: InverseSensitivity,
                         families: Sequence[str] = SENSITIVE_FAMILIES,
                         strides: float = 1.0, masses: np.ndarray | None = None
                         ) -> dict[str, np.ndarray]:
    """The derivative of each figure of merit with respect to each parameter.

    Parameters
    ----------
    model : Model
    result : InverseResult
        The inverse dynamics the figures are computed from.
    sensitivity : InverseSensitivity
        Its derivatives.
    families : sequence of str
        Families of :data:`SENSITIVE_FAMILIES`.
    strides : float
        The window in strides (the energy is per stride).
    masses : ndarray, optional
        The bodies' masses (default the model's), as for
        :func:`~hexapod.sweeps.metrics.inverse_metrics`.

    Returns
    -------
    dict
        Metric column (as :func:`hexapod.sweeps.metrics.inverse_metrics` names it) -> the
        derivatives (P,), in the metric's unit per the parameter's unit.
    """
    out: dict[str, np.ndarray] = {}
    t = result.times
    driven = [j for j in model.joints if j.driver_rows.size and j.type.drivable]
    for joint in driven:
        tau, dtau = result.effort[:, joint.index], sensitivity.effort[:, joint.index]
        if "peak_effort" in families:
            out[f"peak_effort:{joint.name}"] = _peak(tau, dtau)
        if "rms_effort" in families:
            out[f"rms_effort:{joint.name}"] = _rms(t, tau, dtau)
    feet = {c.joint for c in model.contacts}
    for joint in model.joints:
        if joint.index in feet:
            continue
        for family, values, derivatives in (("peak_force", result.force, sensitivity.force),
                                            ("peak_moment", result.torque, sensitivity.torque)):
            if family in families:
                out[f"{family}:{joint.name}"] = _peak(values[:, joint.index],
                                                      derivatives[:, joint.index])
    if "peak_ground" in families and model.contacts:
        from hexapod.output.ground import foot_loads

        legs = foot_loads(model, result).legs
        for c, leg in enumerate(legs):
            out[f"peak_ground:{leg}"] = _peak(result.ground_force[:, c],
                                              sensitivity.ground_force[:, c])
    if {"energy", "cost_of_transport"} & set(families):
        dwork = _work(model, t, result.effort, sensitivity, driven)
        if "energy" in families:
            out["energy"] = dwork / strides
        if "cost_of_transport" in families:
            out["cost_of_transport"] = _transport(model, result, sensitivity, driven, dwork,
                                                  body_masses(model, masses))
    return out


def _rms(t: np.ndarray, tau: np.ndarray, dtau: np.ndarray) -> np.ndarray:
    if t.size < 2:
        return _peak(tau, dtau)
    span = t[-1] - t[0]
    rms = np.sqrt(time_integral(t, tau**2) / span)
    if rms == 0.0:
        return np.zeros(dtau.shape[-1])
    return np.array([time_integral(t, tau * d) for d in dtau.T]) / (span * rms)


def _work(model, t, effort, sensitivity, driven) -> np.ndarray:
    """The derivative of :func:`hexapod.sweeps.metrics.positive_work`: ``int sum [tau w > 0]
    (w dtau + tau dw) dt``, ``dw`` the joint rates' derivatives (nonzero for parameters that
    change the laws). Where a sample's power is exactly zero (a joint at rest there, as a
    coupled joint at the top of its swing) ``max(P, 0)`` has a kink: the mean of its
    one-sided derivatives, which central differences see."""
    deffort = sensitivity.effort
    if len(t) < 2 or not driven:
        return np.zeros(deffort.shape[-1])
    columns = [j.index for j in driven]
    rates = joint_rates(model, t, driven)
    tau = effort[:, columns]
    power = tau * rates
    spending = (power > 0.0) + 0.5 * (power == 0.0)
    drates = _joint_rate_changes(model, sensitivity, driven)
    return np.array([time_integral(t, (spending * (rates * deffort[:, columns, p]
                                                   + tau * drates[..., p])).sum(axis=1))
                     for p in range(deffort.shape[-1])])


def _joint_rate_changes(model, sensitivity, joints) -> np.ndarray:
    """The derivatives of the driven ``joints``' rates (N, len(joints), P), from those of
    their drivers' laws (as :func:`hexapod.sweeps.metrics.joint_rates` reads the rates)."""
    if sensitivity.rates is None:
        n, count = sensitivity.effort.shape[0], sensitivity.effort.shape[-1]
        return np.zeros((n, len(joints), count))
    # (N, n_w, P) -> laws first -> (J, N, P) -> (N, J, P)
    return by_driver_law(model, sensitivity.rates.transpose(1, 0, 2), joints).transpose(1, 0, 2)


def _transport(model, result, sensitivity, driven, dwork, masses) -> np.ndarray:
    """The derivative of :func:`hexapod.sweeps.metrics.cost_of_transport`."""
    work = positive_work(model, result.times, result.effort, driven)
    value = cost_of_transport(model, result.q, work, masses)
    if not np.isfinite(value):
        return np.full(dwork.shape, np.nan)
    g = np.asarray(model.gravity, dtype=float)
    down = g / np.linalg.norm(g)
    mass, dim, q = float(masses.sum()), model.dimension, result.q

    def horizontal(x):
        return x - (x @ down) * down

    shift = horizontal(sum(m * (q[-1, b.q][:dim] - q[0, b.q][:dim])
                           for m, b in zip(masses, model.bodies, strict=True)) / mass)
    distance = np.linalg.norm(shift)
    dq = sensitivity.q[[0, -1]]  # the ends' positions move with a joint's position
    out = np.empty(dwork.shape)
    for p, change in enumerate(sensitivity.parameters):
        dshift = horizontal(sum(m * (dq[1, b.q, p][:dim] - dq[0, b.q, p][:dim])
                                for m, b in zip(masses, model.bodies, strict=True)) / mass)
        if change.mass and getattr(change, "body", None) is not None:  # one body's mass
            # (the scale's, every body's in proportion, leaves the centre of mass in place)
            body = model.bodies[model.body_index[change.body]]
            own = horizontal(q[-1, body.q][:dim] - q[0, body.q][:dim])
            dshift = dshift + change.mass * (own - shift) / mass
        ddistance = shift @ dshift / distance
        out[p] = (dwork[p] / (mass * np.linalg.norm(g) * distance)
                  - value * (change.mass / mass + ddistance / distance))
    return out


def sensitivity_rows(model, metrics: dict[str, float], derivatives: dict[str, np.ndarray],
                     parameters) -> list[dict]:
    """The rows of ``sensitivities.csv``: per metric and parameter the derivative, its unit
    and the elasticity ``(p / m) dm/dp`` (NaN where the metric is zero)."""
    rows = []
    for column, values in derivatives.items():
        metric = metrics[column]
        unit = metric_unit(model, column) or "1"
        for change, value in zip(parameters, values, strict=True):
            per = f"({change.unit})" if " " in change.unit else change.unit
            elasticity = (change.value / metric * value) if metric else float("nan")
            rows.append({"metric": column, "parameter": change.name, "value": float(value),
                         "unit": f"{unit}/{per}", "elasticity": float(elasticity)})
    return rows
