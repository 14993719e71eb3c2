"""The CSV of ``hexapod inverse``, the contract other tools rely on, and its units sidecar.

Columns: ``t``, then for every joint in model order ``tau:<joint>`` (revolute and prismatic
joints: N m or N), ``Fx:<joint>``, ``Fy:<joint>``, ``Fz:<joint>``, ``Tx:<joint>``,
``Ty:<joint>``, ``Tz:<joint>`` (N, N m): the wrench exerted by the parent on the child, about
the joint origin, in the child's joint frame (or world axes on request). Fixed joints and the
other joints without an axis have the force and moment columns without ``tau``. A model with
foot contacts (a walking robot) has, after the joints' columns, ``GRx:<leg>``, ``GRy:<leg>``,
``GRz:<leg>`` per contact: the ground's force on the foot in world axes (N), zero in swing,
``<leg>`` the contact's name without its ``/ground`` suffix, then ``status:<leg>`` per contact:
whether the ground can give the foot its force, as a number (0 swing, 1 ok, 2 slip: outside
the friction cone, 3 pull: the ground pulling the foot). Numbers are written with 17
significant digits, so they read back exactly. Each column's unit and meaning
(:func:`inverse_column_units`) are written beside the CSV: ``OUT.units.json`` for ``hexapod
inverse``, ``units.json`` in the report's directory (``docs/outputs.md``).

Apart from the report (:mod:`hexapod.output.report`, which re-exports these functions) so that
``hexapod inverse`` loads neither the report's statistics nor the feet's (about 8 ms of its
start).
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from hexapod._support.files import write_atomically
from hexapod.errors import HexapodError
from hexapod.simulation.results import Columns, units_json, wrench_columns

if TYPE_CHECKING:
    from hexapod.algorithms.inverse import InverseResult
    from hexapod.model.model import Model


def inverse_column_units(model: Model, frame: str = "joint") -> Columns:
    """The columns of the inverse-dynamics CSV in order, each with its unit and meaning (the
    wrenches in the child's joint frame, or world axes for ``frame="world"``)."""
    columns = {"t": ("s", "time"), **wrench_columns(model, frame)}
    if model.contacts:  # a walking robot's feet (the module that names them loads more)
        from hexapod.output.ground import ground_columns

        columns.update(ground_columns(model))
    return columns


def inverse_columns(model: Model) -> list[str]:
    """The header of the inverse-dynamics CSV.

    Parameters
    ----------
    model : Model

    Returns
    -------
    list of str
        ``t``, then ``tau:<joint>`` (joints with a coordinate), ``Fx:<joint> .. Tz:<joint>``
        per joint, then ``GRx:<leg> .. GRz:<leg>`` and ``status:<leg>`` per foot contact (the
        module's description).
    """
    return list(inverse_column_units(model))


def inverse_table(model: Model, result: InverseResult) -> np.ndarray:
    """The rows of the CSV: one per sample, columns as :func:`inverse_columns`.

    Parameters
    ----------
    model : Model
    result : InverseResult
        From :func:`hexapod.inverse_dynamics` on ``model``.

    Returns
    -------
    ndarray, shape (N, len(inverse_columns(model)))
        s, N, N m.
    """
    columns = [result.times[:, None]]
    for k, joint in enumerate(model.joints):
        if joint.type.drivable:
            columns.append(result.effort[:, k, None])
        columns += [result.force[:, k], result.torque[:, k]]
    if model.contacts:
        if result.ground_force is None:
            raise HexapodError(f"model '{model.name}' has foot contacts but the result has no "
                               "ground forces")
        from hexapod.output.ground import status_codes

        # + 0.0: zero in swing written 0, not -0
        columns.append(np.asarray(result.ground_force).reshape(result.times.size, -1) + 0.0)
        columns.append(status_codes(result.ground_status))
    return np.hstack(columns)


def inverse_csv_text(model: Model, result: InverseResult) -> str:
    """The CSV of ``hexapod inverse``: a header of :func:`inverse_columns` (``t``, then per joint
    ``tau`` where it has one and ``Fx .. Tz``; N, N m; then per foot contact ``GRx .. GRz``, N)
    and one row per sample, every number written to round-trip (17 significant digits).

    Parameters
    ----------
    model : Model
    result : InverseResult
        From :func:`hexapod.inverse_dynamics` on ``model``.

    Returns
    -------
    str
        The file's text (nothing is written).
    """
    rows = inverse_table(model, result)
    line = ",".join(["%.17g"] * rows.shape[1])
    return ",".join(inverse_columns(model)) + "\n" + "".join(
        line % tuple(row) + "\n" for row in rows)


def units_path(csv_path: str | Path) -> Path:
    """Where the units of a CSV written alone go: ``OUT.units.json`` beside ``OUT.csv``."""
    return Path(csv_path).with_suffix(".units.json")


def write_inverse_files(out: str | Path, model: Model, result: InverseResult) -> None:
    """Write ``hexapod inverse --out OUT.csv``: the units sidecar ``OUT.units.json`` first, so
    that the CSV never stands without it, then the CSV, each atomically; a CSV that cannot be
    written (an interruption, a full disk) takes its sidecar with it."""
    text = inverse_csv_text(model, result)
    sidecar = units_path(out)
    write_atomically(sidecar, units_json({Path(out).name: inverse_column_units(model,
                                                                             result.frame)}))
    try:
        write_atomically(out, text)
    except BaseException:
        with contextlib.suppress(OSError):
            sidecar.unlink()
        raise
