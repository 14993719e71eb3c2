"""Reports of inverse dynamics: the CSV of the ``hexapod inverse`` contract.

Columns: ``t``, then for every joint in model order ``tau:<joint>`` (revolute and prismatic
joints: N m or N), ``Fx:<joint>``, ``Fy:<joint>``, ``Fz:<joint>``, ``Tx:<joint>``,
``Ty:<joint>``, ``Tz:<joint>`` (N, N m): the wrench exerted by the parent on the child, about
the joint origin, in the child's joint frame (or world axes on request). Fixed joints and the
other joints without an axis have the force and moment columns without ``tau``. Numbers are
written with 17 significant digits, so they read back exactly.
"""

from __future__ import annotations

import numpy as np

from hexapod.inverse import InverseResult
from hexapod.model import Model

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
    rows = inverse_table(model, result)
    lines = [",".join(inverse_columns(model))]
    lines += [",".join(format(x, ".17g") for x in row) for row in rows]
    return "\n".join(lines) + "\n"
