"""The contact schemes' constrained solve in one CasADi call
(:class:`hexapod.simulation.contact_kernel.CompiledContactStep`: Moreau-Jean's step, the
event-driven scheme's accelerations and impulses) against the same equations formed from the
model's own functions and solved densely by NumPy, on a planar rod hinged at one end
and driven by a PD controller (its gains make the stiffness ``K`` and damping ``C`` of the
linearly implicit step nonzero); and its refusal of a row set that no longer serves."""

from __future__ import annotations

import numpy as np
import pytest
from test_controller import rod as servo_rod

from hexapod.simulation.contact_kernel import CompiledContactStep

SERVO = """
target = { type = "harmonic", sin = [0.3], frequency = 1.0 }
kp = 50.0
kd = 3.0
"""
H, THETA, T = 1e-2, 0.5, 0.13


@pytest.fixture(scope="module")
def rod(tmp_path_factory):
    """The servo rod of tests/test_controller.py under gravity, its PD gains nonzero."""
    return servo_rod(tmp_path_factory.mktemp("rod"), SERVO, gravity=-9.81)


def _named(function, **values):
    return [np.asarray(x) for x in function.call([values[n] for n in function.name_in()])]


def _state(model):
    """The initial positions and a velocity along the hinge's free motion."""
    q = np.asarray(model.q0, dtype=float)
    Phi_v = _named(model.Phi_v, q=q, w=model.law_values(0.0)[0])[0]
    free = np.linalg.svd(Phi_v)[2][-1]  # the null space of the two hinge rows
    return q, 1.7 * free / free[2]


def _dense_step(model, q, v, mid, end, G):
    """The step's equations (see the kernel's description), unscaled, solved densely."""
    w, wd, wdd = mid
    values = dict(q=q, v=v, w=w, wd=wd, wdd=wdd, lam=np.zeros(model.n_c))
    _, _, Q = _named(model.dynamics_terms, **values)
    K, C = _named(model.tangent_matrices, **values)
    Phi_v = _named(model.Phi_v, **values)[0]
    nu = _named(model.nu, q=q, w=end[0], wd=end[1])[0].ravel()
    M = model.mass.dense()
    m_sqrt = np.linalg.inv(model.mass_inv_sqrt.dense())
    a = H * THETA
    iteration = M + a * C + a * a * K
    n_v, n_c = model.n_v, model.n_c
    S = np.block([[iteration, Phi_v.T], [Phi_v, np.zeros((n_c, n_c))]])
    rhs = np.zeros((n_v + n_c, 1 + G.shape[1]))
    rhs[:n_v, 0] = iteration @ v + H * Q.ravel()  # q: where the step's forces act
    rhs[n_v:, 0] = nu
    rhs[:n_v, 1:] = m_sqrt @ G  # J^T = M^1/2 G
    x = np.linalg.solve(S, rhs)
    return m_sqrt @ x[:n_v], x[n_v:], K, C


def test_the_kernel_solves_the_linearly_implicit_step_as_written(rod):
    """``y, lam`` and the responses ``Y, Lam`` to two arbitrary impulse columns agree with
    the dense solve of the same equations to 1e-12 of their size (two direct solves of a
    5 x 5 system whose condition number is under 1e3)."""
    q, v = _state(rod)
    mid = tuple(np.asarray(x) for x in rod.law_values(T + THETA * H))
    end = tuple(np.asarray(x) for x in rod.law_values(T + H))
    G = np.random.default_rng(3).normal(size=(rod.n_v, 2))
    expected, multipliers, K, C = _dense_step(rod, q, v, mid, end, G)
    assert np.abs(K).max() > 1.0 and np.abs(C).max() > 1.0  # the gains are in the step
    kernel = CompiledContactStep(rod, np.arange(rod.n_c), np.zeros(0, int), G.shape[1])
    y, lam, Y, Lam = kernel(q, v, (*mid, *end[:2]), G, H, THETA)
    got = np.column_stack([y, Y])
    assert np.abs(got - expected).max() <= 1e-12 * np.abs(expected).max()
    got = np.column_stack([lam, Lam])
    assert np.abs(got - multipliers).max() <= 1e-12 * np.abs(multipliers).max()


def test_a_row_left_out_that_is_independent_refuses_the_solve(rod):
    """Built as if the hinge's second row were redundant, the kernel's solve violates it: the
    residual of the rows left out says so, and the call returns None (the scheme then decides
    the rows again)."""
    q, v = _state(rod)
    mid = tuple(np.asarray(x) for x in rod.law_values(T + THETA * H))
    end = tuple(np.asarray(x) for x in rod.law_values(T + H))
    kernel = CompiledContactStep(rod, np.array([0]), np.array([1]), 0)
    assert kernel(q, v, (*mid, *end[:2]), np.zeros((rod.n_v, 0)), H, THETA) is None


@pytest.mark.parametrize("level", ["acceleration", "impulse"])
def test_the_event_driven_levels_solve_their_saddle_point_systems(rod, level):
    """The accelerations ``[M Phi_v^T; Phi_v 0] [a; lam] = [Q + J^T F; gamma]`` and an
    impulse's velocities ``[M Phi_v^T; Phi_v 0] [x; lam] = [M v + J^T P; nu]``, each with two
    arbitrary contact columns, against the dense solve (1e-12 of their size)."""
    q, v = _state(rod)
    w, wd, wdd = (np.asarray(x) for x in rod.law_values(T))
    values = dict(q=q, v=v, w=w, wd=wd, wdd=wdd)
    Phi_v, gamma, Q = _named(rod.dynamics_terms, **values)
    M = rod.mass.dense()
    m_sqrt = np.linalg.inv(rod.mass_inv_sqrt.dense())
    G = np.random.default_rng(5).normal(size=(rod.n_v, 2))
    n_v, n_c = rod.n_v, rod.n_c
    rhs = np.zeros((n_v + n_c, 3))
    if level == "acceleration":
        rhs[:n_v, 0], rhs[n_v:, 0], laws = Q.ravel(), gamma.ravel(), (w, wd, wdd)
    else:
        nu = _named(rod.nu, q=q, w=w, wd=wd)[0].ravel()
        rhs[:n_v, 0], rhs[n_v:, 0], laws = M @ v, nu, (w, wd)
    rhs[:n_v, 1:] = m_sqrt @ G
    x = np.linalg.solve(np.block([[M, Phi_v.T], [Phi_v, np.zeros((n_c, n_c))]]), rhs)
    kernel = CompiledContactStep(rod, np.arange(n_c), np.zeros(0, int), 2, level)
    y, lam, Y, Lam = kernel(q, v, laws, G)
    expected = m_sqrt @ x[:n_v]
    assert np.abs(np.column_stack([y, Y]) - expected).max() <= 1e-12 * np.abs(expected).max()
    assert np.abs(np.column_stack([lam, Lam]) - x[n_v:]).max() <= 1e-12 * np.abs(x[n_v:]).max()
