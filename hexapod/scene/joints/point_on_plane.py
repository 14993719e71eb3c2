"""The point-on-plane joint: a foot on the ground."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from hexapod.scene.joints.base import AXIS, Joint, register
from hexapod.scene.joints.geometry import LENGTH


@register
@dataclass(eq=False)
class PointOnPlane(Joint):
    """The child frame's origin stays on the plane through the parent frame's origin with
    normal ``axis`` (joint frame on the parent; default z, or y in the plane, where the plane is
    a line): a foot on the ground. 1 row, ``normal = a_p . d``; the child may be a particle.

    Parameters
    ----------
    name, parent, child, parent_frame, child_frame, origin, rotation, source :
        As for every joint (:class:`~hexapod.scene.joints.base.Joint`).
    axis : array_like, shape (3,) or (2,), optional
        The plane's normal in the joint frame on the parent (default z in space, y in the
        plane).
    """

    axis: np.ndarray | None = None
    kind = "point-on-plane"
    default_axis = {3: (0.0, 0.0, 1.0), 2: (0.0, 1.0)}
    exists_in_plane = True
    particle_ends = {3: "c", 2: "c"}

    @classmethod
    def file_keys(cls, dimension):
        return {"axis": AXIS}

    def rows(self, g, laws=None):
        return [("normal", ca.dot(g.parent_vector(g.axis), g.gap), LENGTH)]
