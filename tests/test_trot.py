"""Gaits with two feet down: the trunk's motion two point feet can carry (legs.carried).

The project's quadruped trots (data/robots/quadruped-trot.toml: each diagonal pair alone on the
ground for 0.4 of the period) and bounds: stance feet on their footholds, the ground forces
balancing the bodies' momentum rate, the efforts equal to Pinocchio's with the reported ground
reactions (a committed fixture), every foot pushing inside its friction cone; where two feet
leave the trunk free to tip about their line, the dynamics' accelerations are the planned
motion's, and without the correction the inverse dynamics stops there, naming the feet.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from robots import ROBOTS, check_pinocchio, described_walk, foot_on_ground, momentum_gap

import hexapod as hx
from hexapod.errors import ModelError
from legs.carried import TrunkSway, lobatto, two_feet_phases


@pytest.fixture(scope="module")
def trot():
    return described_walk("quadruped-trot")


def _two_feet(scene, times) -> np.ndarray:
    """Whether exactly two feet are on the ground at each of ``times``."""
    contacts = [j for name, j in scene.joints.items() if name.endswith("/ground")]
    down = sum(hx.scene.contacts.in_stance(c, times).astype(int) for c in contacts)
    return down == 2


def test_two_feet_carry_the_trot_with_pinocchios_efforts(trot):
    """1e-12 m, 1e-9 of the weight, 1e-8 of the largest effort (2.1e-15 when the fixture was
    made), every foot's force inside its cone; 24 of the stride's 30 samples have two feet
    down."""
    scene, model, result, stored = trot
    assert _two_feet(scene, result.times).sum() == 24
    for name in result.contacts:
        position, foothold, stance = foot_on_ground(scene, model, result, scene.joints[name])
        assert np.abs(position[stance] - foothold[stance]).max() < 1e-12
    assert momentum_gap(model, result) < 1e-9
    assert result.policy == "friction" and result.feasible
    check_pinocchio(model, result, stored)


def test_the_centre_of_pressure_is_on_the_two_feet_line_not_outside(trot):
    """Where two feet carry the trot, the centre of pressure lies on their segment (a
    round-off's distance from it: 1e-12 m), and the report counts no sample outside; the
    centre of mass is off the segment there (a trot is not statically stable)."""
    from hexapod.output.stability import stability_margins, stability_section

    scene, model, result, _ = trot
    margins = stability_margins(model, result)
    two = _two_feet(scene, result.times)
    assert np.abs(margins.cop_margin[two]).max() < 1e-12
    assert np.all(margins.static_margin[two] < -1e-3)
    section = "\n".join(stability_section(margins))
    assert f"| 0 of {result.times.size} |" in section


def test_the_trunk_tips_as_planned_where_two_feet_leave_it_free(trot):
    """Where two feet are down the dynamics decides the trunk's tipping about their line
    (the constraints leave it free): its accelerations are the planned sway's to 1e-6 m/s^2
    (the inverse dynamics' own check), its positions to round-off."""
    scene, model, result, _ = trot
    trunk = model.bodies[model.body_index["trunk"]]
    two = _two_feet(scene, result.times)
    for k, axis in enumerate("xy"):
        value, _, acceleration = scene.drivers[f"trunk/{axis}"].law.evaluate(result.times)
        assert np.abs(result.q[:, trunk.q][:, k] - value).max() < 1e-12
        assert np.abs(result.v_dot[:, trunk.v][two, k] - acceleration[two]).max() < 1e-6


def test_without_the_correction_the_inverse_dynamics_names_the_two_feet(trot):
    """The planned sway alone (the lumped model's centre of pressure on the diagonal) is not
    carried: the trunk would tip, and the inverse dynamics says where and on which feet."""
    scene, _, result, _ = trot
    law = scene.drivers["trunk/y"].law
    assert isinstance(law, TrunkSway) and law.bounds
    uncorrected = hx.load_scene(ROBOTS / "quadruped-trot.toml")
    uncorrected.drivers["trunk/y"].law = replace(law, bounds=(), values=())
    times = result.times[:4]  # t = 0: the feet RF and LH alone on the ground
    with pytest.raises(hx.SingularSystemError, match=(
            r"at t = 0 s only the feet RF and LH are on the ground, leaving 1 degree\(s\) of "
            r"freedom free: trunk turning .*accelerates")):
        hx.inverse_dynamics(hx.assemble(uncorrected), times, method="saddle")


def test_the_correction_is_c2_periodic_and_through_its_values():
    """At the bounds of each two-feet phase the correction's value, rate and acceleration
    are continuous (the polynomials meet the quintics that join them); it repeats with the
    period; at its Chebyshev-Lobatto points it is its values; and its rate and acceleration
    are its value's derivatives (central differences)."""
    bounds, period = (0.0, 0.24, 0.3, 0.54), 0.6
    rng = np.random.default_rng(7)
    values = rng.normal(scale=1e-3, size=2 * 9)
    law = TrunkSway(0.1, 0.0, (0.01,), (0.0,), period, bounds, values)
    plain = replace(law, bounds=(), values=())
    for edge in bounds:
        # a picosecond either side: a jump would be of the order of the values (1e-3 m,
        # 0.1 m/s, 10 m/s^2), smooth change and round-off are below these
        left, right = (np.array(law.evaluate(edge + s)) for s in (-1e-12, 1e-12))
        assert np.all(np.abs(left - right) <= [1e-12, 1e-9, 1e-6])
    t = np.linspace(-1.0, 1.0, 41)
    assert np.allclose(np.array(law.evaluate(t + period)), np.array(law.evaluate(t)),
                       rtol=0.0, atol=1e-12)
    nodes = np.r_[lobatto(0.0, 0.24, 8), lobatto(0.3, 0.54, 8)]
    assert np.abs(law(nodes) - plain(nodes) - values).max() < 1e-15
    h, t = 1e-5, np.linspace(0.005, 0.595, 60)  # off the bounds (the third derivative jumps)
    value, rate, acceleration = law.evaluate(t)
    assert np.abs((law(t + h) - law(t - h)) / (2 * h) - rate).max() < 1e-6
    assert np.abs((law(t + h) - 2 * value + law(t - h)) / h**2 - acceleration).max() < 1e-3


def test_a_scene_written_with_the_correction_reads_back(tmp_path, trot):
    scene = trot[0]
    path = tmp_path / "trot.toml"
    hx.write_scene(scene, path)
    again = hx.read_scene(path)
    t = np.linspace(0.0, 1.2, 61)
    for axis in "xy":
        assert np.array_equal(np.array(again.drivers[f"trunk/{axis}"].law.evaluate(t)),
                              np.array(scene.drivers[f"trunk/{axis}"].law.evaluate(t)))


def test_two_feet_phases_and_the_gaits_they_refuse():
    """A trot of duty 0.6: two phases of 0.4 of the period, one per diagonal. At duty 0.5 the
    load would pass between the pairs in no time; a biped's single support has one foot."""
    trot = {"LF": 0.0, "RH": 0.0, "RF": 0.5, "LH": 0.5}
    phases = two_feet_phases(trot, 0.6, 1.0)
    assert [(round(a, 12), round(b, 12), set(f)) for a, b, f in phases] == [
        (0.0, 0.4, {"RF", "LH"}), (0.5, 0.9, {"LF", "RH"})]
    assert two_feet_phases({"LH": 0.0, "LF": 0.25, "RH": 0.5, "RF": 0.75}, 0.85, 1.0) == []
    with pytest.raises(ValueError, match="duty factor above 0.5"):
        two_feet_phases(trot, 0.5, 1.0)
    with pytest.raises(ValueError, match="between t = 0 s and 0.4 s only R is on the ground"):
        two_feet_phases({"L": 0.0, "R": 0.5}, 0.6, 1.0)


def test_a_trot_of_duty_one_half_is_one_clear_message(tmp_path):
    path = _variant(tmp_path, "duty = 0.6 ", "duty = 0.5 ")
    with pytest.raises(ModelError, match=r"duty factor above 0\.5") as caught:
        hx.load_scene(path)
    assert "gait.duty" in str(caught.value) and str(path) in str(caught.value)


def _variant(tmp_path, old: str, new: str):
    """data/robots/quadruped-trot.toml with ``old`` replaced by ``new``, beside its URDF."""
    for name in ("quadruped.urdf", "quadruped-motors.toml"):
        (tmp_path / name).write_text((ROBOTS / name).read_text())
    text = (ROBOTS / "quadruped-trot.toml").read_text()
    assert old in text
    path = tmp_path / "variant.toml"
    path.write_text(text.replace(old, new))
    return path


def test_a_bound_is_carried_along_the_walk(tmp_path):
    """A bound's pairs stand across the walk: the trunk's correction is along ``x``, and the
    quadruped bounds with its feet pushing inside their cones (one period, 31 samples)."""
    scene = hx.load_scene(_variant(tmp_path, '"trot"', '"bound"'))
    assert scene.drivers["trunk/x"].law.bounds and not scene.drivers["trunk/y"].law.bounds
    model = hx.assemble(scene)
    result = hx.inverse_dynamics(model, np.linspace(0.0, 0.6, 31))
    assert _two_feet(scene, result.times).sum() >= 20
    assert result.feasible and momentum_gap(model, result) < 1e-9


def test_a_trot_turns_carried_by_its_feet(tmp_path):
    """The quadruped trotting and turning left at 20 degrees a second: both world coordinates
    of the trunk hold the correction along its own lateral axis; every sample carried by
    pushing feet inside their cones, the momentum balanced, the trunk's accelerations where
    two feet leave it free its planned ones (1e-6 m/s^2) and its laws' rates and accelerations
    their central differences."""
    path = _variant(tmp_path, "period = 0.6\n", "period = 0.6\nyaw_rate = 20\n")
    scene = hx.load_scene(path)
    laws = [scene.drivers[f"trunk/{axis}"].law for axis in "xy"]
    assert all(law.bounds and law.free == 1 for law in laws)
    model = hx.assemble(scene)
    result = hx.inverse_dynamics(model, np.linspace(0.0, 0.6, 31))
    two = _two_feet(scene, result.times)
    assert two.sum() >= 20 and result.feasible and momentum_gap(model, result) < 1e-9
    trunk = model.bodies[model.body_index["trunk"]]
    h, t = 1e-5, np.linspace(0.005, 0.595, 60)  # off the phases' bounds
    for k, law in enumerate(laws):
        acceleration = law.evaluate(result.times)[2]
        assert np.abs(result.v_dot[two][:, trunk.v][:, k] - acceleration[two]).max() < 1e-6
        value, rate, acceleration = law.evaluate(t)
        assert np.abs((law(t + h) - law(t - h)) / (2 * h) - rate).max() < 1e-6
        assert np.abs((law(t + h) - 2 * value + law(t - h)) / h**2 - acceleration).max() < 1e-3
