"""Unilateral contacts with Coulomb friction and impacts, integrated by Moreau-Jean
time-stepping, against closed forms: the bouncing ball (impact times, order 1, accumulation
and rest), the block on an incline (sliding at ``g (sin - mu cos)``, sticking, a push that
dies out), in space and in the plane; the frictional contact problem against its own
conditions and against a second, independent way of finding the slip."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hexapod
from hexapod.algorithms.frictional import _slip, _slip_by_angle, solve_contacts
from hexapod.errors import HexapodError, ModelError
from hexapod.scene import GroundContact, Particle, PlanarBody

SCENES = Path(__file__).resolve().parent.parent / "data" / "scenes"
G = 9.81
#: the incline of the block's scene (30 degrees) and the unit vector down its slope
GAMMA = np.pi / 6
DOWN = np.array([np.cos(GAMMA), 0.0, -np.sin(GAMMA)])


def ball_height(t: np.ndarray, restitution: float = 0.9, drop: float = 1.0) -> np.ndarray:
    """The bouncing ball's height in closed form: a fall, then parabolas of speeds ``e^k u``."""
    landing = np.sqrt(2 * drop / G)
    z = np.where(t < landing, drop - G * t**2 / 2, 0.0)
    start, speed = landing, G * landing
    for _ in range(200):
        speed *= restitution
        s = t - start
        z = np.where((s >= 0) & (s < 2 * speed / G), speed * s - G * s**2 / 2, z)
        start += 2 * speed / G
    return z


@pytest.fixture(scope="module")
def ball():
    return hexapod.assemble(hexapod.load_scene(SCENES / "bouncing-ball.toml"))


def block(mu: float):
    scene = hexapod.load_scene(SCENES / "sliding-block.toml")
    for element in scene.elements:
        if getattr(element, "kind", "") == "ground-contact":
            element.mu = mu
    return hexapod.assemble(scene)


def test_the_ball_lands_and_rebounds_when_and_as_the_closed_form_says(ball):
    """Impacts at 0.451524 and 1.264266 s within a step (impacts are resolved to a step), with
    the impulse ``m (1 + e) u`` of the landing speed ``u`` (plus the weight's over the step)."""
    h = 1e-3
    result = hexapod.simulate(ball, 1.5, step=h)
    assert result.method == "moreau-jean" and result.success
    impacts = [e for e in result.events if e.kind == "impact"]
    assert len(impacts) == 2
    for event, exact in zip(impacts, (0.451524, 1.264266), strict=True):
        assert abs(event.t - exact) <= h
    u = np.sqrt(2 * G)
    assert impacts[0].impulse[2] == pytest.approx(1.9 * u, abs=2 * G * h)
    assert np.allclose(impacts[0].impulse[:2], 0.0)
    kinds = [e.kind for e in result.events]
    assert kinds == ["touch-down", "impact", "lift-off"] * 2


def test_the_balls_error_falls_at_order_one(ball):
    """The largest height error over two bounces halves with the step (order 1: impacts are
    resolved to a step); measured over three steps, the fitted order lies in [0.7, 1.4]."""
    steps = np.array([2e-3, 1e-3, 5e-4])
    errors = []
    for h in steps:
        result = hexapod.simulate(ball, 1.5, step=h)
        errors.append(np.max(np.abs(result.q[:, 2] - ball_height(result.t))))
    order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert 0.7 <= order <= 1.4, (errors, order)
    assert errors[-1] < 5e-3


def test_the_bounces_accumulate_then_the_ball_rests_without_sinking_or_jitter(ball):
    """The bounces accumulate at 8.578949 s (to a few steps: the last bounces are shorter than
    the step, and the last touch-down, slower than what the weight gives in two steps, is
    plastic); from then on the ball rests: no event, no speed, on the ground, carried by its
    weight."""
    h = 2e-3
    result = hexapod.simulate(ball, 10.0, step=h)
    assert result.events[-1].kind == "touch-down"
    last = result.events[-1].t
    assert abs(last - 8.578949) < 0.05
    after = result.t > last
    assert np.all(result.q[after, 2] >= -1e-9)
    assert np.all(result.q[after, 2] <= 1e-4)  # rests where its last touch-down left it
    assert np.max(np.abs(result.v[after])) <= 1e-12
    assert np.allclose(result.contact_forces[after, 0], [0.0, 0.0, G], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("mu", [0.3, 0.0])
def test_the_block_slides_down_the_incline_at_g_sin_minus_mu_cos(mu):
    """Its four corners slip from the first step; it slides with ``a = g (sin - mu cos)`` to
    1e-9 and does not turn."""
    model = block(mu)
    h = 1e-3
    result = hexapod.simulate(model, 0.05, step=h)
    assert result.success, result.message
    speed = result.v[:, :3] @ DOWN
    accelerations = np.diff(speed) / np.diff(result.t)
    exact = G * (np.sin(GAMMA) - mu * np.cos(GAMMA))
    assert np.max(np.abs(accelerations / exact - 1)) < 1e-9
    assert np.max(np.abs(result.v[:, 3:])) < 1e-9
    starts = [e for e in result.events if e.kind == "slip-start"]
    if mu:
        assert sorted(e.contact for e in starts) == [f"corner-{k}" for k in range(1, 5)]
    # the ground carries the block's weight across the slope
    normal = np.array([np.sin(GAMMA), 0.0, np.cos(GAMMA)])
    total = result.contact_forces[1:].sum(axis=1)
    assert np.allclose(total @ normal, G * np.cos(GAMMA), rtol=1e-9)


def test_the_block_stays_stuck_when_friction_holds_it():
    """With ``mu > tan(30 deg)`` it stays where it is released: speed under 1e-12 m/s."""
    result = hexapod.simulate(block(0.7), 0.05, step=1e-3)
    assert result.success
    assert np.max(np.abs(result.v)) < 1e-12
    assert not result.events


def test_a_push_dies_out_at_g_sin_minus_mu_cos_and_leaves_the_block_stuck():
    """Pushed down the slope at 0.2 m/s with ``mu = 0.7`` it slows at ``g (sin - mu cos)``
    (negative) to 1e-9, stops within a step of ``v0 / |a|`` (its corners' slip ends there),
    and stays stuck."""
    model, h, push = block(0.7), 1e-3, 0.2
    v0 = np.concatenate([push * DOWN, np.zeros(3)])
    result = hexapod.simulate(model, 0.3, step=h, v0=v0)
    assert result.success, result.message
    exact = G * (np.sin(GAMMA) - 0.7 * np.cos(GAMMA))
    stop = push / -exact
    speed = result.v[:, :3] @ DOWN
    sliding = result.t < stop - h
    accelerations = np.diff(speed)[sliding[1:]] / h
    assert np.max(np.abs(accelerations / exact - 1)) < 1e-9
    ends = [e for e in result.events if e.kind == "slip-end"]
    assert len(ends) == 4 and all(abs(e.t - stop) <= h for e in ends)
    assert np.max(np.abs(result.v[result.t > stop + h])) < 1e-12


def planar_incline(mu: float, velocity: float = 0.0):
    """A particle on an incline in the plane (normal ``(sin, cos)``), with friction ``mu``."""
    n = [np.sin(GAMMA), np.cos(GAMMA)]
    scene = hexapod.Scene("planar-incline", dimension=2)
    scene.add(Particle("puck", mass=2.0, position=[0.0, 0.0],
                       velocity=[velocity * np.cos(GAMMA), -velocity * np.sin(GAMMA)]))
    scene.add(GroundContact("slope", "puck", normal=n, mu=mu))
    return hexapod.assemble(scene)


@pytest.mark.parametrize("mu", [0.2, 0.9])
def test_in_the_plane_a_particle_slides_or_sticks_as_coulomb_says(mu):
    model = planar_incline(mu, velocity=0.0)
    result = hexapod.simulate(model, 0.05, step=1e-3)
    down = np.array([np.cos(GAMMA), -np.sin(GAMMA)])
    speed = result.v @ down
    if np.tan(GAMMA) > mu:
        a = np.diff(speed) / np.diff(result.t)
        assert np.max(np.abs(a / (G * (np.sin(GAMMA) - mu * np.cos(GAMMA))) - 1)) < 1e-9
    else:
        assert np.max(np.abs(result.v)) < 1e-12


def test_painleves_rod_is_resolved_by_a_tangential_impact():
    """A rod of 1 m leaning at atan(2) with its lower end sliding away from under it at 1 m/s,
    mu = 1.5 > 4/3: no sliding motion exists at acceleration level (``W_NN - mu W_NT s < 0``:
    friction would press the end into the ground faster than the ground can push). The
    time-stepping scheme stops the slip by a tangential impact in the first step, whose
    impulse is the sticking one, ``-W^-1 b``, with the rod's Delassus operator in closed form
    ``W = [[1 + 3 c^2, -3 s c], [-3 s c, 1 + 3 s^2]] / m`` (normal, then tangent)."""
    theta, half, h = np.arctan(2.0), 0.5, 1e-3
    c, s = np.cos(theta), np.sin(theta)
    assert 1 + 3 * c**2 - 1.5 * 3 * s * c < 0  # Painleve's condition, the end sliding to -x
    scene = hexapod.Scene("painleve", dimension=2)
    scene.add(PlanarBody("rod", mass=1.0, inertia=1.0 / 12, position=[half * c, half * s],
                         angle=float(theta), velocity=[-1.0, 0.0]))
    scene.add(GroundContact("end", "rod", point=[-half, 0.0], mu=1.5))
    result = hexapod.simulate(hexapod.assemble(scene), 0.05, step=h)
    assert result.success, result.message
    W = np.array([[1 + 3 * c**2, -3 * s * c], [-3 * s * c, 1 + 3 * s**2]])
    normal, tangent = np.linalg.solve(W, -np.array([-G * h, -1.0]))
    first = result.events[0]
    assert (first.t, first.kind) == (pytest.approx(h), "impact")
    assert np.allclose(first.impulse, [tangent, normal], rtol=1e-12)
    assert tangent <= 1.5 * normal
    assert [e.kind for e in result.events[:2]] == ["impact", "slip-end"]


def _conditions(D, c, mu, P):
    """How far ``P`` is from satisfying one contact's conditions with ``u = D P + c``: the
    largest violation of the case it claims (open, stick or slip), relative to ``|c|``."""
    u = D @ P + c
    scale = np.abs(c).max()
    if P[0] == 0.0:
        return max(0.0, -u[0]) / scale
    cone = max(0.0, np.linalg.norm(P[1:]) - mu * P[0]) / max(P[0], 1e-300)
    speed = np.linalg.norm(u[1:])
    if speed <= 1e-12 * scale:  # stick
        return max(abs(u[0]) / scale, cone)
    # slip: on the cone, against the slip
    against = np.linalg.norm(P[1:] + mu * P[0] * u[1:] / speed) / max(P[0], 1e-300)
    return max(abs(u[0]) / scale, against)


def test_the_contact_problem_meets_its_conditions_on_random_coupled_contacts():
    """Random Delassus operators (coupled normal and tangential directions, of three and of
    two contacts) and free velocities: the impulses meet Signorini and Coulomb to 1e-9."""
    rng = np.random.default_rng(5)
    for _ in range(40):
        m = int(rng.integers(1, 4))
        A = rng.normal(size=(3 * m, 3 * m))
        W = A @ A.T + 0.1 * np.eye(3 * m)
        b = rng.normal(size=3 * m)
        mu = rng.uniform(0.05, 1.0, size=m)
        solution = solve_contacts(W, b, mu, np.zeros(m))
        u = (W @ solution.impulses.reshape(-1) + b).reshape(m, 3)
        for a in range(m):
            others = b.reshape(m, 3)[a] + (W[3 * a:3 * a + 3] @ solution.impulses.reshape(-1)
                                           - W[3 * a:3 * a + 3, 3 * a:3 * a + 3]
                                           @ solution.impulses[a])
            D = W[3 * a:3 * a + 3, 3 * a:3 * a + 3]
            assert _conditions(D, others, mu[a], solution.impulses[a]) < 1e-9
            assert u[a, 0] >= -1e-9 * np.abs(b).max()


def test_newtons_slip_is_the_bracketed_one():
    """The slip by Newton's method and by bracketing the direction's angle agree to 1e-10 on
    coupled contacts (two independent ways to the same impulse)."""
    rng = np.random.default_rng(11)
    checked = 0
    for _ in range(60):
        A = rng.normal(size=(3, 3))
        D = A @ A.T + 0.2 * np.eye(3)
        c = np.concatenate([[-abs(rng.normal())], 3 * rng.normal(size=2)])
        mu = float(rng.uniform(0.05, 0.6))
        try:
            reference = _slip_by_angle(D, c, mu, "test")
        except HexapodError:
            continue
        assert np.allclose(_slip(D, c, mu, "test"), reference, rtol=1e-10,
                           atol=1e-10 * np.abs(reference).max())
        checked += 1
    assert checked >= 30


@pytest.mark.parametrize("change, key", [
    ({"restitution": -0.1}, "restitution"), ({"restitution": 1.5}, "restitution"),
    ({"mu": -0.2}, "mu"), ({"body": "nobody"}, "body"), ({"normal": [0.0, 0.0, 0.0]}, "normal"),
    ({"normal": [0.0, 1.0]}, "normal"), ({"armed_ahead_of": "nothing"}, "armed_ahead_of"),
    ({"armed_ahead_of": "floor"}, "armed_ahead_of"), ({"forward": [0.0, 0.0, 0.0]}, "forward")])
def test_a_bad_contact_is_one_clear_problem_naming_its_key(change, key):
    scene = hexapod.Scene("ball")
    scene.add(Particle("ball", mass=1.0, position=[0.0, 0.0, 1.0]))
    scene.add(GroundContact(**{"name": "floor", "body": "ball", **change}))
    with pytest.raises(ModelError) as info:
        hexapod.assemble(scene)
    assert len(info.value.problems) == 1
    problem = str(info.value.problems[0])
    assert "floor" in problem and key in problem


def test_the_compass_gait_strikes_within_a_step_of_its_period():
    """The compass-gait walker (``data/scenes/compass-gait.toml``) at a 2 ms step: its swing
    foot, armed once ahead of the stance foot (it passes the slope at mid-swing), strikes
    within a step of the period 0.73472 s (1.28 ms late; 3.28 ms with the step's forces and
    Jacobians at its start instead of mid-step), and the stance foot leaves then, not when the
    swing foot passes it."""
    model = hexapod.assemble(hexapod.load_scene(SCENES / "compass-gait.toml"))
    result = hexapod.simulate(model, 0.76, step=2e-3)
    assert result.success, result.message
    kinds = [(e.kind, e.contact) for e in result.events]
    assert kinds == [("lift-off", "foot-a"), ("touch-down", "foot-b"), ("impact", "foot-b")]
    assert all(abs(e.t - 0.73472) <= 2e-3 for e in result.events)


def test_a_smooth_method_refuses_a_scene_with_unilateral_contacts(ball):
    with pytest.raises(HexapodError, match="unilateral contacts .*'floor'.*moreau-jean"):
        hexapod.simulate(ball, 0.1, method="dopri5")


def test_the_command_writes_the_ground_forces_and_the_events(tmp_path):
    from hexapod.cli.app import main

    out = tmp_path / "ball"
    status = main(["simulate", str(SCENES / "bouncing-ball.toml"), "--t-end", "0.6",
                   "--step", "1e-3", "--out", str(out)])
    assert status == 0
    header = (out / "results.csv").read_text().splitlines()[0].split(",")
    assert header[-3:] == ["GRx:floor", "GRy:floor", "GRz:floor"]
    events = (out / "events.csv").read_text().splitlines()
    assert events[0] == "t,kind,contact,Px,Py,Pz"
    assert [line.split(",")[1] for line in events[1:]] == ["touch-down", "impact", "lift-off"]
    assert '"events.csv"' in (out / "units.json").read_text()
    for figure in ("contacts.png", "gait.png"):  # the ground forces, when it is pushed
        assert (out / figure).read_bytes().startswith(b"\x89PNG")


@pytest.mark.parametrize("change, words", [
    ('restitution = -0.5', "restitution"), ('mu = -0.1', "mu"),
    ('body = "nobody"', "nobody"), ('kp = nan', "kp"), ("", "--step 20")])
def test_bad_input_is_one_message_exit_1_and_nothing_written(tmp_path, capsys, change, words):
    """A negative restitution or friction, a contact on no body, a gain that is not finite, a
    step longer than the run: one message naming it, status 1, no output directory."""
    from hexapod.cli.app import main

    text = (SCENES / "bouncing-ball.toml").read_text()
    if change.startswith("kp"):
        text += ('\n[[body]]\nname = "arm"\nmass = 1.0\ninertia = [0.1, 0.1, 0.1]\n'
                 'position = [1.0, 0.0, 1.0]\n\n[[joint]]\nname = "pin"\ntype = "revolute"\n'
                 'parent = "ground"\nchild = "arm"\naxis = [0.0, 1.0, 0.0]\n'
                 'origin = [0.5, 0.0, 1.0]\n\n[[force]]\nname = "servo"\ntype = "controller"\n'
                 f'joint = "pin"\ntarget = 0.0\n{change}\n')
    elif change:
        key = change.split(" = ")[0]
        lines = [line for line in text.splitlines() if not line.startswith(f"{key} =")]
        text = "\n".join(lines) + f"\n{change}\n"
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    out = tmp_path / "out"
    step = ["--step", "20"] if not change else ["--step", "1e-3"]
    status = main(["simulate", str(scene), "--t-end", "0.1", *step, "--out", str(out)])
    error = capsys.readouterr().err
    assert status == 1 and not out.exists()
    assert words in error
    assert "Traceback" not in error


def test_a_contact_closing_unforeseen_has_the_step_solved_again_with_all(monkeypatch):
    """Moreau-Jean's solve carries the unit impulses of the contacts that may close in the
    step only (the compass gait's stance foot, its swing foot near the strike); one closing
    unforeseen has the step solved again with all of them. Foreseeing none (every closing
    unforeseen, one more solve a step) or all gives the same walk to round-off."""
    from hexapod.simulation.integrators.moreau_jean import MoreauJean

    model = hexapod.assemble(hexapod.load_scene(SCENES / "compass-gait.toml"))
    usual = hexapod.simulate(model, 0.76, step=2e-3)
    steps = usual.counters.steps
    assert usual.counters.rhs == steps + 1
    for foreseen, more in ((False, steps), (True, 0)):
        monkeypatch.setattr(MoreauJean, "_candidates",
                            lambda self, *_, f=foreseen: np.full(len(self.contacts), f))
        other = hexapod.simulate(model, 0.76, step=2e-3)
        assert [(e.kind, e.contact, e.t) for e in other.events] == [
            (e.kind, e.contact, e.t) for e in usual.events]
        assert np.abs(other.q - usual.q).max() <= 1e-12  # measured 4e-15
        assert np.abs(other.contact_forces - usual.contact_forces).max() <= 1e-9  # of 7e3 N
        assert other.counters.rhs == usual.counters.rhs + more


def compiled_in_the_loop(monkeypatch) -> list:
    """The names of the Functions compiled inside a run's time loop from now on (a list that
    fills as runs go): what the loop's CPU would count."""
    from hexapod._support import compiled
    from hexapod.simulation import loop

    inside, in_loop = [False], []
    run, compile_ = loop._run, compiled._compile

    def watched_run(*args, **kwargs):
        inside[0] = True
        try:
            return run(*args, **kwargs)
        finally:
            inside[0] = False

    def watched_compile(function, *args):
        in_loop.extend([function.name()] if inside[0] else [])
        return compile_(function, *args)

    monkeypatch.setattr(loop, "_run", watched_run)
    monkeypatch.setattr(compiled, "_compile", watched_compile)
    return in_loop


def by_lu_and_by_qr(monkeypatch, cache, run) -> tuple[list, dict]:
    """``run()`` compiled twice (``cache`` the compiled code's folder), the contact kernels'
    LU written out allowed (``"lu"``) and refused (``"qr"``: CasADi's sparse QR): the kernels
    the first run pivoted, and both results."""
    from hexapod.simulation.contact_kernel import CompiledContactStep

    chosen, runs = [], {}
    pivoted = CompiledContactStep.pivoted
    for solve in ("lu", "qr"):
        monkeypatch.setattr(CompiledContactStep, "pivoted", lambda self, *a, s=solve: (
            chosen.append(pivoted(self, *a)) or chosen[-1]) if s == "lu" else self)
        with hexapod.executing(compiled=True, cache=str(cache)):
            runs[solve] = run()
    return chosen, runs


def test_compiled_the_step_solves_by_its_lu_and_walks_as_by_the_qr(tmp_path, monkeypatch):
    """Compiled, Moreau-Jean's step solves its saddle-point system by an LU with pivots
    chosen at the run's start, written out (:meth:`CompiledContactStep.pivoted`), instead of
    CasADi's sparse QR: the compass gait walks the same to round-off (4e-15 measured; the
    compiled and interpreted runs differ by 5e-10, their projections' Newton steps not being
    the same), events and forces too. Nothing is compiled inside the time loop (its CPU counts
    the compiler's: the retraction, compiled at its first use there, made a walking robot's
    stride 2.5 times as costly)."""
    in_loop = compiled_in_the_loop(monkeypatch)
    scene = hexapod.load_scene(SCENES / "compass-gait.toml")
    chosen, runs = by_lu_and_by_qr(monkeypatch, tmp_path, lambda: hexapod.simulate(
        hexapod.assemble(scene), 0.76, step=2e-3))
    assert [k.lu is not None for k in chosen] == [True]
    assert in_loop == []
    lu, qr = runs["lu"], runs["qr"]
    assert [(e.kind, e.contact, e.t) for e in lu.events] == [
        (e.kind, e.contact, e.t) for e in qr.events]
    assert np.abs(lu.q - qr.q).max() <= 1e-12
    assert np.abs(lu.contact_forces - qr.contact_forces).max() <= 1e-9
