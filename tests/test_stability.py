"""The walking robot's stability margins (:mod:`hexapod.output.stability`).

* The centre of pressure from the ground forces on the feet equals the zero-moment point
  computed from the bodies' motions alone (their momentum's rate and gravity, no force of the
  solve): ``c_x = (h F_x - M_y) / F_z``, ``c_y = (M_x + h F_y) / F_z`` with ``F`` and ``M``
  (about the world origin) the rates of linear and angular momentum less gravity's, ``h`` the
  ground's height. Both sides agree to round-off plus the assembly's tolerance: 1e-9 m on a
  robot half a metre long.
* The static margin on a tripod's triangle against barycentric coordinates and the distance
  to each edge's line, written here apart from the module's polygon code.
* The signed distance on a unit square, a segment and a point, in closed form.
"""

from __future__ import annotations

import numpy as np
import pytest
from robots import builtin_model

import hexapod as hx


@pytest.fixture(scope="module")
def walking():
    model = builtin_model("hexapod")
    times = np.linspace(0.0, 0.5, 41)
    result = hx.inverse_dynamics(model, times)
    return model, result, hx.output.stability_margins(model, result)


def zero_moment_point(model, result) -> np.ndarray:
    """The ZMP (N, 2) from the bodies' accelerations alone (see the module's description)."""
    positions, rotations = hx.body_poses(model, result.q)
    mass = model.mass.dense()
    g = np.asarray(model.gravity, dtype=float)
    F = np.zeros((result.times.size, 3))
    M = np.zeros((result.times.size, 3))
    for b, body in enumerate(model.bodies):
        v, a = result.v[:, body.v], result.v_dot[:, body.v]
        index = np.arange(model.n_v)[body.v]
        m, J = body.mass, mass[np.ix_(index, index)][3:, 3:]
        linear = m * (a[:, :3] - g)
        omega, alpha = v[:, 3:], a[:, 3:]
        spin = alpha @ J.T + np.cross(omega, omega @ J.T)  # body frame, about the centre
        F += linear
        M += np.cross(positions[:, b], linear) + np.einsum("nij,nj->ni", rotations[:, b], spin)
    h = ground_height(model, result, positions, rotations)
    return np.column_stack([(h * F[:, 0] - M[:, 1]) / F[:, 2], (M[:, 0] + h * F[:, 1]) / F[:, 2]])


def ground_height(model, result, positions, rotations) -> float:
    """The height of the stance feet (the ground's plane), the same for all of them."""
    heights = []
    for contact in model.contacts:
        joint = model.joints[contact.joint]
        local = np.asarray(joint.child_frame.position, dtype=float)
        z = positions[:, joint.child, 2] + rotations[:, joint.child, 2] @ local
        heights += list(z[np.asarray(contact.in_stance(result.times))])
    assert np.ptp(heights) < 1e-12
    return float(np.mean(heights))


def test_the_centre_of_pressure_is_the_zero_moment_point_of_the_motion(walking):
    model, result, margins = walking
    assert all(len(polygon) >= 3 for polygon in margins.support)
    expected = zero_moment_point(model, result)
    assert np.abs(margins.cop - expected).max() < 1e-9
    assert np.all(margins.cop_margin > 0)  # every stance foot is pushed


def test_the_static_margin_on_a_tripod_is_the_distance_to_the_triangles_edges(walking):
    model, result, margins = walking
    checked = 0
    for k, polygon in enumerate(margins.support):
        if len(polygon) != 3:
            continue
        a, b, c = polygon
        p = margins.com[k]
        T = np.column_stack([b - a, c - a])
        u, w = np.linalg.solve(T, p - a)
        inside = u >= 0 and w >= 0 and u + w <= 1
        lines = [abs((q - o)[0] * (p - o)[1] - (q - o)[1] * (p - o)[0]) / np.linalg.norm(q - o)
                 for o, q in ((a, b), (b, c), (c, a))]
        assert inside
        assert margins.static_margin[k] == pytest.approx(min(lines), rel=1e-12)
        checked += 1
    assert checked >= 20


def test_the_signed_distance_in_closed_form():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    distance = hx.output.signed_distance
    assert distance(np.array([0.5, 0.2]), square) == pytest.approx(0.2)
    assert distance(np.array([2.0, 0.5]), square) == pytest.approx(-1.0)
    assert distance(np.array([2.0, 2.0]), square) == pytest.approx(-np.sqrt(2.0))
    segment = square[:2]
    assert distance(np.array([0.5, 0.3]), segment) == pytest.approx(-0.3)
    assert distance(np.array([1.5, 0.0]), segment) == pytest.approx(-0.5)
    assert distance(np.array([3.0, 4.0]), square[:1]) == pytest.approx(-5.0)
    assert np.isnan(distance(np.array([np.nan, 0.0]), square))
    assert np.isnan(distance(np.array([0.0, 0.0]), square[:0]))


def test_the_report_writes_the_margins(walking):
    """``margins.csv`` holds the margins the module computes, and the summary their
    smallest values."""
    model, result, margins = walking
    balance = hx.body_balance(model, result.times, result.q, result.v, result.v_dot,
                              result.force, result.torque, result.frame)
    run = hx.output.RunInfo("hexapod", "hexapod", 1.0, "a stride")
    files = hx.output.report_files(model, result, balance, run, {}, figures=False)
    lines = files["margins.csv"].decode().splitlines()
    assert lines[0] == "t,com:x,com:y,cop:x,cop:y,margin:static,margin:cop"
    table = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
    np.testing.assert_array_equal(table[:, 5], margins.static_margin)
    summary = files["summary.md"].decode()
    smallest = 1e3 * margins.static_margin.min()
    assert "## Stability" in summary and f"| {smallest:.4g} |" in summary
