"""The planar joint: the child slides and turns in a plane of the parent."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from hexapod.scene.joints.base import AXIS, Joint, register
from hexapod.scene.joints.geometry import ANGLE, LENGTH


@register
@dataclass(eq=False)
class PlanarJoint(Joint):
    """The child frame slides and turns in the plane of the parent frame whose normal is
    ``axis`` (joint frame; default z): two translations and a rotation, 3 rows, ``ax1, ax2``
    (the normals stay aligned) and ``t = a_p . d``. Space only.

    Parameters
    ----------
    name, parent, child, parent_frame, child_frame, origin, rotation, source :
        As for every joint (:class:`~hexapod.scene.joints.base.Joint`).
    axis : array_like, shape (3,), optional
        The plane's normal in the joint frame (default z).
    """

    axis: np.ndarray | None = None
    kind = "planar"
    default_axis = {3: (0.0, 0.0, 1.0)}
    plane_hint = "no joint (a free planar body)"

    @classmethod
    def file_keys(cls, dimension):
        return {"axis": AXIS}

    def rows(self, g, laws=None):
        u, w, a = g.triad()
        a_c = g.child_vector(a)
        return [("ax1", ca.dot(g.parent_vector(u), a_c), ANGLE),
                ("ax2", ca.dot(g.parent_vector(w), a_c), ANGLE),
                ("t", ca.dot(g.parent_vector(a), g.gap), LENGTH)]
