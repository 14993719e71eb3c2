"""The extreme-case mechanisms (hexapod.benchmarks: stiff, singular, redundant, mass_ratios,
pendulums): each scene against its own reference.

The references are written in minimal coordinates apart from the engine; the initial
accelerations of the centres of mass are the cheap, strong check that a scene and its
reference describe the same system. A few short runs compare whole motions.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms.topology import mobility
from hexapod.benchmarks import (
    cases,
    jets,
    mass_ratios,
    pendulums,
    redundant,
    reference,
    singular,
    stiff,
)

CASES = {case.name: case for case in cases.suite()}


@pytest.fixture(scope="module")
def solved():
    """Model, consistent initial state and accelerations of every case, built once."""
    out = {}

    def get(name):
        if name not in out:
            case = CASES[name]
            model = hx.assemble(case.scene)
            data = model.create_data()
            q, v = hx.consistent_state(model, data)
            v_dot = hx.forward_dynamics(model, data, 0.0, q, v)
            out[name] = (case, model, q, v, v_dot, data)
        return out[name]

    return get


def test_the_suite_covers_every_category_with_unique_names():
    names = [case.name for case in cases.suite()]
    assert len(set(names)) == len(names) == len(CASES)
    assert {case.category for case in CASES.values()} == set(reference.CATEGORIES)
    for case in CASES.values():
        assert case.description and "\n" not in case.description
        assert case.t_end > 0 and case.length > 0
        assert set(case.accelerations) >= set(case.observed)


@pytest.mark.parametrize("name", list(CASES))
def test_scene_is_consistent_and_its_mobility_is_as_documented(name, solved):
    """The initial state is already on the constraints; degrees of freedom counted and
    numerical, with the drivers, and redundant rows as the case says."""
    case, model, q, v, _, data = solved(name)
    assert np.abs(q - model.q0).max() < 1e-12
    assert np.abs(v - model.v0).max() < 1e-12 * (1 + np.abs(model.v0).max())
    m = mobility(model, data, 0.0, q)
    assert (m.numerical, m.counted) == (case.dof, case.counted_dof)
    assert m.numerical_with_drivers == case.dof_with_drivers
    assert len(m.redundant_rows) == case.redundant == data.redundant_rows.size
    assert model.energy_conserved == case.energy_conserved


@pytest.mark.parametrize("name", list(CASES))
def test_initial_accelerations_equal_the_reference(name, solved):
    case, model, q, _, v_dot, _ = solved(name)
    assert np.abs(case.observable(model, q) - np.concatenate(
        [case.scene.bodies[b].com_pose.position for b in case.observed])).max() < 1e-12
    for body, expected in case.accelerations.items():
        info = model.bodies[model.body_index[body]]
        got = v_dot[info.v.start:info.v.start + expected.size]
        assert np.allclose(got, expected, rtol=1e-9, atol=1e-9 * (1 + np.abs(expected).max())), (
            body, got, expected)


def test_bricard_grubler_counts_zero_but_it_moves_with_one_redundant_row(solved):
    case, model, q, _, v_dot, data = solved("bricard")
    m = mobility(model, data, 0.0, q)
    assert m.counted == 0 and m.numerical == 1 and m.redundancy == 1
    assert [model.rows[i].name.split("/")[0] for i in data.redundant_rows] == ["P5"]
    assert np.abs(v_dot).max() > 1.0  # released at rest, it falls


@pytest.mark.parametrize("name, t_end, tol", [
    ("stiff-slider-k1e+05", 0.05, 1e-7),        # 25 periods against the closed form
    ("mass-ratio-pendulum-1e-06", 0.5, 1e-8),   # Lagrange's equations by hand
    ("stretched-leg-driven", 0.4, 1e-9),        # through the singular instant, closed form
    ("n-four-bar-10", 0.3, 1e-8),               # ten windows, before the flat pose
])
def test_short_runs_follow_the_reference(name, t_end, tol):
    case = CASES[name]
    model = hx.assemble(case.scene)
    result = hx.simulate(model, t_end, method="dopri5-projection", rtol=1e-10, atol=1e-12)
    assert result.success, result.message
    assert case.error(model, result.t, result.q) < tol


# ------------------------------------------------------------------ the references themselves


def test_kane_with_taylor_jets_equals_the_double_pendulum_by_hand():
    """The minimal-coordinate machinery of the references against Lagrange's equations of a
    double pendulum of uniform rods written out (mass_ratio_pendulum's, with a 0.3 kg rod)."""
    m1, m2, l1, l2, g = 1.0, 0.3, 1.0, 0.7, reference.G
    I1, I2 = m1 * l1**2 / 12, m2 * l2**2 / 12

    def kinematics(x):
        d1 = jets.stack([jets.sin(x[0]), -jets.cos(x[0]), 0.0 * x[0]])
        d2 = jets.stack([jets.sin(x[1]), -jets.cos(x[1]), 0.0 * x[1]])
        frames = {"r1": (d1 * (l1 / 2), jets.rotation([0, 0, 1], x[0])),
                  "r2": (d1 * l1 + d2 * (l2 / 2), jets.rotation([0, 0, 1], x[1]))}
        return frames, {}

    model = reference.MinimalModel(kinematics, {"r1": (m1, np.diag([0, I1, I1])),
                                            "r2": (m2, np.diag([0, I2, I2]))}, [0, -g, 0])
    th, thd = np.array([1.0, 2.0]), np.array([0.3, -0.7])
    c1, c2, d = l1 / 2, l2 / 2, th[0] - th[1]
    M = np.array([[I1 + m1 * c1**2 + m2 * l1**2, m2 * l1 * c2 * np.cos(d)],
                  [m2 * l1 * c2 * np.cos(d), I2 + m2 * c2**2]])
    f = np.array([-m2 * l1 * c2 * np.sin(d) * thd[1] ** 2 - (m1 * c1 + m2 * l1) * g
                  * np.sin(th[0]), m2 * l1 * c2 * np.sin(d) * thd[0] ** 2
                  - m2 * c2 * g * np.sin(th[1])])
    assert np.allclose(model.accelerations(th, thd), np.linalg.solve(M, f), rtol=1e-13)


def test_flyball_reduction_equals_the_four_coordinate_model():
    """Routh's symmetric reduction (the trajectory reference) against Kane's equations in the
    four joint coordinates (the acceleration reference) at a symmetric state."""
    reduced = stiff._Flyball()
    full = stiff._flyball_minimal(reduced.m_rod, reduced.m_sleeve, reduced.I_sleeve_z,
                                 reference.rod_inertia(reduced.m_rod, 1.0, 2, 0.01))
    beta0 = np.pi / 2 + stiff.FLYBALL["alpha"]
    s, phi, sd, phid, psid = 0.52, 0.1, 0.3, -0.7, 5.0
    xdd = full.accelerations([0.3, s, phi, phi], [psid, sd, phid, phid])
    Iz, dIz = reduced.inertia_z(beta0 + phi)
    rates = reduced.rates(0.0, np.array([s, beta0 + phi, sd, phid, 0.3]), Iz * psid)
    assert np.allclose(rates[2:4], xdd[1:3], rtol=1e-12)
    assert xdd[2] == pytest.approx(xdd[3], rel=1e-12)  # the arms stay symmetric
    assert xdd[0] == pytest.approx(-psid * dIz * phid / Iz, rel=1e-12)  # H = I_z psi' kept


def test_bricard_configuration_curve_closes_the_loop():
    """On ``sin t + sin u + sin t sin u = 0`` the open chain's end returns to P5 with its last
    axis along x, and the joint's velocity too."""
    model = redundant._bricard_minimal()
    for t in np.linspace(-0.5, 3.6, 9):
        _, points = model.kinematics(jets.Jet.variables([t], [1.3], [0.4]))
        end = points["P5"]
        assert np.abs(end.c0 - redundant.BRICARD_POINTS[5]).max() < 1e-14
        assert np.abs(end.c1).max() < 1e-13 and np.abs(end.c2).max() < 1e-13


def test_anti_parallelogram_branch_keeps_the_lengths_and_meets_the_parallelogram():
    a, d = singular.ANTI_PARALLELOGRAM["crank"], singular.ANTI_PARALLELOGRAM["ground"]
    D = np.array([d, 0.0, 0.0])
    for theta in np.linspace(-3.0, 3.0, 13):
        B, C = singular._anti_parallelogram_points(theta)
        assert np.linalg.norm(C - B) == pytest.approx(d, rel=1e-14)
        assert np.linalg.norm(C - D) == pytest.approx(a, rel=1e-14)
    for theta in (0.0, np.pi):
        B, C = singular._anti_parallelogram_points(theta)
        assert np.allclose(C, B + D, atol=1e-15)  # the parallelogram's C: a change point


def test_reference_energy_is_conserved_over_a_bricard_step():
    """The minimal model's energy along its own solution (a consistency check of Kane's
    equations with the closed-form curve), over 0.3 s."""
    model = redundant._bricard_minimal()
    from scipy.integrate import solve_ivp

    solution = solve_ivp(model.rates, (0.0, 0.3), [0.0, 0.0], method="DOP853", rtol=1e-12,
                         atol=1e-12)
    energies = [model.energy(y[:1], y[1:]) for y in solution.y.T]
    assert np.ptp(energies) < 1e-10 * max(abs(e) for e in energies[1:])


CASE_MODULES = (cases, jets, mass_ratios, pendulums, redundant, reference, singular, stiff)


@pytest.mark.parametrize("module", CASE_MODULES, ids=lambda module: module.__name__)
def test_the_module_imports_only_numpy_scipy_and_the_scene_layer(module):
    """Each module of the cases imports the scene layer and the other case modules, nothing of
    the engine above the scene."""
    path = Path(module.__file__)
    allowed = ("numpy", "scipy", "hexapod.scene", "hexapod.spatial", "hexapod.errors",
               "__future__", "collections", "dataclasses")
    siblings = {m.__name__ for m in CASE_MODULES}
    for node in ast.walk(ast.parse(path.read_text())):
        names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                 else [node.module] if isinstance(node, ast.ImportFrom) else [])
        if names == ["hexapod.benchmarks"]:  # from hexapod.benchmarks import <case module>
            names = [f"hexapod.benchmarks.{a.name}" for a in node.names]
        for name in names:
            assert name.startswith(allowed) or name in siblings, name


@pytest.mark.parametrize("name", [n for n, c in CASES.items()
                                  if getattr(c.reference, "model", None) is not None])
def test_fast_reference_equations_equal_kanes(name):
    """Where a reference integrates a faster form of its equations (written by hand, or
    tabulated in Chebyshev series), that form against Kane's equations of the same model at
    states near the motion's."""
    reference = CASES[name].reference
    n = reference.y0.size // 2
    rng = np.random.default_rng(7)
    for _ in range(3):
        y = reference.y0 + rng.normal(size=2 * n) * 0.2
        expected = reference.model.accelerations(y[:n], y[n:])
        got = reference.rates(0.0, y)[n:]
        assert np.allclose(got, expected, rtol=1e-11, atol=1e-11 * np.abs(expected).max())
