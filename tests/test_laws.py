"""Time laws: derivatives, smoothness, and the problems they report."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod as hx
from hexapod.scene.laws import Scaled

SAMPLES_T = np.linspace(0.0, 2.0, 11)
TIMES = np.linspace(0.05, 1.95, 37)
TIMES = TIMES[np.min(np.abs(TIMES[:, None] - SAMPLES_T), axis=1) > 1e-3]  # off the knots,
# where a spline's third derivative jumps and central differences straddling them lose accuracy
SAMPLES_Y = np.sin(2 * SAMPLES_T) + 0.3 * SAMPLES_T**2

LAWS = {
    "constant": hx.Constant(0.7),
    "polynomial": hx.Polynomial([0.1, -0.4, 2.0, 0.5], t0=0.3),
    "harmonic": hx.Harmonic(offset=0.2, cos=[0.3, -0.1], sin=[0.5, 0.05], frequency=0.8, t0=0.1),
    "spline3": hx.Spline(SAMPLES_T, SAMPLES_Y),
    "spline3-natural": hx.Spline(SAMPLES_T, SAMPLES_Y, boundary="natural"),
    "spline5": hx.Spline(SAMPLES_T, SAMPLES_Y, degree=5),
    "spline5-clamped": hx.Spline(SAMPLES_T, SAMPLES_Y, degree=5, boundary="clamped"),
    "scaled": Scaled(hx.Harmonic(sin=[1.0], frequency=1.0), -2.5),
}


@pytest.mark.parametrize("name", LAWS)
def test_derivatives_match_finite_differences(name):
    law = LAWS[name]
    h = 1e-4
    f, fd, fdd = law.evaluate(TIMES)
    assert f.shape == fd.shape == fdd.shape == TIMES.shape
    # central differences: O(h^2) truncation, here < 1e-6 of the values' size
    fd_num = (law(TIMES + h) - law(TIMES - h)) / (2 * h)
    assert np.allclose(fd, fd_num, rtol=1e-6, atol=1e-6)
    fdd_num = (law.evaluate(TIMES + h)[1] - law.evaluate(TIMES - h)[1]) / (2 * h)
    assert np.allclose(fdd, fdd_num, rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize("degree, order", [(3, 2), (5, 4)])
def test_splines_interpolate_and_are_smooth_at_the_knots(degree, order):
    law = hx.Spline(SAMPLES_T, SAMPLES_Y, degree=degree)
    assert np.allclose(law(SAMPLES_T), SAMPLES_Y, atol=1e-13)
    spline = law._spline
    eps = 1e-9
    inner = SAMPLES_T[1:-1]
    for nu in range(order + 1):  # continuous up to the spline's smoothness
        left, right = spline(inner - eps, nu=nu), spline(inner + eps, nu=nu)
        assert np.allclose(left, right, atol=1e-5 * (1 + np.abs(left).max())), nu


def test_periodic_spline_repeats():
    y = np.sin(2 * np.pi * SAMPLES_T / 2.0)
    y[-1] = y[0]
    law = hx.Spline(SAMPLES_T, y, boundary="periodic")
    for t in (0.3, 1.1, 1.9):
        assert np.allclose(np.array(law.evaluate(t)), np.array(law.evaluate(t + 2.0)),
                           atol=1e-12)


@pytest.mark.parametrize("law, message", [
    (hx.Spline([0, 1, 0.5, 2], [0, 1, 2, 3]), "strictly increasing"),
    (hx.Spline([0, 1, 2], [0, 1, 2]), "at least 4 samples"),
    (hx.Spline([0, 1, 2, 3], [0, 1, 2]), "3 values"),
    (hx.Spline([0, 1, 2, 3], [0, 1, 2, 3], degree=4), "degree must be 3 or 5"),
    (hx.Spline([0, 1, 2, 3], [0, 1, 2, 3], boundary="periodic"), "periodic"),
    (hx.Spline([0, 1, 2, 3], [0, np.nan, 2, 3]), "not finite"),
    (hx.Harmonic(sin=[1.0], frequency=-2.0), "frequency must be positive"),
    (hx.Polynomial([]), "empty"),
    (hx.Constant(np.inf), "not finite"),
])
def test_bad_laws_report_their_problem(law, message):
    assert any(message in p for p in law.problems())


def test_unit_scaling_of_laws():
    for name, law in LAWS.items():
        scaled = law.scaled(10.0)
        for a, b in zip(scaled.evaluate(TIMES), law.evaluate(TIMES), strict=True):
            # a new spline is fitted to the scaled samples: round-off of its collocation solve
            assert np.allclose(a, 10.0 * b, rtol=1e-10, atol=1e-12), name
