"""The universal (Cardan) joint."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from hexapod.scene.element import check_axis
from hexapod.scene.joints.base import AXIS, Joint, register
from hexapod.scene.joints.geometry import ANGLE, point_rows


@register
@dataclass(eq=False)
class Universal(Joint):
    """A Cardan joint: rotations about ``axis`` (fixed to the parent, default x) and ``axis2``
    (fixed to the child, default y), both given in the joint frame and perpendicular. The two
    frame origins coincide: 4 rows, ``x, y, z`` and ``cross = a_p . b_c`` (``a`` the parent's
    axis, ``b`` the child's). Space only.

    Parameters
    ----------
    name, parent, child, parent_frame, child_frame, origin, rotation, source :
        As for every joint (:class:`~hexapod.scene.joints.base.Joint`).
    axis, axis2 : array_like, shape (3,), optional
        The axis fixed to the parent (default x) and the one fixed to the child (default y),
        in the joint frame; perpendicular.
    """

    axis: np.ndarray | None = None
    axis2: np.ndarray | None = None
    kind = "universal"
    default_axis = {3: (1.0, 0.0, 0.0)}
    plane_hint = "a revolute joint"

    def __post_init__(self):
        self.axis = np.array(self.default_axis[3] if self.axis is None else self.axis,
                             dtype=float).reshape(-1)
        self.axis2 = np.array((0.0, 1.0, 0.0) if self.axis2 is None else self.axis2,
                              dtype=float).reshape(-1)
        super().__post_init__()

    def problems(self):
        out = super().problems()
        check_axis(self, "axis2", self.axis2, out)
        if not out and self.axis.size == self.axis2.size == 3:
            cosine = self.axis @ self.axis2 / np.linalg.norm(self.axis) / np.linalg.norm(
                self.axis2)
            if abs(cosine) > 1e-9:
                out.append(self.problem("axis2", f"must be perpendicular to axis (cosine "
                                        f"{cosine:.3g})"))
        return out

    @classmethod
    def file_keys(cls, dimension):
        return {"axis": AXIS, "axis2": AXIS}

    def rows(self, g, laws=None):
        b = self.axis2 / np.linalg.norm(self.axis2)  # the child's axis, unit
        return point_rows(g) + [("cross", ca.dot(g.parent_vector(g.axis), g.child_vector(b)),
                                 ANGLE)]
