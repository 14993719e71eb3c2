"""The liaison force report: its files, its numbers against independent checks, its errors."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from commands import in_process as run_cli

import hexapod as hx
from hexapod._support.files import write_directory_atomically
from hexapod.algorithms.balance import body_balance
from hexapod.algorithms.inverse import inverse_dynamics
from hexapod.algorithms.kinematics import body_poses, marker_trajectories
from hexapod.cli import main
from hexapod.errors import InputFileError
from hexapod.output.actuation import driver_efforts_over_time, driver_statistics
from hexapod.output.report import inverse_columns, joint_statistics
from hexapod.output.summary_parts import time_rms
from hexapod.scene.builtin import DEFAULT_SCENE, builtin_scenes
from legs import front_leg_scene, walking_leg_scene

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "data" / "scenes"
MALFORMED = Path(__file__).resolve().parent / "data" / "malformed_scene.toml"
FIGURES = {"forces.png", "torques.png", "efforts.png", "foot.png"}
FILES = {"inverse.csv", "units.json", "summary.md"} | FIGURES
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def default_report(tmp_path_factory):
    """``hexapod report`` as the README runs it (in this process), from an empty directory."""
    cwd = tmp_path_factory.mktemp("report")
    result = run_cli("report", cwd=cwd)
    return cwd, result


def read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    lines = path.read_text().splitlines()
    return lines[0].split(","), np.array([[float(x) for x in line.split(",")]
                                         for line in lines[1:]])


# ------------------------------------------------------------------ the default report

def test_report_writes_every_file_of_the_default_scene(default_report):
    cwd, result = default_report
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    out = cwd / f"{DEFAULT_SCENE}-report"
    assert {p.name for p in out.iterdir()} == FILES
    assert [p.name for p in cwd.iterdir()] == [out.name]  # no temporary directory left behind
    assert f"wrote {out.name}/" in result.stdout


def test_report_csv_is_the_inverse_contract(default_report):
    """The CSV is that of ``hexapod inverse``: columns, and the numbers of the engine's inverse
    dynamics at 501 samples over the gait's stride (0.5 s), read back exactly."""
    cwd, _ = default_report
    header, table = read_csv(cwd / f"{DEFAULT_SCENE}-report" / "inverse.csv")
    model = hx.assemble(builtin_scenes()[DEFAULT_SCENE].load()())
    assert header == inverse_columns(model)
    assert table.shape[0] == 501
    assert table[0, 0] == 0.0 and table[-1, 0] == 0.5
    result = inverse_dynamics(model, table[:, 0])
    k = header.index("tau:fti")
    assert np.array_equal(table[:, k], result.effort[:, model.joint_index["fti"]])
    fx = header.index("Fx:thc_levation")
    assert np.array_equal(table[:, fx:fx + 3], result.force[:, model.joint_index["thc_levation"]])


def test_report_summary_matches_the_csv(default_report):
    """Every joint's peak |F| and |T| in the summary, recomputed from the CSV; the balance
    residuals at round-off."""
    cwd, _ = default_report
    out = cwd / f"{DEFAULT_SCENE}-report"
    header, table = read_csv(out / "inverse.csv")
    summary = (out / "summary.md").read_text()
    assert summary.startswith(f"# Liaison force report: {DEFAULT_SCENE}")
    rows = {m.group(1): m.group(2).split(" | ")
            for m in re.finditer(r"^\| F\d+ \| `([^`]+)` \| (.*) \|$", summary, re.M)}
    model = hx.assemble(builtin_scenes()[DEFAULT_SCENE].load()())
    assert list(rows) == [j.name for j in model.joints]
    for name, cells in rows.items():
        c = header.index(f"Fx:{name}")
        force = np.linalg.norm(table[:, c:c + 3], axis=1)
        torque = np.linalg.norm(table[:, c + 3:c + 6], axis=1)
        assert float(cells[1]) == pytest.approx(force.max(), rel=1e-3)
        assert float(cells[2]) == pytest.approx(table[force.argmax(), 0], abs=1e-9)
        assert float(cells[4]) == pytest.approx(torque.max(), rel=1e-3)
    residuals = re.findall(r"^\| \w+ \| ([\d.e+-]+) \| ([\d.e+-]+) \| ([\d.e+-]+) \|$",
                           summary.split("## Balance")[1], re.M)
    assert len(residuals) == len(model.bodies)
    assert max(float(r[2]) for r in residuals) < 1e-12
    for name in sorted(FIGURES):
        assert f"]({name})" in summary


def test_report_figures_are_drawn(default_report):
    """Valid PNGs with curves on them: empty axes and grids are grey, the curves coloured, so
    coloured pixels count the curves (about 0.7 % of a figure here, none on empty axes); the
    wrench figures show all three components (red, green, blue)."""
    from matplotlib.image import imread

    cwd, _ = default_report
    out = cwd / f"{DEFAULT_SCENE}-report"
    for name in sorted(FIGURES):
        assert (out / name).read_bytes().startswith(PNG_SIGNATURE), name
        image = imread(out / name)[..., :3]
        height, width = image.shape[:2]
        assert width >= 1000 and height >= 400, name
        coloured = image.max(axis=2) - image.min(axis=2) > 0.3
        assert coloured.mean() > 0.003, f"{name}: {coloured.mean():.4f} of the pixels coloured"
        if name in ("forces.png", "torques.png"):
            dominant = image.argmax(axis=2)
            for channel in range(3):
                assert np.mean(coloured & (dominant == channel)) > 0.001, (name, channel)


# ------------------------------------------------------------------ numbers

def test_driver_power_is_the_rate_of_mechanical_energy():
    """A leg with its trunk held and no load: the drivers' power is the rate of change of the
    kinetic plus potential energy, v^T M v_dot - m g . r_dot, at every sample; over the stride
    (periodic motion) the net work is zero."""
    model = hx.assemble(front_leg_scene())
    t = np.linspace(0.0, 0.5, 2001)
    result = inverse_dynamics(model, t)
    drivers = driver_statistics(model, result)
    power = sum(d.power for d in drivers)
    kinetic_rate = np.einsum("ni,ni->n", result.v, result.v_dot @ model.mass.dense())
    potential_rate = np.zeros_like(t)
    for body in model.bodies:
        potential_rate -= body.mass * result.v[:, body.v][:, :3] @ model.gravity
    expected = kinetic_rate + potential_rate
    assert np.abs(power - expected).max() < 1e-10 * np.abs(expected).max()
    total_work = sum(d.work for d in drivers)
    assert abs(total_work) < 1e-6 * sum(abs(d.power).max() for d in drivers) * 0.5


def test_driver_effort_excludes_springs_across_the_joint():
    """A driven pendulum with a torsion spring across its hinge: the joint carries both, the
    driver (the -lambda of the saddle-point solve) only its share."""
    scene = hx.Scene("sprung", 3, gravity=[0.0, -9.81, 0.0])
    scene.add(hx.scene.SpatialBody("arm", 1.1, [0.02] * 3, position=[0.5, 0.0, 0.0]))
    scene.add(hx.scene.Revolute("hinge", "ground", "arm", origin=[0.0, 0.0, 0.0], axis=[0, 0, 1]))
    scene.add(hx.scene.JointDriver("drive", "hinge",
                                   hx.scene.Harmonic(offset=0.1, sin=[0.6], frequency=1)))
    scene.add(hx.scene.forces.RotationalSpringDamper("torsion", "hinge", stiffness=7.0,
                                                      damping=0.3, free_angle=0.4))
    model = hx.assemble(scene)
    t = np.linspace(0.0, 1.0, 7)
    result = inverse_dynamics(model, t, method="saddle")
    driver = driver_efforts_over_time(model, result)["hinge"]
    for k, time in enumerate(t):
        data = model.create_data()
        hx.forward_dynamics(model, data, time, result.q[k], result.v[k])
        assert driver[k] == pytest.approx(hx.driver_efforts(model, data)["drive"],
                                          rel=1e-10, abs=1e-12)
    theta, theta_dot = model.laws[0](t), model.laws[0].evaluate(t)[1]
    spring = -7.0 * (theta - 0.4) - 0.3 * theta_dot
    assert np.allclose(result.effort[:, 0] - driver, spring, rtol=1e-10, atol=1e-12)


def test_peaks_and_rms():
    t = np.linspace(0.0, 1.0, 2001)
    assert time_rms(t, np.sin(2 * np.pi * t)) == pytest.approx(np.sqrt(0.5), rel=1e-6)
    assert time_rms(np.array([0.3]), np.array([-2.0])) == 2.0
    model = hx.assemble(front_leg_scene())
    result = inverse_dynamics(model, t * 0.5)
    stats = joint_statistics(model, result)
    assert [s.label for s in stats] == ["F10", "F21", "F32", "F43", "F54", "F65"]
    k = model.joint_index["ctr"]
    magnitude = np.linalg.norm(result.force[:, k], axis=1)
    assert stats[k].peak_force.value == magnitude.max()
    assert stats[k].peak_force.time == result.times[magnitude.argmax()]


@pytest.mark.parametrize("method", ["tree", "saddle"])
def test_body_balance_closes_and_catches_a_wrong_frame(method):
    model = hx.assemble(walking_leg_scene("L1"))
    t = np.linspace(0.2, 0.45, 11)  # in stance: the ground's reaction on the foot
    result = inverse_dynamics(model, t, method=method)
    balance = body_balance(model, t, result.q, result.v, result.v_dot, result.force,
                           result.torque)
    assert balance.relative().max() < 1e-12
    wrong = body_balance(model, t, result.q, result.v, result.v_dot, result.force,
                         result.torque, frame="world")
    assert wrong.relative().max() > 0.1
    shifted = body_balance(model, t, result.q, result.v, result.v_dot, result.force,
                           np.roll(result.torque, 1, axis=2))
    assert shifted.relative().max() > 0.1


def test_body_balance_of_a_planar_closed_loop():
    """The four-bar in 3-D (saddle path, a loop-closing joint) and a driven planar double pendulum:
    both close to round-off."""
    scene = hx.read_scene(SCENES / "four_bar_3d.toml")
    model = hx.assemble(scene)
    t = np.linspace(0.0, 0.3, 4)
    result = inverse_dynamics(model, t)
    balance = body_balance(model, t, result.q, result.v, result.v_dot, result.force,
                           result.torque)
    assert balance.relative().max() < 1e-11
    planar = hx.read_scene(SCENES / "double_pendulum_planar.toml")
    for joint in list(planar.joints):
        planar.add(hx.scene.JointDriver(f"drive_{joint}", joint,
                                        hx.scene.Harmonic(offset=0.3, sin=[0.4], frequency=0.7)))
    model = hx.assemble(planar)
    result = inverse_dynamics(model, t)
    balance = body_balance(model, t, result.q, result.v, result.v_dot, result.force,
                           result.torque)
    assert balance.relative().max() < 1e-12


def test_poses_and_markers_over_samples():
    model = hx.assemble(walking_leg_scene("R3"))
    t = np.linspace(0.0, 0.5, 7)
    q = inverse_dynamics(model, t).q
    position, rotation = body_poses(model, q)
    for k in range(t.size):
        for b in range(len(model.bodies)):
            pose = model.body_pose(q[k], b)
            assert np.allclose(position[k, b], pose.position, atol=1e-15)
            assert np.allclose(rotation[k, b], pose.rotation, atol=1e-15)
    (foot,) = marker_trajectories(model, q, "foot").values()
    tarsus = model.bodies[-1]
    for k in range(t.size):
        pose = model.body_pose(q[k], len(model.bodies) - 1)
        assert np.allclose(foot[k], pose.transform_point(tarsus.markers["foot"].position))
    assert marker_trajectories(model, q, "no-such-marker") == {}
    loads = model.call_samples("Q", q=q, v=np.zeros((t.size, model.n_v)),
                               w=model.law_values(t)[0].T)
    for k in range(t.size):
        assert np.array_equal(loads[k], model.call("Q", q=q[k], v=np.zeros(model.n_v),
                                                   w=model.law_values(t[k])[0]))


def test_laws_know_their_cycle():
    assert hx.scene.Harmonic(sin=[1.0], frequency=4.0).cycle_time() == 0.25
    assert hx.scene.Gait(cos=[1.0], period=0.7).cycle_time() == 0.7
    assert hx.scene.Spline([0, 1, 2, 3], [0, 1, -1, 0], boundary="periodic").cycle_time() == 3.0
    assert hx.scene.Spline([0, 1, 2, 3], [0, 1, -1, 0]).cycle_time() is None
    assert hx.scene.Constant(2.0).cycle_time() is None
    assert hx.scene.Harmonic(offset=1.0).cycle_time() is None


# ------------------------------------------------------------------ errors and no partial output

def test_malformed_scene_gives_one_error_and_no_output(tmp_path):
    """One error naming the file and listing its problems (every one, each with its element
    and key), no traceback, nothing written."""
    result = run_cli("report", str(MALFORMED), "--out", "out", cwd=tmp_path)
    assert result.returncode == 1 and result.stdout == ""
    assert "Traceback" not in result.stderr
    first, *problems = result.stderr.strip().splitlines()
    assert first.startswith("hexapod: error: scene file ") and MALFORMED.name in first
    assert first.endswith(f"{len(problems)} problems")
    assert all(line.startswith("  - ") for line in problems)
    assert list(tmp_path.iterdir()) == []


def test_scene_with_free_motion_is_refused_without_output(tmp_path, capsys):
    assert main(["report", str(SCENES / "pendulum.toml"), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert "degree(s) of freedom free" in err and "pivot" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args, message", [
    (["--samples", "1"], "must be at least 2"),
    (["--duration", "-1"], "must be positive"),
    (["--duration", "nan"], "must be positive"),
])
def test_bad_options_are_usage_errors(args, message, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["report", *args])
    assert stop.value.code == 2
    assert message in capsys.readouterr().err


def test_report_replaces_an_earlier_report_but_nothing_else(tmp_path, capsys):
    out = tmp_path / "leg"
    assert main(["report", "--samples", "11", "--out", str(out)]) == 0
    first = (out / "inverse.csv").read_text()
    assert main(["report", "--samples", "21", "--duration", "0.25", "--out", str(out)]) == 0
    second = (out / "inverse.csv").read_text()
    assert second != first and len(second.splitlines()) == 22
    (out / "notes.txt").write_text("mine")
    assert main(["report", "--samples", "11", "--out", str(out)]) == 1
    assert "holds other files (notes.txt)" in capsys.readouterr().err
    assert (out / "inverse.csv").read_text() == second and (out / "notes.txt").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["leg"]


def test_directory_writer_leaves_nothing_when_it_fails(tmp_path):
    target = tmp_path / "out"
    with pytest.raises(InputFileError, match="cannot write"):
        write_directory_atomically(target, {"a.txt": b"1", "sub/b.txt": b"2"})
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputFileError, match="not a directory"):
        write_directory_atomically(tmp_path / "file", {"a.txt": b"1"})
    write_directory_atomically(target, {"a.txt": b"1"})
    assert (target / "a.txt").read_bytes() == b"1"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "out"]


def test_particles_balance_forces_only():
    """The particles of Richard, Anderson and Andrews have no moment equation: their balance is that
    of forces (a moment built of round-off must not read as a 100 % residual)."""
    model = hx.assemble(hx.read_scene(SCENES / "closed_pendulum_seed002.toml"))
    data = model.create_data()
    q, v = hx.consistent_state(model, data)
    v_dot = hx.forward_dynamics(model, data, 0.0, q, v)
    wrenches = hx.joint_wrenches(model, data)
    balance = body_balance(model, np.array([0.0]), q[None], v[None], v_dot[None],
                           wrenches.force[None], wrenches.torque[None])
    assert np.all(balance.moment_scale == 0.0)
    assert balance.relative().max() < 1e-12


def test_a_report_driven_by_a_motion_file_writes_what_inverse_writes(tmp_path):
    """``hexapod report MODEL --motion FILE`` spans the motion's samples; its inverse.csv is
    ``hexapod inverse``'s on the same files, to the last digit; window options are refused."""
    fixture = ROOT / "tests" / "data" / "pinocchio-fixtures" / "chain-3"
    model, motion = str(fixture / "model.urdf"), str(fixture / "motion.csv")
    done = run_cli("report", model, "--motion", motion, "--out", "report", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    done = run_cli("inverse", model, "--motion", motion, "--out", "inverse.csv", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    reported = (tmp_path / "report" / "inverse.csv").read_text()
    assert reported == (tmp_path / "inverse.csv").read_text()
    assert len(reported.splitlines()) - 1 == len((fixture / "motion.csv").read_text().split()) - 1
    refused = run_cli("report", model, "--motion", motion, "--duration", "1", cwd=tmp_path)
    assert refused.returncode == 1 and "--duration: the motion file" in refused.stderr


def test_no_figures_writes_the_same_tables_and_summary_without_the_figures(tmp_path):
    """``--no-figures`` (for scripts: the figures are most of a report's time) leaves out the
    PNG files and the summary's list of them, and nothing else."""
    for out, extra in (("drawn", ()), ("bare", ("--no-figures",))):
        done = run_cli("report", "front-leg", "--samples", "41", "--out", out, *extra,
                       cwd=tmp_path)
        assert done.returncode == 0, done.stderr
    drawn, bare = tmp_path / "drawn", tmp_path / "bare"
    assert sorted(p.name for p in bare.iterdir()) == sorted(
        p.name for p in drawn.iterdir() if p.suffix != ".png")
    assert any(p.suffix == ".png" for p in drawn.iterdir())
    assert (bare / "inverse.csv").read_bytes() == (drawn / "inverse.csv").read_bytes()
    summary = (drawn / "summary.md").read_text()
    without = summary.partition("\n## Figures\n")[0].rstrip("\n") + "\n"
    run_time = re.compile(r"[\d.]+ s of inverse dynamics")  # differs from run to run
    assert (run_time.sub("", (bare / "summary.md").read_text())
            == run_time.sub("", without))
