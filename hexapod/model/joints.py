"""Constraint rows of each joint type, and the joint coordinates drivers and efforts act on.

Rows are residuals in CasADi SX, named within their joint; their Jacobians and ``gamma`` are
derived by CasADi (nothing here is differentiated by hand). Notation: ``d`` is the world vector
from the parent frame's origin to the child frame's origin; ``u, w, a`` is a right-handed
orthonormal triad of the joint frame with ``a`` the joint axis.

* revolute: ``x, y, z`` (components of ``d``), ``ax1 = u_p . a_c``, ``ax2 = w_p . a_c``;
  in the plane ``x, y``.
* prismatic: ``ax1, ax2`` as above, ``rot = w_p . u_c``, ``t1 = u_p . d``, ``t2 = w_p . d``;
  in the plane ``rot`` (relative angle) and ``t = n_p . d`` (``n`` normal to the axis).
* spherical: ``x, y, z``.
* fixed: ``x, y, z``, ``rx = z_p . y_c``, ``ry = x_p . z_c``, ``rz = y_p . x_c``; in the plane
  ``x, y, rot``.
* distance: ``length = (d . d - L^2) / (2 L)``, in space and in the plane.
* universal: ``x, y, z``, ``cross = a_p . b_c`` (``a`` the parent's axis, ``b`` the child's).
* cylindrical: ``ax1, ax2, t1, t2`` as for a prismatic joint, without ``rot``; in the plane (a
  pin in a slot along the axis) ``t = n_p . d``.
* planar: ``ax1, ax2`` and ``t = a_p . d`` (``a`` the plane's normal).
* point-on-plane: ``normal = a_p . d`` (``a`` the plane's normal), in space and in the plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from hexapod.model.frames import BodyState
from hexapod.spatial import Placement, orthonormal_complement

LENGTH, ANGLE = "length", "angle"


@dataclass
class JointGeometry:
    """A joint's two frames on their bodies, as the rows need them."""

    parent: BodyState
    child: BodyState
    parent_frame: Placement  # in the parent's centre-of-mass frame
    child_frame: Placement  # in the child's centre-of-mass frame
    axis: np.ndarray | None  # unit, joint frame
    dimension: int
    axis2: np.ndarray | None = None  # a universal joint's child axis, unit, joint frame

    @property
    def gap(self) -> ca.SX:
        """World vector from the parent frame's origin to the child frame's origin."""
        return (self.child.point(self.child_frame.position)
                - self.parent.point(self.parent_frame.position))

    def parent_vector(self, u) -> ca.SX:
        return self.parent.direction(self.parent_frame.rotation @ np.asarray(u, dtype=float))

    def child_vector(self, u) -> ca.SX:
        return self.child.direction(self.child_frame.rotation @ np.asarray(u, dtype=float))

    def relative_angle(self) -> ca.SX:
        """Planar: angle of the child frame relative to the parent frame."""
        return (self.child.frame_angle(self.child_frame.rotation)
                - self.parent.frame_angle(self.parent_frame.rotation))

    def triad(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        u, w = orthonormal_complement(self.axis)
        return u, w, self.axis


def _dot(a, b):
    return ca.dot(a, b)


def _point_rows(g: JointGeometry):
    d = g.gap
    return [(name, d[i], LENGTH) for i, name in enumerate("xyz"[: g.dimension])]


def revolute_rows(g: JointGeometry):
    if g.dimension == 2:
        return _point_rows(g)
    u, w, a = g.triad()
    a_c = g.child_vector(a)
    return _point_rows(g) + [("ax1", _dot(g.parent_vector(u), a_c), ANGLE),
                             ("ax2", _dot(g.parent_vector(w), a_c), ANGLE)]


def prismatic_rows(g: JointGeometry):
    d = g.gap
    if g.dimension == 2:
        a = g.axis
        n = np.array([-a[1], a[0]])
        return [("rot", g.relative_angle(), ANGLE), ("t", _dot(g.parent_vector(n), d), LENGTH)]
    u, w, a = g.triad()
    a_c = g.child_vector(a)
    u_p, w_p = g.parent_vector(u), g.parent_vector(w)
    return [("ax1", _dot(u_p, a_c), ANGLE), ("ax2", _dot(w_p, a_c), ANGLE),
            ("rot", _dot(w_p, g.child_vector(u)), ANGLE),
            ("t1", _dot(u_p, d), LENGTH), ("t2", _dot(w_p, d), LENGTH)]


def spherical_rows(g: JointGeometry):
    return _point_rows(g)


def fixed_rows(g: JointGeometry):
    if g.dimension == 2:
        return _point_rows(g) + [("rot", g.relative_angle(), ANGLE)]
    e = np.eye(3)
    x_p, y_p, z_p = (g.parent_vector(e[i]) for i in range(3))
    x_c, y_c, z_c = (g.child_vector(e[i]) for i in range(3))
    return _point_rows(g) + [("rx", _dot(z_p, y_c), ANGLE), ("ry", _dot(x_p, z_c), ANGLE),
                             ("rz", _dot(y_p, x_c), ANGLE)]


def universal_rows(g: JointGeometry):
    return _point_rows(g) + [("cross", _dot(g.parent_vector(g.axis), g.child_vector(g.axis2)),
                              ANGLE)]


def _normal_in_plane(axis: np.ndarray) -> np.ndarray:
    return np.array([-axis[1], axis[0]])


def cylindrical_rows(g: JointGeometry):
    d = g.gap
    if g.dimension == 2:
        return [("t", _dot(g.parent_vector(_normal_in_plane(g.axis)), d), LENGTH)]
    u, w, a = g.triad()
    a_c = g.child_vector(a)
    u_p, w_p = g.parent_vector(u), g.parent_vector(w)
    return [("ax1", _dot(u_p, a_c), ANGLE), ("ax2", _dot(w_p, a_c), ANGLE),
            ("t1", _dot(u_p, d), LENGTH), ("t2", _dot(w_p, d), LENGTH)]


def planar_rows(g: JointGeometry):
    u, w, a = g.triad()
    a_c = g.child_vector(a)
    return [("ax1", _dot(g.parent_vector(u), a_c), ANGLE),
            ("ax2", _dot(g.parent_vector(w), a_c), ANGLE),
            ("t", _dot(g.parent_vector(a), g.gap), LENGTH)]


def point_on_plane_rows(g: JointGeometry):
    return [("normal", _dot(g.parent_vector(g.axis), g.gap), LENGTH)]


def distance_rows(g: JointGeometry, length: float):
    d = g.gap
    return [("length", (_dot(d, d) - length**2) / (2.0 * length), LENGTH)]


ROWS = {"revolute": revolute_rows, "prismatic": prismatic_rows,
        "spherical": spherical_rows, "fixed": fixed_rows, "universal": universal_rows,
        "cylindrical": cylindrical_rows, "planar": planar_rows,
        "point-on-plane": point_on_plane_rows}


# ------------------------------------------------------------------ joint coordinates

def revolute_sin_cos(g: JointGeometry) -> tuple[ca.SX, ca.SX]:
    """``(sin theta, cos theta)`` of the joint angle (up to a common positive factor in space)."""
    if g.dimension == 2:
        theta = g.relative_angle()
        return ca.sin(theta), ca.cos(theta)
    u, w, _ = g.triad()
    u_c = g.child_vector(u)
    return _dot(g.parent_vector(w), u_c), _dot(g.parent_vector(u), u_c)


def prismatic_displacement(g: JointGeometry) -> ca.SX:
    """Displacement of the child frame's origin along the parent's axis."""
    return _dot(g.parent_vector(g.axis), g.gap)


def wrapped_angle(g: JointGeometry, f) -> ca.SX:
    """``atan2(sin(theta - f), cos(theta - f))``: the joint angle minus ``f``, brought into
    (-pi, pi]. Derivative +1 in theta, correct past +-pi; the angle is about
    the joint axis (revolute and cylindrical joints)."""
    if g.dimension == 2:
        delta = g.relative_angle() - f
        return ca.atan2(ca.sin(delta), ca.cos(delta))
    s, c = revolute_sin_cos(g)
    return ca.atan2(s * ca.cos(f) - c * ca.sin(f), c * ca.cos(f) + s * ca.sin(f))


def driver_row(kind: str, g: JointGeometry, f: ca.SX) -> ca.SX:
    """The driver residual: the wrapped angle difference (revolute) or ``s - f`` (prismatic)."""
    if kind == "prismatic":
        return prismatic_displacement(g) - f
    return wrapped_angle(g, f)


def joint_rate(kind: str, g: JointGeometry, q: ca.SX, qdot: ca.SX) -> ca.SX:
    """Rate of the joint coordinate: the power-conjugate of an effort on the joint (the angle's
    rate for revolute and cylindrical joints, the displacement's for prismatic joints)."""
    if kind == "prismatic":
        return ca.jtimes(prismatic_displacement(g), q, qdot)
    zero = ca.DM.zeros(3 if g.dimension == 3 else 1)
    omega_c = g.child.omega if g.child.omega is not None else zero
    omega_p = g.parent.omega if g.parent.omega is not None else zero
    if g.dimension == 2:
        return omega_c - omega_p
    return _dot(g.child_vector(g.axis), omega_c - omega_p)
