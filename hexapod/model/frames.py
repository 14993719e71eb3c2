"""Symbolic pose and motion of each body, from which joints and forces are written.

A :class:`BodyState` gives, as CasADi SX expressions of the model's symbols, a body's centre of
mass ``r``, its rotation ``R`` (body -> world), and its angular velocity in world axes; the ground
is a :class:`BodyState` of constants. Joint residuals and force elements only use these, so one
formula serves spatial bodies, planar bodies, particles and the ground.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod.spatial import g_matrix, rotation_2d, rotation_from_euler_parameters


class BodyState:
    """Pose and motion of one body (or the ground) as SX expressions.

    Attributes
    ----------
    r : SX (d,)          centre of mass, world
    R : SX (d, d)        rotation, body -> world (identity for particles and the ground)
    angle : SX or None   the planar angle coordinate (plane only)
    omega : SX or None   angular velocity, world axes: 3 in space, 1 in the plane; None when the
                         body cannot rotate (particles, ground)
    qdot : SX            ``B(q) v`` for this body's coordinates
    """

    def __init__(self, r, R, angle=None, omega=None, qdot=None):
        self.r = r
        self.R = R
        self.angle = angle
        self.omega = omega
        self.qdot = qdot
        self._vectors: dict = {}  # one expression per body-fixed vector: rows share it
        #: every length times this where a design parameter scales the model (its points
        #: from the centre of mass; the ground's from the origin), else None
        self.scale = None

    @classmethod
    def ground(cls, dimension: int) -> BodyState:
        return cls(ca.DM.zeros(dimension), ca.DM.eye(dimension), angle=ca.DM(0.0))

    @classmethod
    def spatial(cls, q: ca.SX, v: ca.SX) -> BodyState:
        p = q[3:7]
        omega_body = v[3:6]
        A = rotation_from_euler_parameters(p)
        qdot = ca.vertcat(v[0:3], 0.5 * ca.mtimes(g_matrix(p).T, omega_body))
        return cls(q[0:3], A, omega=ca.mtimes(A, omega_body), qdot=qdot)

    @classmethod
    def planar(cls, q: ca.SX, v: ca.SX) -> BodyState:
        return cls(q[0:2], rotation_2d(q[2]), angle=q[2], omega=v[2], qdot=v)

    @classmethod
    def particle(cls, q: ca.SX, v: ca.SX) -> BodyState:
        d = q.numel()
        return cls(q, ca.DM.eye(d), qdot=v)

    def point(self, s) -> ca.SX:
        """World position of the body point ``s`` (centre-of-mass frame)."""
        return self._world("point", s)

    def direction(self, u) -> ca.SX:
        """World components of the body-fixed vector ``u``."""
        return self._world("direction", u)

    def _world(self, kind: str, vector):
        # the same point or axis asked by several rows (a joint's, its driver's, a marker's)
        # is one expression, not a copy each: its derivatives are then formed once too
        vector = np.asarray(vector, dtype=float)
        key = (kind, vector.tobytes())
        if key not in self._vectors:
            turned = ca.mtimes(self.R, ca.DM(vector))
            if kind == "point" and self.scale is not None:
                turned = self.scale * turned
            self._vectors[key] = self.r + turned if kind == "point" else turned
        return self._vectors[key]

    def frame_angle(self, rotation: np.ndarray):
        """Planar: world angle of a body-fixed frame with the given 2 x 2 rotation."""
        return self.angle + float(np.arctan2(rotation[1, 0], rotation[0, 0]))
