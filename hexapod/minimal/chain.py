"""Recursive joint-coordinate dynamics of open chains and trees (Vukobratović and Potkonjak (1979),
Part I).

Vukobratovic and Potkonjak form ``W(q) q_dd = P + V(q, q_d)`` by adding one member at a time
("circling" the chain) with recurrent relations for the angular accelerations and the
accelerations of the centres of mass, written as coefficients of the generalized accelerations
plus free terms (their eqs. (11)-(14), (23)-(30)):

    eps_i = Gamma_i q_dd + phi_i,        w_i = Omega_i q_dd + theta_i

and then apply the **theorems of kinetic momentum and of the motion of the centre of mass** to
the part of the chain beyond each joint (their eqs. (15)-(22)): for a revolute joint ``k`` with
axis ``e_k`` through ``A_k``,

    e_k . sum_{j beyond k} [ (r_j - A_k) x m_j (w_j - g) + J_j eps_j + omega_j x J_j omega_j ] = P_k

and for a prismatic joint ``e_k . sum_{j beyond k} m_j (w_j - g) = P_k``. ``W`` collects the
coefficients of ``q_dd`` and ``V`` minus the free terms, so ``V`` carries minus the Coriolis,
centrifugal and gravity terms (they stand on the right-hand side). The same sums without the
projection on ``e_k`` are the force and moment the parent transmits to the part beyond joint ``k``:
the joint's wrench.

The same ``W`` and ``V`` can be formed by the Lagrange and Gibbs-Appell methods of the paper's
Part II (reconstructed from the literature: :mod:`hexapod.minimal.forming`): pass
``method="lagrange"`` or ``method="gibbs-appell"`` to :meth:`ChainModel.matrices`,
:meth:`ChainModel.inverse` and :meth:`ChainModel.forward`.

This module works in joint coordinates only, independently of the absolute-coordinate engine; it
takes the geometry (joint frames, axes, masses, inertias) from a :class:`~hexapod.model.model.Model`
of a tree of spatial bodies with revolute, prismatic and fixed joints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.errors import ModelError, Problem
from hexapod.minimal.forming import METHODS, Layout, form, layout
from hexapod.model.model import GROUND_INDEX, Model
from hexapod.spatial import Placement, rotation_about_axis, skew


@dataclass(frozen=True)
class ChainLink:
    """One joint and the body it carries, in tree order (parents before children)."""

    name: str
    kind: str  # "revolute", "prismatic" or "fixed"
    parent: int  # index of the parent link, -1 for the ground
    on_parent: Placement  # the joint frame at q = 0 in the parent's centre-of-mass frame
    on_child: Placement  # the joint frame in the child's centre-of-mass frame
    axis: np.ndarray  # unit, joint frame
    mass: float
    inertia: np.ndarray  # about the centre of mass, body axes
    coordinate: int  # index in q, -1 for a fixed joint


@dataclass
class ChainState:
    """Kinematics of every link at one state (world components)."""

    R: np.ndarray  # (n, 3, 3) body -> world
    r: np.ndarray  # (n, 3) centres of mass
    origin: np.ndarray  # (n, 3) joint origins (on the child)
    axis: np.ndarray  # (n, 3) joint axes
    omega: np.ndarray  # (n, 3)
    Gamma: np.ndarray  # (n, 3, dof): eps_i = Gamma_i q_dd + phi_i
    phi: np.ndarray  # (n, 3)
    Omega: np.ndarray  # (n, 3, dof): w_i = Omega_i q_dd + theta_i
    theta: np.ndarray  # (n, 3)


def _link_kind(joint) -> str | None:
    """What a model's joint is to the chain, asked of its type: ``"fixed"`` (a tree step and no
    coordinate), ``"revolute"`` (its twist a rotation about its axis), ``"prismatic"`` (a
    translation along it); None for any other."""
    if joint.type.tree_step is None:
        return None
    if not joint.type.drivable:
        return "fixed"
    linear, angular = joint.type.twist(3)
    if not np.any(linear):
        return "revolute"
    return "prismatic" if not np.any(angular) else None


class ChainModel:
    """An open chain or tree in joint coordinates (one coordinate per revolute or prismatic
    joint, in the model's joint order)."""

    def __init__(self, links: list[ChainLink], gravity: np.ndarray):
        self.links = links
        self.gravity = np.asarray(gravity, dtype=float)
        self.dof = sum(link.coordinate >= 0 for link in links)
        self.names = tuple(link.name for link in links)
        self.children: list[list[int]] = [[] for _ in links]
        for k, link in enumerate(links):
            if link.parent >= 0:
                self.children[link.parent].append(k)

    # ---------------------------------------------------------------- construction

    @classmethod
    def from_model(cls, model: Model) -> ChainModel:
        """The joint-coordinate form of a tree of spatial bodies; raises ``ModelError`` for
        loops, free bodies, other joint or body kinds."""
        problems = []
        if model.dimension != 3 or any(b.kind != "spatial" for b in model.bodies):
            problems.append(Problem("model", "the recursive model takes spatial bodies only"))
        child_of: dict[int, int] = {}
        kinds = [_link_kind(joint) for joint in model.joints]
        for joint in model.joints:
            if kinds[joint.index] is None:
                problems.append(Problem(f"joint '{joint.name}'", f"a {joint.kind} joint: the "
                                        "recursive model takes revolute, prismatic and fixed"))
            if joint.child == GROUND_INDEX or joint.child in child_of:
                problems.append(Problem(f"joint '{joint.name}'", "closes a loop or has the "
                                        "ground as child: the model is not a tree"))
            child_of[joint.child] = joint.index
        missing = [b.name for b in model.bodies if b.index not in child_of]
        if missing:
            problems.append(Problem("model", "free bodies (no joint to a parent): "
                                    + ", ".join(missing)))
        if problems:
            raise ModelError(f"model '{model.name}'", problems)
        order: list[int] = []  # joints, parents first
        placed = {GROUND_INDEX}
        while len(order) < len(model.joints):
            progress = False
            for joint in model.joints:
                if joint.index not in order and joint.parent in placed:
                    order.append(joint.index)
                    placed.add(joint.child)
                    progress = True
            if not progress:
                raise ModelError(f"model '{model.name}'", [Problem(
                    "model", "some bodies are not connected to the ground")])
        link_of_body = {model.joints[j].child: k for k, j in enumerate(order)}
        coordinate = {}
        for j in sorted(order):  # coordinates in the model's joint order
            if kinds[j] != "fixed":
                coordinate[j] = len(coordinate)
        links = []
        for j in order:
            joint = model.joints[j]
            body = model.bodies[joint.child]
            axis = np.zeros(3) if joint.axis is None else np.asarray(joint.axis, dtype=float)
            links.append(ChainLink(joint.name, kinds[j], link_of_body.get(joint.parent, -1),
                                   joint.parent_frame, joint.child_frame, axis, body.mass,
                                   np.asarray(body.inertia, dtype=float),
                                   coordinate.get(j, -1)))
        return cls(links, model.gravity)

    # ---------------------------------------------------------------- kinematics

    def kinematics(self, q: np.ndarray, q_d: np.ndarray) -> ChainState:
        """Poses, angular velocities and the acceleration coefficients of every link: the
        recurrent relations (11)-(14) of Vukobratović and Potkonjak (1979), written as eqs.
        (23)-(30)."""
        n, dof = len(self.links), self.dof
        s = ChainState(np.zeros((n, 3, 3)), np.zeros((n, 3)), np.zeros((n, 3)),
                       np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3, dof)),
                       np.zeros((n, 3)), np.zeros((n, 3, dof)), np.zeros((n, 3)))
        zero3, zero_dof = np.zeros(3), np.zeros((3, dof))
        for k, link in enumerate(self.links):
            p = link.parent
            if p < 0:  # the ground: at rest, world axes
                R_p, r_p, omega_p = np.eye(3), zero3, zero3
                Gamma_p, phi_p, Omega_p, theta_p = zero_dof, zero3, zero_dof, zero3
            else:
                R_p, r_p, omega_p = s.R[p], s.r[p], s.omega[p]
                Gamma_p, phi_p, Omega_p, theta_p = s.Gamma[p], s.phi[p], s.Omega[p], s.theta[p]
            frame = R_p @ link.on_parent.rotation  # the joint frame on the parent
            point = r_p + R_p @ link.on_parent.position  # joint point, fixed on the parent
            e = frame @ link.axis
            c = link.coordinate
            qc = q[c] if c >= 0 else 0.0
            qc_d = q_d[c] if c >= 0 else 0.0
            # acceleration of the joint point (a point of the parent): coefficients, free term
            arm_p = point - r_p
            Omega_P = Omega_p - skew(arm_p) @ Gamma_p
            theta_P = theta_p + np.cross(phi_p, arm_p) + np.cross(omega_p, np.cross(omega_p,
                                                                                     arm_p))
            Gamma, phi, Omega_o, theta_o = Gamma_p.copy(), phi_p.copy(), Omega_P, theta_P
            omega = omega_p.copy()
            origin = point
            if link.kind == "revolute":
                rotation = frame @ rotation_about_axis(link.axis, qc)
                omega = omega_p + qc_d * e
                Gamma[:, c] += e  # eps_i = eps_p + q_dd e + q_d omega_p x e
                phi = phi_p + qc_d * np.cross(omega_p, e)
            else:
                rotation = frame
                if link.kind == "prismatic":
                    origin = point + qc * e
                    # (q e)'' with e turning with the parent: q_dd e + 2 q_d w x e
                    #                                         + q (eps_p x e + w x (w x e))
                    Omega_o = Omega_P - qc * skew(e) @ Gamma_p
                    Omega_o[:, c] += e
                    theta_o = (theta_P + 2 * qc_d * np.cross(omega_p, e)
                               + qc * (np.cross(phi_p, e) + np.cross(omega_p,
                                                                      np.cross(omega_p, e))))
            R = rotation @ link.on_child.rotation.T
            r = origin - R @ link.on_child.position
            arm = r - origin
            s.R[k], s.r[k], s.origin[k], s.axis[k], s.omega[k] = R, r, origin, e, omega
            s.Gamma[k], s.phi[k] = Gamma, phi
            s.Omega[k] = Omega_o - skew(arm) @ Gamma
            s.theta[k] = theta_o + np.cross(phi, arm) + np.cross(omega, np.cross(omega, arm))
        return s

    def _subtrees(self) -> list[list[int]]:
        out = [[k] for k in range(len(self.links))]
        for k in reversed(range(len(self.links))):
            for child in self.children[k]:
                out[k].extend(out[child])
        return out

    # ---------------------------------------------------------------- dynamics

    @property
    def layout(self) -> Layout:
        """The constants of the chain for :mod:`hexapod.minimal.forming` (built once)."""
        if getattr(self, "_layout", None) is None:
            self._layout = layout(self)
        return self._layout

    def matrices(self, q: np.ndarray, q_d: np.ndarray,
                 method: str = "basic") -> tuple[np.ndarray, np.ndarray]:
        """``W(q)`` and ``V(q, q_d)`` of ``W q_dd = P + V``: by the method of basic theorems
        (``"basic"``, this module's vectorised form), ``"lagrange"`` or ``"gibbs-appell"``
        (:mod:`hexapod.minimal.forming`)."""
        if method != "basic":
            if method not in METHODS:
                raise ValueError(f"unknown method '{method}': choose one of "
                                 + ", ".join(METHODS))
            return form(self.layout, q, q_d, method)
        s = self.kinematics(q, q_d)
        W, V = np.zeros((self.dof, self.dof)), np.zeros(self.dof)
        subtrees = self._subtrees()
        for k, link in enumerate(self.links):
            c = link.coordinate
            if c < 0:
                continue
            e = s.axis[k]
            for j in subtrees[k]:
                m, J = self.links[j].mass, s.R[j] @ self.links[j].inertia @ s.R[j].T
                if link.kind == "revolute":
                    arm = s.r[j] - s.origin[k]
                    W[c] += e @ (skew(arm) @ (m * s.Omega[j]) + J @ s.Gamma[j])
                    V[c] -= e @ (np.cross(arm, m * (s.theta[j] - self.gravity)) + J @ s.phi[j]
                                 + np.cross(s.omega[j], J @ s.omega[j]))
                else:
                    W[c] += m * e @ s.Omega[j]
                    V[c] -= m * e @ (s.theta[j] - self.gravity)
        return W, V

    def inverse(self, q, q_d, q_dd, method: str = "basic") -> np.ndarray:
        """Driving forces and torques ``P = W q_dd - V`` (``W``, ``V`` formed by ``method``)."""
        W, V = self.matrices(q, q_d, method)
        return W @ q_dd - V

    def forward(self, q, q_d, P, method: str = "basic") -> np.ndarray:
        """Generalized accelerations ``q_dd = W^-1 (P + V)`` (``W``, ``V`` formed by
        ``method``)."""
        W, V = self.matrices(q, q_d, method)
        return np.linalg.solve(W, np.asarray(P, dtype=float) + V)

    def joint_wrenches(self, q, q_d, q_dd) -> tuple[np.ndarray, np.ndarray]:
        """Force and moment (about the joint origin) that each joint's parent transmits to the
        part of the tree beyond it, world components: arrays (n_links, 3)."""
        s = self.kinematics(q, q_d)
        q_dd = np.asarray(q_dd, dtype=float)
        subtrees = self._subtrees()
        force, moment = np.zeros((len(self.links), 3)), np.zeros((len(self.links), 3))
        for k in range(len(self.links)):
            for j in subtrees[k]:
                m, J = self.links[j].mass, s.R[j] @ self.links[j].inertia @ s.R[j].T
                inertial = m * (s.Omega[j] @ q_dd + s.theta[j] - self.gravity)
                eps = s.Gamma[j] @ q_dd + s.phi[j]
                force[k] += inertial
                moment[k] += (np.cross(s.r[j] - s.origin[k], inertial) + J @ eps
                              + np.cross(s.omega[j], J @ s.omega[j]))
        return force, moment
