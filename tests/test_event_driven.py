"""The event-driven contact scheme against closed forms: the bouncing ball's impact times to
1e-8 s and its accumulation point (a Zeno point ended by sticking), the block on an incline
(sliding at ``g (sin - mu cos)``, sticking, a push that stops when the closed form says),
a particle in the plane, Painleve's rod, which it reports by name, and the compass-gait
walker's periodic step (Goswami, Thuilot and Espiau 1996). The same cases as the
time-stepping scheme's (``test_contacts.py``), at the integrator's tolerance instead of at
order 1."""

from __future__ import annotations

import numpy as np
import pytest
from test_contacts import (
    DOWN,
    GAMMA,
    SCENES,
    G,
    block,
    by_lu_and_by_qr,
    compiled_in_the_loop,
    planar_incline,
)

import hexapod
from hexapod.scene import GroundContact, Particle, PlanarBody

#: the ball's landings: sqrt(2 h / g), then bounces of 2 e u / g, u the landing speed
LANDING = np.sqrt(2.0 / G)
BOUNCE = 2 * 0.9 * np.sqrt(2 * G) / G


@pytest.fixture(scope="module")
def bounced():
    model = hexapod.assemble(hexapod.load_scene(SCENES / "bouncing-ball.toml"))
    return hexapod.simulate(model, 10.0, method="event-driven")


def test_the_ball_lands_when_the_closed_form_says(bounced):
    """Landings at 0.451524 s and 1.264266 s to 1e-8 s (the gap is located on DOP853's dense
    output, exact for a parabola: to round-off), each an impact with the impulse
    ``(1 + e) m u``."""
    assert bounced.success, bounced.message
    impacts = [e for e in bounced.events if e.kind == "impact"]
    assert abs(impacts[0].t - LANDING) < 1e-8 and abs(impacts[1].t - LANDING - BOUNCE) < 1e-8
    assert round(impacts[0].t, 6) == 0.451524 and round(impacts[1].t, 6) == 1.264266
    u = G * LANDING
    assert np.allclose(impacts[0].impulse, [0.0, 0.0, 1.9 * u], rtol=1e-10)
    kinds = [e.kind for e in bounced.events[:3]]
    assert kinds == ["touch-down", "impact", "lift-off"]


def test_the_bounces_accumulate_then_the_ball_rests_without_sinking(bounced):
    """The bounces accumulate at ``LANDING + BOUNCE / (1 - e)`` = 8.578949 s (the last
    rebound's flight is cut at ZENO_FLIGHT, 1e-9 s: 1e-8 s early at most); after it the
    ball's gap is never below -1e-9 m and its speed is zero, exactly."""
    accumulation = LANDING + BOUNCE / (1 - 0.9)
    last = [e for e in bounced.events if e.kind == "impact"][-1]
    assert abs(last.t - accumulation) < 2e-8 and round(last.t, 6) == 8.578949
    assert bounced.events[-1].kind == "impact" and bounced.events[-2].kind == "touch-down"
    assert bounced.q[:, 2].min() >= -1e-9
    after = bounced.t > accumulation + 1e-6
    assert np.all(bounced.v[after] == 0.0)
    assert np.allclose(bounced.contact_forces[after, 0], [0.0, 0.0, G], rtol=1e-12)


@pytest.mark.parametrize("mu", [0.3, 0.0])
def test_the_block_slides_at_g_sin_minus_mu_cos(mu):
    result = hexapod.simulate(block(mu), 0.2, method="event-driven")
    assert result.success, result.message
    speed = result.v[:, :3] @ DOWN
    exact = G * (np.sin(GAMMA) - mu * np.cos(GAMMA))
    assert np.max(np.abs(speed - exact * result.t)) <= 1e-9 * exact * result.t[-1]
    assert np.max(np.abs(result.v[:, 3:])) < 1e-9
    assert sorted(e.kind for e in result.events) == ["slip-start"] * 4


def test_the_block_stays_stuck_and_a_push_stops_when_the_closed_form_says():
    """``mu = 0.7 > tan(30 deg)``: released at rest it never moves (speed under 1e-12 m/s, no
    event); pushed down the slope at 0.2 m/s its four corners' slip ends together at
    ``v0 / |a|`` to 1e-10 s, and it stays stuck."""
    still = hexapod.simulate(block(0.7), 0.1, method="event-driven")
    assert still.success and not still.events and np.max(np.abs(still.v)) < 1e-12
    push = 0.2
    pushed = hexapod.simulate(block(0.7), 0.3, method="event-driven",
                              v0=np.concatenate([push * DOWN, np.zeros(3)]))
    assert pushed.success, pushed.message
    stop = push / -(G * (np.sin(GAMMA) - 0.7 * np.cos(GAMMA)))
    ends = [e for e in pushed.events if e.kind == "slip-end"]
    assert len(ends) == 4 and all(abs(e.t - stop) < 1e-10 for e in ends)
    assert np.max(np.abs(pushed.v[pushed.t > stop])) < 1e-12


def test_a_landing_beside_a_resting_block_leaves_its_corners_sticking():
    """A particle lands 1 mm down the incline from the stuck block (mu = 0.7). The impact's
    contact problem holds the block's closed corners too; its zero-speed answer for them,
    "slip" at round-off speeds, is not a slip: no event but the landing's, the block still."""
    scene = hexapod.load_scene(SCENES / "sliding-block.toml")
    for element in scene.elements:
        if getattr(element, "kind", "") == "ground-contact":
            element.mu = 0.7
    normal = np.array([np.sin(GAMMA), 0.0, np.cos(GAMMA)])
    where = np.array([0.5, 0.0, -0.5 * np.tan(GAMMA)]) + 1e-3 * normal  # 1 mm above
    scene.add(Particle("ball", mass=0.1, position=where))
    scene.add(GroundContact("ball-contact", "ball", normal=normal, mu=0.7))
    result = hexapod.simulate(hexapod.assemble(scene), 0.05, method="event-driven")
    assert result.success, result.message
    assert [(e.kind, e.contact) for e in result.events] == [
        ("touch-down", "ball-contact"), ("impact", "ball-contact")]
    assert np.max(np.abs(result.v[:, :6])) < 1e-12


def test_a_contact_let_go_touches_again_only_past_the_gap_tolerance():
    """A lift-off (a force let the contact go) leaves at zero speed, and a walking foot's gap
    then grows as the fifth power of the time since: its gap stays within round-off of zero,
    and a touch-down found there is followed by a lift-off at the same instant, endlessly
    (the walking robot under 100 Hz gains stopped at 0.3 ms after 257 of them). Until its
    gap has passed the gap tolerance, such a contact touches down only that far into the
    ground; past the tolerance, at zero gap again."""
    from hexapod.simulation.integrators.event_driven import EventDriven

    scene = hexapod.Scene("resting", dimension=3, gravity=[0.0, 0.0, 0.0])
    scene.add(Particle("ball", mass=1.0, position=[0.0, 0.0, 0.0]))
    scene.add(GroundContact("floor", "ball", mu=0.5))
    run = EventDriven(hexapod.assemble(scene), 0.0, 1.0)
    tol = run._gap_tol
    run._mode(0, "open", 0.0)  # a lift-off
    values = [run._gap_value(0, gap, 0.0, 1.0, True) for gap in (-0.5 * tol, -2 * tol)]
    assert values[0] > 0 > values[1]
    run.q = run.q + np.array([0.0, 0.0, 2 * tol])  # a step leaves it clear of the ground
    run._step()
    assert not run.events[1:] and run._gap_value(0, -0.5 * tol, 0.0, 1.0, True) < 0


def test_a_dip_below_the_ground_inside_one_step_is_a_touch_down():
    """A particle 1 mm up, falling at 1 m/s, pushed up at 400 m/s^2: its gap
    ``1e-3 - t + 200 t^2`` is below zero from ``(1 - sqrt(0.2)) / 400`` (1.382 ms) to 3.618
    ms. A first step of 5 ms (DOP853 is exact for a parabola: accepted) ends 1 mm up again,
    both its ends clear of the ground: the gap's watch inside the step finds the touch-down,
    to round-off; a scheme that watched the step's ends alone would fly through the
    ground."""
    scene = hexapod.Scene("dip", dimension=3, gravity=[0.0, 0.0, 400.0])
    scene.add(Particle("ball", mass=1.0, position=[0.0, 0.0, 1e-3], velocity=[0.0, 0.0, -1.0]))
    scene.add(GroundContact("floor", "ball", mu=0.5))
    result = hexapod.simulate(hexapod.assemble(scene), 0.01, method="event-driven",
                              step=5e-3)
    assert result.success, result.message
    assert [e.kind for e in result.events][:2] == ["touch-down", "impact"]
    assert abs(result.events[0].t - (1 - np.sqrt(0.2)) / 400) < 1e-15
    assert result.q[:, 2].min() >= -1e-15


@pytest.mark.parametrize("mu", [0.2, 0.9])
def test_in_the_plane_a_particle_slides_or_sticks(mu):
    result = hexapod.simulate(planar_incline(mu), 0.2, method="event-driven")
    assert result.success, result.message
    exact = G * (np.sin(GAMMA) - mu * np.cos(GAMMA))
    down = np.array([np.cos(GAMMA), -np.sin(GAMMA)])
    if exact > 0:
        assert abs(result.v[-1] @ down - exact * 0.2) < 1e-9 * exact
    else:
        assert np.max(np.abs(result.v)) < 1e-12


def test_painleves_rod_is_reported_by_name():
    """The rod of ``test_contacts`` (mu = 1.5 > 4/3, its end sliding): no sliding motion
    exists at acceleration level; the run fails as a result, naming the contact and the
    paradox and pointing to the time-stepping scheme."""
    theta, half = np.arctan(2.0), 0.5
    c, s = np.cos(theta), np.sin(theta)
    scene = hexapod.Scene("painleve", dimension=2)
    scene.add(PlanarBody("rod", mass=1.0, inertia=1.0 / 12, position=[half * c, half * s],
                         angle=float(theta), velocity=[-1.0, 0.0]))
    scene.add(GroundContact("end", "rod", point=[-half, 0.0], mu=1.5))
    result = hexapod.simulate(hexapod.assemble(scene), 0.05, method="event-driven")
    assert not result.success
    assert "Painleve's paradox at contact 'end'" in result.message
    assert "moreau-jean" in result.message


def test_the_compass_gait_returns_to_its_state_after_one_step():
    """Started just after an impact on its periodic gait (the issue's five-decimal state,
    ``data/scenes/compass-gait.toml``), the walker's swing foot strikes at 0.73472 s (to
    5e-6 s: the published period's rounding) and, the legs' roles swapped, the stance and
    swing angles and rates return to the starting ones to 5e-6 (the starting state's five
    decimals; the integrator's tolerance is 1e-10). Its swing foot passes the slope at
    mid-swing unarmed (no event there); at the strike the old stance foot leaves."""
    model = hexapod.assemble(hexapod.load_scene(SCENES / "compass-gait.toml"))
    result = hexapod.simulate(model, 0.8, method="event-driven", rtol=1e-10, atol=1e-12)
    assert result.success, result.message
    kinds = [(e.kind, e.contact) for e in result.events]
    assert kinds == [("lift-off", "foot-a"), ("touch-down", "foot-b"), ("impact", "foot-b")]
    strike = result.events[-1].t
    assert abs(strike - 0.73472) < 5e-6
    after = np.flatnonzero(result.t == strike)[-1]  # the state after the impact
    q, v = result.q[after], result.v[after]
    # leg b now stands: its angle is pi/2 + the stance angle; leg a's pi/2 - the swing angle
    state = [q[5] - np.pi / 2, np.pi / 2 - q[2], v[5], -v[2]]
    assert np.allclose(state, [-0.21867, -0.32339, 1.09183, -0.37718], rtol=0, atol=5e-6)
    assert result.events[-1].impulse[1] > 0  # the ground pushes the striking foot up


def test_a_slipping_contacts_normal_compliance_is_its_schur_complement():
    """The Painleve check reads, for a slipping contact among others held, the Schur complement
    of the others' unknowns: ``1 / (A^-1)_jj`` for an invertible contact system (the walking
    robot's feet: a raw diagonal entry, or another contact's, said "paradox" where there was
    none); a contact alone, its own entry; redundant contacts, zero (not a paradox)."""
    from hexapod.simulation.integrators.event_driven import _normal_compliance

    rng = np.random.default_rng(3)
    A = rng.normal(size=(5, 5)) + 5 * np.eye(5)
    for j in range(5):
        assert _normal_compliance(A, j) == pytest.approx(1 / np.linalg.inv(A)[j, j], rel=1e-10)
    assert _normal_compliance(np.array([[-0.3]]), 0) == -0.3
    shared = np.ones((4, 4))  # four contacts that carry one load (rank 1)
    assert abs(_normal_compliance(shared, 2)) < 1e-12


@pytest.mark.slow
def test_compiled_its_solves_by_the_lu_walk_as_by_the_qr(tmp_path, monkeypatch):
    """Compiled, the event-driven scheme's acceleration and impulse solves go by an LU with
    pivots chosen at the run's start, written out (:meth:`CompiledContactStep.pivoted`),
    instead of CasADi's sparse QR: the compass gait's step is the same, its strike at the
    same instant to 1e-12 s and its end state to 1e-9 (measured 5e-15 s, 8e-15 and 1.3e-13:
    the two factorisations' round-off), and neither kernel is compiled inside the time
    loop."""
    in_loop = compiled_in_the_loop(monkeypatch)
    model = hexapod.assemble(hexapod.load_scene(SCENES / "compass-gait.toml"))
    chosen, runs = by_lu_and_by_qr(monkeypatch, tmp_path, lambda: hexapod.simulate(
        model, 0.8, method="event-driven", rtol=1e-10, atol=1e-12))
    assert [(k.level, k.lu is not None) for k in chosen] == [("acceleration", True),
                                                             ("impulse", True)]
    # (the base step's check of a rejected step, W W^T, is compiled at its first use)
    assert [name for name in in_loop if name != "row_gram"] == []
    lu, qr = runs["lu"], runs["qr"]
    assert lu.success and qr.success, (lu.message, qr.message)
    assert [(e.kind, e.contact) for e in lu.events] == [(e.kind, e.contact) for e in qr.events]
    assert max(abs(a.t - b.t) for a, b in zip(lu.events, qr.events, strict=True)) <= 1e-12
    assert np.abs(lu.q[-1] - qr.q[-1]).max() <= 1e-9
    assert np.abs(lu.v[-1] - qr.v[-1]).max() <= 1e-9
