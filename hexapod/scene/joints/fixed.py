"""The fixed joint (a weld)."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from hexapod.scene.joints.base import Joint, register
from hexapod.scene.joints.geometry import ANGLE, point_rows


@register
@dataclass(eq=False)
class Fixed(Joint):
    """A weld: no relative motion (6 rows in space, 3 in the plane).

    Rows: ``x, y, z``, ``rx = z_p . y_c``, ``ry = x_p . z_c``, ``rz = y_p . x_c``; in the plane
    ``x, y, rot``.

    Parameters
    ----------
    name, parent, child, parent_frame, child_frame, origin, rotation, source :
        As for every joint (:class:`~hexapod.scene.joints.base.Joint`).
    """

    kind = "fixed"
    exists_in_plane = True
    urdf_types = ("fixed",)

    def rows(self, g, laws=None):
        if g.dimension == 2:
            return point_rows(g) + [("rot", g.relative_angle(), ANGLE)]
        e = np.eye(3)
        x_p, y_p, z_p = (g.parent_vector(e[i]) for i in range(3))
        x_c, y_c, z_c = (g.child_vector(e[i]) for i in range(3))
        return point_rows(g) + [("rx", ca.dot(z_p, y_c), ANGLE), ("ry", ca.dot(x_p, z_c), ANGLE),
                                ("rz", ca.dot(y_p, x_c), ANGLE)]

    def tree_step(self, value):
        """The child frame is the parent's: no rotation, no translation."""
        return None, None
