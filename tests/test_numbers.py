"""Every number checked finite and in range, big jobs weighed before the work, and runs that end
early (a non-finite value, a limit, an interruption) ending as results that say so.

Each case of issue 21 is reproduced here: a command-line option out of range is one argparse
error naming it (status 2); a number of a scene file out of range is one problem naming the file
and the key (status 1); a job too big is refused, or stopped, within seconds, with the estimate
and how to raise the limit (status 1); a run's overflow ends it as a failed result.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod import cli
from hexapod._support import limits
from hexapod.errors import HexapodError, ModelError
from hexapod.scene.reader import read_scene
from hexapod.simulation.integrators import RungeKutta4Baumgarte
from hexapod.simulation.loop import simulate

ROOT = Path(__file__).resolve().parents[1]
PENDULUM = str(ROOT / "data" / "scenes" / "pendulum.toml")


def run_main(argv: list[str], capsys) -> tuple[int, str]:
    status = cli.main(argv)
    return status, capsys.readouterr().err


def planar_pendulum(force=None, driven=None) -> hx.Scene:
    """A particle on a 1 m rod in the plane: a model that assembles in milliseconds."""
    scene = hx.Scene("rod", dimension=2)
    scene.add(hx.scene.Particle(name="p", mass=1.0, position=np.array([1.0, 0.0])))
    scene.add(hx.scene.Distance(name="rod", parent="ground", child="p", length=1.0))
    if force is not None:
        scene.add(hx.scene.AppliedForce(name="push", body="p", force=force))
    if driven is not None:
        scene.add(hx.scene.CoordinateDriver(name="drive", body="p", coordinate="x", law=driven))
    return scene


# ------------------------------------------------------------------ command-line options

@pytest.mark.parametrize("argv, option", [
    (["simulate", "--start", "nan"], "--start"),
    (["simulate", "--start", "inf"], "--start"),
    (["simulate", "--start", "1e17"], "--start"),
    (["report", "--start", "nan"], "--start"),
    (["dynamics", "--t", "nan"], "--t"),
    (["info", "--t", "-inf"], "--t"),
    (["simulate", "--t-end", "1e308"], "--t-end"),
    (["simulate", "--t-end", "0"], "--t-end"),
    (["check", "--t-end", "nan"], "--t-end"),
    (["report", "--duration", "1e10"], "--duration"),
    (["simulate", "--rtol", "1"], "--rtol"),
    (["simulate", "--rtol", "0"], "--rtol"),
    (["simulate", "--atol", "inf"], "--atol"),
    (["simulate", "--step", "nan"], "--step"),
    (["simulate", "--every", "0"], "--every"),
    (["simulate", "--cpu-budget", "-1"], "--cpu-budget"),
    (["simulate", "--max-steps", "0.5"], "--max-steps"),
    (["simulate", "--max-memory", "lots"], "--max-memory"),
    (["report", "--samples", "1"], "--samples"),
    (["report", "--samples", "1e20"], "--samples"),
    (["report", "--faces", "100000"], "--faces"),
    (["report", "--mu", "nan"], "--mu"),
    (["inverse", "m.urdf", "--motion", "m.csv", "--out", "o.csv", "--max-memory", "0"],
     "--max-memory"),
    (["export", "results", "--vtk", "out", "--every", "0"], "--every"),
    (["sweep", "study.toml", "--workers", "5000"], "--workers"),
    (["bench", "--budget", "inf"], "--budget"),
])
def test_an_option_out_of_range_is_an_argparse_error_naming_it(argv, option, capsys):
    with pytest.raises(SystemExit) as ended:
        cli.main(argv)
    err = capsys.readouterr().err
    assert ended.value.code == 2
    assert f"error: argument {option}" in err and "Traceback" not in err
    assert len([line for line in err.splitlines() if "error:" in line]) == 1


def test_whole_numbers_may_be_written_with_an_exponent():
    from hexapod.cli.common import at_least, seconds, time_value

    assert at_least(2)("1e3") == 1000 and at_least(1)("7") == 7
    assert time_value("-1e9") == -1e9 and seconds("1e9") == 1e9


def test_a_step_longer_than_the_run_names_both_options(tmp_path, capsys):
    status, err = run_main(["simulate", PENDULUM, "--t-end", "0.5", "--step", "1",
                            "--out", str(tmp_path / "run")], capsys)
    assert status == 1 and "--step 1" in err and "--t-end 0.5" in err
    assert not (tmp_path / "run").exists()


# ------------------------------------------------------------------ numbers of scene files

SCENE = """\
[scene]
name = "rod"
dimension = 2
length_unit = "{unit}"
gravity = [0.0, {gravity}]

[[body]]
name = "p"
type = "particle"
mass = {mass}
position = [{x}, 0.0]

[[joint]]
name = "rod"
type = "distance"
parent = "ground"
child = "p"

[[driver]]
name = "drive"
body = "p"
coordinate = "y"
law = {law}
"""
FINE = {"unit": "m", "gravity": -9.81, "mass": 1.0, "x": 1.0,
        "law": '{type = "spline", times = [0, 1, 2, 3], values = [0, 0.1, 0, 0.1]}'}


@pytest.mark.parametrize("change, key, words", [
    ({"gravity": -1e308}, "scene.gravity", "1e6 m/s^2"),
    ({"gravity": -2e9, "unit": "mm"}, "scene.gravity", "1e6 m/s^2"),
    ({"mass": 1e20}, "body[0].mass", "1e9 kg"),
    ({"x": 1e12, "unit": "mm"}, "body[0].position", "1e9 m in SI"),
    ({"law": '{type = "spline", times = [0, 1e-300, 2e-300, 3e-300], values = [0, 1, 0, 1]}'},
     "driver[0].law", "cannot be interpolated"),
    ({"law": '{type = "hermite", times = [0, 1e-12], values = [0, 1], rates = [0, 0], '
             'accelerations = [0, 0]}'}, "driver[0].law", "nanosecond"),
    ({"law": "1e300"}, "driver[0].law", "beyond the 1e15"),
    ({"law": '{type = "gait", sin = [0.1], period = 1e-300}'}, "driver[0].law",
     "period must be at least"),
])
def test_a_number_out_of_range_in_a_scene_file_names_the_file_and_key(tmp_path, change, key,
                                                                      words):
    path = tmp_path / "rod.toml"
    path.write_text(SCENE.format(**{**FINE, **change}))
    with pytest.raises(ModelError) as raised:
        read_scene(path)
    problems = raised.value.problems
    assert len(problems) == 1, problems
    assert problems[0].where == f"{path}, {key}" and words in problems[0].message


def test_the_scene_file_within_range_reads(tmp_path):
    path = tmp_path / "rod.toml"
    path.write_text(SCENE.format(**FINE))
    assert read_scene(path).bodies["p"].mass == 1.0


# ------------------------------------------------------------------ jobs weighed before work

def test_a_report_of_a_billion_samples_is_refused_before_any_allocation(tmp_path, capsys):
    started = time.perf_counter()
    status, err = run_main(["report", "front-leg", "--samples", "1000000000", "--out",
                            str(tmp_path / "r")], capsys)
    assert status == 1 and time.perf_counter() - started < 10
    assert "1000000000 samples" in err and "TiB of memory" in err
    assert "--samples" in err and "--max-memory" in err and "Traceback" not in err
    assert not (tmp_path / "r").exists()


def test_the_memory_limit_is_raised_and_lowered_by_option_and_environment(monkeypatch):
    assert limits.max_memory(2 * limits.GIB) == 2 * limits.GIB
    monkeypatch.setenv("HEXAPOD_MAX_MEMORY", "16G")
    assert limits.max_memory() == 16 * limits.GIB
    with pytest.raises(HexapodError, match=r"would need about 20 GiB of memory \(limit 16 GiB\)"
                       r": ask for less, or raise the limit with --max-memory 20G"):
        limits.check_memory(20 * limits.GIB, "the job", "ask for less")
    limits.check_memory(20 * limits.GIB, "the job", "ask for less", limit=32 * limits.GIB)
    monkeypatch.setenv("HEXAPOD_MAX_MEMORY", "a lot")
    with pytest.raises(HexapodError, match="HEXAPOD_MAX_MEMORY: not a memory size"):
        limits.max_memory()
    monkeypatch.delenv("HEXAPOD_MAX_MEMORY")
    assert 0 < limits.max_memory() <= limits.MEMORY_CAP
    assert [limits.parse_size(t) for t in ("512M", "1.5GiB", "2k", "100")] == [
        512 * 1024**2, 3 * limits.GIB // 2, 2048, 100]


def test_a_fixed_step_run_of_too_many_steps_is_refused_before_it_starts(tmp_path, capsys):
    status, err = run_main(["simulate", PENDULUM, "--method", "rk4-baumgarte", "--step",
                            "1e-9", "--out", str(tmp_path / "run")], capsys)
    assert status == 1 and "would take about 1e9 steps (limit 10,000,000)" in err
    assert "--step" in err and "--max-steps 1e9" in err
    assert not (tmp_path / "run").exists()
    with pytest.raises(HexapodError, match="limit 10 bytes\\): save fewer"):
        simulate(hx.assemble(planar_pendulum()), 1.0, method="idas-bdf", step=1e-3,
                 max_memory=10)


def test_simulate_to_a_billion_seconds_stops_within_seconds(tmp_path, capsys):
    """The adaptive run is weighed on its pace after a few dozen steps: the estimate, the
    option to shorten and the limit to raise are said; the states so far are written."""
    started = time.perf_counter()
    status, err = run_main(["simulate", PENDULUM, "--t-end", "1e9", "--out",
                            str(tmp_path / "run")], capsys)
    assert status == 1 and time.perf_counter() - started < 20
    assert "--t-end" in err and "--max-steps" in err and "steps (limit 10,000,000)" in err
    import json

    stats = json.loads((tmp_path / "run" / "stats.json").read_text())
    assert stats["status"] == "failed" and stats["t_end"] == 1e9
    assert 0 < stats["t_reached"] < 10 and "would take about" in stats["reason"]


def _weighed(pace: list[tuple[int, float]], max_steps: int) -> list[str | None]:
    """What the pace weighing of a run from 0 to 20 s says at each of ``pace``'s (steps, time),
    with a step limit (states are saved too seldom to count)."""
    from types import SimpleNamespace

    from hexapod.simulation.loop import _Weighing

    weighing = _Weighing(hx.assemble(planar_pendulum()), RungeKutta4Baumgarte, 0.0, 20.0,
                         every=10**9, max_steps=max_steps, max_memory=None,
                         advice={"steps": "advice", "memory": "advice"})
    said = []
    for steps, t in pace:
        run = SimpleNamespace(counters=SimpleNamespace(steps=steps, rejected=0), t=t,
                              crossing=False)
        said.append(weighing.during(run, returned=steps))
    return said


def test_a_burst_of_short_steps_is_not_taken_for_the_pace_of_the_run():
    """The N-four-bar with 40 windows at rtol 1e-10 reached its first flat pose after 14 steps
    (t = 0.72 s of 20) and crossed it in hundreds of short ones: weighed since the weighing
    before, the burst was extrapolated to 500 GiB, and the run (0.3 GiB) was stopped. A
    burst doubles the estimate at each weighing; a steady pace keeps it, and is stopped."""
    burst = [(20, 0.70), (40, 0.7205), (80, 0.7210), (160, 0.7212), (320, 0.7214),
             (640, 8.0), (1280, 19.0)]
    assert _weighed(burst, max_steps=100_000) == [None] * len(burst)
    steady = [(20, 0.0020), (40, 0.0040), (80, 0.0080)]  # 2e5 steps to 20 s
    said = _weighed(steady, max_steps=100_000)
    assert said[:2] == [None, None] and "at its pace" in said[2]


def test_the_step_limit_comes_from_the_option_then_the_environment(monkeypatch):
    model = hx.assemble(planar_pendulum())
    monkeypatch.setenv("HEXAPOD_MAX_STEPS", "100")
    with pytest.raises(HexapodError, match="about 1e3 steps \\(limit 100\\)"):
        simulate(model, 1.0, method="rk4-baumgarte")
    assert simulate(model, 1.0, method="rk4-baumgarte", max_steps=1000).success


def test_a_model_beyond_the_body_limit_is_refused_naming_the_scene(monkeypatch):
    scene = planar_pendulum()
    scene.add(hx.scene.Particle(name="q", mass=1.0, position=np.array([2.0, 0.0])))
    monkeypatch.setenv("HEXAPOD_MAX_BODIES", "1")
    with pytest.raises(HexapodError, match="scene 'rod' has 2 bodies \\(limit 1\\).*"
                       "HEXAPOD_MAX_BODIES=2"):
        hx.assemble(scene)


# ------------------------------------------------------------------ non-finite values in a run

@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # NumPy's own overflow warnings
@pytest.mark.parametrize("method", ["dopri5-projection", "radau5-ggl"])
def test_a_rate_too_large_for_the_starting_step_ends_as_a_result(method, monkeypatch):
    """An applied force of 1e300 N (out of range in a file; let through here): the starting-
    step heuristic divided by a zero step (ZeroDivisionError) before; now the run is a result,
    and the heuristic gives a positive step for any norms."""
    monkeypatch.setattr(hx.scene.Constant, "problems", lambda self: [])
    model = hx.assemble(planar_pendulum(force=(hx.scene.Constant(1e300), hx.scene.Constant(1e300))))
    result = simulate(model, 1.0, method=method)
    assert result.status in ("finished", "failed")
    integrator = hx.get_integrator(method)(hx.assemble(planar_pendulum()), 0.0, 1.0)
    for d0, d1, d2 in ((1.0, np.inf, np.inf), (np.inf, np.inf, np.nan), (0.0, 0.0, 0.0),
                       (1.0, 1e-300, 1e300)):
        h = integrator._starting_step(d0, d1, lambda h0, d2=d2: d2, 4)
        assert np.isfinite(h) and 0 < h <= 1.0


def test_an_overflowing_step_ends_as_a_failed_result_not_an_exception():
    model = hx.assemble(planar_pendulum())
    result = simulate(model, 1e308, method="generalized-alpha")
    assert result.status == "failed" and "overflow" in result.message
    with pytest.raises(ValueError, match="finite"):
        simulate(model, np.nan)


def test_non_finite_accelerations_end_the_run_with_the_time():
    class Blowing(RungeKutta4Baumgarte):
        name = "blowing"

        def _step(self):
            super()._step()
            if self.t > 0.25:
                self.v_dot = np.full_like(self.v_dot, np.nan)

    result = simulate(hx.assemble(planar_pendulum()), 1.0, method=Blowing, step=0.1)
    assert result.status == "failed"
    assert "non-finite accelerations at t = 0.3 s" in result.message
    assert result.t[-1] == pytest.approx(0.2) and np.isfinite(result.v_dot).all()


class _Kick(hx.scene.Law):
    """A law whose acceleration is infinite after t = 0.5 s (no scene file can say this)."""

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        return 0.1 * t, np.full_like(t, 0.1), np.where(t > 0.5, np.inf, 0.0)


@pytest.mark.parametrize("method", ["tree", "saddle"])
def test_a_non_finite_inverse_dynamics_result_names_the_sample(method):
    scene = read_scene(PENDULUM)
    scene.add(hx.scene.JointDriver(name="drive", joint="pivot", law=_Kick()))
    model = hx.assemble(scene)
    assert np.isfinite(hx.inverse_dynamics(model, [0.0, 0.5], method=method).force).all()
    with pytest.raises(HexapodError, match="non-finite"):
        hx.inverse_dynamics(model, [0.0, 0.25, 1.0], method=method)


# ------------------------------------------------------------------ interrupted runs

def test_an_interrupted_run_is_a_result_with_the_states_so_far():
    def interrupt(t, t_end):
        if t > 0.35:
            raise KeyboardInterrupt

    result = simulate(hx.assemble(planar_pendulum()), 1.0, method="rk4-baumgarte",
                      step=0.1, progress=interrupt)
    assert result.status == "interrupted" and not result.success
    assert result.message == "rk4-baumgarte: interrupted at t = 0.4 s"
    stats = result.statistics()
    assert stats["status"] == "interrupted" and stats["t_end"] == 1.0
    assert stats["t_reached"] == pytest.approx(0.4) and stats["reason"] == result.message
    assert result.t.size == 5
