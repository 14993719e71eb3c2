"""Kinematic analysis: assembly from a rough guess, clear failures, velocity and acceleration
analysis, and the condition number of the saddle-point solve."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms.linalg import equilibrate

from mechanisms import four_bar
from test_joints import CASES, case_id


def test_assembly_from_a_rough_guess():
    model = hx.assemble(four_bar(3, 1.05, driven=False))
    rng = np.random.default_rng(5)
    guess = model.integrate(model.q0, rng.normal(size=model.n_v) * 0.05)
    data = model.create_data()
    q = hx.assemble_positions(model, data, q=guess)
    w, _, _ = model.law_values(0.0)
    assert np.max(np.abs(model.call("phi", q=q, w=w) / model.row_scale)) <= 1e-12
    p = q.reshape(-1, 7)[:, 3:]
    assert np.allclose(np.linalg.norm(p, axis=1), 1.0, atol=1e-14)
    # it stays near the guess (same assembly branch)
    assert np.linalg.norm(model.difference(q, guess)) < 0.5


@pytest.mark.parametrize("case", [c for c in CASES if c.child != "ground"], ids=case_id)
def test_assembly_of_every_joint_from_a_perturbed_pose(case):
    model = hx.assemble(case.scene(drive=False))
    rng = np.random.default_rng(6)
    guess = model.integrate(case.coordinates(model, 0.0), rng.normal(size=model.n_v) * 0.03)
    data = model.create_data()
    q = hx.assemble_positions(model, data, q=guess)
    w, _, _ = model.law_values(0.0)
    assert np.max(np.abs(model.call("phi", q=q, w=w) / model.row_scale)) <= 1e-12


def test_an_impossible_loop_names_the_violated_constraints():
    scene = four_bar(2, 1.05, driven=False)
    joint = scene.joints["rocker_ground"]
    on_rocker, on_ground = scene.joint_frames(joint)
    # the ground pivot 0.9 m from the crank's: farther than crank + coupler + rocker (0.55 m)
    joint.origin, joint.parent_frame = None, on_rocker
    joint.child_frame = hx.spatial.Placement([0.9, 0.0])
    model = hx.assemble(scene)
    with pytest.raises(hx.AssemblyError, match=r"rocker_ground/x|rocker_pin/x"):
        data = model.create_data()
        hx.assemble_positions(model, data)


def test_fully_driven_kinematics_match_the_dynamics():
    """Prescribed motion: velocities and accelerations are fixed by the constraints alone."""
    model = hx.assemble(four_bar(2, 1.05))
    for t in (0.0, 0.4, 1.1):
        data = model.create_data()
        q = hx.assemble_positions(model, data, t)
        v = hx.solve_velocities(model, data, t, q)
        w, wd, wdd = model.law_values(t)
        assert np.allclose(model.call("Phi_v", q=q, w=w) @ v, model.call("nu", q=q, w=w, wd=wd),
                           atol=1e-13)
        a = hx.solve_accelerations(model, data, t, q, v)
        assert np.allclose(hx.forward_dynamics(model, data, t, q, v), a, rtol=1e-11,
                           atol=1e-11)
        # the driver's law: crank angle from the crank's pose, rate and acceleration
        crank = model.bodies[model.body_index["crank"]]
        assert v[crank.v][2] == pytest.approx(wd[0], rel=1e-12)
        assert a[crank.v][2] == pytest.approx(wdd[0], rel=1e-12)


def test_condition_number_equals_the_direct_computation():
    model = hx.assemble(four_bar(2, 1.05, driven=False))
    data = model.create_data()
    q = hx.assemble_positions(model, data)
    hx.forward_dynamics(model, data, 0.0, q, model.v0, condition=True)
    W, _ = equilibrate(data.Phi_v, model.mass_inv_sqrt)
    n_v, n_c = W.shape[1], W.shape[0]
    kkt = np.block([[np.eye(n_v), W.T], [W, np.zeros((n_c, n_c))]])
    assert data.condition_number == pytest.approx(np.linalg.cond(kkt), rel=1e-8)
    assert data.sigma_min == pytest.approx(np.linalg.svd(W, compute_uv=False).min(),
                                                    rel=1e-10)
