"""Euler parameters, rotations and frames (the conventions of docs/scene-format.md)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from hexapod.spatial import (
    Placement,
    e_matrix,
    euler_parameters_from_rotation,
    g_matrix,
    quaternion_exp,
    quaternion_log,
    quaternion_product,
    rotation_about_axis,
    rotation_from_euler_parameters,
    rotation_from_rpy,
    skew,
)

RNG = np.random.default_rng(11)
QUATERNIONS = [q / np.linalg.norm(q) for q in RNG.normal(size=(20, 4))]


@pytest.mark.parametrize("p", QUATERNIONS[:8])
def test_haug_matrices(p):
    A, G, E = rotation_from_euler_parameters(p), g_matrix(p), e_matrix(p)
    assert np.allclose(A.T @ A, np.eye(3), atol=1e-14) and np.linalg.det(A) > 0
    assert np.allclose(A, E @ G.T, atol=1e-14)  # A = E G^T
    assert np.allclose(G @ p, 0, atol=1e-15) and np.allclose(E @ p, 0, atol=1e-15)
    assert np.allclose(G @ G.T, np.eye(3), atol=1e-14)
    # omega' = 2 G p_dot is the body angular velocity: A^T A_dot = skew(omega')
    omega = RNG.normal(size=3)
    p_dot = 0.5 * G.T @ omega
    h = 1e-6
    A_dot = (rotation_from_euler_parameters(p + h * p_dot)
             - rotation_from_euler_parameters(p - h * p_dot)) / (2 * h)
    assert np.allclose(A.T @ A_dot, skew(omega), atol=1e-8)
    assert np.allclose(2 * G @ p_dot, omega, atol=1e-14)
    assert np.allclose(2 * E @ p_dot, A @ omega, atol=1e-14)  # world angular velocity


def test_symbolic_and_numeric_forms_agree():
    p = ca.SX.sym("p", 4)
    f = ca.Function("A", [p], [rotation_from_euler_parameters(p), g_matrix(p), e_matrix(p)])
    for q in QUATERNIONS[:4]:
        for sym, num in zip(f(q), (rotation_from_euler_parameters(q), g_matrix(q),
                                   e_matrix(q)), strict=True):
            assert np.allclose(sym.full(), num, atol=1e-15)


def test_quaternion_product_composes_rotations():
    for p, q in zip(QUATERNIONS[:5], QUATERNIONS[5:10], strict=True):
        assert np.allclose(rotation_from_euler_parameters(quaternion_product(p, q)),
                           rotation_from_euler_parameters(p) @ rotation_from_euler_parameters(q),
                           atol=1e-14)
    stacked = quaternion_product(np.array(QUATERNIONS[:5]), np.array(QUATERNIONS[5:10]))
    assert np.allclose(stacked[2], quaternion_product(QUATERNIONS[2], QUATERNIONS[7]))


@pytest.mark.parametrize("angle", [0.0, 1e-10, 1e-5, 0.3, 2.0, np.pi - 1e-7])
def test_exp_and_log_are_inverse(angle):
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    theta = angle * axis
    p = quaternion_exp(theta)
    assert np.linalg.norm(p) == pytest.approx(1.0, abs=1e-15)
    assert np.allclose(rotation_from_euler_parameters(p), rotation_about_axis(axis, angle),
                       atol=1e-14)
    assert np.allclose(quaternion_log(p), theta, atol=1e-12)
    assert np.allclose(quaternion_log(-p), theta, atol=1e-12)  # p and -p: the same rotation


def test_rotation_matrix_round_trip_takes_every_branch():
    # identity-like, and half turns about x, y and z (Shepperd's four branches)
    rotations = [np.eye(3)] + [rotation_about_axis(e, np.pi - 0.01) for e in np.eye(3)]
    rotations += [rotation_from_euler_parameters(q) for q in QUATERNIONS]
    for R in rotations:
        p = euler_parameters_from_rotation(R)
        assert p[0] >= 0 and np.linalg.norm(p) == pytest.approx(1.0)
        assert np.allclose(rotation_from_euler_parameters(p), R, atol=1e-13)


def test_rpy_is_urdf_convention():
    roll, pitch, yaw = 0.3, -0.7, 1.9
    Rx = np.array([[1, 0, 0], [0, np.cos(roll), -np.sin(roll)], [0, np.sin(roll), np.cos(roll)]])
    Ry = np.array([[np.cos(pitch), 0, np.sin(pitch)], [0, 1, 0],
                   [-np.sin(pitch), 0, np.cos(pitch)]])
    Rz = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    assert np.allclose(rotation_from_rpy(roll, pitch, yaw), Rz @ Ry @ Rx, atol=1e-15)


def test_placements_compose_and_invert():
    a = Placement([1.0, 2.0, 3.0], rotation_about_axis([1, 1, 0], 0.4))
    b = Placement([-0.5, 0.2, 0.1], rotation_about_axis([0, 0, 1], -1.1))
    x = np.array([0.3, -0.2, 0.9])
    assert np.allclose((a @ b).transform_point(x), a.transform_point(b.transform_point(x)))
    identity = a @ a.inverse()
    assert np.allclose(identity.position, 0) and np.allclose(identity.rotation, np.eye(3))
    planar = Placement([1.0, 2.0], 0.5)
    assert planar.angle == pytest.approx(0.5) and planar.dimension == 2


@pytest.mark.parametrize("pitch", [0.3, np.pi / 2 - 1e-9, -np.pi / 2 + 1e-7, np.pi / 2])
def test_rpy_round_trip_is_exact_even_near_gimbal_lock(pitch):
    from hexapod.spatial import rpy_from_rotation
    R = rotation_from_rpy(0.4, pitch, -1.1)
    assert np.allclose(rotation_from_rpy(*rpy_from_rotation(R)), R, rtol=0, atol=2e-16 * 8)
