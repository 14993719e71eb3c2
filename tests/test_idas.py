"""``idas-bdf``: SUNDIALS IDAS (variable-order BDF) on the index-1 equations, with Baumgarte
terms in the DAE and projection restarts, against exact solutions and its own drift promise.

The registry-wide tests (tests/test_integrators.py) run it too; these check what is its own:
the error against the tolerance, the drift tolerance and the restarts it costs, the time laws
compiled into the DAE (closed forms and the callback), and the states it returns."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod.benchmarks import ClosedLoopPendulum, pendulum_exact
from hexapod.scene.reader import read_scene
from hexapod.simulation.integrators import IdasBDF
from hexapod.simulation.loop import simulate

SCENES = Path(__file__).resolve().parents[1] / "data" / "scenes"
G = 9.81


def seed002():
    return hx.assemble(read_scene(SCENES / "closed_pendulum_seed002.toml"))


def seed002_error(result) -> float:
    """Largest distance of either particle from the one-degree-of-freedom solution (m)."""
    p1, p2, _ = ClosedLoopPendulum().solve(float(result.t[-1]))(result.t)
    return float(max(np.abs(result.q[:, 0:2] - p1).max(), np.abs(result.q[:, 2:4] - p2).max()))


def planar_rod(law=None):
    """A 1 m, 1 kg rod (centre of mass 0.5 m from the pivot, I_G = 0.0833 kg m^2) on a revolute
    joint at the origin of the plane, gravity -y; its angle from +x driven by ``law``."""
    scene = hx.Scene("rod", 2)
    scene.add(hx.scene.PlanarBody("rod", 1.0, 0.0833, position=[0.5, 0.0]))
    scene.add(hx.scene.Revolute("pivot", "ground", "rod", origin=[0.0, 0.0]))
    if law is not None:
        scene.add(hx.scene.JointDriver("motor", "pivot", law))
    return hx.assemble(scene)


def test_error_follows_the_tolerance_on_the_exact_pendulum():
    """The rod released horizontal against the elliptic-function solution over two periods
    (4 s), rtol = atol = tol from 1e-4 to 1e-10: the error shrinks with the tolerance, in
    proportion (fitted slope of log error against log tol within 0.75 and 1.25: a variable-order
    method's global error is a problem-dependent multiple of its tolerance, measured here
    between 1 and 4), and stays within 10 tol (1 + arm), the registry's promise."""
    model = planar_rod()
    omega0, arm = np.sqrt(G * 0.5 / (0.0833 + 0.25)), 0.5
    tolerances = [1e-4, 1e-6, 1e-8, 1e-10]
    errors = []
    for tol in tolerances:
        result = simulate(model, 4.0, method="idas-bdf", rtol=tol, atol=tol, step=0.04)
        assert result.success, result.message
        psi, _ = pendulum_exact(result.t, np.pi / 2, omega0)
        exact = arm * np.column_stack([np.sin(psi), -np.cos(psi)])
        errors.append(float(np.abs(result.q[:, :2] - exact).max()))
        assert errors[-1] <= 10 * tol * (1 + arm), (tol, errors[-1])
    assert all(a > b for a, b in zip(errors, errors[1:], strict=False)), errors
    slope = np.polyfit(np.log(tolerances), np.log(errors), 1)[0]
    assert 0.75 <= slope <= 1.25, (errors, slope)


def test_seed002_at_a_tight_tolerance():
    """The closed loop of Richard, Anderson and Andrews over 3 s (two swings) at rtol 1e-9, atol
    1e-11: within 1e-7 m of its Lagrange equation (measured: 2e-10 m), the drift of every returned
    state under the stated tolerance (positions: |phi_i| / s_i <= drift_tol = rtol; velocities: per
    second, scaled by alpha = 10/s), energy kept, and the run's statistics report its restarts."""
    model = seed002()
    result = simulate(model, 3.0, method="idas-bdf", rtol=1e-9, atol=1e-11)
    assert result.success, result.message
    assert seed002_error(result) < 1e-7
    assert result.max_position_violation <= 1e-9
    assert result.max_velocity_violation <= 10 * 1e-9
    assert result.energy_drift < 1e-8
    stats = result.statistics()
    assert stats["restarts"] == result.counters.restarts >= 0
    assert stats["projections"] == result.counters.projections <= result.counters.restarts
    # IDAS's own steps, many per returned state (1000 output times by default)
    assert result.t.size == 1001 and stats["steps"] > result.t.size


@pytest.mark.parametrize("alpha, drift_tol", [(0.0, 2e-10), (10.0, 5e-11)])
def test_projection_restarts_hold_the_drift_under_its_tolerance(alpha, drift_tol):
    """The closed loop of Richard, Anderson and Andrews over 1 s at rtol 1e-9, the plain index-1
    equations (alpha = 0) and the Baumgarte-stabilised ones (alpha = 10/s), each with a drift
    tolerance below the drift it reaches unprojected (measured 3.3e-10 and 8.2e-11): states are
    projected and IDAS restarted, the drift of every returned state stays under the tolerance
    (positions |phi_i| / s_i; velocities |Phi_v v - nu|_i / s_i over max(alpha, 1/s)), each
    projection is followed by a restart, and the motion is still right (within 1e-7 m). The same
    runs without projections (a tolerance of 1) pass it: the projections are what hold it."""
    model = seed002()
    rate = max(alpha, 1.0)
    result = simulate(model, 1.0, method="idas-bdf", rtol=1e-9, atol=1e-11,
                      options={"alpha": alpha, "drift_tol": drift_tol})
    assert result.success, result.message
    assert result.counters.projections >= 1
    assert result.counters.restarts >= result.counters.projections
    assert result.max_position_violation <= drift_tol
    assert result.max_velocity_violation <= drift_tol * rate
    assert seed002_error(result) < 1e-7
    free = simulate(model, 1.0, method="idas-bdf", rtol=1e-9, atol=1e-11,
                    options={"alpha": alpha, "drift_tol": 1.0})
    assert free.counters.projections == free.counters.restarts == 0
    assert max(free.max_position_violation, free.max_velocity_violation / rate) > drift_tol


@pytest.mark.parametrize("kind", ["harmonic", "spline"])
def test_driven_rod_follows_its_law_and_needs_its_torque(kind):
    """The rod driven through its joint by a harmonic law (a closed form compiled into the DAE)
    or a cubic spline (no closed form: a callback to its numeric evaluation): its angle is the
    law's and its centre of mass 0.5 (cos, sin) of it, to 1e-9 at rtol 1e-9; the driver's
    effort, tau = -lambda = I_O theta'' + m g l cos(theta), to 1e-7 N m (multipliers solved at
    each returned state: their error is that of the state, ~1e-9 relative to ~5 N m)."""
    times = np.linspace(0.0, 2.0, 21)
    law = (hx.scene.Harmonic(offset=0.3, cos=[0.4], sin=[0.2, 0.1], frequency=0.7)
           if kind == "harmonic" else hx.scene.Spline(times, 0.3 + 0.4 * np.sin(2 * times)))
    model = planar_rod(law)
    integrator = IdasBDF(model, 0.0, 2.0, rtol=1e-9, atol=1e-11)
    assert (integrator.equations.callback is None) == (kind == "harmonic")
    result = simulate(model, 2.0, method="idas-bdf", rtol=1e-9, atol=1e-11)
    assert result.success, result.message
    theta, _, theta_dd = law.evaluate(result.t)
    assert np.abs(result.q[:, 2] - theta).max() < 1e-9
    exact = 0.5 * np.column_stack([np.cos(theta), np.sin(theta)])
    assert np.abs(result.q[:, :2] - exact).max() < 1e-9
    tau = (0.0833 + 0.25) * theta_dd + 1.0 * G * 0.5 * np.cos(theta)
    assert np.abs(-result.lam[:, model.row_index["motor"]] - tau).max() < 1e-7


def test_every_saves_every_nth_returned_state():
    """IDAS counts its own steps, several per returned state: ``every`` counts returned states
    (100 output times of 0.01 s, every 10th saved: 11 states, at 0, 0.1, ..., 1 s)."""
    result = simulate(seed002(), 1.0, method="idas-bdf", step=0.01, every=10)
    assert result.success, result.message
    assert np.allclose(result.t, np.linspace(0.0, 1.0, 11), atol=1e-12)
    assert result.counters.steps > 100


def test_options_are_checked():
    model = planar_rod()
    with pytest.raises(ValueError, match="alpha"):
        IdasBDF(model, 0.0, 1.0, alpha=-1.0)
    with pytest.raises(ValueError, match="drift_tol"):
        IdasBDF(model, 0.0, 1.0, drift_tol=0.0)


def test_andrews_squeezer_at_rtol_1e_12():
    """Andrews' squeezing mechanism (7 bodies, a stiff spring, 0.03 s) at rtol = atol = 1e-12:
    BDF up to order 5 (19 000 steps, under a second); the seven angles at
    0.03 s agree with the Test Set's published values to their own precision (about 1e-10
    relative, the study's floor 3e-10; measured 2.5e-10)."""
    from hexapod.benchmarks.work_precision import andrews_problem

    problem = andrews_problem(SCENES.parent)
    result = simulate(problem.model, problem.t_end, method="idas-bdf", rtol=1e-12, atol=1e-12,
                      forces=False, every=100)
    assert result.status == "finished", result.message
    assert problem.error(result) <= 3 * problem.floor
