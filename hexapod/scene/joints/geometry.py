"""A joint's two frames on their bodies, as the rows, driver rows and rates of the joint types
need them, and the measures several types share (the point, the angle about the axis, the
displacement along it).

A :class:`JointGeometry` is handed to a joint type by the assembly (:mod:`hexapod.model`): its
two body states give each body's pose and motion as CasADi expressions of the model's symbols
(``point``, ``direction``, ``frame_angle``, ``omega``: :class:`hexapod.model.frames.BodyState`),
so the joint types write their residuals without knowing how bodies are parametrised. Notation:
``d`` is the world vector from the parent frame's origin to the child frame's origin; ``u, w, a``
is a right-handed orthonormal triad of the joint frame with ``a`` the joint axis; a subscript
``p`` or ``c`` is that vector fixed to the parent's or to the child's frame, in world axes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from hexapod.spatial import Placement, orthonormal_complement

#: the unit kinds of a row (and of a joint coordinate)
LENGTH, ANGLE = "length", "angle"

#: one constraint row: its name within the joint, its residual (CasADi SX), its unit kind
Row = tuple[str, Any, str]


@dataclass
class JointGeometry:
    """A joint's two frames on their bodies.

    Attributes
    ----------
    parent, child : BodyState
        The bodies' poses and motions as CasADi expressions (the ground's: constants).
    parent_frame, child_frame : Placement
        The joint's frame on each body, in that body's centre-of-mass frame (world for the
        ground).
    axis : ndarray (d,) or None
        The joint's unit axis in the joint frame (:meth:`Joint.unit_axis`).
    dimension : int
        3 in space, 2 in the plane.
    initial : tuple of ndarray (d,), optional
        World positions of the parent's and the child's frame origins at the initial pose.
    shifts : tuple of SX (d,), optional
        Symbolic shifts of the parent's and the child's frame origins, in each body's axes
        (design parameters: zero at the scene's values).
    scale : SX or float
        What every length is multiplied by (a design parameter's ``1 + sigma``; 1): the body
        states scale their points themselves, a joint type its own world lengths with it.
    """

    parent: Any
    child: Any
    parent_frame: Placement
    child_frame: Placement
    axis: np.ndarray | None
    dimension: int
    initial: tuple[np.ndarray, np.ndarray] | None = None
    shifts: tuple | None = None
    scale: Any = 1.0

    @property
    def gap(self):
        """``d``: world vector from the parent frame's origin to the child frame's origin."""
        gap = (self.child.point(self.child_frame.position)
               - self.parent.point(self.parent_frame.position))
        if self.shifts is None:
            return gap
        parent, child = self.shifts
        return gap + self.scale * (ca.mtimes(self.child.R, child)
                                   - ca.mtimes(self.parent.R, parent))

    def parent_vector(self, u):
        """Joint-frame vector ``u`` fixed to the parent, in world axes."""
        return self.parent.direction(self.parent_frame.rotation @ np.asarray(u, dtype=float))

    def child_vector(self, u):
        """Joint-frame vector ``u`` fixed to the child, in world axes."""
        return self.child.direction(self.child_frame.rotation @ np.asarray(u, dtype=float))

    def relative_angle(self):
        """Planar: angle of the child frame relative to the parent frame."""
        return (self.child.frame_angle(self.child_frame.rotation)
                - self.parent.frame_angle(self.parent_frame.rotation))

    def triad(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``u, w, a``: the axis completed to a right-handed orthonormal triad."""
        u, w = orthonormal_complement(self.axis)
        return u, w, self.axis


def point_rows(g: JointGeometry) -> list[Row]:
    """``x, y(, z)``: the components of ``d`` (the two frame origins coincide)."""
    d = g.gap
    return [(name, d[i], LENGTH) for i, name in enumerate("xyz"[: g.dimension])]


def normal_in_plane(axis: np.ndarray) -> np.ndarray:
    """The in-plane normal ``n`` of a planar axis (``a`` turned by +90 degrees)."""
    return np.array([-axis[1], axis[0]])


def angle_sin_cos(g: JointGeometry):
    """``(sin theta, cos theta)`` of the angle about the axis from the parent frame to the child
    frame (up to a common positive factor in space, where the axes need not be aligned)."""
    if g.dimension == 2:
        theta = g.relative_angle()
        return ca.sin(theta), ca.cos(theta)
    u, w, _ = g.triad()
    u_c = g.child_vector(u)
    return ca.dot(g.parent_vector(w), u_c), ca.dot(g.parent_vector(u), u_c)


def wrapped_angle(g: JointGeometry, f):
    """``atan2(sin(theta - f), cos(theta - f))``: the angle about the axis minus ``f``, brought
    into (-pi, pi]. Derivative +1 in theta, correct past +-pi (a crank that turns many times)."""
    if g.dimension == 2:
        delta = g.relative_angle() - f
        return ca.atan2(ca.sin(delta), ca.cos(delta))
    s, c = angle_sin_cos(g)
    return ca.atan2(s * ca.cos(f) - c * ca.sin(f), c * ca.cos(f) + s * ca.sin(f))


def angle_rate(g: JointGeometry):
    """Rate of the angle about the axis: the child's angular velocity relative to the parent's,
    along the child's axis (in the plane, the relative angular velocity)."""
    zero = ca.DM.zeros(3 if g.dimension == 3 else 1)
    omega_c = g.child.omega if g.child.omega is not None else zero
    omega_p = g.parent.omega if g.parent.omega is not None else zero
    if g.dimension == 2:
        return omega_c - omega_p
    return ca.dot(g.child_vector(g.axis), omega_c - omega_p)


def axial_displacement(g: JointGeometry):
    """``a_p . d``: displacement of the child frame's origin along the parent's axis."""
    return ca.dot(g.parent_vector(g.axis), g.gap)


def embedded(vector) -> np.ndarray:
    """A planar vector (2,) as a spatial one (3,) with zero z; a spatial one unchanged."""
    vector = np.asarray(vector, dtype=float)
    return vector if vector.size == 3 else np.append(vector, 0.0)
