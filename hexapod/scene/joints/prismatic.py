"""The prismatic joint: one translation along an axis."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from hexapod.scene.joints.base import AXIS, LIMITS, Joint, register
from hexapod.scene.joints.geometry import (
    ANGLE,
    LENGTH,
    JointGeometry,
    axial_displacement,
    normal_in_plane,
)


@register
@dataclass(eq=False)
class Prismatic(Joint):
    """One translation along ``axis`` (in the joint frame; default x in the plane, z in space).
    5 rows in space, 2 in the plane. The displacement is that of the child frame's origin from
    the parent frame's origin, along the axis.

    Rows: ``ax1, ax2`` (the axes stay aligned), ``rot = w_p . u_c``, ``t1 = u_p . d``,
    ``t2 = w_p . d``; in the plane ``rot`` (relative angle) and ``t = n_p . d`` (``n`` normal to
    the axis). A driver sets ``a_p . d - f``.

    Parameters
    ----------
    name, parent, child, parent_frame, child_frame, origin, rotation, source :
        As for every joint (:class:`~hexapod.scene.joints.base.Joint`).
    axis : array_like, shape (3,) or (2,), optional
        The sliding axis in the joint frame (default z in space, x in the plane).
    limits : array_like, shape (2,), optional
        ``[lower, upper]``, the range of the displacement, L, which the inverse dynamics
        checks a motion against (default: none).
    """

    axis: np.ndarray | None = None
    limits: np.ndarray | None = None
    kind = "prismatic"
    drivable = True
    default_axis = {3: (0.0, 0.0, 1.0), 2: (1.0, 0.0)}
    exists_in_plane = True
    coordinate_unit, effort_unit = LENGTH, "N"
    urdf_types = ("prismatic",)

    @classmethod
    def file_keys(cls, dimension):
        return {"axis": AXIS, "limits": LIMITS}

    def rows(self, g: JointGeometry, laws=None):
        d = g.gap
        if g.dimension == 2:
            return [("rot", g.relative_angle(), ANGLE),
                    ("t", ca.dot(g.parent_vector(normal_in_plane(g.axis)), d), LENGTH)]
        u, w, a = g.triad()
        a_c = g.child_vector(a)
        u_p, w_p = g.parent_vector(u), g.parent_vector(w)
        return [("ax1", ca.dot(u_p, a_c), ANGLE), ("ax2", ca.dot(w_p, a_c), ANGLE),
                ("rot", ca.dot(w_p, g.child_vector(u)), ANGLE),
                ("t1", ca.dot(u_p, d), LENGTH), ("t2", ca.dot(w_p, d), LENGTH)]

    def driver_row(self, g, f):
        return axial_displacement(g) - f

    def rate(self, g, q, qdot):
        return ca.jtimes(axial_displacement(g), q, qdot)

    def twist(self, dimension):
        return self._axis_twist(dimension, 1.0, 0.0)

    def tree_step(self, value):
        """No rotation, a translation by ``value`` along the axis (parent's joint frame)."""
        return None, value * ca.DM(self.unit_axis(3))
