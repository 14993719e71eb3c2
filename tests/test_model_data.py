"""The model/data split: one workspace per model from ``model.create_data()``, algorithms that
leave their results in it and never write to the model, and clear errors when a workspace is
read before it is filled."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "data" / "scenes"


@pytest.fixture(scope="module")
def pendulum():
    return hx.assemble(hx.load_scene(SCENES / "pendulum.toml"))


def test_joint_wrenches_before_a_solve_is_a_clear_error(pendulum):
    data = pendulum.create_data()
    with pytest.raises(hx.HexapodError, match="call forward_dynamics"):
        hx.joint_wrenches(pendulum, data)
    hx.consistent_state(pendulum, data)  # positions and velocities, no multipliers yet
    with pytest.raises(hx.HexapodError, match="lam"):
        hx.driver_efforts(pendulum, data)


def test_a_workspace_of_another_model_is_refused(pendulum):
    other = hx.assemble(hx.load_scene(SCENES / "double_pendulum_planar.toml"))
    data = other.create_data()
    q, v = hx.consistent_state(other, data)
    hx.forward_dynamics(other, data, 0.0, q, v)
    with pytest.raises(hx.HexapodError, match="another model"):
        hx.joint_wrenches(pendulum, data)


def test_a_new_state_clears_what_was_computed_at_the_old_one(pendulum):
    data = pendulum.create_data()
    q, v = hx.consistent_state(pendulum, data)
    hx.forward_dynamics(pendulum, data, 0.0, q, v)
    assert data.lam is not None
    hx.assemble_positions(pendulum, data, 0.0, pendulum.integrate(q, np.full(pendulum.n_v, 0.1)))
    assert data.lam is None and data.v is None  # never read as belonging to the new pose
    with pytest.raises(hx.HexapodError):
        hx.joint_wrenches(pendulum, data)


def test_the_algorithms_leave_the_model_as_built(pendulum):
    """Running every kind of algorithm changes none of the model's descriptive attributes."""
    before = {k: v for k, v in vars(pendulum).items() if not k.startswith("_")}
    data = pendulum.create_data()
    q, v = hx.consistent_state(pendulum, data)
    hx.forward_dynamics(pendulum, data, 0.0, q, v)
    hx.joint_wrenches(pendulum, data)
    hx.simulate(pendulum, 0.05)
    after = {k: v for k, v in vars(pendulum).items()
             if not k.startswith("_") and k in before}
    assert after.keys() == before.keys()
    for key, value in before.items():
        assert after[key] is value, key


def _writes_to_model(source: str) -> list[int]:
    """Lines assigning to an attribute (or an item of one) of a name ``model``."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        targets = node.targets if isinstance(node, ast.Assign) else (
            [node.target] if isinstance(node, (ast.AugAssign, ast.AnnAssign)) else [])
        for target in targets:
            while isinstance(target, (ast.Subscript, ast.Attribute)):
                if isinstance(target.value, ast.Name) and target.value.id == "model":
                    lines.append(node.lineno)
                    break
                target = target.value
    return lines


def test_no_algorithm_writes_to_the_model():
    found = [f"{path.relative_to(ROOT)}:{line}"
             for folder in ("algorithms", "minimal", "simulation", "output", "benchmarks")
             for path in sorted((ROOT / "hexapod" / folder).rglob("*.py"))
             for line in _writes_to_model(path.read_text())]
    assert found == []
    # and the check sees such a write
    assert _writes_to_model("model.derived['tree'] = 1\nmodel.cache = {}\n") == [1, 2]


def test_a_fixed_step_method_says_it_ignores_tolerances(pendulum):
    with pytest.warns(UserWarning, match="rk4-baumgarte is a fixed-step method: it ignores"):
        hx.simulate(pendulum, 0.01, method="rk4-baumgarte", rtol=1e-9)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hx.simulate(pendulum, 0.01, method="rk4-baumgarte", step=1e-3)  # nothing to say
        hx.simulate(pendulum, 0.01, rtol=1e-9)  # an adaptive method uses it
