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
