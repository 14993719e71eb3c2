"""The recursive joint-coordinate model of Vukobratović and Potkonjak against the
absolute-coordinate engine."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod as hx
from hexapod.minimal.chain import ChainModel
from legs import front_leg_scene

from mechanisms import four_bar, random_tree

CASES = [(seed, n, chain) for seed, n, chain in ((1, 2, True), (2, 4, True), (3, 6, False),
                                                 (4, 7, False), (5, 5, True))]


def _joint_values(model, t):
    """Coordinates, rates and accelerations of the driven joints (model joint order)."""
    w, wd, wdd = model.law_values(t)
    order = sorted(model.drivers, key=lambda d: d.joint)
    return (np.array([w[d.law] for d in order]), np.array([wd[d.law] for d in order]),
            np.array([wdd[d.law] for d in order]))


@pytest.mark.parametrize("seed, n, chain", CASES)
def test_inverse_dynamics_agree(seed, n, chain):
    model = hx.assemble(random_tree(seed, n, chain=chain))
    recursive = ChainModel.from_model(model)
    for t in (0.0, 0.37, 1.3):
        data = model.create_data()
        q = hx.assemble_positions(model, data, t)
        v = hx.solve_velocities(model, data, t, q)
        hx.forward_dynamics(model, data, t, q, v)
        engine = hx.joint_wrenches(model, data, frame="world")
        qj, qj_d, qj_dd = _joint_values(model, t)
        P = recursive.inverse(qj, qj_d, qj_dd)
        force, moment = recursive.joint_wrenches(qj, qj_d, qj_dd)
        order = [model.joint_index[name] for name in recursive.names]
        # torques/forces of the drivers: P in the joint order of the model
        assert np.allclose(engine.effort, P, rtol=1e-9, atol=1e-9 * np.abs(P).max())
        scale = np.abs(force).max()
        assert np.allclose(engine.force[order], force, rtol=0, atol=1e-9 * scale)
        assert np.allclose(engine.torque[order], moment, rtol=0, atol=1e-9 * np.abs(
            moment).max())
        # the kinematics agree too: centres of mass
        state = recursive.kinematics(qj, qj_d)
        for k, name in enumerate(recursive.names):
            body = model.joints[model.joint_index[name]].child
            assert np.allclose(model.body_pose(q, body).position, state.r[k], atol=1e-12)


@pytest.mark.parametrize("seed, n, chain", CASES[:3])
def test_forward_dynamics_agree(seed, n, chain):
    """Undriven: the engine's accelerations equal W^-1 (P + V) with P = 0."""
    model = hx.assemble(random_tree(seed, n, chain=chain, driven=False))
    recursive = ChainModel.from_model(model)
    rng = np.random.default_rng(seed)
    qj = rng.normal(size=recursive.dof) * 0.5
    qj_d = rng.normal(size=recursive.dof)
    # the absolute state of those joint values, from the driven twin of the model
    driven = random_tree(seed, n, chain=chain)
    for k in range(n):
        driven.drivers[f"d{k}"].law = hx.scene.Polynomial([qj[k], qj_d[k]])
    twin = hx.assemble(driven)
    data = twin.create_data()
    q = hx.assemble_positions(twin, data, 0.0)
    v = hx.solve_velocities(twin, data, 0.0, q)
    v_dot = hx.forward_dynamics(model, model.create_data(), 0.0, q, v)
    qj_dd = recursive.forward(qj, qj_d, np.zeros(recursive.dof))
    state = recursive.kinematics(qj, qj_d)
    for k, name in enumerate(recursive.names):
        body = model.bodies[model.joints[model.joint_index[name]].child]
        a = state.Omega[k] @ qj_dd + state.theta[k]
        assert np.allclose(v_dot[body.v][:3], a, rtol=1e-9, atol=1e-9 * np.abs(a).max())


def test_front_leg_matrices_are_symmetric_positive_definite():
    model = hx.assemble(front_leg_scene())
    recursive = ChainModel.from_model(model)
    W, _ = recursive.matrices(np.full(6, 0.2), np.zeros(6))
    assert np.allclose(W, W.T, atol=1e-15 * np.abs(W).max())
    assert np.linalg.eigvalsh(W).min() > 0


def test_loops_are_refused():
    with pytest.raises(hx.ModelError, match="not a tree"):
        ChainModel.from_model(hx.assemble(four_bar(3, 1.0)))
