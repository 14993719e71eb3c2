"""The spherical (ball) joint."""

from __future__ import annotations

from dataclasses import dataclass

from hexapod.scene.joints.base import Joint, register
from hexapod.scene.joints.geometry import point_rows


@register
@dataclass(eq=False)
class Spherical(Joint):
    """A ball joint: the two frame origins coincide (3 rows ``x, y, z``). Space only (in the
    plane it would be a revolute joint).

    Parameters
    ----------
    name, parent, child, parent_frame, child_frame, origin, rotation, source :
        As for every joint (:class:`~hexapod.scene.joints.base.Joint`).
    """

    kind = "spherical"
    plane_hint = "a revolute joint"
    particle_ends = {3: "pc"}

    def rows(self, g, laws=None):
        return point_rows(g)
