"""Generalized forces ``Q`` of the force elements, derived from their power.

A force ``F`` at a point moving with velocity ``v_P(q, v)`` contributes ``dv_P/dv^T F``; a torque
``T`` contributes ``domega/dv^T T``; a spring-damper of tension ``f`` contributes
``-f dL_dot/dv``; an actuator effort ``e`` on a joint contributes ``e d(rate)/dv``. CasADi forms
these derivatives, so every body kind is handled by the same lines.

The builder also keeps the potential energy of the springs (``k (L - L0)^2 / 2``, and
``k wrap(theta - theta0)^2 / 2`` for torsion springs) and the names of the elements that are
not conservative (dampers, time laws, applied loads, efforts), so that the energy of a scene
is defined, and known to be conserved or not.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod.model.frames import BodyState


class ForceBuilder:
    """Accumulates the generalized force of each element, kept apart by element name."""

    def __init__(self, q: ca.SX, v: ca.SX, qdot: ca.SX):
        self.q, self.v, self.qdot = q, v, qdot
        self.terms: dict[str, ca.SX] = {}
        self.potential: ca.SX = ca.SX(0.0)
        self.nonconservative: list[str] = []  # elements doing work not from a potential

    def _add(self, name: str, generalized: ca.SX) -> None:
        self.terms[name] = self.terms.get(name, 0) + generalized

    def velocity(self, expr: ca.SX) -> ca.SX:
        """Time derivative of a position-level expression along the motion."""
        return ca.jtimes(expr, self.q, self.qdot)

    def force_at(self, name: str, body: BodyState, point, force: ca.SX) -> None:
        """A world-frame force at the body point ``point`` (centre-of-mass frame)."""
        v_point = self.velocity(body.point(point))
        self._add(name, ca.jtimes(v_point, self.v, force, True))

    def torque_on(self, name: str, body: BodyState, torque: ca.SX) -> None:
        """A world-frame torque (3 components in space, 1 in the plane)."""
        if body.omega is None:
            return
        self._add(name, ca.jtimes(body.omega, self.v, torque, True))

    def spring_damper(self, name: str, a: BodyState, point_a, b: BodyState, point_b,
                      stiffness: float, damping: float, free_length: float,
                      force: ca.SX | None) -> None:
        d = b.point(point_b) - a.point(point_a)
        length = ca.sqrt(ca.dot(d, d))
        rate = self.velocity(length)
        tension = stiffness * (length - free_length)
        self.potential = self.potential + stiffness * (length - free_length) ** 2 / 2
        if damping:
            tension = tension + damping * rate
        if force is not None:
            tension = tension + force
        if damping or force is not None:
            self.nonconservative.append(name)
        self._add(name, -tension * ca.gradient(rate, self.v))

    def effort(self, name: str, rate: ca.SX, effort: ca.SX) -> None:
        """An actuator effort whose power is ``effort * rate``."""
        self._add(name, effort * ca.gradient(rate, self.v))

    def total(self) -> ca.SX:
        out = ca.SX.zeros(self.v.numel())
        for term in self.terms.values():
            out = out + term
        return out


def gravity_potential(bodies, q: ca.SX, gravity: np.ndarray) -> ca.SX:
    """``-sum m g . r`` over the bodies' centres of mass."""
    out = ca.SX(0.0)
    dim = gravity.size
    for info in bodies:
        out = out - info.mass * ca.dot(ca.DM(gravity), q[info.q.start:info.q.start + dim])
    return out


def inertial_forces(bodies, v: ca.SX, gravity: np.ndarray, n_v: int) -> ca.SX:
    """Gravity ``m g`` and the gyroscopic term ``-omega' x J' omega'`` of every body."""
    Q = ca.SX.zeros(n_v)
    g = ca.DM(gravity)
    dim = gravity.size
    for info in bodies:
        start = info.v.start
        Q[start:start + dim] = info.mass * g
        if info.kind == "spatial":
            omega = v[start + 3:start + 6]
            J = ca.DM(info.inertia)
            Q[start + 3:start + 6] = -ca.cross(omega, ca.mtimes(J, omega))
    return Q
