"""Topology: the body-joint graph, Grubler-Kutzbach against the numerical DOF, and the
vector-network graph of Richard, Anderson and Andrews with its incidence, cutset and circuit
matrices."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms.topology import body_joint_graph, mobility, vector_network
from hexapod.scene.reader import read_scene
from legs import front_leg_scene

from mechanisms import four_bar

DATA = Path(__file__).resolve().parent.parent / "data"


def _model(name):
    return hx.assemble(read_scene(DATA / "scenes" / name))


def _counts(network):
    v, e = len(network.vertices), len(network.edges)
    return v, e, network.cutset.shape[0], network.circuit.shape[0]


def test_seed002_figure2_graph():
    network = vector_network(_model("seed002_figure2.toml"))
    assert _counts(network) == (6, 8, 5, 3)
    assert network.orthogonal()
    kinds = sorted(e.kind for e in network.edges if e.tree)
    assert kinds == ["inertial", "rigid-arm", "rigid-arm", "specified-point",
                     "specified-point"]
    assert sorted(e.name for e in network.edges if not e.tree) == ["dashpot", "spring1",
                                                                    "spring2"]


def test_seed002_closed_pendulum_graph():
    network = vector_network(_model("closed_pendulum_seed002.toml"))
    assert _counts(network) == (5, 9, 4, 5)
    assert network.orthogonal()
    # tree: the two masses and the two specified points; chords: two weights, three links
    assert sorted(e.kind for e in network.edges if e.tree) == ["inertial", "inertial",
                                                               "specified-point",
                                                               "specified-point"]
    assert sorted(e.kind for e in network.edges if not e.tree) == ["joint"] * 3 + ["weight"] * 2


def test_cutsets_and_circuits_are_those_of_the_graph():
    """Beyond orthogonality: each cutset row splits the graph (removing its edges disconnects
    the branch's two ends) and each circuit is a closed walk (incidence times it is zero)."""
    network = vector_network(_model("closed_pendulum_seed002.toml"))
    K = network.incidence
    assert np.all(K @ network.circuit.T == 0)
    # the cutset matrix is the reduced incidence matrix brought to [U A] by row operations:
    # both span the same row space
    reduced = K[1:]
    assert np.linalg.matrix_rank(np.vstack([reduced, network.cutset])) == reduced.shape[0]
    assert np.array_equal(network.cutset[:, :network.branches], np.eye(network.branches))
    assert np.array_equal(network.A, -network.B.T)


def test_andrews_mechanism_has_three_loops_and_one_dof():
    model = _model("andrews.toml")
    graph = body_joint_graph(model)
    assert graph.independent_loops == 3 and len(graph.loops) == 3
    assert graph.cotree == ("E3", "E4", "E6")
    assert all(loop.joints[0] == loop.closing for loop in graph.loops)
    data = model.create_data()
    q = hx.assemble_positions(model, data)
    m = mobility(model, data, 0.0, q)
    assert (m.counted, m.numerical, m.redundancy) == (1, 1, 0)
    network = vector_network(model)
    assert network.orthogonal()


def test_andrews_reactions_at_joint_e_equal_the_published_multipliers():
    """The forces rod 2 exerts at E on the triangle, rod 4 and rod 6 (world axes) are the
    test set's lambda1..6 at t = 0 (published to 16 digits, consistent initial values)."""
    reference = json.loads((DATA / "benchmarks" / "andrews.json").read_text())["initial"]["y"]
    model = _model("andrews.toml")
    data = model.create_data()
    q = hx.assemble_positions(model, data)
    v_dot = hx.forward_dynamics(model, data, 0.0, q, np.zeros(model.n_v))
    wrenches = hx.joint_wrenches(model, data, frame="world")
    forces = np.concatenate([wrenches.force[model.joint_index[j]][:2]
                             for j in ("E3", "E4", "E6")])
    assert np.allclose(forces, reference[21:27], rtol=0, atol=1e-10 * 98.57)
    beta_dd, theta_dd = reference[14], reference[15]
    assert v_dot[model.bodies[0].v][2] == pytest.approx(beta_dd, rel=1e-11)
    assert v_dot[model.bodies[1].v][2] == pytest.approx(beta_dd + theta_dd, rel=1e-11)


def test_redundant_four_bar_counts():
    model = hx.assemble(four_bar(3, 1.05))
    graph = body_joint_graph(model)
    assert graph.independent_loops == 1 and graph.cotree == ("rocker_ground",)
    data = model.create_data()
    m = mobility(model, data, 0.0, hx.assemble_positions(model, data))
    # Grubler-Kutzbach: 3 bodies x 6 - 4 revolutes x 5 = -2; numerically 1: 3 redundant rows
    assert (m.counted, m.numerical, m.redundancy) == (-2, 1, 3)
    assert m.redundant_rows == ("rocker_ground/z", "rocker_ground/ax1", "rocker_ground/ax2")
    assert (m.counted_with_drivers, m.numerical_with_drivers) == (-3, 0)


def test_open_chain_and_free_body():
    scene = front_leg_scene(gait=False)
    scene.add(hx.scene.SpatialBody("free", 1.0, [1, 1, 1], position=[2.0, 0, 0]))
    model = hx.assemble(scene)
    graph = body_joint_graph(model)
    assert graph.independent_loops == 0 and graph.components == 2
    data = model.create_data()
    m = mobility(model, data, 0.0, hx.assemble_positions(model, data))
    assert m.counted == m.numerical == 6 + 6


def _reference_examples():
    import re
    text = (DATA.parent / "docs" / "scene-format.md").read_text()
    return {m.group(2): m.group(1) for m in
            re.finditer(r'```toml\n(.*?name = "([^"]+)".*?)```', text, re.S)}


@pytest.mark.parametrize("name, counted, with_drivers", [("four-bar", 1, 0), ("leg", 2, 0),
                                                         ("slider-crank", 1, 0)])
def test_degrees_of_freedom_stated_by_the_reference(tmp_path, name, counted, with_drivers):
    path = tmp_path / f"{name}.toml"
    path.write_text(_reference_examples()[name])
    model = hx.assemble(read_scene(path))
    data = model.create_data()
    m = mobility(model, data, 0.3, hx.assemble_positions(model, data, 0.3))
    assert (m.counted, m.numerical, m.numerical_with_drivers) == (counted, counted,
                                                                   with_drivers)
