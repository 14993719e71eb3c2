"""The cylindrical joint: rotation about and translation along an axis."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from hexapod.scene.joints.base import AXIS, Joint, register
from hexapod.scene.joints.geometry import ANGLE, LENGTH, normal_in_plane


@register
@dataclass(eq=False)
class Cylindrical(Joint):
    """Rotation about and translation along ``axis`` (joint frame; default z): 4 rows in space,
    ``ax1, ax2`` (the axes stay aligned), ``t1 = u_p . d``, ``t2 = w_p . d`` (the child frame's
    origin stays on the parent's axis). In the plane it is a pin in a slot along ``axis``
    (default x): the child frame's origin stays on the parent's line, ``t = n_p . d``, and the
    child may turn (1 row).

    Parameters
    ----------
    name, parent, child, parent_frame, child_frame, origin, rotation, source :
        As for every joint (:class:`~hexapod.scene.joints.base.Joint`).
    axis : array_like, shape (3,) or (2,), optional
        The axis in the joint frame (default z in space, x in the plane).
    """

    axis: np.ndarray | None = None
    kind = "cylindrical"
    default_axis = {3: (0.0, 0.0, 1.0), 2: (1.0, 0.0)}
    exists_in_plane = True
    particle_ends = {2: "c"}
    turns = True

    @classmethod
    def file_keys(cls, dimension):
        return {"axis": AXIS}

    def rows(self, g, laws=None):
        d = g.gap
        if g.dimension == 2:
            return [("t", ca.dot(g.parent_vector(normal_in_plane(g.axis)), d), LENGTH)]
        u, w, a = g.triad()
        a_c = g.child_vector(a)
        u_p, w_p = g.parent_vector(u), g.parent_vector(w)
        return [("ax1", ca.dot(u_p, a_c), ANGLE), ("ax2", ca.dot(w_p, a_c), ANGLE),
                ("t1", ca.dot(u_p, d), LENGTH), ("t2", ca.dot(w_p, d), LENGTH)]
