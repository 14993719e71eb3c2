"""The Runge-Kutta coefficients of hexapod.simulation.integrators.tableaus: equal to SciPy's where
its public classes expose them (RK45, DOP853), and checked by their defining conditions (order
conditions of the tableaus and of the continuous extensions, Radau IIA's collocation
conditions) everywhere."""

import math

import numpy as np
import scipy.integrate

from hexapod.simulation.integrators import tableaus as tb

#: the relative round-off of a sum of a few dozen products of coefficients of size up to 50
ROUND = 1e-13


def quadrature(b, c, order):
    """The largest k <= order with sum_i b_i c_i^(j-1) = 1/j for every j <= k."""
    for j in range(1, order + 1):
        if not math.isclose(b @ c ** (j - 1), 1 / j, rel_tol=ROUND, abs_tol=ROUND):
            return j - 1
    return order


def order_conditions(A, b, c):
    """The residuals of the conditions of order 1 to 4 (the eight trees):
    b.1 = 1, b.c = 1/2, b.c^2 = 1/3, b.Ac = 1/6, b.c^3 = 1/4, b.(c*Ac) = 1/8,
    b.A c^2 = 1/12, b.A A c = 1/24."""
    Ac = A @ c
    return np.array([
        b.sum() - 1, b @ c - 1 / 2, b @ c**2 - 1 / 3, b @ Ac - 1 / 6,
        b @ c**3 - 1 / 4, b @ (c * Ac) - 1 / 8, b @ (A @ c**2) - 1 / 12, b @ (A @ Ac) - 1 / 24])


def test_dopri5_equals_scipy_rk45():
    """SciPy's RK45 holds the six stages and the embedded error weights E = b_hat - b (its
    seventh stage, the rate at the new state, has weight 0 in b)."""
    rk = scipy.integrate.RK45
    assert np.array_equal(tb.DOPRI5_C[:6], rk.C)
    assert np.array_equal(tb.DOPRI5_A[:6, :5], rk.A)
    assert np.array_equal(tb.DOPRI5_B[:6], rk.B)
    assert np.array_equal(tb.DOPRI5_DENSE, rk.P)
    # the difference of weights of size up to 0.65, to their round-off
    np.testing.assert_allclose(tb.DOPRI5_B_HAT - tb.DOPRI5_B, rk.E, rtol=0, atol=3e-16)


def test_dopri5_order_conditions():
    A, b, b_hat, c = tb.DOPRI5_A, tb.DOPRI5_B, tb.DOPRI5_B_HAT, tb.DOPRI5_C
    np.testing.assert_allclose(A.sum(axis=1), c, atol=ROUND)
    np.testing.assert_array_equal(A[-1], b)  # first same as last
    assert np.abs(order_conditions(A, b, c)).max() < ROUND
    assert np.abs(order_conditions(A, b_hat, c)).max() < ROUND
    assert quadrature(b, c, 7) == 5  # order 5, not 6
    assert quadrature(b_hat, c, 7) == 4
    # the fifth-order trees b.A c^3 = 1/20 and b.A A c^2 = 1/60 (with the quadrature ones)
    assert abs(b @ (A @ c**3) - 1 / 20) < ROUND
    assert abs(b @ (A @ (A @ c**2)) - 1 / 60) < ROUND


def test_dopri5_dense_output():
    """Shampine's extension: b(1) = b, and order 4 along the stages (sum b_i(theta) c_i^(k-1)
    = theta^k / k for k <= 4, and b(theta).A c = theta^3 / 6)."""
    P, A, b, c = tb.DOPRI5_DENSE, tb.DOPRI5_A, tb.DOPRI5_B, tb.DOPRI5_C
    np.testing.assert_allclose(P.sum(axis=1), b, atol=ROUND)
    for theta in (0.2, 0.5, 0.9):
        weights = P @ theta ** np.arange(1, 5)
        for k in range(1, 5):
            assert abs(weights @ c ** (k - 1) - theta**k / k) < ROUND
        assert abs(weights @ (A @ c) - theta**3 / 6) < ROUND


def test_dop853_equals_scipy():
    dop = scipy.integrate.DOP853
    n = tb.DOP853_STAGES
    assert n == dop.n_stages and dop.order == 8
    assert np.array_equal(tb.DOP853_A[:n, :n], dop.A)
    assert np.array_equal(tb.DOP853_B, dop.B)
    assert np.array_equal(tb.DOP853_C[:n], dop.C)
    assert np.array_equal(tb.DOP853_E3, dop.E3)
    assert np.array_equal(tb.DOP853_E5, dop.E5)
    assert np.array_equal(tb.DOP853_D, dop.D)
    assert np.array_equal(tb.DOP853_A[n + 1:], dop.A_EXTRA)
    assert np.array_equal(tb.DOP853_C[n + 1:], dop.C_EXTRA)


def test_dop853_order_conditions():
    n = tb.DOP853_STAGES
    A, b, c = tb.DOP853_A[:n, :n], tb.DOP853_B, tb.DOP853_C[:n]
    np.testing.assert_allclose(A.sum(axis=1), c, atol=1e-12)
    np.testing.assert_allclose(tb.DOP853_A.sum(axis=1), tb.DOP853_C, atol=1e-12)
    np.testing.assert_array_equal(tb.DOP853_A[n, :n], b)  # stage 13: the new state's rate
    assert np.abs(order_conditions(A, b, c)).max() < 1e-12
    assert quadrature(b, c, 9) == 8
    # the error estimators are differences of weights of methods of order 5 and 3: E5 and
    # E3 (E3 = b - b3) annihilate the quadrature conditions up to those orders
    c13 = tb.DOP853_C[:n + 1]
    for k in range(1, 6):
        assert abs(tb.DOP853_E5 @ c13 ** (k - 1)) < 1e-12
    for k in range(1, 4):
        assert abs(tb.DOP853_E3 @ c13 ** (k - 1)) < 1e-12


def test_radau_iia_collocation():
    """Radau IIA, three stages: nodes the zeros of d^2/dx^2 (x^2 (x - 1)^3), the last one;
    the collocation conditions sum_j a_ij c_j^(k-1) = c_i^k / k (k = 1, 2, 3); stiffly
    accurate (b = last row of A) with b of quadrature order 5."""
    A, c = tb.RADAU_A, tb.RADAU_C
    radau = np.polynomial.Polynomial([0, 0, 1]) * np.polynomial.Polynomial([-1, 1]) ** 3
    np.testing.assert_allclose(np.sort(radau.deriv(2).roots().real), c, atol=ROUND)
    np.testing.assert_allclose(c, [(4 - math.sqrt(6)) / 10, (4 + math.sqrt(6)) / 10, 1],
                               atol=1e-16)
    for k in range(1, 4):
        np.testing.assert_allclose(A @ c ** (k - 1), c**k / k, atol=ROUND)
    b = A[-1]
    assert quadrature(b, c, 6) == 5


def test_radau_error_weights():
    """RADAU5's estimate ``gamma0 h f(y0) + sum_i e_i Z_i`` is the difference of the solution
    and an embedded one of order 3 with weights ``b_hat = b + gamma0 A^T e`` and ``gamma0`` at
    the node 0: ``gamma0 [k = 1] + (b_hat - b).c^(k-1) = 0`` for k = 1, 2, 3, whatever
    ``gamma0``, i.e. ``(A^T e).c^(k-1) = -[k = 1]``."""
    A, c, e = tb.RADAU_A, tb.RADAU_C, tb.RADAU_E
    weights = A.T @ e
    for k in range(1, 4):
        assert abs(weights @ c ** (k - 1) + (k == 1)) < ROUND


def test_radau_dense_output():
    """The collocation polynomial u(theta) = sum_i Z_i sum_k P_ik theta^(k+1) passes through
    0 at theta = 0 and through each stage increment at its node."""
    P, c = tb.RADAU_DENSE, tb.RADAU_C
    powers = c[:, None] ** np.arange(1, 4)[None, :]  # (node j, power k)
    np.testing.assert_allclose(P @ powers.T, np.eye(3), atol=1e-12)


def test_rk4():
    A, b, c, P = tb.RK4_A, tb.RK4_B, tb.RK4_C, tb.RK4_DENSE
    np.testing.assert_allclose(A.sum(axis=1), c, atol=0)
    assert np.abs(order_conditions(A, b, c)).max() < ROUND
    assert quadrature(b, c, 5) == 4
    np.testing.assert_allclose(P.sum(axis=1), b, atol=ROUND)
    for theta in (0.3, 0.7):  # the extension's order 3: the trees of order 1 to 3
        weights = P @ theta ** np.arange(1, 4)
        assert abs(weights.sum() - theta) < ROUND
        assert abs(weights @ c - theta**2 / 2) < ROUND
        assert abs(weights @ c**2 - theta**3 / 3) < ROUND
        assert abs(weights @ (A @ c) - theta**3 / 6) < ROUND
