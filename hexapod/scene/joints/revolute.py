"""The revolute joint: one rotation about an axis."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from hexapod.scene.joints.base import AXIS, LIMITS, Joint, register
from hexapod.scene.joints.geometry import (
    ANGLE,
    JointGeometry,
    angle_rate,
    point_rows,
    wrapped_angle,
)


@register
@dataclass(eq=False)
class Revolute(Joint):
    """One rotation about ``axis`` (in the joint frame; default z). 5 rows in space, 2 in the plane
    (where the axis is always normal to the plane). The joint angle is measured from the parent
    frame to the child frame, positive about the axis.

    Rows: ``x, y, z`` (the frame origins coincide), ``ax1 = u_p . a_c``, ``ax2 = w_p . a_c``;
    in the plane ``x, y``. A driver sets the **wrapped** angle difference
    ``atan2(sin(theta - f), cos(theta - f))``.

    Parameters
    ----------
    name, parent, child, parent_frame, child_frame, origin, rotation, source :
        As for every joint (:class:`~hexapod.scene.joints.base.Joint`).
    axis : array_like, shape (3,), optional
        The rotation axis in the joint frame (default z); ignored in the plane.
    limits : array_like, shape (2,), optional
        ``[lower, upper]``, the range of the joint angle, rad, which the inverse dynamics
        checks a motion against (default: none).
    """

    axis: np.ndarray | None = None
    limits: np.ndarray | None = None
    kind = "revolute"
    drivable = True
    default_axis = {3: (0.0, 0.0, 1.0)}  # in the plane: the plane's normal, not stored
    exists_in_plane = True
    particle_ends = {2: "pc"}
    turns = True
    coordinate_unit, effort_unit = ANGLE, "N m"
    urdf_types = ("revolute", "continuous")

    def __post_init__(self):
        self.axis = np.array(self.default_axis[3] if self.axis is None else self.axis,
                             dtype=float).reshape(-1)
        super().__post_init__()

    @classmethod
    def file_keys(cls, dimension):
        return {"axis": AXIS, "limits": LIMITS} if dimension == 3 else {"limits": LIMITS}

    def rows(self, g: JointGeometry, laws=None):
        if g.dimension == 2:
            return point_rows(g)
        u, w, a = g.triad()
        a_c = g.child_vector(a)
        return point_rows(g) + [("ax1", ca.dot(g.parent_vector(u), a_c), ANGLE),
                                ("ax2", ca.dot(g.parent_vector(w), a_c), ANGLE)]

    def driver_row(self, g, f):
        return wrapped_angle(g, f)

    def rate(self, g, q, qdot):
        return angle_rate(g)

    def twist(self, dimension):
        return self._axis_twist(dimension, 0.0, 1.0)

    def tree_step(self, value):
        """A rotation by ``value`` about the axis (Euler parameters), no translation."""
        half = value / 2
        return ca.vertcat(ca.cos(half), ca.sin(half) * ca.DM(self.unit_axis(3))), None
