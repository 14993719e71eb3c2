"""Output times from each method's own dense output, absolute tolerances per kind of coordinate,
and the methods' short names.

The dense output is judged on the spatial pendulum of ``data/scenes/pendulum.toml`` (a rod
released horizontal, Euler parameters interpolated and renormalised) against its exact solution
in Jacobi elliptic functions, at output times chosen strictly inside the steps (37 % into each,
the steps taken from a run without output times). Two errors are measured at those times:

* the **global error** of the dense state, ``dense - exact``. An adaptive method keeps its
  global error on this pendulum within 10 times its tolerance (``tests/test_integrators.py``),
  and its continuous extension adds an error of the order of one step's local error, itself
  below the tolerance: bound ``10 (atol + rtol max|y|)``. A fixed-step method's global error is
  ``C h^p`` (``p`` its order); ``C`` was measured once at ``h = 0.01`` (positions: 19 for RK4,
  5.2 for generalized-alpha and 3.2 for RATTLE; velocities 130, 29 and 21) and the bound is
  three times that.
* the **interpolation error** alone: the dense state's error less the linear blend of the
  errors of the two steps around it, ``(dense - exact) - lerp(step - exact)``. For linear
  interpolation of the steps it is that of the exact motion, ``h^2 |q''| / 8`` at most (1.7e-4 m
  at ``h = 0.01``); for the methods' own extensions it is of their order: ``40 h^4`` for RK4's
  (order 3), ``6 h^3`` for the Hermite interpolation of the second-order methods (measured
  ``O(h^3)``: 6.3e-6, 7.4e-7, 9.7e-8 m for generalized-alpha at h = 0.02, 0.01, 0.005), and
  the adaptive bound above. The dense states differ from the linear interpolation of the same
  steps by more than ten times that bound: they are not linear interpolation.

``python tests/test_dense_output.py`` prints both errors and the linear interpolation's for
every method.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod.benchmarks import pendulum_exact
from hexapod.cli.app import main
from hexapod.scene.reader import read_scene
from hexapod.simulation.integrators import Integrator
from hexapod.simulation.loop import simulate, uniform_times
from hexapod.simulation.methods import ALIASES, ATOL_KINDS
from hexapod.simulation.registry import INTEGRATORS, get_integrator

ROOT = Path(__file__).resolve().parents[1]
PENDULUM = ROOT / "data" / "scenes" / "pendulum.toml"
OMEGA0, ARM, T_END = np.sqrt(9.81 * 0.5 / (0.0833 + 0.25)), 0.5, 1.0
TOL, STEP = 1e-6, 1e-2
#: fixed-step methods: (order, C of the global error of positions, of velocities, C of the
#: interpolation error and its power of h), three times the constants measured at h = 0.01
FIXED = {"rk4-baumgarte": (4, 60.0, 400.0, 40.0, 4),
         "generalized-alpha": (2, 15.0, 90.0, 6.0, 3),
         "rattle": (2, 15.0, 90.0, 6.0, 3)}


@pytest.fixture(scope="module")
def pendulum():
    return hx.assemble(read_scene(PENDULUM))


def exact(t):
    """Centre of mass and its velocity of the rod (the rod turns about +y from +x to -z)."""
    psi, rate = pendulum_exact(t, np.pi / 2, OMEGA0)
    zero = np.zeros_like(psi)
    return (np.column_stack([ARM * np.sin(psi), zero, -ARM * np.cos(psi)]),
            np.column_stack([ARM * rate * np.cos(psi), zero, ARM * rate * np.sin(psi)]))


def lerp(T, Y, t):
    """Linear interpolation of the rows ``Y`` at the times ``T``."""
    return np.column_stack([np.interp(t, T, column) for column in Y.T])


def settings(method: str) -> dict:
    if not INTEGRATORS[method].adaptive:
        return {"step": STEP}
    # idas-bdf returns states at output times (every 0.05 s here): the output times asked
    # for lie between those, where only its own interpolation gives states
    return {"rtol": TOL, "atol": TOL, **({"step": 0.05} if method == "idas-bdf" else {})}


def bounds(method: str) -> tuple[float, float, float]:
    """Bounds of the global error of positions and velocities, and of the interpolation error
    of positions (see the module's description)."""
    if method in FIXED:
        order, c_q, c_v, c_i, power = FIXED[method]
        return c_q * STEP**order, c_v * STEP**order, c_i * STEP**power
    q, v = exact(np.linspace(0.0, T_END, 201))
    position = 10 * (TOL + TOL * np.abs(q).max())
    return position, 10 * (TOL + TOL * np.abs(v).max()), position


def dense_run(model, method: str):
    """The run's steps (a run saving every step) and the run saving at output times 37 % into
    each step, with the same settings."""
    steps = simulate(model, T_END, method=method, **settings(method))
    grid = steps.t[:-1] + 0.37 * np.diff(steps.t)
    return steps, grid, simulate(model, T_END, method=method, t_eval=grid, **settings(method))


def errors(steps, grid, dense) -> dict[str, float]:
    q, v = exact(grid)
    q_steps, _ = exact(steps.t)
    return {"position": float(np.abs(dense.q[:, :3] - q).max()),
            "velocity": float(np.abs(dense.v[:, :3] - v).max()),
            "interpolation": float(np.abs((dense.q[:, :3] - q)
                                          - lerp(steps.t, steps.q[:, :3] - q_steps, grid)).max()),
            "linear": float(np.abs(dense.q[:, :3] - lerp(steps.t, steps.q[:, :3], grid)).max())}


# ------------------------------------------------------------------ every method's dense output

@pytest.mark.parametrize("method", INTEGRATORS)
def test_dense_output_of_every_method_between_its_steps(pendulum, method):
    steps, grid, dense = dense_run(pendulum, method)
    assert dense.success and np.array_equal(dense.t, grid)  # exactly the times, nothing else
    assert dense.statistics()["t_reached"] == T_END and dense.statistics()["saved"] == grid.size
    if method != "idas-bdf":  # the steps are the method's own, not cut at the output times
        assert dense.counters.steps == steps.counters.steps
    error = errors(steps, grid, dense)
    position, velocity, interpolation = bounds(method)
    assert error["position"] <= position and error["velocity"] <= velocity, error
    assert error["interpolation"] <= interpolation, error
    assert error["linear"] >= 10 * interpolation, error  # not linear interpolation
    # consistent states: on the constraints to round-off, accelerations and multipliers those
    # of the equations of motion there
    w, wd, _ = pendulum.law_values(0.0)
    data = pendulum.create_data()
    for q, v, v_dot, lam in zip(dense.q, dense.v, dense.v_dot, dense.lam, strict=True):
        assert np.abs(pendulum.call("phi", q=q, w=w)).max() < 1e-13
        assert np.abs(pendulum.call("Phi_v", q=q, w=w) @ v).max() < 1e-12
        assert abs(np.linalg.norm(q[3:]) - 1) < 1e-14
        assert np.allclose(hx.forward_dynamics(pendulum, data, 0.0, q, v), v_dot, atol=1e-9)
        assert np.allclose(data.lam, lam, atol=1e-9)
    assert dense.energy is not None and dense.energy.size == grid.size


def test_output_times_at_the_ends_and_on_steps(pendulum):
    """The first and last output times are the run's ends when asked; a time on a step of a
    fixed-step method is that step's state, projected."""
    grid = uniform_times(0.0, 0.5, 0.1)
    assert grid.size == 6 and grid[-1] == 0.5
    plain = simulate(pendulum, 0.5, method="rattle", step=0.05)
    dense = simulate(pendulum, 0.5, method="rattle", step=0.05, t_eval=grid)
    assert np.array_equal(dense.t, grid)
    assert np.allclose(dense.q, plain.q[::2], rtol=0, atol=1e-12)
    assert np.allclose(dense.v, plain.v[::2], rtol=0, atol=1e-9)


def test_output_times_are_checked(pendulum):
    for grid, message in (([0.2, 0.1], "must increase"), ([0.1, np.nan], "finite"),
                          ([0.5, 1.5], "outside the run"), ([], "no output time"),
                          ([-0.1], "outside the run")):
        with pytest.raises(ValueError, match=message):
            simulate(pendulum, 1.0, t_eval=grid)
    with pytest.raises(ValueError, match="every and t_eval"):
        simulate(pendulum, 1.0, t_eval=[0.5], every=2)
    # a time past the end by round-off is the end
    start, end = 0.7, 0.7 + 0.1
    assert end < 0.8
    result = simulate(pendulum, end, t0=start, t_eval=[0.75, 0.8], method="rk4", step=0.01)
    assert result.t[-1] == end


def test_a_method_without_dense_output_is_refused(pendulum):
    class Euler(Integrator):
        name = "euler"
        order = 1

        def _step(self):
            h = self.next_step()
            self.q = self.model.integrate(self.q, h * self.v)
            self.v, self.t = self.v + h * self.v_dot, self.t + h
            self.v_dot, self.lam = self._dynamics(self.t, self.q, self.v)

    assert not Euler.has_dense_output()
    assert all(cls.has_dense_output() for cls in INTEGRATORS.values())
    with pytest.raises(ValueError, match="euler has no dense output"):
        simulate(pendulum, 0.1, method=Euler, step=0.01, t_eval=[0.05])
    with pytest.raises(NotImplementedError, match="no dense output"):
        Euler(pendulum, 0.0, 0.1, step=0.01).dense_output()


# ------------------------------------------------------------------ tolerances per kind

def tumbler():
    """A free box tumbling about its intermediate axis (positions: a free fall, integrated
    exactly; the rotation is what the error test sees)."""
    scene = hx.Scene("tumbler", 3)
    scene.add(hx.scene.SpatialBody("box", 1.0, [0.01, 0.02, 0.03], position=[0.0, 0.0, 0.0],
                                   angular_velocity=[1.0, 8.0, 0.5]))
    return hx.assemble(scene)


@pytest.mark.parametrize("method", [m for m, cls in INTEGRATORS.items() if cls.adaptive])
def test_a_looser_angle_tolerance_takes_fewer_steps(method):
    model = tumbler()
    tight = simulate(model, 2.0, method=method, rtol=1e-10, atol=1e-10, every=10**9)
    kinds = {"position": 1e-10, "velocity": 1e-10, "angle": 1e-4, "angular_velocity": 1e-4}
    loose = simulate(model, 2.0, method=method, rtol=1e-10, atol=kinds, every=10**9)
    assert tight.success and loose.success
    assert loose.counters.steps < tight.counters.steps / 2
    assert loose.options["atol"] == kinds
    assert tight.options["atol"] == dict.fromkeys(ATOL_KINDS, 1e-10)


def test_tolerances_per_kind_and_their_defaults(pendulum):
    from hexapod.simulation.integrators.tolerances import absolute_tolerances
    from hexapod.simulation.scales import characteristic_time

    length = pendulum.characteristic_length
    time = np.sqrt(length / 9.81)
    assert characteristic_time(pendulum) == pytest.approx(time)
    assert absolute_tolerances(pendulum, None) == dict.fromkeys(ATOL_KINDS, 1e-8)
    kinds = absolute_tolerances(pendulum, {"angle": 1e-5})
    assert kinds == pytest.approx({"position": 1e-8 * length, "angle": 1e-5,
                                   "velocity": 1e-8 * length / time,
                                   "angular_velocity": 1e-8 / time})
    integrator = get_integrator("dopri5")(pendulum, 0.0, 1.0, atol={"angle": 1e-5})
    units = [integrator.atol_kinds[kind] for kind in ("position",) * 3 + ("angle",) * 4
             + ("velocity",) * 3 + ("angular_velocity",) * 3]
    assert np.array_equal(integrator.atol_vector, units)
    assert integrator.atol == min(kinds.values())
    for bad, message in (({"angel": 1e-5}, "unknown kind 'angel'"),
                         ({"angle": -1.0}, "positive"), ({"angle": "x"}, "positive")):
        with pytest.raises(ValueError, match=message):
            simulate(pendulum, 0.1, atol=bad)


# ------------------------------------------------------------------ short names

def test_short_names_resolve_to_the_registered_ones(pendulum):
    assert set(ALIASES.values()) <= set(INTEGRATORS)
    for alias, name in [*ALIASES.items(), ("rattle", "rattle")]:
        assert get_integrator(alias) is INTEGRATORS[name]
    result = simulate(pendulum, 0.02, method="gen-alpha", step=0.01)
    assert result.method == "generalized-alpha"
    with pytest.raises(ValueError, match="unknown integrator 'euler'"):
        get_integrator("euler")


# ------------------------------------------------------------------ the command line

def cli(*args: str) -> int:
    try:
        return main(list(args))
    except SystemExit as ended:  # argparse's errors
        return ended.code


def test_command_line_writes_exactly_the_output_times(tmp_path, capsys):
    times = [0.013, 0.25, 0.4, 1.0]
    (tmp_path / "times.txt").write_text("# output times\n0.013\n0.25\n\n0.4\n1\n")
    for option, out in ((",".join(map(str, times)), "inline"),
                        (f"@{tmp_path / 'times.txt'}", "file")):
        assert cli("simulate", str(PENDULUM), "--t-end", "1", "--method", "dop853",
                   "--t-eval", option, "--out", str(tmp_path / out)) == 0
        lines = (tmp_path / out / "results.csv").read_text().splitlines()
        assert [float(line.split(",")[0]) for line in lines[1:]] == times
        stats = json.loads((tmp_path / out / "stats.json").read_text())
        assert stats["method"] == "dop853-projection" and stats["saved"] == 4
        assert stats["options"]["output_times"] == 4
    assert cli("simulate", str(PENDULUM), "--t-end", "1", "--start", "0.5", "--method", "rk4",
               "--dt-out", "0.25", "--atol-angle", "1e-5", "--out", str(tmp_path / "dt")) == 0
    lines = (tmp_path / "dt" / "results.csv").read_text().splitlines()
    assert [float(line.split(",")[0]) for line in lines[1:]] == [0.5, 0.75, 1.0, 1.25, 1.5]
    stats = json.loads((tmp_path / "dt" / "stats.json").read_text())
    assert stats["method"] == "rk4-baumgarte" and stats["options"]["atol"]["angle"] == 1e-5
    assert set(stats["options"]["atol"]) == set(ATOL_KINDS)
    capsys.readouterr()


@pytest.mark.parametrize("options, option, message", [
    (["--t-eval", "0.5,0.2"], "--t-eval", "must increase: 0.2 after 0.5"),
    (["--t-eval", "0.1,nan"], "--t-eval", "must be finite"),
    (["--t-eval", "0.1,1.5"], "--t-eval", "1.5 s is outside the run, from 0 to 1 s"),
    (["--t-eval", "@EMPTY"], "--t-eval", "holds no time"),
    (["--t-eval", "0.5", "--dt-out", "0.1"], "--dt-out", "not allowed with argument --t-eval"),
    (["--t-eval", "0.5", "--every", "2"], "--every", "not allowed with argument --t-eval"),
    (["--dt-out", "2"], "--dt-out", "longer than the run"),
    (["--dt-out", "1e-8", "--max-steps", "1000"], "--dt-out", "more than the limit of steps"),
    (["--atol-angle", "-1"], "--atol-angle", "must be positive"),
])
def test_command_line_refuses_bad_output_times(tmp_path, capsys, options, option, message):
    (tmp_path / "empty.txt").write_text("\n# nothing\n")
    options = [o.replace("@EMPTY", f"@{tmp_path / 'empty.txt'}") for o in options]
    status = cli("simulate", str(PENDULUM), "--t-end", "1", *options, "--out",
                 str(tmp_path / "run"))
    error = capsys.readouterr().err
    assert status == 2 and f"argument {option}: " in error and message in error, error
    assert not (tmp_path / "run").exists()


if __name__ == "__main__":
    model = hx.assemble(read_scene(PENDULUM))
    print(f"pendulum over {T_END} s; adaptive methods at rtol = atol = {TOL:g}, fixed-step "
          f"methods at h = {STEP:g} s; errors of the centre of mass at output times 37 % into "
          "each step")
    print(f"{'method':18} {'steps':>5} {'position':>9} {'velocity':>9} {'interp.':>9} "
          f"{'linear':>9}   bounds")
    for name in INTEGRATORS:
        steps, grid, dense = dense_run(model, name)
        e = errors(steps, grid, dense)
        print(f"{name:18} {steps.t.size - 1:5d} {e['position']:9.1e} {e['velocity']:9.1e} "
              f"{e['interpolation']:9.1e} {e['linear']:9.1e}   "
              + " ".join(f"{b:.1e}" for b in bounds(name)))
