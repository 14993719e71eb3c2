"""Dumitru, Marin and Margine's own formulation of the leg, as a cross-check of the engine
(Section 3 of their paper).

Dumitru, Marin and Margine model the leg with **mixed coordinates**: the centre of mass
``x_i = (x, y, z)`` of each of the six elements and its joint angle ``q_i`` (24 unknowns), tied by
the 18 rows of their eq. (26), ``x_i - c_i(q) = 0``, where ``c_i`` is the centre of mass given by
the chain's kinematics (their eqs. (24)-(25)). The equations of motion are their eq. (12),
``M q_dd + J^T lambda = Q^a``, with the 18 x 24 Jacobian ``J = [I, -dc/dq]``:

* the translational rows give ``m_i x_i_dd + lambda_i = m_i g (+ f on the foot's element)``, so
  each multiplier is the net force on an element, and the force that joint ``k`` transmits to the
  part beyond it is **minus the sum of the multipliers of elements k and beyond**;
* the angle rows give the driving torques ``P = M_qq q_dd + h - (dc/dq)^T lambda (- external)``.

Their mass matrix is diagonal and ignores the rotational coupling; here ``M_qq`` is the exact
rotational inertia in joint angles, ``sum_i J_w_i^T (R_i J_i R_i^T) J_w_i``, and Lagrange's
equations give its velocity terms, so the two formulations must agree exactly. The kinematics are
written here from the leg's rest-pose geometry (rotations about the rest-pose axes through the
rest-pose joint points, composed from the trunk outwards), not taken from the engine.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from legs.leg import LegGeometry

GRAVITY = np.array([0.0, 0.0, -9.81])


def _rotation(axis: np.ndarray, angle):
    """Rodrigues' formula, symbolic in the angle."""
    K = ca.DM(np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]],
                        [-axis[1], axis[0], 0]]))
    return ca.DM.eye(3) + ca.sin(angle) * K + (1 - ca.cos(angle)) * ca.mtimes(K, K)


@dataclass
class MixedSolution:
    """The mixed model's inverse dynamics at the samples (world axes)."""

    multipliers: np.ndarray  # (N, 6, 3): lambda_i of eq. (26), one 3-vector per element
    joint_forces: np.ndarray  # (N, 6, 3): minus the sums over the elements beyond each joint
    torques: np.ndarray  # (N, 6): the driving torques P
    jacobian: np.ndarray  # (18, 24) at the first sample


class MixedModel:
    """Dumitru, Marin and Margine's mixed-coordinate model of a layout-A leg (elements E1-E6)."""

    def __init__(self, geometry: LegGeometry, gravity=GRAVITY, foot_load: bool = False):
        g = geometry
        self.gravity = np.asarray(gravity, dtype=float)
        q, q_d, q_dd = (ca.SX.sym(n, 6) for n in ("q", "q_d", "q_dd"))
        force = ca.SX.sym("f", 3)  # the ground on the foot (world)
        axes = [np.asarray(a, dtype=float) for a in g.axes]
        points = [np.asarray(p, dtype=float) for p in g.points[:6]]
        # rest pose of each element: centre of mass and rotation (segments: x along them)
        rest_com = [points[0], points[0]] + [
            points[k] + g.segment_frames[k - 2][:, 0] * g.lengths[k - 2] / 2 for k in (2, 3, 4, 5)]
        rest_rotation = [np.eye(3), np.eye(3)] + [g.segment_frames[k] for k in range(4)]
        foot_rest = np.asarray(g.points[6], dtype=float)

        def moved(point, i):
            """A point of element i (rest position) moved by joints i, i-1, ..., 1."""
            x = ca.DM(point)
            for k in reversed(range(i + 1)):
                x = points[k] + ca.mtimes(_rotation(axes[k], q[k]), x - points[k])
            return x

        centres = [moved(rest_com[i], i) for i in range(6)]
        turn = ca.DM.eye(3)
        rotations, world_axes = [], []
        for i in range(6):
            world_axes.append(ca.mtimes(turn, ca.DM(axes[i])))
            turn = ca.mtimes(turn, _rotation(axes[i], q[i]))
            rotations.append(ca.mtimes(turn, ca.DM(rest_rotation[i])))
        c = ca.vertcat(*centres)  # (18,)
        C = ca.jacobian(c, q)  # dc/dq
        self.jacobian = ca.Function("J", [q], [ca.horzcat(ca.DM.eye(18), -C)])  # eq. (26)
        # translational accelerations of the centres (the constraints twice differentiated)
        x_dd = ca.mtimes(C, q_dd) + ca.jtimes(ca.mtimes(C, q_d), q, q_d)
        masses = list(g.masses)
        # rotational kinetic energy in the angles, exact
        omega = [sum((world_axes[k] * q_d[k] for k in range(i + 1)), ca.DM.zeros(3))
                 for i in range(6)]
        energy = 0
        for i in range(6):
            J_world = ca.mtimes([rotations[i], ca.DM(np.diag(g.inertias[i])), rotations[i].T])
            energy += 0.5 * ca.dot(omega[i], ca.mtimes(J_world, omega[i]))
        p_energy = ca.gradient(energy, q_d)  # Lagrange: d/dt (dT/dq_d) - dT/dq
        lagrange = (ca.jtimes(p_energy, q, q_d) + ca.jtimes(p_energy, q_d, q_dd)
                    - ca.gradient(energy, q))
        # multipliers from the translational rows, torques from the angle rows
        lam = []
        for i in range(6):
            external = masses[i] * ca.DM(self.gravity)
            if foot_load and i == 5:
                external = external + force
            lam.append(external - masses[i] * x_dd[3 * i:3 * i + 3])
        lam_all = ca.vertcat(*lam)
        generalized = lagrange - ca.mtimes(C.T, lam_all)
        if foot_load:  # the foot's own lever arm: dp/dq^T f beyond the element's centre
            foot = moved(foot_rest, 5)
            generalized = generalized - ca.mtimes(ca.jacobian(foot - centres[5], q).T, force)
        self.solve_sample = ca.Function("mixed", [q, q_d, q_dd, force],
                                        [ca.horzcat(*lam), generalized])

    def inverse(self, q, q_d, q_dd, foot_force=None) -> MixedSolution:
        """Inverse dynamics at N samples: arrays (N, 6) of angles, rates and accelerations,
        and optionally the ground's force on the foot (N, 3)."""
        q, q_d, q_dd = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, q_d, q_dd))
        n = q.shape[0]
        forces = np.zeros((n, 3)) if foot_force is None else np.atleast_2d(foot_force)
        lam, torques = np.zeros((n, 6, 3)), np.zeros((n, 6))
        for k in range(n):
            multipliers, generalized = self.solve_sample(q[k], q_d[k], q_dd[k], forces[k])
            lam[k] = multipliers.full().T
            torques[k] = generalized.full().ravel()
        beyond = -np.cumsum(lam[:, ::-1], axis=1)[:, ::-1]  # minus the sums over j >= k
        return MixedSolution(lam, beyond, torques, self.jacobian(q[0]).full())
