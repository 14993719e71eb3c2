"""The distance joint: a rigid link between two points."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from hexapod.scene.element import check_finite
from hexapod.scene.joints.base import NUMBER, Joint, register
from hexapod.scene.joints.geometry import LENGTH


@register
@dataclass(eq=False)
class Distance(Joint):
    """A rigid link between the parent frame's origin and the child frame's origin (1 row,
    ``length = (d . d - L^2) / (2 L)``, in space and in the plane).

    ``length`` defaults to the distance at the initial pose; the rods of Richard, Anderson and
    Andrews (1989/90) are distance joints between particles.

    Parameters
    ----------
    name, parent, child, parent_frame, child_frame, origin, rotation, source :
        As for every joint (:class:`~hexapod.scene.joints.base.Joint`).
    length : float, optional
        The distance held between the two frame origins (L); default: the distance at the
        initial pose.
    """

    length: float | None = None
    kind = "distance"
    exists_in_plane = True
    particle_ends = {3: "pc", 2: "pc"}
    joins_two_points = True

    def problems(self):
        out = super().problems()
        if self.length is not None and check_finite(self, "length", self.length, out) and (
            not self.length > 0
        ):
            out.append(self.problem("length", f"must be positive, got {self.length}"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        if self.length is not None:
            out.length = self.length * length
        return out

    @classmethod
    def file_keys(cls, dimension):
        return {"length": (NUMBER, False)}

    def rows(self, g, laws=None):
        length = self.length
        if length is None:
            parent, child = g.initial
            length = float(np.linalg.norm(child - parent))
        d = g.gap
        return [("length", (ca.dot(d, d) - length**2) / (2.0 * length), LENGTH)]
