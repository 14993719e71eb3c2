"""The walking hexapod: a free trunk carried by its legs, feet held at their footholds in stance,
ground forces shared by a stated policy.

Checks independent of the solver's multipliers: the feet in stance stay at their footholds and
the trunk walks level at the gait's speed (the gait's exact inverse kinematics); the ground
reactions plus gravity equal the rate of change of the robot's momentum computed from the body
motions alone; the policies reach the optimum an independent solver (SciPy's SLSQP on the
multipliers themselves) finds; forces are continuous at touch-down and lift-off.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from robots import walking_robot

import hexapod as hx
from legs.gait import GAITS
from legs.robot import WALKING_DUTY, hexapod_scene

PERIOD = 0.5


@pytest.fixture(scope="module")
def tripod():
    model = walking_robot()
    times = np.linspace(0.0, PERIOD, 21)
    return model, hx.inverse_dynamics(model, times)


def footholds(model, t):
    """Each contact's foothold at ``t`` and whether its foot is in stance, from the laws."""
    w = model.law_values(t)[0]
    out = {}
    for c in model.contacts:
        laws = [k for k, law in enumerate(model.laws)
                if getattr(law, "contact", None) is c.schedule and law.kind == "foothold"]
        out[c.name] = (w[laws], bool(c.in_stance(t)))
    return out


def test_stance_feet_do_not_slip_and_the_trunk_walks_at_the_gait_speed(tripod):
    model, result = tripod
    feet = hx.marker_trajectories(model, result.q, "foot")
    slip = 0.0
    for k, t in enumerate(result.times):
        for contact in model.contacts:
            anchor, stance = footholds(model, t)[contact.name]
            if stance:
                foot = feet[contact.name.split("/")[0] + "/tarsus"][k]
                slip = max(slip, float(np.abs(foot - anchor).max()))
    size = model.characteristic_length
    assert slip < 1e-14 * size / 1e-2  # round-off: 1e-12 of the robot's size
    trunk = model.bodies[model.body_index["trunk"]]
    position, rotation = hx.body_poses(model, result.q)
    speed = replace(GAITS["tripod"], duty=WALKING_DUTY["tripod"]).walking_speed(PERIOD)
    expected = np.column_stack([speed * result.times, np.zeros(result.times.size),
                                np.full(result.times.size, position[0, trunk.index, 2])])
    assert np.abs(position[:, trunk.index] - expected).max() < 1e-12 * size / 1e-2
    assert np.abs(rotation[:, trunk.index] - np.eye(3)).max() < 1e-12


def centroidal_residual(model, result):
    """Ground reactions plus gravity against the rate of change of linear momentum and of
    angular momentum about the world origin, from the bodies' accelerations alone; relative to
    the robot's weight (and weight times its size)."""
    position, rotation = hx.body_poses(model, result.q)
    feet = hx.marker_trajectories(model, result.q, "foot")
    weight = sum(b.mass for b in model.bodies) * 9.81
    worst = 0.0
    for k in range(result.times.size):
        force = np.zeros(3)
        moment = np.zeros(3)
        for b in model.bodies:
            a = result.v_dot[k][b.v]
            w = result.v[k][b.v][3:]
            r = position[k, b.index]
            linear = b.mass * a[:3]
            angular = rotation[k, b.index] @ (b.inertia @ a[3:] + np.cross(w, b.inertia @ w))
            gravity = b.mass * model.gravity
            force += linear - gravity
            moment += np.cross(r, linear - gravity) + angular
        for c, name in enumerate(result.contacts):
            ground = result.ground_force[k, c]
            foot = feet[name.split("/")[0] + "/tarsus"][k]
            force -= ground
            moment -= np.cross(foot, ground)
        size = model.characteristic_length
        worst = max(worst, np.abs(force).max() / weight,
                    np.abs(moment).max() / (weight * size))
    return worst


def test_the_robot_balances_centroidally_and_body_by_body(tripod):
    model, result = tripod
    assert centroidal_residual(model, result) < 1e-9
    balance = hx.body_balance(model, result.times, result.q, result.v, result.v_dot,
                              result.force, result.torque)
    assert np.max(balance.force / np.maximum(balance.force_scale, 1e-300)) < 1e-9
    assert np.max(balance.moment / np.maximum(balance.moment_scale, 1e-300)) < 1e-9


def test_ground_forces_carry_the_robot_and_vanish_in_swing(tripod):
    model, result = tripod
    weight = sum(b.mass for b in model.bodies) * 9.81
    swing = result.ground_status == "swing"
    assert np.all(result.ground_force[swing] == 0.0)
    assert np.all(result.ground_force[..., 2][~swing] > -1e-9 * weight)
    vertical = result.ground_force[..., 2].sum(axis=1)
    assert np.allclose(vertical.mean(), weight, rtol=0.05)  # the trunk barely accelerates


def test_forces_are_continuous_at_touch_down_and_lift_off():
    """Across a switch of the tripod (duty 0.6: both tripods down for 0.05 s), the ground
    forces change by O(epsilon), and the foot lifting off carries nothing at its lift-off."""
    model = walking_robot()
    switch = 0.5 * PERIOD  # L2, R1, R3 lift off (L1, R2, L3 touched down at 0.2 s)
    weight = sum(b.mass for b in model.bodies) * 9.81
    jumps = []
    for epsilon in (1e-3, 1e-4):
        result = hx.inverse_dynamics(model, [switch - epsilon, switch + epsilon])
        jumps.append(np.abs(np.diff(result.ground_force, axis=0)).max() / weight)
    assert jumps[1] < 0.2 * jumps[0] and jumps[1] < 1e-3
    touch = hx.inverse_dynamics(model, [0.2 * PERIOD + 0.1 * PERIOD, switch - 1e-9])
    lifting = [k for k, name in enumerate(touch.contacts) if name[:2] in ("L2", "R1", "R3")]
    assert np.abs(touch.ground_force[1, lifting]).max() < 1e-6 * weight


@pytest.mark.parametrize("policy", ["min-wrench", "min-effort", "friction"])
def test_loads_ramp_over_the_ramp_under_every_policy(policy):
    """Over the last 32 ms of a stance (its ramp is a tenth of the 0.3 s stance), the ground
    forces change between consecutive samples by at most a constant times the spacing, the same
    constant at 1 ms and at 0.25 ms: a Lipschitz ramp, not a jump squeezed into its last
    percent (which gave 60 N in 2 ms and a rate that grew as the spacing fell). The constant's
    bound: the weight's steepest slope (15/8 per ramp, the quintic smooth step) moving four
    times the robot's weight, far above the 5e3 to 1.3e4 N/s measured and far below the old
    8e4 N/s."""
    model = walking_robot(policy=policy)
    weight = sum(b.mass for b in model.bodies) * 9.81
    lift_off = PERIOD  # L1, R2 and L3 lift off
    fine = 2.5e-4
    times = lift_off - 0.032 + fine * np.arange(129)  # 0.25 ms apart up to the lift-off
    force = hx.inverse_dynamics(model, times).ground_force
    rates = []
    for every in (4, 1):  # 1 ms apart (every fourth sample), then 0.25 ms
        spacing = every * fine
        rates.append(np.abs(np.diff(force[::every], axis=0)).max() / spacing)
    assert rates[1] <= 1.1 * rates[0]
    assert rates[1] <= 4 * weight * 15 / 8 / (0.1 * 0.6 * PERIOD)


def test_a_foothold_off_is_named_with_its_offset():
    """R2's foothold 25 mm off along x: assembly fails and the error names R2 alone, 25 mm off
    along x (found by lifting each foot in turn: with R2 lifted the others agree)."""
    scene = hexapod_scene("tripod", trunk="free")
    contact = scene.joints["R2/ground"]
    contact.foothold = contact.foothold + np.array([0.025, 0.0, 0.0])
    model = hx.assemble(scene)
    t = 0.7 * PERIOD  # L1, L3 and R2 down
    assert sorted(c.name for c in model.contacts if c.in_stance(t)) == [
        "L1/ground", "L3/ground", "R2/ground"]
    with pytest.raises(hx.AssemblyError) as caught:
        hx.inverse_dynamics(model, [t], method="saddle")
    said = str(caught.value).partition("(model")[0]
    assert "the footholds do not agree with the legs' motion: R2 25 mm off (x -25," in said
    assert "L1 " not in said and "L3 " not in said


def test_min_wrench_does_not_depend_on_the_length_unit():
    scene = hexapod_scene(trunk="free")  # walking_robot()'s scene
    millimetres = hx.Scene(scene.name, 3, "mm", scene.gravity * 1000)
    millimetres._elements = list(scene.scaled_elements(1000.0))
    times = np.array([0.03, 0.11, 0.27])
    metres = hx.inverse_dynamics(walking_robot(), times)
    other = hx.inverse_dynamics(hx.assemble(millimetres), times)
    scale = np.abs(metres.ground_force).max()
    assert np.abs(other.ground_force - metres.ground_force).max() < 1e-9 * scale


# ------------------------------------------------------------------ the policies


def _state(model, t):
    data = model.create_data()
    q = model.q0
    for step in np.linspace(0.0, t, 8):  # from the scene's pose, following the motion
        q = hx.assemble_positions(model, data, step, q)
    v = hx.solve_velocities(model, data, t, q)
    hx.forward_dynamics(model, data, t, q, v)
    return data


def _independent(model, data, t, cone=False):
    """The policy's problem solved by SLSQP over all multipliers, with the equations of
    motion ``Phi_v^T lam = Q - M v_dot`` as equality constraints."""
    from scipy.optimize import minimize

    ground = model.ground
    A_eq = data.Phi_v.T
    b_eq = data.Q - model.mass.dense() @ data.v_dot
    weight = sum(b.mass for b in model.bodies) * np.linalg.norm(model.gravity)
    drivers = [(d.row, ground.reference(model.joints[d.joint].name)) for d in model.drivers]
    weights = {c.name: float(c.weight(t)) for c in model.contacts}
    lever = model.characteristic_length / ground.default_reference  # docs/walking.md's rule

    def objective(lam):
        value = sum((lam[row] / ref) ** 2 for row, ref in drivers)
        for c in model.contacts:
            w = weights[c.name]
            if 1e-12 < w < 1.0:
                value += (1.0 / w - 1.0) * np.sum(lam[c.rows] ** 2) * lever**2
        return value

    constraints = [{"type": "eq", "fun": lambda lam: (A_eq @ lam - b_eq) / weight}]
    for c in model.contacts:
        w = weights[c.name]
        if w <= 1e-12:
            constraints.append({"type": "eq", "fun": lambda lam, r=c.rows: lam[r] / weight})
        elif cone:
            n = ground.faces
            angles = 2 * np.pi * (np.arange(n) + 0.5) / n
            limit = ground.mu * np.cos(np.pi / n)

            def inside(lam, r=c.rows, w=w, angles=angles, limit=limit):
                F = -lam[r]
                faces = limit * F[2] - (np.cos(angles) * F[0] + np.sin(angles) * F[1])
                return np.concatenate([faces, [F[2] - w * ground.min_normal]]) / weight

            constraints.append({"type": "ineq", "fun": inside})
    start = np.linalg.lstsq(A_eq, b_eq, rcond=None)[0]  # balanced, but by no policy
    # Exact derivatives for SLSQP, which otherwise differences every function over all the
    # multipliers at every iteration (27 000 calls of the objective at t = 0.21, 5 s): the
    # objective is a weighted sum of squares of single multipliers, its weights the values at
    # the unit vectors; each constraint is affine in the multipliers, its Jacobian the
    # differences at the unit vectors. Both read off the functions above, and checked at the
    # start.
    unit = np.eye(start.size)
    weights_of_squares = np.array([objective(e) for e in unit])
    assert np.isclose(objective(start), weights_of_squares @ start**2, rtol=1e-12)
    for constraint in constraints:
        fun = constraint["fun"]
        offset = fun(np.zeros(start.size))
        jacobian = np.column_stack([fun(e) - offset for e in unit])
        assert np.allclose(fun(start), jacobian @ start + offset, rtol=1e-12, atol=1e-12)
        constraint["jac"] = lambda lam, jacobian=jacobian: jacobian
    solution = minimize(objective, start, jac=lambda lam: 2.0 * weights_of_squares * lam,
                        constraints=constraints, method="SLSQP",
                        options={"maxiter": 1000, "ftol": 1e-14})
    return solution, objective


@pytest.mark.parametrize("t", [0.04, 0.12, 0.21])  # three feet; both tripods in the ramps
def test_min_effort_is_the_least_effort_an_independent_solver_finds(t):
    model = walking_robot(policy="min-effort", references=(("L1/ctr", 2.0),))
    data = _state(model, t)
    solution, objective = _independent(model, data, t)
    assert solution.success, solution.message
    ours = objective(data.lam)
    assert ours <= solution.fun * (1 + 1e-6) + 1e-12
    assert ours == pytest.approx(solution.fun, rel=1e-5)


@pytest.mark.parametrize("t", [0.04, 0.12, 0.21])
def test_friction_is_the_least_effort_inside_the_cone(t):
    model = walking_robot(policy="friction", mu=0.5, faces=6, min_normal=5.0)
    data = _state(model, t)
    assert all(status in ("ok", "swing") for status in data.ground_status)
    solution, objective = _independent(model, data, t, cone=True)
    assert solution.success, solution.message
    assert objective(data.lam) == pytest.approx(solution.fun, rel=1e-5)
    forces = hx.ground_reactions(model, data.lam)
    for c, F in zip(model.contacts, forces, strict=True):
        w = float(c.weight(t))
        if w > 1e-12:
            assert np.hypot(F[0], F[1]) <= 0.5 * F[2] * (1 + 1e-9)
            assert F[2] >= w * 5.0 - 1e-9


def test_friction_says_which_foot_would_slip_instead_of_clamping():
    model = walking_robot(policy="friction", mu=0.02, faces=4)
    data = _state(model, 0.05)
    forces = hx.ground_reactions(model, data.lam)
    flagged = [k for k, s in enumerate(data.ground_status) if s in ("slip", "pull")]
    assert flagged
    for k in flagged:
        F = forces[k]
        assert np.hypot(F[0], F[1]) > 0.02 * np.cos(np.pi / 4) * F[2] * (1 + 1e-9)


def test_exact_cone_and_pyramid_agree_as_faces_grow():
    exact = _state(walking_robot(policy="friction", mu=0.4, faces=0), 0.12)
    fine = _state(walking_robot(policy="friction", mu=0.4, faces=64), 0.12)
    weight = sum(b.mass for b in walking_robot().bodies) * 9.81
    model = walking_robot()
    difference = (hx.ground_reactions(model, exact.lam) - hx.ground_reactions(model, fine.lam))
    assert np.abs(difference).max() < 0.02 * weight


def test_a_tripod_of_duty_one_half_passes_its_load_in_an_instant():
    model = hx.assemble(hexapod_scene("tripod", trunk="free", duty=0.5))
    result = hx.inverse_dynamics(model, [0.24, 0.25, 0.26])
    assert centroidal_residual(model, result) < 1e-9
    down = result.ground_status != "swing"
    assert down.sum(axis=1).tolist() == [3, 3, 3]
    assert not np.any(down[0] & down[2])  # the other tripod after the switch
    assert np.all(result.ground_force[1, down[1], 2] > 0)  # touching down, it carries


def test_every_gait_walks_with_its_feet_on_the_ground():
    for gait in ("tetrapod", "wave"):
        model = walking_robot(gait)
        result = hx.inverse_dynamics(model, np.linspace(0.0, PERIOD, 7))
        assert result.max_violation < 1e-12
        assert centroidal_residual(model, result) < 1e-9
        down = (result.ground_status != "swing").sum(axis=1)
        assert down.min() >= 3


def test_a_single_leg_loaded_by_its_ground_reaction_works_as_in_the_robot():
    """The built-in single-leg scenes: the leg on a fixed trunk with the robot's laws and its
    foot's ground reaction transmits the joint wrenches it has in the walking robot (whose
    trunk moves at constant velocity, an inertial frame); the kept reactions are the robot's."""
    from legs.front_leg import walking_leg_scene
    from legs.loads import tabulated_reactions

    table_times, table = tabulated_reactions("tripod")
    picks = [3, 57, 90, 140]  # swing, stance, ramps
    times = table_times[picks]
    model = walking_robot()
    robot = hx.inverse_dynamics(model, times)
    weight = sum(b.mass for b in model.bodies) * 9.81
    for k, name in enumerate(robot.contacts):
        leg = name.split("/")[0]
        assert np.abs(robot.ground_force[:, k] - table[leg][picks, 0]).max() < 1e-9 * weight
    for leg in ("L1", "L2", "L3"):
        single = hx.inverse_dynamics(hx.assemble(walking_leg_scene(leg)), times)
        columns = [robot.joints.index(f"{leg}/{joint}") for joint in single.joints]
        scale = np.abs(robot.effort[:, columns]).max()
        assert np.abs(single.effort - robot.effort[:, columns]).max() < 1e-8 * scale
        scale = np.abs(robot.force[:, columns]).max()
        assert np.abs(single.force - robot.force[:, columns]).max() < 1e-8 * scale


def test_the_prescribed_walk_simulates_across_touch_down_and_lift_off(tripod):
    """Every degree of freedom driven: a simulation must follow the inverse dynamics' motion
    through a touch-down (0.2 s) and a lift-off (0.25 s). The compiled kernels follow the
    contact set (a foot in swing has no rows, one that touched down has new ones); before, a
    lift-off left a singular compiled system and a silently wrong motion (|phi| ~ 1)."""
    model, result = tripod
    k = int(np.argmin(np.abs(result.times - 0.175)))
    run = hx.simulate(model, 0.275, t0=result.times[k], q0=result.q[k], v0=result.v[k])
    assert run.status == "finished", run.message
    assert run.max_position_violation < 1e-9
    reference = hx.inverse_dynamics(model, [0.275])
    assert np.abs(run.q[-1] - reference.q[0]).max() < 1e-6 * model.characteristic_length
