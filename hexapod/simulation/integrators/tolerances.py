"""Absolute tolerances per kind of coordinate (positions, angles and Euler parameters, and
their rates), and the unit of each component of an integrator's state."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from hexapod.model.model import Model
from hexapod.model.units import COORDINATE_UNITS, VELOCITY_UNITS, component
from hexapod.simulation.methods import ATOL_KINDS, DEFAULT_ATOL
from hexapod.simulation.scales import characteristic_time

#: the kind of tolerance of a coordinate, by the coordinate's unit
KIND_OF_UNIT = {unit: kind for kind, units in ATOL_KINDS.items() for unit in units}


def state_units(model: Model) -> list[str]:
    """The unit of each component of ``(q, v)``, as the results' columns say it (read once
    per model: every run's start asked, 0.15 ms of a 10-link chain's)."""
    return list(model.built_once(("state units",), lambda m: tuple(
        [COORDINATE_UNITS[component(name)][0] for name in m.coordinate_names]
        + [VELOCITY_UNITS[component(name)][0] for name in m.velocity_names])))


def default_tolerances(model: Model) -> dict[str, float]:
    """The absolute tolerances per kind when a mapping leaves a kind out: positions
    ``DEFAULT_ATOL L`` (m), angles and Euler parameters ``DEFAULT_ATOL`` (rad), their rates the
    same over :func:`characteristic_time` (m/s, rad/s)."""
    length, time = float(model.characteristic_length), characteristic_time(model)
    return {"position": DEFAULT_ATOL * length, "angle": DEFAULT_ATOL,
            "velocity": DEFAULT_ATOL * length / time, "angular_velocity": DEFAULT_ATOL / time}


def absolute_tolerances(model: Model, atol) -> dict[str, float]:
    """The absolute tolerance of each kind of coordinate (:data:`ATOL_KINDS`: ``position`` m,
    ``angle`` rad and Euler parameters, ``velocity`` m/s, ``angular_velocity`` rad/s).

    Parameters
    ----------
    atol : float, mapping or None
        None: :data:`DEFAULT_ATOL` for every kind; a number: that for every kind (SI units); a
        mapping of kinds to numbers: those, and :func:`default_tolerances` for the kinds it
        leaves out.

    Raises
    ------
    ValueError
        A mapping names an unknown kind, or gives a value that is not a positive number.
    """
    if atol is None:
        return dict.fromkeys(ATOL_KINDS, DEFAULT_ATOL)
    if not isinstance(atol, Mapping):
        return dict.fromkeys(ATOL_KINDS, float(atol))
    unknown = set(atol) - set(ATOL_KINDS)
    if unknown:
        raise ValueError(f"atol: unknown kind {sorted(unknown)[0]!r}: choose among "
                         + ", ".join(ATOL_KINDS))
    kinds = default_tolerances(model)
    for kind, value in atol.items():
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"atol[{kind!r}] must be a positive number, got {value!r}") from None
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"atol[{kind!r}] must be a positive number, got {value}")
        kinds[kind] = value
    return kinds
