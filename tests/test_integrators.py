"""Every integrator of the registry against exact solutions, conservation laws and its own
declared order; failures as results; consistent starts."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod.benchmarks import ClosedLoopPendulum, pendulum_exact, pendulum_period
from hexapod.scene.laws import Polynomial
from hexapod.scene.reader import read_scene
from hexapod.simulation.integrators import Integrator
from hexapod.simulation.loop import simulate
from hexapod.simulation.methods import DEFAULT_ATOL, DEFAULT_RTOL
from hexapod.simulation.registry import INTEGRATORS, get_integrator, register
from hexapod.simulation.scales import ENERGY_JUMP

from mechanisms import four_bar, sprung_top

SCENES = Path(__file__).resolve().parents[1] / "data" / "scenes"
G = 9.81
FIXED = [name for name, cls in INTEGRATORS.items() if not cls.adaptive]
ADAPTIVE = [name for name, cls in INTEGRATORS.items() if cls.adaptive]


# ------------------------------------------------------------------ scenes with known motions

def spatial_pendulum():
    """A 1 m, 1 kg rod about the world y axis through its end, released horizontal
    (data/scenes/pendulum.toml): psi0 = pi/2 from the downward vertical."""
    model = hx.assemble(read_scene(SCENES / "pendulum.toml"))
    inertia_o = 0.0833 + 0.25
    return model, np.sqrt(G * 0.5 / inertia_o), 0.5


def planar_pendulum():
    """The same rod in the plane: a planar body on a revolute joint, gravity -y."""
    scene = hx.Scene("planar-pendulum", 2)
    scene.add(hx.scene.PlanarBody("rod", 1.0, 0.0833, position=[0.5, 0.0]))
    scene.add(hx.scene.Revolute("pivot", "ground", "rod", origin=[0.0, 0.0]))
    return hx.assemble(scene), np.sqrt(G * 0.5 / (0.0833 + 0.25)), 0.5


def pendulum_centre(t, omega0, arm, dimension):
    """Exact centre of mass: (l sin psi, -l cos psi) in the plane; (l sin psi, 0, -l cos psi)
    in space (the rod turns about +y from +x towards -z)."""
    psi, _ = pendulum_exact(t, np.pi / 2, omega0)
    if dimension == 2:
        return np.column_stack([arm * np.sin(psi), -arm * np.cos(psi)])
    return np.column_stack([arm * np.sin(psi), np.zeros_like(psi), -arm * np.cos(psi)])


PENDULUMS = {"spatial": spatial_pendulum, "planar": planar_pendulum}


def pendulum_error(result, omega0, arm) -> float:
    dim = result.model.dimension
    exact = pendulum_centre(result.t, omega0, arm, dim)
    return float(np.abs(result.q[:, :dim] - exact).max())


def symmetric_top():
    """A heavy symmetric top on a spherical joint at its tip: axis tilted 30 deg from the
    vertical, spinning at 40 rad/s about it, centre of mass 0.1 m up the axis."""
    A, C, mass, arm, tilt, spin = 0.002, 0.004, 0.5, 0.1, np.radians(30.0), 40.0
    rotation = hx.spatial.rotation_about_axis([1.0, 0.0, 0.0], tilt)
    axis = rotation @ [0.0, 0.0, 1.0]
    scene = hx.Scene("top", 3)
    scene.add(hx.scene.SpatialBody("top", mass, [A, A, C], position=arm * axis, rotation=rotation,
                                   angular_velocity=spin * axis))
    scene.add(hx.scene.Spherical("tip", "ground", "top", origin=[0.0, 0.0, 0.0]))
    return hx.assemble(scene)


# ------------------------------------------------------------------ the contract

def test_registry_declares_every_method():
    assert {"rk4-baumgarte", "dopri5-projection", "generalized-alpha"} <= set(INTEGRATORS)
    for name, cls in INTEGRATORS.items():
        info = cls.describe()
        assert info["name"] == name and cls.order >= 2 and cls.index in (1, 2, 3)
        assert info["stabilisation"] and info["description"]
        assert get_integrator(name) is cls and get_integrator(cls) is cls
    with pytest.raises(ValueError, match="unknown integrator 'euler'"):
        get_integrator("euler")
    with pytest.raises(TypeError):
        register(object)



def applicable(method: str, **settings) -> dict:
    """The settings a method uses: tolerances only for adaptive ones (a fixed-step method given
    tolerances warns that it ignores them)."""
    if not INTEGRATORS[method].adaptive:
        settings.pop("rtol", None)
        settings.pop("atol", None)
    return settings

@pytest.mark.parametrize("method", INTEGRATORS)
def test_start_is_made_consistent(method):
    """From a guess off the constraints: positions assembled, velocities projected,
    accelerations and multipliers those of the saddle-point system."""
    model = hx.assemble(read_scene(SCENES / "closed_pendulum_seed002.toml"))
    rng = np.random.default_rng(7)
    q0 = model.q0 + 0.01 * rng.standard_normal(model.n_q)
    v0 = rng.standard_normal(model.n_v)
    integrator = get_integrator(method)(model, 0.0, 0.1, q0, v0, step=1e-3)
    w, wd, wdd = model.law_values(0.0)
    q, v = integrator.q, integrator.v
    assert np.abs(model.call("phi", q=q, w=w)).max() < 1e-13
    Phi_v = model.call("Phi_v", q=q, w=w)
    assert np.abs(Phi_v @ v - model.call("nu", q=q, w=w, wd=wd)).max() < 1e-12
    mass = model.mass.dense()
    Q = model.call("Q", q=q, v=v, w=w)
    assert np.allclose(mass @ integrator.v_dot + Phi_v.T @ integrator.lam, Q, atol=1e-10)
    gamma = model.call("gamma", q=q, v=v, w=w, wd=wd, wdd=wdd)
    assert np.allclose(Phi_v @ integrator.v_dot, gamma, atol=1e-10)


# ------------------------------------------------------------------ accuracy

@pytest.mark.parametrize("kind", PENDULUMS)
@pytest.mark.parametrize("method", FIXED)
def test_fixed_step_methods_show_their_order(method, kind):
    """Error at t = 0.5 s against the exact pendulum for steps h, h/2, h/4, h/8: the fitted
    slope of log(error) against log(h) is the declared order, within 0.3."""
    model, omega0, arm = PENDULUMS[kind]()
    cls = INTEGRATORS[method]
    base = {4: 10, 2: 40}.get(cls.order, 20)  # coarse enough to stay above round-off
    steps = [0.5 / (base * 2**k) for k in range(4)]
    errors = []
    for h in steps:
        result = simulate(model, 0.5, method=method, step=h, every=10**9)
        assert result.success, result.message
        exact = pendulum_centre(np.array([0.5]), omega0, arm, model.dimension)
        errors.append(float(np.abs(result.q[-1, :model.dimension] - exact[0]).max()))
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert abs(slope - cls.order) <= 0.3, (errors, slope)
    assert errors[-1] > 1e-13  # the fit saw truncation error, not round-off


@pytest.mark.parametrize("kind", PENDULUMS)
@pytest.mark.parametrize("method", ADAPTIVE)
@pytest.mark.parametrize("tol", [1e-5, 1e-8])
def test_adaptive_methods_meet_their_tolerance(method, kind, tol):
    """Global error of the centre of mass over two periods within 10x the tolerance."""
    model, omega0, arm = PENDULUMS[kind]()
    result = simulate(model, 4.0, method=method, rtol=tol, atol=tol)
    assert result.success, result.message
    assert pendulum_error(result, omega0, arm) <= 10 * tol * (1 + arm)


@cache
def seed002_reference():
    """The Lagrange equation's motion of data/scenes/closed_pendulum_seed002.toml over 1.5 s
    (DOP853 at 1e-12 in SciPy: a function of time giving ``p1, p2, theta``).

    One solve for every method of the test below: the reference does not depend on the method,
    and each solve took one to two seconds, as long as some of the runs it judges."""
    return ClosedLoopPendulum().solve(1.5)


@pytest.mark.parametrize("method", INTEGRATORS)
def test_closed_loop_pendulum_of_seed002_follows_its_lagrange_equation(method):
    """The two particles of Richard, Anderson and Andrews on a four-bar (decimetres, y down),
    against the one-degree-of-freedom Lagrange equation over 1.5 s (more than one swing). 1e-6 m
    with the accurate settings of each method (the paper's figures resolve 1e-2 dm); 1e-5 with
    the second-order methods at 1e-3 s, whose errors are ``C h^2``: measured 2.9e-6 (RATTLE) and
    5.1e-6 (generalized-alpha), 16 times those at 2.5e-4 s (1.8e-7, 3.2e-7), which took four
    times as long."""
    model = hx.assemble(read_scene(SCENES / "closed_pendulum_seed002.toml"))
    settings = {"rk4-baumgarte": dict(step=1e-3), "dopri5-projection": dict(rtol=1e-9,
                atol=1e-11), "generalized-alpha": dict(step=1e-3),
                "rattle": dict(step=1e-3)}.get(method, {})
    result = simulate(model, 1.5, method=method, **settings)
    assert result.success, result.message
    p1, p2, _ = seed002_reference()(result.t)
    error = max(np.abs(result.q[:, 0:2] - p1).max(), np.abs(result.q[:, 2:4] - p2).max())
    bound = {"generalized-alpha": 1e-5, "rattle": 1e-5}.get(method, 1e-6)
    assert error < bound, error


# ------------------------------------------------------------------ conservation and drift

@pytest.mark.parametrize("method", INTEGRATORS)
def test_energy_of_a_double_pendulum_converges_with_the_method(method):
    """A conservative planar double pendulum over 1 s: the energy error is within the
    method's truncation error, small and shrinking at its order (fixed step) or within a
    multiple of the tolerance (adaptive)."""
    model = hx.assemble(read_scene(SCENES / "double_pendulum_planar.toml"))
    assert model.energy_conserved
    cls = INTEGRATORS[method]
    if cls.adaptive:
        drift = simulate(model, 1.0, method=method, rtol=1e-8, atol=1e-8).energy_drift
        assert drift < 1e-6
        return
    drifts = [simulate(model, 1.0, method=method, step=h, every=10**9).energy_drift
              for h in (4e-3, 2e-3)]
    assert drifts[0] < 1e-2 and drifts[1] < 1e-3
    assert drifts[0] / drifts[1] > 2 ** (cls.order - 0.7), drifts


@pytest.mark.parametrize("method", INTEGRATORS)
def test_spinning_top_keeps_its_energy_and_vertical_momentum(method):
    """A heavy symmetric top precessing on a spherical joint (spatial, Euler parameters,
    gyroscopic terms): energy and the angular momentum about the vertical through the tip are
    conserved (gravity and the joint force have no moment about that axis)."""
    model = symmetric_top()
    settings = {"dopri5-projection": dict(rtol=1e-9, atol=1e-9), "rattle": dict(step=1e-3),
                "generalized-alpha": dict(step=1e-3)}.get(method, dict(step=5e-4))
    result = simulate(model, 0.5, method=method, **settings)
    assert result.success, result.message
    # rattle: second order, its energy error 3.9e-6 at 1e-3 s (9.6e-7 at 5e-4 s; bounded, not
    # drifting); generalized-alpha's 2.4e-6, its momentum's 1.4e-5 relative
    bound = {"generalized-alpha": 1e-3, "rattle": 1e-5}.get(method, 1e-6)
    assert result.energy_drift < bound
    body = model.bodies[0]
    momentum = []
    for q, v in zip(result.q, result.v, strict=True):
        R = model.body_pose(q, 0).rotation
        omega = R @ v[3:6]
        momentum.append(R @ body.inertia @ R.T @ omega + np.cross(q[:3], body.mass * v[:3]))
    vertical = np.array(momentum)[:, 2]
    assert np.abs(vertical - vertical[0]).max() < bound * np.abs(np.array(momentum)).max()


def newton_held(cls) -> bool:
    """Whether a method solves the position constraints by Newton's method every step
    (generalized-alpha and RATTLE)."""
    return "constraints solved every step" in cls.stabilisation


@pytest.mark.parametrize("method", INTEGRATORS)
def test_constraint_drift_is_bounded(method):
    """Projection and index 3: position residuals at round-off at every step; Baumgarte:
    bounded by the truncation error."""
    model = hx.assemble(read_scene(SCENES / "closed_pendulum_seed002.toml"))
    result = simulate(model, 1.0, method=method, **applicable(method, step=2e-3, rtol=1e-6,
                                                               atol=1e-8))
    assert result.success
    cls = INTEGRATORS[method]
    if method == "idas-bdf":  # projected only when the drift passes its tolerance, rtol here
        assert result.max_position_violation <= 1e-6
        assert result.max_velocity_violation <= 1e-6 * 10  # scaled by alpha = 10/s
    elif newton_held(cls) or "projection" in cls.stabilisation:
        assert result.max_position_violation < 1e-13
    else:
        assert result.max_position_violation < 1e-6
    if "projection" in cls.stabilisation and method != "idas-bdf":
        assert result.max_velocity_violation < 1e-12


# ------------------------------------------------------------------ failure is a result

def _stiff_spring_scene() -> hx.Scene:
    """A 1 kg mass on a 1e9 N/m spring (period 0.2 ms), stretched by 1 mm."""
    scene = hx.Scene("stiff", 3, gravity=[0.0, 0.0, 0.0])
    scene.add(hx.scene.Particle("mass", 1.0, position=[1.001, 0.0, 0.0]))
    scene.add(hx.scene.SpringDamper("spring", "ground", "mass", point_a=[0.0, 0.0, 0.0],
                                    stiffness=1e9, free_length=1.0))
    return scene


def test_a_step_too_large_fails_with_a_message_not_an_exception():
    """The stiff spring with RK4 at 1 ms: the first step multiplies the energy by 60; the run
    ends as failed, with the time and the cause, keeping the state before (before the energy
    guard the state blew up to non-finite numbers a few steps later, also reported)."""
    with np.errstate(over="ignore", invalid="ignore"):
        result = simulate(hx.assemble(_stiff_spring_scene()), 0.5, method="rk4", step=1e-3)
    assert result.status == "failed" and not result.success
    assert "rk4-baumgarte" in result.message and "step is too long" in result.message
    assert result.t.size >= 1 and np.all(np.isfinite(result.q))


def test_rattle_halves_a_step_that_would_change_the_energy():
    """The same spring with RATTLE at 1 ms, five times its period: a step that would change the
    energy by more than ENERGY_JUMP of the largest kinetic energy is refused and halved, as one
    where Newton's method fails (it used to blow up to non-finite numbers). The halved steps
    stop just inside the kick-drift-kick map's stability limit (h omega < 2), where its energy
    oscillates by about its own size but stays bounded: the run ends, its rejections counted,
    no step changing the energy by more than the bound."""
    model = hx.assemble(_stiff_spring_scene())
    result = simulate(model, 0.05, method="rattle", step=1e-3)
    assert result.status == "finished", result.message
    assert result.counters.rejected > 0 and np.all(np.isfinite(result.v))
    energy = np.array([float(sum(model.energy(q, v))) for q, v in zip(result.q, result.v,
                                                                       strict=True)])
    kinetic = np.array([float(model.energy(q, v)[0]) for q, v in zip(result.q, result.v,
                                                                     strict=True)])
    assert np.abs(np.diff(energy)).max() <= ENERGY_JUMP * kinetic.max()
    assert result.energy_drift < 2.0


@pytest.mark.parametrize("method", INTEGRATORS)
def test_a_driver_pulling_past_reach_fails_with_a_message(method):
    """A particle on a 1 m rod, its x driven at 2 m/s: from t = 0.5 s no position satisfies
    the constraints. Every method ends the run as failed, at or after the limit, saying why;
    the methods that hold the positions on the constraints stop at the limit."""
    scene = hx.Scene("unreachable", 2)
    scene.add(hx.scene.Particle("p", 1.0, position=[0.0, -1.0]))
    scene.add(hx.scene.Distance("rod", "ground", "p",
                                parent_frame=hx.spatial.Placement(np.zeros(2))))
    scene.add(hx.scene.CoordinateDriver("push", "p", "x", Polynomial((0.0, 2.0))))
    result = simulate(hx.assemble(scene), 1.0, method=method, step=1e-2)
    assert result.status == "failed" and method in result.message
    assert result.t[-1] >= 0.5 - 1e-6 and np.all(np.isfinite(result.q))
    cls = INTEGRATORS[method]
    if newton_held(cls) or "projection" in cls.stabilisation:
        # t = 0.5 itself has a solution (x = 1, y = 0): a method may reach it, not pass it;
        # idas-bdf holds the constraints to drift_tol = rtol = 1e-6 m / L (L = 1 m), and at
        # 0.5 + d no position violates them by less than d (m): it may pass by 1e-6 s; a
        # projection holds them to 1e-12 m in the rows it keeps, and at the stretched pose the
        # rank decision leaves one out: an explicit step crossing it may end 1e-11 s past
        late = 1e-6 if method == "idas-bdf" else 1e-10
        assert result.t[-1] <= 0.5 + late and result.counters.rejected > 10
        assert ("Newton" in result.message) == newton_held(cls)


def test_step_after_the_end_is_misuse():
    model = planar_pendulum()[0]
    integrator = get_integrator("rk4-baumgarte")(model, 0.0, 0.01, step=0.01)
    integrator.step()
    assert integrator.status == "finished" and integrator.t == 0.01
    with pytest.raises(RuntimeError, match="finished"):
        integrator.step()


def test_integrator_base_class_is_abstract():
    class Nothing(Integrator):
        name = "nothing"

    integrator = Nothing(planar_pendulum()[0], 0.0, 1.0)
    with pytest.raises(NotImplementedError):
        integrator.step()


# ------------------------------------------------------------------ services of the model

@pytest.mark.parametrize("which", ["sprung-top", "four-bar"])
def test_tangent_matrices_are_the_derivatives_on_the_group(which):
    """K and C of the implicit methods against central differences of the force residual
    g = Phi_v^T lam - Q along q (+) eps e_j and v + eps e_j (gyroscopic, spring-damper and
    constraint terms; a closed loop with redundant rows)."""
    model = (sprung_top(damping=3.0) if which == "sprung-top"
             else hx.assemble(read_scene(SCENES / "four_bar_3d.toml")))
    rng = np.random.default_rng(3)
    q, v = model.q0, rng.standard_normal(model.n_v)
    lam = rng.standard_normal(model.n_c)
    w = model.law_values(0.3)[0]
    K, C = (np.array(m) for m in model.tangent_matrices(q, v, lam, *([w] if model.n_w else [])))

    def residual(q_, v_):
        return model.call("Phi_v", q=q_, w=w).T @ lam - model.call("Q", q=q_, v=v_, w=w)

    eps = 1e-6
    K_fd = np.column_stack([(residual(model.integrate(q, eps * e), v)
                             - residual(model.integrate(q, -eps * e), v)) / (2 * eps)
                            for e in np.eye(model.n_v)])
    C_fd = np.column_stack([(residual(q, v + eps * e) - residual(q, v - eps * e)) / (2 * eps)
                            for e in np.eye(model.n_v)])
    # central differences: error O(eps^2) plus round-off O(1e-16 / eps) of the entries
    assert np.abs(K - K_fd).max() < 1e-7 * max(np.abs(K).max(), 1.0)
    assert np.abs(C - C_fd).max() < 1e-7 * max(np.abs(C).max(), 1.0)
    # the forces' part alone (a linearly implicit step's): the same with no multiplier
    laws = [w] if model.n_w else []
    at_zero = model.tangent_matrices(q, v, np.zeros(model.n_c), *laws)
    for alone, full in zip(model.force_tangents(q, v, *laws)[:2], at_zero, strict=True):
        alone, full = np.array(alone), np.array(full)
        assert np.abs(alone - full).max() <= 1e-14 * max(np.abs(full).max(), 1.0)
    forces = np.array(model.force_tangents(q, v, *laws)[2]).ravel()  # Q, given with them
    Q = np.array(model.Q(q, v, *laws)).ravel()
    assert np.abs(forces - Q).max() <= 1e-14 * max(np.abs(Q).max(), 1.0)


@pytest.mark.parametrize("method", INTEGRATORS)
def test_energy_with_a_spring_is_conserved_and_lost_to_its_damper(method):
    """The top on a spring: without damping kinetic + gravity + spring energy is constant
    (within the method's error); with damping the scene is no longer conservative and the run
    says so (no drift reported)."""
    model = sprung_top(damping=0.0)
    assert model.energy_conserved
    settings = {"generalized-alpha": dict(step=5e-4), "rattle": dict(step=5e-4)}.get(
        method, applicable(method, step=1e-3, rtol=1e-9, atol=1e-9))
    result = simulate(model, 0.3, method=method, **settings)
    assert result.success, result.message
    # the second-order methods at 5e-4 s: 1.3e-5 (RATTLE) and 4.6e-6 (generalized-alpha),
    # 6.25 times their drifts at 2e-4 s (2.0e-6, 7.4e-7), as h^2 says
    assert result.energy_drift < {"generalized-alpha": 5e-5, "rattle": 5e-5}.get(method, 1e-6)
    kinetic, potential = model.energy(result.q[-1], result.v[-1])
    assert float(kinetic) + float(potential) == pytest.approx(result.energy[-1], abs=1e-15)
    damped = simulate(sprung_top(damping=3.0), 0.05, method=method, **settings)
    assert damped.success and damped.energy_drift is None and damped.energy is None


@pytest.mark.parametrize("method", INTEGRATORS)
def test_redundant_closed_chain_runs_and_keeps_the_policy(method):
    """The spatial four-bar (four revolutes: three redundant rows) swinging freely under
    gravity: constraints held, energy kept, and the multipliers at the last state those of
    the dynamics there, redundancy policy included."""
    # released with the crank at 0.7 rad, away from equilibrium (the scene file's pose is one)
    model = hx.assemble(four_bar(3, 0.7, driven=False, gravity=[0.0, -9.81, 0.0]))
    # generalized-alpha at 1e-3 s: energy drift 2.3e-4, multipliers 6.5e-6 off (5.7e-5 and
    # 1.6e-6 at 5e-4 s, which took twice as long)
    settings = applicable(method, step=1e-3, rtol=1e-9, atol=1e-10)
    result = simulate(model, 0.4, method=method, **settings)
    assert result.success, result.message
    assert np.abs(result.v).max() > 0.5  # it swings (m/s, rad/s)
    # projection and index 3: round-off; Baumgarte: the truncation error; Radau and IDAS hold
    # the constraints to their tolerance (rtol 1e-9)
    loose = ("rk4-baumgarte", "radau5-ggl", "idas-bdf")
    assert result.max_position_violation < (1e-8 if method in loose else 1e-12)
    # second-order fixed-step methods: an energy error O(h^2)
    second_order = ("generalized-alpha", "rattle")
    assert result.energy_drift < (1e-3 if method in second_order else 1e-6)
    data = model.create_data()
    hx.forward_dynamics(model, data, result.t[-1], result.q[-1], result.v[-1])
    tolerance = {"generalized-alpha": 1e-3}.get(method, 1e-8)
    assert np.abs(result.lam[-1] - data.lam).max() < tolerance * np.abs(data.lam).max()


@pytest.mark.parametrize("method", INTEGRATORS)
def test_a_scene_without_constraints_follows_the_exact_parabola(method):
    """A free particle thrown under gravity: no constraint rows at all (the compiled
    projection once failed on its empty residual). Every method ends on the exact parabola:
    its accelerations are constant, so any method of order 2 or more is exact to round-off,
    and the implicit ones to their tolerance."""
    scene = hx.Scene("thrown", 3)
    scene.add(hx.scene.Particle("p", 1.0, position=[0.0, 0.0, 0.0], velocity=[1.0, 0.0, 2.0]))
    result = simulate(hx.assemble(scene), 1.0, method=method, step=1e-2)
    assert result.success, result.message
    exact = [1.0, 0.0, 2.0 - 9.81 / 2]
    assert np.allclose(result.q[-1], exact, atol=1e-6)


def particle_pendulum(dimension: int):
    """A 1 kg particle held 1 m from the ground point by a distance joint (one row), released
    at rest level with it: the simple pendulum ``psi'' = -(g / l) sin psi`` from ``psi0 = pi/2``,
    in the plane (gravity -y) or in space (gravity -z, the swing in the x-z plane)."""
    scene = hx.Scene(f"particle-pendulum-{dimension}d", dimension)
    scene.add(hx.scene.Particle("bob", 1.0, position=[1.0] + [0.0] * (dimension - 1)))
    origin = hx.spatial.Placement(np.zeros(dimension))
    scene.add(hx.scene.Distance("rod", "ground", "bob", parent_frame=origin, child_frame=origin))
    return hx.assemble(scene)


@pytest.mark.parametrize("dimension", [2, 3])
@pytest.mark.parametrize("method", INTEGRATORS)
def test_a_particle_pendulum_follows_the_exact_swing(method, dimension):
    """Every method on particles (RATTLE once failed to build its functions for a single row:
    ``Phi_v`` a row vector), at its default settings over one period (2.37 s), against the
    exact motion (Jacobi elliptic functions).

    The bound is the suite's error level (tests/test_redundant_every_method.py): an adaptive
    method keeps its local errors within ``e = max(rtol, atol / l)``, a fixed-step method of
    order ``p`` makes errors of ``e = (h / tau)^p``, ``tau = sqrt(l / g)`` (``h = T / 1000``:
    3e-9 for RK4, 5.5e-5 for the second-order methods); the distance from the exact
    position (m, ``l = 1 m``) at every saved state, the energy drift (relative to the largest
    kinetic energy) and the position residual within ``10 e``, the velocity residual within
    ``10 e / tau``, none asked below 1e-10 (1e-9 for velocities). Measured: 3e-6 (DOPRI5), 1e-6
    (DOP853, IDAS), 1e-7 (Radau5), 6e-9 (RK4), 6e-5 (RATTLE) and 1e-4 (generalized-alpha)."""
    model = particle_pendulum(dimension)
    omega0 = np.sqrt(G)
    period = pendulum_period(np.pi / 2, omega0)
    cls = INTEGRATORS[method]
    tau = np.sqrt(1.0 / G)
    level = (max(DEFAULT_RTOL, DEFAULT_ATOL) if cls.adaptive
             else (period / cls.default_steps / tau) ** cls.order)
    result = simulate(model, period, method=method)
    assert result.status == "finished", result.message
    psi, _ = pendulum_exact(result.t, np.pi / 2, omega0)
    exact = np.zeros((result.t.size, dimension))
    exact[:, 0], exact[:, -1] = np.sin(psi), -np.cos(psi)
    assert np.abs(result.q - exact).max() <= max(1e-10, 10 * level)
    assert result.energy_drift <= max(1e-10, 10 * level)
    assert result.max_position_violation <= max(1e-10, 10 * level)
    assert result.max_velocity_violation <= max(1e-9, 10 * level / tau)


def test_dop853_takes_the_rate_at_a_steps_end_only_for_its_dense_output():
    """DOP853's error estimates give the rate at the step's end no weight (the last
    coefficients of E3 and E5 are zero): an attempted step costs its eleven later stages, an
    accepted one also the rate at its projected end, and the rate at the unprojected end is
    taken once for the dense output (with its three more stages), however often it is asked
    (8 % of the walking robot's right-hand sides went to it at every attempt)."""
    method = get_integrator("dop853-projection")(spatial_pendulum()[0], 0.0, 1.0)
    for _ in range(5):
        method.step()
    counters = method.counters
    start = counters.rhs - 11 * (counters.steps + counters.rejected) - counters.steps
    assert 0 <= start <= 2  # the start's solve and Hairer's starting-step trial
    before = counters.rhs
    first, again = method.dense_output(), method.dense_output()
    assert counters.rhs == before + 1 + 3  # the end's rate once, and DOP853's three more stages
    t = method.t - 0.5 * method._dense_step[1]
    assert again is first and np.isfinite(first(t)[0]).all()
