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
    "constant": hx.scene.Constant(0.7),
    "polynomial": hx.scene.Polynomial([0.1, -0.4, 2.0, 0.5], t0=0.3),
    "harmonic": hx.scene.Harmonic(offset=0.2, cos=[0.3, -0.1], sin=[0.5, 0.05], frequency=0.8,
                                  t0=0.1),
    "spline3": hx.scene.Spline(SAMPLES_T, SAMPLES_Y),
    "spline3-natural": hx.scene.Spline(SAMPLES_T, SAMPLES_Y, boundary="natural"),
    "spline5": hx.scene.Spline(SAMPLES_T, SAMPLES_Y, degree=5),
    "spline5-clamped": hx.scene.Spline(SAMPLES_T, SAMPLES_Y, degree=5, boundary="clamped"),
    "scaled": Scaled(hx.scene.Harmonic(sin=[1.0], frequency=1.0), -2.5),
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
    law = hx.scene.Spline(SAMPLES_T, SAMPLES_Y, degree=degree)
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
    law = hx.scene.Spline(SAMPLES_T, y, boundary="periodic")
    for t in (0.3, 1.1, 1.9):
        assert np.allclose(np.array(law.evaluate(t)), np.array(law.evaluate(t + 2.0)),
                           atol=1e-12)


@pytest.mark.parametrize("law, message", [
    (hx.scene.Spline([0, 1, 0.5, 2], [0, 1, 2, 3]), "strictly increasing"),
    (hx.scene.Spline([0, 1, 2], [0, 1, 2]), "at least 4 samples"),
    (hx.scene.Spline([0, 1, 2, 3], [0, 1, 2]), "3 values"),
    (hx.scene.Spline([0, 1, 2, 3], [0, 1, 2, 3], degree=4), "degree must be 3 or 5"),
    (hx.scene.Spline([0, 1, 2, 3], [0, 1, 2, 3], boundary="periodic"), "periodic"),
    (hx.scene.Spline([0, 1, 2, 3], [0, np.nan, 2, 3]), "not finite"),
    (hx.scene.Harmonic(sin=[1.0], frequency=-2.0), "frequency must be positive"),
    (hx.scene.Polynomial([]), "empty"),
    (hx.scene.Constant(np.inf), "not finite"),
])
def test_bad_laws_report_their_problem(law, message):
    assert any(message in p for p in law.problems())


def test_unit_scaling_of_laws():
    for name, law in LAWS.items():
        scaled = law.scaled(10.0)
        for a, b in zip(scaled.evaluate(TIMES), law.evaluate(TIMES), strict=True):
            # a new spline is fitted to the scaled samples: round-off of its collocation solve
            assert np.allclose(a, 10.0 * b, rtol=1e-10, atol=1e-12), name


# ------------------------------------------------------------------ the warped-phase law

GAIT_CASES = [(0.5, 0.1, 0.0), (2 / 3, 0.1, 0.25), (5 / 6, 0.08, 0.6)]  # duty, blend, shift


@pytest.mark.parametrize("duty, blend, shift", GAIT_CASES)
def test_gait_law_is_c2(duty, blend, shift):
    law = hx.scene.Gait(0.1, cos=[0.3, -0.05], sin=[0.4, 0.02], period=0.5, duty=duty, shift=shift,
                        blend=blend)
    t = np.linspace(-0.3, 1.3, 4001)
    f, fd, fdd = law.evaluate(t)
    h = 1e-6
    assert np.allclose((law(t + h) - law(t - h)) / (2 * h), fd, atol=1e-6 * np.abs(fd).max())
    assert np.allclose((law.evaluate(t + h)[1] - law.evaluate(t - h)[1]) / (2 * h), fdd,
                       atol=1e-5 * np.abs(fdd).max())
    # no jump in value, rate or acceleration across the rate switches: the one-sided limits
    # agree there to within what the third derivative allows over the 2e-9 s gap (a C1 blend
    # would leave a jump of order one in the acceleration)
    a, d = 1.0 - duty, blend / 2
    edges = np.array([0.0, d, a - d, a + d, 1.0 - d]) if duty != 0.5 else np.array([0.0])
    switches = (edges - shift) * law.period
    eps = 1e-9
    left, right = law.evaluate(switches - eps), law.evaluate(switches + eps)
    for k, (lo, hi) in enumerate(zip(left, right, strict=True)):
        scale = np.abs((f, fd, fdd)[k]).max()
        assert np.abs(hi - lo).max() < 1e-6 * scale, f"derivative {k} jumps at a switch"


@pytest.mark.parametrize("duty, blend, shift", GAIT_CASES)
def test_gait_law_phase_reaches_pi_at_touch_down(duty, blend, shift):
    """Phase 0 at lift-off (t = -shift * period), pi at touch-down, a fraction 1 - duty of the
    period later, 2 pi one period after lift-off; the stance (phase past pi) lasts duty."""
    period = 0.5
    law = hx.scene.Gait(sin=[1.0], period=period, duty=duty, shift=shift, blend=blend)
    lift = -shift * period
    phi = law.phase(np.array([lift, lift + (1 - duty) * period, lift + period]))[0]
    assert phi[0] == pytest.approx(0.0, abs=1e-12)
    assert phi[1] == pytest.approx(np.pi, abs=1e-12)
    assert phi[2] == pytest.approx(2 * np.pi, abs=1e-12)
    t = np.linspace(0.0, period, 60001)[:-1]
    assert (law.phase(t)[0] % (2 * np.pi) >= np.pi).mean() == pytest.approx(duty, abs=1e-4)
    assert np.all(law.phase(t)[1] > 0)  # the phase never runs backwards


# ------------------------------------------------------------------ closed forms for CasADi

@pytest.mark.parametrize("name", LAWS)
def test_symbolic_form_equals_the_numeric_law(name):
    """``Law.symbolic`` (the CasADi expression compiled integrators use) against
    ``Law.evaluate`` at the sample times, in SX and MX: value, first and second derivative
    equal to round-off (two evaluations of one closed form). Laws without a closed form (the
    splines) say so with None, and are then evaluated numerically through a callback."""
    import casadi as ca

    law = LAWS[name]
    for kind in (ca.SX, ca.MX):
        t = kind.sym("t")
        form = law.symbolic(t)
        if name.startswith("spline"):
            assert form is None
            continue
        function = ca.Function("law", [t], list(form))
        got = np.array([np.array(function(x)).reshape(-1) for x in TIMES]).T
        for k, (a, b) in enumerate(zip(got, law.evaluate(TIMES), strict=True)):
            assert np.allclose(a, b, rtol=1e-13, atol=1e-13 * (1 + np.abs(b).max())), (name, k)
    for other in (hx.scene.Gait(sin=[1.0]), hx.scene.Hermite([0.0, 1.0], [0.0, 1.0], [0.0, 0.0],
                                                             [0.0, 0.0])):
        assert other.symbolic(ca.SX.sym("t")) is None


@pytest.mark.parametrize("periodic", [False, True])
def test_hermite_laws_on_one_array_of_times_read_together_give_their_own_bits(periodic):
    """A motion's joints (one array of times) are read together, the basis at the times once:
    each law's values, rates and accelerations are those it gives alone, bit for bit, at a
    time alone or among others, inside the table and outside it; laws on another array are
    not batched with them."""
    from hexapod.model.law_values import batches, evaluate_together
    from hexapod.model.tabulation import sampled_laws

    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0.0, 1.0, 17))
    t[0], t[-1] = 0.0, 1.0
    table = rng.normal(size=(3, 4, t.size))
    if periodic:
        table[..., -1] = table[..., 0]
    laws = sampled_laws(t, *table)
    if periodic:
        laws = [hx.scene.Hermite(law.times, law.values, law.rates, law.accelerations,
                                 periodic=True) for law in laws]
    other = hx.scene.Hermite(t.copy(), *table[:, 0])
    mixed = [*laws, other]
    assert len({law.batch_key() for law in laws}) == 1
    assert [len(group) for _, group in batches(mixed).groups] == [4, 1]
    for times in (np.linspace(-0.3, 2.2, 53), np.float64(0.61)):
        together = evaluate_together(mixed, times)
        for k, law in enumerate(mixed):
            for m, alone in enumerate(law.evaluate(times)):
                assert np.array_equal(together[m, k], alone), (k, m)


def test_a_periodic_hermite_table_repeats_and_round_trips(tmp_path):
    """A closed table of sin(2 pi t) over one second, periodic: a time k periods later reads
    the same value, rate and acceleration to round-off, where the open table's end
    polynomial runs away; a table that does not close is refused; written and read back, the
    same law."""
    t = np.linspace(0.0, 1.0, 41)
    w = 2 * np.pi
    table = (t, np.sin(w * t), w * np.cos(w * t), -w * w * np.sin(w * t))
    table[1][-1], table[3][-1] = table[1][0], table[3][0]  # closed exactly
    periodic, open_ = hx.scene.Hermite(*table, periodic=True), hx.scene.Hermite(*table)
    assert periodic.cycle_time() == 1.0 and open_.cycle_time() is None
    inside = np.linspace(0.0, 1.0, 97)
    for k in (1.0, 3.0, -2.0):
        for a, b in zip(periodic.evaluate(inside + k), periodic.evaluate(inside), strict=True):
            assert np.abs(a - b).max() < 1e-9 * np.abs(b).max()
    assert abs(open_(2.5)) > 10 * abs(periodic(2.5))
    assert hx.scene.Hermite(t, t, t, t, periodic=True).problems()  # does not close
    scene = hx.Scene("beam")
    scene.add(hx.scene.SpatialBody("beam", 1.0, [0.1, 0.1, 0.1]))
    scene.add(hx.scene.Revolute("hinge", "ground", "beam", origin=[0, 0, 0], axis=[0, 0, 1]))
    scene.add(hx.scene.JointDriver("turn", "hinge", periodic))
    copy = hx.read_scene(hx.write_scene(scene, tmp_path / "beam.toml"))
    assert "periodic = true" in (tmp_path / "beam.toml").read_text()
    assert np.array_equal(copy.drivers["turn"].law.evaluate(inside + 2.0)[2],
                          periodic.evaluate(inside + 2.0)[2])
