"""Topology of a model: the body-joint graph and the vector-network element graph of Richard,
Anderson and Andrews (1989/90).

**Body-joint graph**: vertices are the ground and the bodies, edges the joints. Its spanning tree
follows the order of the joints (a joint that closes a loop formed by earlier joints is a chord,
a *loop-closing* joint); the independent loops are ``e - v + components``. Mobility is counted
by Grubler-Kutzbach, ``sum of body freedoms - sum of joint rows``, and compared with the
numerical ``n_v - rank(Phi_v)``: their difference is the number of redundant rows.

**Vector network** (Richard, Anderson and Andrews, 1989/90): vertices are the ground, each centre of
mass and each point of interconnection; edges are the elements. Tree branches are the inertial
elements (ground to centre of mass), the rigid arms (centre of mass to a point of its body) and the
specified points (ground to a fixed point); chords are everything else: joints, drivers, springs and
dampers, force and torque drivers, weights. The cutset matrix ``[U A]`` comes from row reduction of
the incidence matrix, the circuit matrix ``[B U]`` from tree paths,
independently; ``A = -B^T`` checks both.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hexapod._support.graphs import (
    circuit_matrix,
    components,
    cutset_matrix,
    incidence_matrix,
    spanning_forest,
)
from hexapod.algorithms.kinematics import degrees_of_freedom
from hexapod.model.model import GROUND_INDEX, Data, Model

GROUND = "ground"
_BODY_FREEDOMS = {("spatial", 3): 6, ("planar", 2): 3, ("particle", 3): 3, ("particle", 2): 2}


# ------------------------------------------------------------------ body-joint graph

@dataclass(frozen=True)
class Loop:
    """An independent loop: its loop-closing joint and the joints around it, in order."""

    closing: str
    joints: tuple[str, ...]


@dataclass(frozen=True)
class BodyJointGraph:
    """The body-joint graph of :func:`body_joint_graph`.

    Attributes
    ----------
    vertices : tuple of str
        The ground, then the bodies in model order.
    joints : tuple of str
        The edges: every joint, in model order.
    tree, cotree : tuple of str
        The spanning tree's joints and the loop-closing joints.
    components : int
        Connected parts: 1 unless some body is free or floats.
    loops : tuple of Loop
        The independent loops, one per loop-closing joint.
    """

    vertices: tuple[str, ...]  # the ground, then the bodies
    joints: tuple[str, ...]
    tree: tuple[str, ...]
    cotree: tuple[str, ...]  # loop-closing joints
    components: int  # connected parts: 1 unless some body is free or floats
    loops: tuple[Loop, ...]

    @property
    def independent_loops(self) -> int:
        """``e - v + components``, the number of loop-closing joints."""
        return len(self.joints) - len(self.vertices) + self.components


def _name(model: Model, body: int) -> str:
    return GROUND if body == GROUND_INDEX else model.bodies[body].name


def body_joint_graph(model: Model) -> BodyJointGraph:
    """The body-joint graph (vertices: the ground and the bodies; edges: the joints): its
    spanning tree, the loop-closing joints (cotree) and the independent loops they close.

    Parameters
    ----------
    model : Model

    Returns
    -------
    BodyJointGraph
    """
    vertices = (GROUND, *(b.name for b in model.bodies))
    edges = [(_name(model, j.parent), _name(model, j.child)) for j in model.joints]
    tree, chords = spanning_forest(vertices, edges)
    loops = []
    if chords:
        C = circuit_matrix(vertices, edges, tree, chords)
        for i, c in enumerate(chords):
            around = [model.joints[c].name] + [model.joints[j].name for j in np.flatnonzero(C[i])
                                               if j != c]
            loops.append(Loop(model.joints[c].name, tuple(around)))
    return BodyJointGraph(vertices, tuple(j.name for j in model.joints),
                          tuple(model.joints[k].name for k in tree),
                          tuple(model.joints[k].name for k in chords),
                          components(vertices, edges), tuple(loops))


@dataclass(frozen=True)
class Mobility:
    """Degrees of freedom counted (Grubler-Kutzbach) and numerical, without and with drivers.

    Attributes
    ----------
    counted, numerical : int
        The joints alone: ``sum of body freedoms - sum of joint rows``, and
        ``n_v - rank(Phi_v)``.
    counted_with_drivers, numerical_with_drivers : int
        The same with the drivers' rows.
    redundant_rows : tuple of str
        The rows the rank decision names redundant, drivers included.
    """

    counted: int
    numerical: int
    counted_with_drivers: int
    numerical_with_drivers: int
    redundant_rows: tuple[str, ...]  # named by the rank decision, drivers included

    @property
    def redundancy(self) -> int:
        """Redundant joint rows: numerical minus counted degrees of freedom."""
        return self.numerical - self.counted


def mobility(model: Model, data: Data, t: float, q: np.ndarray) -> Mobility:
    """Grubler-Kutzbach's count against the numerical ``n_v - rank(Phi_v)`` at ``(t, q)``
    (see :func:`~hexapod.algorithms.kinematics.degrees_of_freedom`, which fills ``data``).

    Parameters
    ----------
    model, data : Model, Data
        The model and a workspace of it.
    t : float
        s.
    q : ndarray, shape (n_q,)
        Positions (need not satisfy the constraints: the rank is that of ``Phi_v`` there).

    Returns
    -------
    Mobility
    """
    freedoms = sum(_BODY_FREEDOMS[(b.kind, model.dimension)] for b in model.bodies)
    counted = freedoms - sum(j.rows.size for j in model.joints)
    numerical = degrees_of_freedom(model, data, t, q)
    return Mobility(counted, numerical["dof"], counted - len(model.drivers),
                    numerical["dof_with_drivers"], tuple(numerical["redundant_rows"]))


# ------------------------------------------------------------------ vector network

@dataclass(frozen=True)
class NetworkEdge:
    """One element of the vector network, oriented ``tail -> head``."""

    name: str
    kind: str  # inertial, rigid-arm, specified-point, joint, driver, spring, force, torque,
    #            effort, weight
    tail: str
    head: str
    tree: bool


@dataclass(frozen=True)
class VectorNetwork:
    """The element graph, its incidence, cutset and circuit matrices.

    ``edges`` lists the tree branches first, then the chords, so ``cutset = [U A]`` and
    ``circuit = [B U]`` in that column order.

    Attributes
    ----------
    vertices : tuple of str
        The ground, the centres of mass and the points of interconnection.
    edges : tuple of NetworkEdge
        The elements, oriented ``tail -> head``: tree branches, then chords.
    incidence : ndarray of int, shape (len(vertices), len(edges))
        +1 at an edge's tail, -1 at its head.
    cutset : ndarray of int, shape (branches, len(edges))
        The fundamental cutsets ``[U A]``, one per tree branch.
    circuit : ndarray of int, shape (chords, len(edges))
        The fundamental circuits ``[B U]``, one per chord.
    """

    vertices: tuple[str, ...]
    edges: tuple[NetworkEdge, ...]
    incidence: np.ndarray = field(repr=False)
    cutset: np.ndarray = field(repr=False)
    circuit: np.ndarray = field(repr=False)

    @property
    def branches(self) -> int:
        return sum(e.tree for e in self.edges)

    @property
    def A(self) -> np.ndarray:
        return self.cutset[:, self.branches:]

    @property
    def B(self) -> np.ndarray:
        return self.circuit[:, :self.branches]

    def orthogonal(self) -> bool:
        """``cutset circuit^T = 0`` and ``A = -B^T``: each matrix checks the other."""
        return bool(np.all(self.cutset @ self.circuit.T == 0) and np.array_equal(self.A,
                                                                                 -self.B.T))


class _NetworkBuilder:
    def __init__(self, model: Model):
        self.model = model
        self.vertices = [GROUND]
        self.tree: list[NetworkEdge] = []
        self.chords: list[NetworkEdge] = []
        self.points: dict = {}
        for body in model.bodies:
            self.vertices.append(body.name)
            self.tree.append(NetworkEdge(body.name, "inertial", GROUND, body.name, True))

    def point(self, body: int, position, label: str) -> str:
        """The vertex of a point of interconnection; a new one brings its tree branch."""
        position = np.asarray(position, dtype=float)
        if body != GROUND_INDEX and np.allclose(position, 0.0, atol=1e-12):
            return self.model.bodies[body].name  # the centre of mass itself
        key = (body, tuple(np.round(position, 12)))
        if key not in self.points:
            owner = _name(self.model, body)
            vertex = f"{owner}@{label}"
            self.points[key] = vertex
            self.vertices.append(vertex)
            if body == GROUND_INDEX:
                self.tree.append(NetworkEdge(f"point {label}", "specified-point", GROUND,
                                             vertex, True))
            else:
                self.tree.append(NetworkEdge(f"{owner} arm {label}", "rigid-arm", owner,
                                             vertex, True))
        return self.points[key]

    def chord(self, name: str, kind: str, tail: str, head: str) -> None:
        self.chords.append(NetworkEdge(name, kind, tail, head, False))

    def joint_points(self, k: int, label: str) -> tuple[str, str]:
        joint = self.model.joints[k]
        return (self.point(joint.parent, joint.parent_frame.position, label),
                self.point(joint.child, joint.child_frame.position, label))

    def build(self) -> VectorNetwork:
        model = self.model
        for k, joint in enumerate(model.joints):
            self.chord(joint.name, "joint", *self.joint_points(k, joint.name))
        for driver in model.drivers:
            if driver.kind == "joint":
                joint = model.joints[driver.joint]
                self.chord(driver.name, "driver", *self.joint_points(driver.joint, joint.name))
            else:
                frame = (GROUND if driver.frame == GROUND_INDEX
                         else model.bodies[driver.frame].name)
                self.chord(driver.name, "driver", frame, model.bodies[driver.body].name)
        for force in model.forces:
            if force.joint is not None:
                joint = model.joints[force.joint]
                self.chord(force.name, "effort", *self.joint_points(force.joint, joint.name))
            elif force.kind == "spring":
                ends = [self.point(b, p, force.name) for b, p in zip(force.bodies, force.points,
                                                                      strict=True)]
                self.chord(force.name, "spring", *ends)
            elif force.kind == "applied-force":
                self.chord(force.name, "force", GROUND,
                           self.point(force.bodies[0], force.points[0], force.name))
            else:
                self.chord(force.name, "torque", GROUND, _name(model, force.bodies[0]))
        if np.any(model.gravity != 0):
            for body in model.bodies:
                self.chord(f"weight {body.name}", "weight", GROUND, body.name)
        edges = self.tree + self.chords
        ends = [(e.tail, e.head) for e in edges]
        K = incidence_matrix(self.vertices, ends)
        tree = list(range(len(self.tree)))
        chords = list(range(len(self.tree), len(edges)))
        return VectorNetwork(tuple(self.vertices), tuple(edges), K, cutset_matrix(K, tree),
                             circuit_matrix(self.vertices, ends, tree, chords))


def vector_network(model: Model) -> VectorNetwork:
    """The vector-network graph of the model (Richard, Anderson and Andrews).

    Parameters
    ----------
    model : Model

    Returns
    -------
    VectorNetwork
        The graph and its incidence, cutset and circuit matrices (the module's description).
    """
    return _NetworkBuilder(model).build()
