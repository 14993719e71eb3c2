"""Inverse dynamics of prescribed motion over a gait: the tree path, the saddle path, the recursive
model of Vukobratović and Potkonjak and a virtual-power balance agree."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms.inverse import inverse_dynamics, tree_plan
from hexapod.minimal.chain import ChainModel
from legs import front_leg_scene

from mechanisms import four_bar, random_tree

TIMES = np.linspace(0.0, 1.2, 25)


def _close(a, b, rel=1e-10):
    scale = max(np.nanmax(np.abs(a)), 1e-300)
    return np.nanmax(np.abs(a - b)) <= rel * scale


@pytest.mark.parametrize("scene", [front_leg_scene(), random_tree(3, 6), random_tree(4, 7),
                                   random_tree(5, 5, chain=True)],
                         ids=["front-leg", "tree-6", "tree-7", "chain-5"])
@pytest.mark.parametrize("frame", ["joint", "world"])
def test_tree_and_saddle_paths_agree(scene, frame):
    model = hx.assemble(scene)
    assert tree_plan(model) is not None
    tree = inverse_dynamics(model, TIMES, method="tree", frame=frame)
    saddle = inverse_dynamics(model, TIMES, method="saddle", frame=frame)
    assert tree.method == "tree" and saddle.method == "saddle"
    for key in ("force", "torque", "effort", "v_dot"):
        assert _close(getattr(tree, key), getattr(saddle, key)), key
    assert tree.max_violation < 1e-13


@pytest.mark.parametrize("seed, n, chain", [(2, 4, True), (3, 6, False)])
def test_tree_path_equals_seed000(seed, n, chain):
    model = hx.assemble(random_tree(seed, n, chain=chain))
    result = inverse_dynamics(model, TIMES, frame="world")
    recursive = ChainModel.from_model(model)
    order = sorted(model.drivers, key=lambda d: d.joint)
    w, wd, wdd = model.law_values(TIMES)
    for k in range(TIMES.size):
        q, q_d, q_dd = (np.array([x[d.law, k] for d in order]) for x in (w, wd, wdd))
        force, moment = recursive.joint_wrenches(q, q_d, q_dd)
        links = [model.joint_index[name] for name in recursive.names]
        assert _close(result.effort[k], recursive.inverse(q, q_d, q_dd), 1e-9)
        assert _close(result.force[k][links], force, 1e-9)
        assert _close(result.torque[k][links], moment, 1e-9)


def test_four_bar_crank_torque_balances_the_power():
    """Closed loop (saddle path): the crank's torque times its rate equals the rate of change
    of kinetic energy minus the power of gravity, sum of m v.(a - g) + I w alpha."""
    model = hx.assemble(four_bar(2, 1.05, law=hx.scene.Harmonic(offset=1.05, sin=[0.6],
                                                                frequency=0.8)))
    assert tree_plan(model) is None
    result = inverse_dynamics(model, TIMES)
    crank = model.joint_index["crank_pin"]
    g = np.array([0.0, -9.81])
    for k in range(TIMES.size):
        v, a = result.v[k], result.v_dot[k]
        power = 0.0
        for b in model.bodies:
            vb, ab = v[b.v], a[b.v]
            power += b.mass * vb[:2] @ (ab[:2] - g) + b.inertia[0, 0] * vb[2] * ab[2]
        crank_rate = v[model.bodies[model.body_index["crank"]].v][2]
        assert result.effort[k, crank] * crank_rate == pytest.approx(power, abs=1e-9 * (
            1 + abs(power)))


def test_driven_pendulum_effort_over_a_gait():
    m, l, Ic = 1.3, 0.7, 0.02
    law = hx.scene.Harmonic(offset=0.3, sin=[1.1], cos=[-0.4], frequency=0.9)
    scene = hx.Scene("arm")
    scene.add(hx.scene.SpatialBody("arm", m, [Ic, Ic, Ic], position=[l, 0.0, 0.0]))
    scene.add(hx.scene.Revolute("motor_pin", "ground", "arm", origin=[0, 0, 0], axis=[0, -1, 0]))
    scene.add(hx.scene.JointDriver("motor", "motor_pin", law))
    result = inverse_dynamics(hx.assemble(scene), TIMES)
    theta, _, theta_dd = law.evaluate(TIMES)
    # about -y, theta lifts the arm from the horizontal: tau = I_O theta_dd + m g l cos(theta)
    expected = (Ic + m * l**2) * theta_dd + m * 9.81 * l * np.cos(theta)
    assert np.allclose(result.effort[:, 0], expected, rtol=1e-11)


def test_motion_must_fix_every_degree_of_freedom():
    scene = front_leg_scene()
    scene._elements = [e for e in scene.elements if e.name != "drive_fti"]
    model = hx.assemble(scene)
    assert tree_plan(model) is None
    with pytest.raises(hx.SingularSystemError, match="1 degree"):
        inverse_dynamics(model, TIMES)


def test_hermite_law_is_exact_at_samples_and_smooth():
    times = np.linspace(0, 1, 9)
    values, rates, accelerations = np.sin(3 * times), 3 * np.cos(3 * times), -9 * np.sin(
        3 * times)
    law = hx.scene.laws.Hermite(times, values, rates, accelerations)
    f, fd, fdd = law.evaluate(times)
    assert np.allclose(f, values, atol=1e-14) and np.allclose(fd, rates, atol=1e-12)
    assert np.allclose(fdd, accelerations, atol=1e-10)
    inner, eps = times[1:-1], 1e-9
    for left, right in zip(law.evaluate(inner - eps), law.evaluate(inner + eps), strict=True):
        assert np.allclose(left, right, atol=1e-5)  # C2 across the samples
    assert "strictly increasing" in hx.scene.laws.Hermite([0, 0], [0, 1], [0, 0],
                                                          [0, 0]).problems()[0]


def test_compiled_and_interpreted_tree_paths_agree():
    """The tree path compiled to C (the execution setting ``compiled``) gives the
    interpreter's numbers."""
    model = hx.assemble(front_leg_scene())
    plan = tree_plan(model)
    interpreted = inverse_dynamics(model, TIMES)
    with hx.executing(compiled=True):
        compiled = inverse_dynamics(model, TIMES)
    for key in ("force", "torque", "effort", "q", "v_dot"):
        assert _close(getattr(interpreted, key), getattr(compiled, key), 1e-13), key
    if __import__("hexapod._support.compiled", fromlist=["compiler"]).compiler() is not None:
        assert plan.compiled.class_name() != "SXFunction"  # a library, loaded


@pytest.mark.skipif(__import__("hexapod._support.compiled", fromlist=["compiler"]).compiler()
                    is None, reason="no C compiler")
def test_another_model_of_the_same_scene_loads_the_compiled_tree_from_the_cache(tmp_path,
                                                                                monkeypatch):
    """With a cache, the second model of a scene (as in a second run) compiles nothing: its
    tree Function is the library of the cache, with the same numbers to the last bit."""
    from hexapod._support import compiled

    with hx.executing(compiled=True, cache=tmp_path / "cache"):
        first = inverse_dynamics(hx.assemble(front_leg_scene()), TIMES)
        monkeypatch.setattr(compiled, "_compile",
                            lambda *args: pytest.fail("the tree was compiled again"))
        second = inverse_dynamics(hx.assemble(front_leg_scene()), TIMES)
    for key in ("force", "torque", "effort", "q", "v", "v_dot"):
        assert np.array_equal(getattr(first, key), getattr(second, key)), key


def test_reactions_on_the_parent():
    """The reaction on the parent is the opposite wrench about the parent's joint point: for a
    prismatic joint that point is apart from the child's, and the moments differ by the arm."""
    model = hx.assemble(random_tree(9, 5, prismatic=0.6))
    assert any(j.kind == "prismatic" for j in model.joints)
    data = model.create_data()
    q = hx.assemble_positions(model, data, 0.4)
    v = hx.solve_velocities(model, data, 0.4, q)
    hx.forward_dynamics(model, data, 0.4, q, v)
    child = hx.joint_wrenches(model, data, frame="world")
    parent = hx.joint_wrenches(model, data, frame="world", on="parent")
    local = hx.joint_wrenches(model, data, on="parent")
    from hexapod.algorithms.liaison import joint_origin, parent_point
    for k, joint in enumerate(model.joints):
        origin, _ = joint_origin(model, q, joint)
        point, R = parent_point(model, q, joint)
        assert np.allclose(parent.force[k], -child.force[k], atol=1e-12)
        # moved back to the child's point, the parent's moment is the child's, reversed
        back = parent.torque[k] + np.cross(point - origin, parent.force[k])
        assert np.allclose(back, -child.torque[k], atol=1e-10 * (1 + np.abs(child.torque).max()))
        assert np.allclose(R @ local.force[k], parent.force[k], atol=1e-12)
        if joint.kind == "prismatic":
            assert np.linalg.norm(point - origin) > 1e-6  # the points are apart


def test_without_a_compiler_the_interpreter_is_used(monkeypatch):
    monkeypatch.setenv("HEXAPOD_NO_JIT", "1")
    model = hx.assemble(front_leg_scene())
    with hx.executing(compiled=True):
        result = inverse_dynamics(model, TIMES)
    plan = tree_plan(model)
    assert plan.compiled is plan.function
    assert np.all(np.isfinite(result.effort))


def test_the_tree_method_on_a_closed_loop_is_refused_with_a_message():
    """A four-bar is no open tree: asking for the tree method is a user error (a HexapodError,
    one line at the command line), not an internal one."""
    from hexapod.errors import HexapodError

    model = hx.assemble(four_bar(2, 0.5))
    with pytest.raises(HexapodError, match="not an open tree"):
        inverse_dynamics(model, np.linspace(0.0, 0.1, 3), method="tree")
