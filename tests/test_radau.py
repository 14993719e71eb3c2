"""Radau IIA of order 5 on the GGL index-2 equations (``radau5-ggl``): global error against exact
motions, both constraint levels and the vanishing multiplier ``mu``, a stiff spring against an
explicit method, unit Euler parameters, redundant rows against a planar twin, and its Jacobian
and Lie-group kinematics against differences."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import hexapod as hx
from hexapod.benchmarks import pendulum_exact
from hexapod.scene.reader import read_scene
from hexapod.simulation.integrators.ggl import dexp_inverse_sx, ggl_functions
from hexapod.simulation.integrators.radau import RadauIIA5GGL
from hexapod.simulation.loop import simulate
from hexapod.simulation.registry import INTEGRATORS

from mechanisms import four_bar, four_bar_points, rod_pendulum, sprung_top

SCENES = Path(__file__).resolve().parents[1] / "data" / "scenes"
G = 9.81
METHOD = "radau5-ggl"


def test_registered_with_its_declarations():
    cls = INTEGRATORS[METHOD]
    assert cls is RadauIIA5GGL
    assert cls.order == 5 and cls.index == 2 and cls.adaptive
    assert cls.stabilisation == "GGL: position and velocity constraints, B Phi_v^T mu"


# ------------------------------------------------------------------ (a) accuracy

def pendulum(dimension: int):
    """A 1 m, 1 kg rod on a revolute joint at its end, released horizontal at rest (the
    spatial one turns about the world y axis): model, small-oscillation frequency, arm."""
    model, omega0 = rod_pendulum(dimension)
    return model, omega0, 0.5


def pendulum_error(result, omega0: float, arm: float) -> float:
    """Largest distance of the centre of mass from the exact elliptic-function motion."""
    psi, _ = pendulum_exact(result.t, np.pi / 2, omega0)
    exact = [arm * np.sin(psi), -arm * np.cos(psi)]
    if result.model.dimension == 3:  # the rod turns about +y from +x towards -z
        exact = [exact[0], np.zeros_like(psi), exact[1]]
    return float(np.abs(result.q[:, :result.model.dimension] - np.column_stack(exact)).max())


# a ladder of three tolerances with a fitted slope, a study: the default run checks Radau's global
# error within ten times the tolerance at 1e-5 and 1e-8 on the same pendulums, planar and
# spatial (test_integrators.py: test_adaptive_methods_meet_their_tolerance[radau5-ggl])
@pytest.mark.slow
@pytest.mark.parametrize("dimension", [2, 3])
def test_global_error_follows_the_tolerance(dimension):
    """Over one period (1.93 s) of the exact pendulum, at rtol = atol = 1e-4, 1e-6, 1e-8: the
    error of the centre of mass stays within 10 times the tolerance (RADAU5's map of the
    tolerances aims at a global error of the order of the tolerance; measured 1.0 to 1.8
    times it) and falls with it: the fitted slope of log(error) against log(tol) is within
    0.7 and 1.3 (steps h ~ rtol'^(1/4) ~ tol^(1/6) and an error h^5 make 5/6; measured 1.03
    and 0.99)."""
    model, omega0, arm = pendulum(dimension)
    tolerances = np.array([1e-4, 1e-6, 1e-8])
    errors = []
    for tol in tolerances:
        result = simulate(model, 2.0, method=METHOD, rtol=tol, atol=tol)
        assert result.success, result.message
        errors.append(pendulum_error(result, omega0, arm))
    errors = np.array(errors)
    assert np.all(errors <= 10 * tolerances), errors
    slope = np.polyfit(np.log(tolerances), np.log(errors), 1)[0]
    assert 0.7 <= slope <= 1.3, (errors, slope)


# ------------------------------------------------------------------ (b) constraints and mu

def run(model, t_end: float, tol: float):
    """Step the integrator to the end; at every accepted step the largest ``|phi|``,
    ``|Phi_v v - nu|``, ``|Phi_v^T mu|`` (the velocity correction of the positions) and
    ``|v|``, and the states."""
    integrator = RadauIIA5GGL(model, 0.0, t_end, rtol=tol, atol=tol)
    worst, times, states = np.zeros(4), [], []
    while integrator.status == "running":
        integrator.step()
        t, q, v = integrator.t, integrator.q, integrator.v
        w, wd, _ = model.law_values(t)
        Phi_v = model.call("Phi_v", q=q, w=w)
        sizes = [np.abs(model.call("phi", q=q, w=w)).max(),
                 np.abs(Phi_v @ v - model.call("nu", q=q, w=w, wd=wd)).max(),
                 np.abs(Phi_v.T @ integrator.mu).max(), np.abs(v).max()]
        worst = np.maximum(worst, sizes)
        times.append(t)
        states.append(q)
    assert integrator.status == "finished", integrator.message
    return integrator, worst, np.array(times), np.array(states)


def driven_four_bar():
    """A planar four-bar whose crank turns by 0.8 sin(2 pi t) rad from 0.3 rad: a rheonomic
    driver, the whole motion known in closed form (:func:`mechanisms.four_bar_points`)."""
    law = hx.scene.Harmonic(sin=[0.8], frequency=1.0)
    return hx.assemble(four_bar(2, 0.3, law=law, gravity=[0.0, -G])), law


SCENES_B = {
    "seed002": lambda: (hx.assemble(read_scene(SCENES / "closed_pendulum_seed002.toml")), 1.5),
    "driven-four-bar": lambda: (driven_four_bar()[0], 1.0),
}


@pytest.mark.parametrize("which", SCENES_B)
def test_both_constraint_levels_hold_and_mu_vanishes(which):
    """The closed loop of Richard, Anderson and Andrews (three rigid links, 1.5 s) and a driven
    four-bar (rheonomic position and velocity rows, 1 s), at rtol = atol = 1e-6 and 1e-9, at every
    step:

    - ``|phi| <= tol L`` (L the characteristic length; Newton's tolerance sets it: measured
      0.01 to 0.15 tol L);
    - ``|Phi_v v - nu| <= 10 tol max|v|`` (the velocities to the tolerance relative to the
      motion's speed; measured up to 4.2 tol max|v|);
    - ``mu`` is zero along exact motions; numerically it carries the local error of an
      index-2 variable, O(h^3): ``|Phi_v^T mu|`` stays below 1e-3 max|v| at 1e-6 (measured
      1.1e-4 and 5e-5) and falls by more than 5 from 1e-6 to 1e-9 (steps shrink by about
      1000^(1/6): O(h^3) makes 30; measured 34 and 33).
    """
    model, t_end = SCENES_B[which]()
    length = model.characteristic_length
    corrections = []
    for tol in (1e-6, 1e-9):
        _, (phi, rate, correction, speed), _, _ = run(model, t_end, tol)
        assert phi <= tol * length, (tol, phi)
        assert rate <= 10 * tol * speed, (tol, rate)
        corrections.append(correction / speed)
    assert corrections[0] < 1e-3 and corrections[0] > 5 * corrections[1], corrections


def test_rheonomic_driver_moves_the_four_bar_as_its_closed_form():
    """The driven four-bar's laws enter at every stage time: every body's centre of mass
    follows the closed-form pose of the crank angle 0.3 + 0.8 sin(2 pi t) (the midpoints of
    its pivots) to within the tolerance times its 0.1 to 0.3 m size (measured 3.6e-9 m at
    1e-6)."""
    model, law = driven_four_bar()
    _, _, times, states = run(model, 1.0, 1e-6)
    theta = 0.3 + law.evaluate(times)[0]
    A, B, C, D = (np.array(p) for p in zip(*[four_bar_points(x) for x in theta], strict=True))
    centres = {"crank": (A + B) / 2, "coupler": (B + C) / 2, "rocker": (D + C) / 2}
    for name, exact in centres.items():
        body = model.bodies[model.body_index[name]]
        assert np.abs(states[:, body.q][:, :2] - exact).max() < 1e-7


# ------------------------------------------------------------------ (c) stiffness

def stiff_double_pendulum(stiffness: float = 1e6, mass: float = 0.01):
    """A 1 kg particle on a 1 m rigid rod, released horizontal, and a 10 g particle hanging
    0.1 m below it on a spring of 1e6 N/m: an oscillation of sqrt(k / m) = 1e4 rad/s (0.6 ms)
    on a slow swing. Both particles start in free fall with the spring at its free length,
    so the fast mode is hardly excited: its amplitude is bounded by the static stretch,
    m (3 g) / k = 3e-7 m at the bottom of the swing."""
    scene = hx.Scene("stiff-spring", 2)
    scene.add(hx.scene.Particle("a", 1.0, position=[1.0, 0.0]))
    scene.add(hx.scene.Distance("rod", "ground", "a",
                                parent_frame=hx.spatial.Placement(np.zeros(2))))
    scene.add(hx.scene.Particle("b", mass, position=[1.0, -0.1]))
    scene.add(hx.scene.SpringDamper("spring", "a", "b", stiffness=stiffness, free_length=0.1))
    return hx.assemble(scene)


def test_stiff_spring_takes_far_fewer_steps_than_an_explicit_method():
    """Over 0.3 s at rtol 1e-6, atol 1e-8: DOPRI5 must resolve the 0.6 ms oscillation for
    stability (measured 2465 steps), Radau IIA (L-stable) only the slow motion (measured 198):
    at least 5 times fewer steps and right-hand sides (measured 12 and 10). The answers agree:
    both particles within 1e-6 m (the fast mode's amplitude is below 3e-7 m, the tolerance
    1e-6 m; measured 6e-8 m), the rod's particle within 1e-5 m/s (measured 1e-7), and both
    conserve the energy (the scene is conservative) to 1e-7 of the kinetic energy (measured
    5e-10)."""
    model = stiff_double_pendulum()
    radau = simulate(model, 0.3, method=METHOD, rtol=1e-6, atol=1e-8, every=10**9)
    dopri = simulate(model, 0.3, method="dopri5-projection", rtol=1e-6, atol=1e-8, every=10**9)
    assert radau.success and dopri.success, (radau.message, dopri.message)
    assert 5 * radau.counters.steps < dopri.counters.steps, (radau.counters, dopri.counters)
    assert 5 * radau.counters.rhs < dopri.counters.rhs
    assert np.abs(radau.q[-1] - dopri.q[-1]).max() < 1e-6
    assert np.abs(radau.v[-1, :2] - dopri.v[-1, :2]).max() < 1e-5
    assert radau.energy_drift < 1e-7 and dopri.energy_drift < 1e-7


# ------------------------------------------------------------------ (d) Euler parameters

def tumbling_body():
    """A free body spinning at 6 rad/s about its intermediate principal axis, slightly
    perturbed: it flips over and back (the tennis-racket effect), with large rotations."""
    scene = hx.Scene("tumbling", 3, gravity=[0.0, 0.0, 0.0])
    scene.add(hx.scene.SpatialBody("body", 1.0, [0.01, 0.02, 0.03],
                                   angular_velocity=[0.05, 6.0, 0.05]))
    return hx.assemble(scene)


def test_euler_parameters_stay_unit_through_large_rotations():
    """The tumbling body over 4 s at rtol = atol = 1e-8: steps turn it by up to 0.45 rad and
    its spin reverses, yet ``|p| = 1`` to round-off at every step (the positions are composed
    on the group, never added: an additive update would drift by the local error), while the
    energy and the angular momentum in world axes, both conserved, hold to 1e-6 (measured
    5e-9 and 6e-8: the tolerance level)."""
    model = tumbling_body()
    result = simulate(model, 4.0, method=METHOD, rtol=1e-8, atol=1e-8)
    assert result.success, result.message
    p = result.q[:, 3:7]
    assert np.abs(np.linalg.norm(p, axis=1) - 1.0).max() < 1e-14
    assert result.v[:, 4].min() < -5.9  # the spin about the intermediate axis reversed
    inertia = np.diag([0.01, 0.02, 0.03])
    momentum = np.array([model.body_pose(q, 0).rotation @ inertia @ v[3:]
                         for q, v in zip(result.q, result.v, strict=True)])
    assert np.abs(momentum - momentum[0]).max() < 1e-6 * np.linalg.norm(momentum[0])
    assert result.energy_drift < 1e-6


def test_dexp_inverse_is_the_rate_of_the_rotation_vector():
    """``J_r(x)^-1 u`` against central differences on the group: the rotation vector ``y``
    with ``Exp(y) = Exp(x) Exp(eps u)`` (numbers, :meth:`Model.integrate` and
    :meth:`Model.difference`) moves at ``J_r(x)^-1 u``, below and above the series threshold
    (1e-3 rad) and up to 2.5 rad. Differences of step 1e-6: error O(eps^2) ~ 1e-12."""
    model = tumbling_body()
    q0 = model.q0
    rng = np.random.default_rng(11)
    u = rng.standard_normal(3)
    eps = 1e-6
    for size in (0.0, 1e-4, 2e-3, 0.5, 2.5):
        direction = rng.standard_normal(3)
        x = size * direction / np.linalg.norm(direction)
        dv = np.concatenate([np.zeros(3), x])

        def rotation_vector(e, dv=dv):
            moved = model.integrate(model.integrate(q0, dv), np.concatenate([np.zeros(3),
                                                                             e * u]))
            return model.difference(moved, q0)[3:]

        rate = (rotation_vector(eps) - rotation_vector(-eps)) / (2 * eps)
        formula = np.array(dexp_inverse_sx(ca.DM(x), ca.DM(u))).reshape(-1)
        assert np.abs(formula - rate).max() < 1e-8 * max(1.0, np.abs(rate).max()), size


# ------------------------------------------------------------------ Jacobian, redundant rows

def test_jacobian_is_the_derivative_of_the_residual():
    """The iteration matrix's Jacobian (CasADi, at ``xi = 0``) against central differences of
    the residual in ``(xi, v, lambda, mu)``: a top on a spherical joint with a spring-damper
    (gyroscopic, spring, damper and constraint terms, Lie-group positions). Error O(eps^2)
    plus round-off O(1e-16 / eps) relative to the entries."""
    model = sprung_top(damping=3.0)
    functions = ggl_functions(model)
    rng = np.random.default_rng(5)
    n_v, n_c = model.n_v, model.n_c
    y = rng.standard_normal(2 * n_v + 2 * n_c)
    y[:n_v] = 0.0

    def residual(y):
        parts = np.split(y, [n_v, 2 * n_v, 2 * n_v + n_c])
        return np.array(functions["residual"](model.q0, *parts)).reshape(-1)

    parts = np.split(y, [n_v, 2 * n_v, 2 * n_v + n_c])
    _, J, _ = (np.array(x) for x in functions["start"](model.q0, *parts))
    eps = 1e-6
    J_fd = np.column_stack([(residual(y + eps * e) - residual(y - eps * e)) / (2 * eps)
                            for e in np.eye(y.size)])
    assert np.abs(J - J_fd).max() < 1e-7 * np.abs(J).max()


def test_redundant_rows_move_as_the_planar_twin():
    """A spatial four-bar (four parallel revolutes: 20 rows for 18 velocities, 3 redundant)
    swinging under gravity from 0.3 rad moves exactly as the planar four-bar of the same
    links: over 0.5 s at rtol = atol = 1e-8, every centre of mass within 1e-7 m of the planar
    twin's (integrated by DOPRI5 at 1e-10; measured 4e-10 m), the crank having turned by
    0.08 m, with the constraints held."""
    spatial = hx.assemble(four_bar(3, 0.3, driven=False, gravity=[0.0, -G, 0.0]))
    planar = hx.assemble(four_bar(2, 0.3, driven=False, gravity=[0.0, -G]))
    result = simulate(spatial, 0.5, method=METHOD, rtol=1e-8, atol=1e-8, every=10**9)
    twin = simulate(planar, 0.5, method="dopri5-projection", rtol=1e-10, atol=1e-12,
                    every=10**9)
    assert result.success and twin.success, result.message
    for body, other in zip(spatial.bodies, planar.bodies, strict=True):
        assert np.abs(result.q[-1, body.q][:2] - twin.q[-1, other.q][:2]).max() < 1e-7
    crank = spatial.bodies[0].q
    assert np.abs(result.q[-1, crank][:2] - result.q[0, crank][:2]).max() > 0.05
    assert result.max_position_violation < 1e-8


class SparseRadau(RadauIIA5GGL):
    """The same method with the sparse factorisation whatever the size."""

    name = "radau5-ggl-sparse"
    sparse_above = 0


def test_sparse_and_dense_factorisations_agree():
    """The iteration matrices of large models are factorised by SuperLU, of small ones by
    LAPACK: on the spatial four-bar (redundant rows dropped from both) the two do the same
    work and end in the same state, within 1e-12 m (measured 9e-16). The steps agree to
    1e-8 s, not to round-off: the iteration matrices of index-2 problems have condition
    numbers of order h^-2, and their round-off moves the error estimates (measured 3e-9 s)."""
    model = hx.assemble(four_bar(3, 0.3, driven=False, gravity=[0.0, -G, 0.0]))
    dense = simulate(model, 0.3, method=METHOD, rtol=1e-8, atol=1e-8)
    sparse = simulate(model, 0.3, method=SparseRadau, rtol=1e-8, atol=1e-8)
    assert dense.success and sparse.success
    assert dense.counters == sparse.counters
    assert np.abs(dense.t - sparse.t).max() < 1e-8
    assert np.abs(dense.q[-1] - sparse.q[-1]).max() < 1e-12


def test_a_tighter_newton_tolerance_lowers_the_error():
    """Newton's stopping errors add up over the steps: on the planar pendulum at rtol 1e-4, a
    hundredth of RADAU5's Newton tolerance (``min(0.03, rtol'^(1/2))``, rtol' = 0.1 rtol^(2/3))
    lowers the global error more than 5 times (measured 25)."""
    model, omega0, arm = pendulum(2)
    default = simulate(model, 2.0, method=METHOD, rtol=1e-4, atol=1e-4)
    rtol = 0.1 * 1e-4 ** (2 / 3)
    tight = simulate(model, 2.0, method=METHOD, rtol=1e-4, atol=1e-4,
                     options={"newton_tol": 0.01 * min(0.03, rtol**0.5)})
    assert tight.success and tight.counters.newton > default.counters.newton
    assert 5 * pendulum_error(tight, omega0, arm) < pendulum_error(default, omega0, arm)


@pytest.mark.slow  # rtol 1e-12, the tightest of a tolerance study
def test_andrews_squeezer_at_rtol_1e_12():
    """Andrews' squeezing mechanism (7 bodies, a stiff spring, 0.03 s) at rtol = atol = 1e-12:
    RADAU5's map of the tolerances (``rtol' = 0.1 rtol^(2/3)``, ``atol' = atol rtol' / rtol``,
    and Newton's tolerance kept above round-off) lets it reach such tolerances; the seven angles
    at 0.03 s then agree with the Test Set's published values to their own precision (about
    1e-10 relative, the study's floor 3e-10; measured 2.8e-10, in 2500 steps)."""
    from hexapod.benchmarks.work_precision import andrews_problem

    problem = andrews_problem(SCENES.parent)
    result = simulate(problem.model, problem.t_end, method=METHOD, rtol=1e-12, atol=1e-12,
                      forces=False, every=100)
    assert result.status == "finished", result.message
    assert problem.error(result) <= 3 * problem.floor
