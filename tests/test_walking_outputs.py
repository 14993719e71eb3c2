"""What the walking robot's outputs say: the ground's force on each foot in the inverse CSV,
the feet's and the trunk's tables, the ground-force options, the total mass of ``hexapod info``,
the figures and the export's ``ground_force`` field.

The walking robot costs about 0.1 s per sample on the saddle path: one inverse-dynamics run of
11 samples (one every 0.05 s over the stride) serves the whole module.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re

import meshio
import numpy as np
import pytest
from robots import builtin_model

import hexapod as hx
from hexapod.algorithms.balance import body_balance
from hexapod.algorithms.inverse import inverse_dynamics
from hexapod.algorithms.liaison import joint_origin
from hexapod.cli import main
from hexapod.cli.common import POLICIES, apply_ground_options, ground_arguments
from hexapod.errors import HexapodError
from hexapod.output import figures
from hexapod.output.actuation import driver_statistics
from hexapod.output.ground import (
    foot_events,
    foot_loads,
    ground_csv_text,
    leg_groups,
    trunk_csv_text,
    trunk_motion,
)
from hexapod.output.recording import read_recording
from hexapod.output.report import (
    RunInfo,
    _effort_figures,
    _wrench_figures,
    inverse_columns,
    inverse_csv_text,
    summary_markdown,
    walking_headlines,
)
from hexapod.output.vtk import frames, vtk_files
from hexapod.scene.builtin import load_scene
from hexapod.scene.contacts import POLICIES as ENGINE_POLICIES
from hexapod.scene.drivers import JointDriver
from hexapod.scene.writer import write_scene

LEGS = ("L1", "L2", "L3", "R1", "R2", "R3")


@pytest.fixture(scope="module")
def walking():
    """The built-in walking robot over one stride at 11 samples: (model, result)."""
    model = builtin_model("hexapod")
    times = np.linspace(0.0, 0.5, 11)
    return model, inverse_dynamics(model, times)


def parse_csv(text: str) -> tuple[list[str], list[list[str]]]:
    lines = text.splitlines()
    return lines[0].split(","), [line.split(",") for line in lines[1:]]


def columns(header: list[str], rows: list[list[str]], prefix: str) -> np.ndarray:
    """The numbers of the columns whose names start with ``prefix``, in header order."""
    picked = [k for k, name in enumerate(header) if name.startswith(prefix)]
    return np.array([[float(row[k]) for k in picked] for row in rows])


# ------------------------------------------------------------------ the inverse CSV

def test_inverse_csv_gives_each_foot_its_ground_force_after_the_joints(walking):
    model, result = walking
    header, rows = parse_csv(inverse_csv_text(model, result))
    assert header == inverse_columns(model)
    ground = ([f"{c}:{leg}" for leg in LEGS for c in ("GRx", "GRy", "GRz")]
              + [f"status:{leg}" for leg in LEGS])
    assert header[-len(ground):] == ground
    # the joints' columns are those of any other scene: t, then tau and Fx .. Tz per joint
    joints = ["t"]
    for joint in model.joints:
        joints += ([f"tau:{joint.name}"] if joint.kind == "revolute" else []) + [
            f"{c}:{joint.name}" for c in ("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")]
    assert header[:-len(ground)] == joints
    table = columns(header, rows, "GR")
    assert np.array_equal(table, result.ground_force.reshape(result.times.size, -1))
    codes = columns(header, rows, "status:")  # 0 swing, 1 ok: this gait is feasible
    assert result.feasible and not result.infeasible.any()
    assert np.array_equal(codes, np.where(result.ground_status == "swing", 0.0, 1.0))


def test_ground_columns_are_zero_in_swing_and_carry_the_weight_in_stance(walking):
    """Swing from the contacts' schedules, not from the result; in full stance the foot
    presses on the ground; the feet together carry the robot (summed vertical forces equal the
    weight plus the vertical momentum rate, here the trunk walks level: the weight)."""
    model, result = walking
    header, rows = parse_csv(inverse_csv_text(model, result))
    t = result.times
    weight = sum(b.mass for b in model.bodies) * 9.81
    vertical = np.zeros(t.size)
    for contact in model.contacts:
        leg = contact.name.removesuffix("/ground")
        picked = [header.index(f"{c}:{leg}") for c in ("GRx", "GRy", "GRz")]
        cells = [[row[k] for k in picked] for row in rows]
        force = np.array(cells, dtype=float)
        swing = ~np.asarray(contact.in_stance(t))
        assert swing.any() and (~swing).any()
        assert np.all(force[swing] == 0.0), leg
        assert all(cell == "0" for k in np.flatnonzero(swing) for cell in cells[k]), leg
        full = np.asarray(contact.weight(t)) == 1.0
        assert full.any() and np.all(force[full, 2] > 0.05 * weight), leg
        vertical += force[:, 2]
    momentum_rate = sum(b.mass * result.v_dot[:, b.v.start + 2] for b in model.bodies)
    assert np.allclose(vertical, weight + momentum_rate, rtol=1e-9, atol=1e-9 * weight)


def test_hexapod_inverse_on_a_walking_scene_writes_the_ground_forces_of_the_policy_given(
        walking, tmp_path, capsys):
    """The walking robot without its drivers, written as a scene file and driven by a motion
    file of the same laws (values, rates and accelerations at the samples): the command's CSV
    has the GR columns, zero in swing, carrying the weight, shared by the policy given."""
    from legs.replay import joint_laws

    model, result = walking
    scene = load_scene("hexapod")
    laws = joint_laws(scene)  # (the feet's guides place three joints a leg: their motion)
    scene._elements = [e for e in scene.elements if not isinstance(e, JointDriver)
                       and not getattr(e, "guide", False)]
    write_scene(scene, tmp_path / "walking.toml")
    header, table = ["t"], [result.times]
    for joint, law in laws.items():
        header += [joint, f"qd:{joint}", f"qdd:{joint}"]
        table += list(law.evaluate(result.times))
    np.savetxt(tmp_path / "motion.csv", np.column_stack(table), delimiter=",", fmt="%.17g",
               header=",".join(header), comments="")
    assert main(["inverse", str(tmp_path / "walking.toml"), "--motion",
                 str(tmp_path / "motion.csv"), "--out", str(tmp_path / "out.csv"),
                 "--policy", "min-effort"]) == 0
    assert "6 feet (ground forces by the policy min-effort)" in capsys.readouterr().out
    header, rows = parse_csv((tmp_path / "out.csv").read_text())
    assert header[-24:-6] == [f"{c}:{leg}" for leg in LEGS for c in ("GRx", "GRy", "GRz")]
    force = columns(header, rows, "GR").reshape(-1, 6, 3)
    assert np.array_equal(force == 0.0, result.ground_force == 0.0)  # the same feet in swing
    weight = sum(b.mass for b in model.bodies) * 9.81
    momentum_rate = sum(b.mass * result.v_dot[:, b.v.start + 2] for b in model.bodies)
    assert np.allclose(force[..., 2].sum(axis=1), weight + momentum_rate, rtol=1e-8)
    assert np.abs(force - result.ground_force).max() > 1e-3 * weight  # not min-wrench's


def test_a_scene_without_contacts_keeps_its_columns():
    model = hx.assemble(load_scene("front-leg"))
    assert not any(name.startswith("GR") for name in inverse_columns(model))
    assert len(inverse_columns(model)) == 1 + 7 * len(model.joints)


# ------------------------------------------------------------------ feet and trunk tables

def test_ground_csv_splits_each_force_into_normal_tangential_and_ratio(walking):
    model, result = walking
    loads = foot_loads(model, result)
    header, rows = parse_csv(ground_csv_text(loads))
    assert header[0] == "t" and header[1:5] == ["Fn:L1", "Ft:L1", "ratio:L1", "status:L1"]
    force = result.ground_force
    normal, tangential = columns(header, rows, "Fn:"), columns(header, rows, "Ft:")
    assert np.array_equal(normal, force[..., 2] + 0.0)
    assert np.allclose(tangential, np.hypot(force[..., 0], force[..., 1]), rtol=1e-15)
    ratio = columns(header, rows, "ratio:")
    loaded = np.linalg.norm(force, axis=2) > 1e-6
    assert np.allclose(ratio[loaded], tangential[loaded] / (model.ground.mu * normal[loaded]))
    assert np.all(np.isnan(ratio[np.linalg.norm(force, axis=2) == 0.0]))
    status = [[row[k] for k, name in enumerate(header) if name.startswith("status:")]
              for row in rows]
    assert status == result.ground_status.tolist()


def test_trunk_csv_is_the_free_trunk_pose_and_velocity(walking):
    model, result = walking
    trunks = trunk_motion(model, result.q, result.v)
    assert [m.body for m in trunks] == ["trunk"]
    header, rows = parse_csv(trunk_csv_text(result.times, trunks))
    trunk = model.bodies[model.body_index["trunk"]]
    coordinates = columns(header, rows, "")[:, 1:]
    assert header[1:8] == [f"q:trunk.{c}" for c in ("x", "y", "z", "e0", "e1", "e2", "e3")]
    assert header[8:11] == [f"angle:trunk.{c}" for c in ("roll", "pitch", "yaw")]
    assert header[11:] == [f"v:trunk.{c}" for c in ("vx", "vy", "vz", "wx", "wy", "wz")]
    assert np.array_equal(coordinates[:, :7], result.q[:, trunk.q])
    assert np.array_equal(coordinates[:, 10:13], result.v[:, trunk.v][:, :3])
    # level walking straight ahead at the gait's speed: the stride's length over the period
    speed = model.contacts[0].schedule.advance[0] / model.contacts[0].schedule.period
    assert np.allclose(coordinates[:, 10], speed, rtol=1e-9)
    assert np.allclose(coordinates[:, 7:10], 0.0, atol=1e-9)


def test_stance_intervals_follow_the_schedule(walking):
    model, _ = walking
    t = np.linspace(0.0, 1.0, 2001)
    for contact in model.contacts:
        intervals = contact.stances(0.0, 1.0)
        inside = np.zeros(t.size, dtype=bool)
        for a, b in intervals:
            inside |= (t >= a - 1e-12) & (t < b - 1e-12)
        edge = np.zeros(t.size, dtype=bool)
        for a, b in intervals:
            edge |= np.isclose(t, a) | np.isclose(t, b)
        assert np.array_equal(inside[~edge], np.asarray(contact.in_stance(t))[~edge])


# ------------------------------------------------------------------ summary and headlines

def test_summary_states_the_policy_the_feet_the_trunk_and_every_slip(walking):
    model, result = walking
    balance = body_balance(model, result.times, result.q, result.v, result.v_dot,
                           result.force, result.torque, result.frame)
    loads = foot_loads(model, result)
    summary = summary_markdown(model, result, balance, RunInfo("hexapod", "hexapod", 1.0, "x"),
                               [], [], loads, trunk_motion(model, result.q, result.v))
    assert "Ground forces shared by the policy `min-wrench`." in summary
    assert f"redundant rows: {', '.join(result.redundant_rows)}." in summary
    weight = sum(b.mass for b in model.bodies) * 9.81
    for c, leg in enumerate(LEGS):
        row = re.search(rf"^\| {leg} \| [^|]+ \| ([\d.]+) \| ([\d.]+) \|", summary, re.M)
        peak = np.linalg.norm(result.ground_force[:, c], axis=1).max()
        assert float(row.group(1)) == pytest.approx(peak, rel=1e-3)
        assert float(row.group(2)) == pytest.approx(peak / weight, rel=1e-3)
    assert "## Trunk" in summary and "`trunk`" in summary
    # a slip is named, never hidden: mark one sample of R2 as the friction policy would
    status = result.ground_status.copy()
    status[3, 4] = "slip"
    flagged = foot_loads(model, dataclasses.replace(result, ground_status=status))
    events = foot_events(flagged)
    assert [str(e) for e in events] == [f"R2: slip at t = {result.times[3]:.4g} s"]
    text = summary_markdown(model, result, balance, RunInfo("hexapod", "hexapod", 1.0, "x"),
                            [], [], flagged, None)
    assert f"- R2: slip at t = {result.times[3]:.4g} s" in text


def test_headlines_give_peaks_in_body_weights_and_per_joint_type(walking):
    model, result = walking
    lines = walking_headlines(model, result)
    assert lines[0].startswith("ground forces by the policy min-wrench")
    weight = sum(b.mass for b in model.bodies) * 9.81
    # each foot: the peak of |F| and the peak of the vertical (world z) component, both in body
    # weights, from the inverse result's ground forces
    head, _, values = lines[1].partition("N): ")
    assert head.startswith("peak ground reaction per foot, |F| / vertical Fz (body weights")
    peaks = {leg: (float(f), float(z))
             for leg, f, z in re.findall(r"(\w\d) ([\d.]+) / ([\d.]+)", values)}
    assert list(peaks) == list(LEGS)
    for c, leg in enumerate(LEGS):
        force = result.ground_force[:, c]
        magnitude = np.sqrt((force**2).sum(axis=1)).max() / weight
        vertical = force[:, 2].max() / weight
        assert peaks[leg][0] == pytest.approx(magnitude, rel=2e-3)
        assert peaks[leg][1] == pytest.approx(vertical, rel=2e-3)
        assert peaks[leg][1] <= peaks[leg][0]
    kinds = re.findall(r"(\w+) [\d.]+ N m \((\w\d)\)", lines[2])
    assert [k for k, _ in kinds] == ["thc_protraction", "thc_levation", "coxa_rotation", "ctr",
                                     "fti", "tita"]
    for kind, leg in kinds:
        k = model.joint_index[f"{leg}/{kind}"]
        best = max(np.abs(result.effort[:, model.joint_index[f"{other}/{kind}"]]).max()
                   for other in LEGS)
        assert np.abs(result.effort[:, k]).max() == pytest.approx(best)
    assert lines[-1].startswith("slip or pull: ")


# ------------------------------------------------------------------ options and info

def parse_ground(*args: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    ground_arguments(parser)
    return parser.parse_args(list(args))


def test_ground_options_replace_the_scenes_settings_and_only_those():
    assert POLICIES == ENGINE_POLICIES
    scene = load_scene("hexapod")
    before = scene.ground
    apply_ground_options(scene, parse_ground("--policy", "friction", "--mu", "0.5",
                                             "--faces", "0", "--min-normal", "2.5"))
    assert (scene.ground.policy, scene.ground.mu, scene.ground.faces,
            scene.ground.min_normal) == ("friction", 0.5, 0, 2.5)
    assert scene.ground is not before and before.policy == "min-wrench"
    apply_ground_options(scene, parse_ground("--mu", "0.7"))
    assert (scene.ground.policy, scene.ground.mu) == ("friction", 0.7)
    with pytest.raises(HexapodError, match="--policy: scene 'front-leg' has no foot contacts"):
        apply_ground_options(load_scene("front-leg"), parse_ground("--policy", "friction"))
    for bad in (["--faces", "2"], ["--mu", "0"], ["--min-normal", "-1"], ["--policy", "x"]):
        with pytest.raises(SystemExit):
            parse_ground(*bad)


def test_dynamics_solves_with_the_policy_given(capsys):
    forces = {}
    for policy in ("min-wrench", "min-effort"):
        assert main(["dynamics", "hexapod", "--t", "0.1", "--json", "--policy", policy]) == 0
        joints = json.loads(capsys.readouterr().out)["joints"]
        feet = [joints[f"{leg}/ground"] for leg in LEGS]
        assert all(foot["policy"] == policy for foot in feet)
        forces[policy] = np.array([foot["ground_force"] for foot in feet])
    assert main(["dynamics", "hexapod", "--t", "0.1", "--policy", "friction", "--mu", "0.5"]) == 0
    assert ("ground forces of 6 foot contacts by the policy friction (mu = 0.5)"
            in capsys.readouterr().out)
    weight = sum(b.mass for b in builtin_model("hexapod").bodies) * 9.81
    assert forces["min-wrench"][:, 2].sum() == pytest.approx(forces["min-effort"][:, 2].sum())
    assert np.abs(forces["min-wrench"] - forces["min-effort"]).max() > 1e-3 * weight


@pytest.mark.parametrize("scene", ["hexapod", "front-leg"])
def test_info_json_gives_the_total_mass(scene, capsys):
    assert main(["info", scene, "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    masses = [body.mass for body in load_scene(scene).bodies.values()]
    assert info["mass"] == pytest.approx(sum(masses), rel=1e-15)
    assert ("ground" in info) == (scene == "hexapod")
    assert main(["info", scene]) == 0
    assert f"total mass {sum(masses):.6g} kg" in capsys.readouterr().out.splitlines()[0]


# ------------------------------------------------------------------ figures

def panels(figure) -> list:
    return [ax for ax in figure.axes if ax.get_visible()]


def by_title(figure) -> dict:
    return {ax.get_title(): ax for ax in panels(figure)}


def test_ground_figures_have_one_panel_per_foot_placed_as_the_legs_stand(walking):
    model, result = walking
    loads = foot_loads(model, result)
    legs = list(loads.legs)
    for figure in (
            figures.ground_reaction_figure(loads.times, loads.force, legs, loads.stance,
                                           loads.weight, "g"),
            figures.friction_ratio_figure(loads.times, loads.ratio, loads.status, legs,
                                          loads.stance, loads.mu, "f")):
        axes = by_title(figure)
        assert len(panels(figure)) == len(axes) == 6 and set(axes) == set(legs)
        places = {leg: (ax.get_subplotspec().rowspan.start, ax.get_subplotspec().colspan.start)
                  for leg, ax in axes.items()}
        assert places == {"L1": (0, 0), "L2": (1, 0), "L3": (2, 0),
                          "R1": (0, 1), "R2": (1, 1), "R3": (2, 1)}
        for c, leg in enumerate(legs):  # stance shaded: one grey span per stance
            assert len(axes[leg].patches) == len(loads.stance[c])
    ground = by_title(figures.ground_reaction_figure(loads.times, loads.force, legs,
                                                     loads.stance, loads.weight, "g"))
    for c, leg in enumerate(legs):  # after the zero line: vertical, fore-aft, lateral
        drawn = [line.get_ydata() for line in ground[leg].lines[1:4]]
        assert np.array_equal(np.array(drawn).T, loads.force[:, c][:, [2, 0, 1]])
    friction = by_title(figures.friction_ratio_figure(loads.times, loads.ratio, loads.status,
                                                      legs, loads.stance, loads.mu, "f"))
    for c, leg in enumerate(legs):
        assert list(friction[leg].lines[0].get_ydata()) == [1.0, 1.0]
        assert np.array_equal(friction[leg].lines[1].get_ydata(), loads.ratio[:, c],
                              equal_nan=True)


def test_gait_diagram_has_a_bar_per_stance(walking):
    model, result = walking
    loads = foot_loads(model, result)
    figure = figures.gait_diagram_figure(list(loads.legs), loads.stance, 0.0, 0.5, "gait")
    (ax,) = panels(figure)
    assert [label.get_text() for label in ax.get_yticklabels()] == list(reversed(LEGS))
    bars = [len(collection.get_paths()) for collection in ax.collections]
    assert bars == [len(s) for s in loads.stance]


def test_force_and_torque_figures_put_the_legs_side_by_side_or_one_sheet_per_leg(walking):
    model, result = walking
    names = [j.name for j in model.joints]
    assert list(leg_groups(names)) == list(LEGS)
    assert leg_groups(["ctr", "fti"]) is None
    drawn = _wrench_figures(model, result, "hexapod")
    assert set(drawn) == {"forces.png", "torques.png"}
    figure = drawn["forces.png"]()
    roles = [n.split("/")[1] for n in names if n.startswith("L1/")]
    assert [ax.get_title() for ax in panels(figure)] == roles
    # each panel: one line per leg, the magnitude of that leg's joint of the panel
    for ax, role in zip(panels(figure), roles, strict=True):
        lines = [line for line in ax.get_lines() if line.get_label() in LEGS]
        assert [line.get_label() for line in lines] == list(LEGS)
        for line in lines:
            k = names.index(f"{line.get_label()}/{role}")
            assert np.array_equal(line.get_ydata(), np.linalg.norm(result.force[:, k], axis=1))
    drivers = driver_statistics(model, result)
    (efforts,) = _effort_figures(model, result.times, drivers, "hexapod").values()
    for ax in panels(efforts()):
        for line in ax.get_lines():
            joint = f"{line.get_label()}/{ax.get_title()}"
            (driver,) = [d for d in drivers if d.joint == joint]
            assert np.array_equal(line.get_ydata(), driver.effort)
    sheets = _wrench_figures(model, result, "hexapod", leg_figures=True)
    assert set(sheets) == {"forces.png", "torques.png"} | {
        f"{kind}-{leg}.png" for kind in ("forces", "torques") for leg in LEGS}
    for name, build in sheets.items():
        if "-" in name:
            leg = name[:-4].split("-")[1]
            assert [ax.get_title().split()[-1] for ax in panels(build())] == [
                n for n in names if n.startswith(f"{leg}/")], name


# ------------------------------------------------------------------ export

def test_export_draws_the_ground_forces_at_the_feet(walking, tmp_path):
    """A report of the walking robot read back and exported: ``feet_k.vtu`` has a point at
    each foot with ``ground_force`` equal to the CSV's (zero in swing)."""
    model, result = walking
    report = tmp_path / "report"
    report.mkdir()
    (report / "inverse.csv").write_text(inverse_csv_text(model, result))
    (report / "summary.md").write_text(
        "# Liaison force report: hexapod\n\nScene `hexapod`: ...\n\nWrenches ... in the child's "
        "joint frame; ...\n")
    recording = read_recording(report)
    files = vtk_files(model, frames(model, recording), every=4)
    chosen = [0, 4, 8, 10]
    assert {name for name in files if name.startswith("feet_")} == {
        f"feet_{k:04d}.vtu" for k in chosen}
    assert b'file="feet_0004.vtu"' in files["feet.pvd"]
    assert files["feet.csv"].decode().splitlines()[1] == "0,L1/ground,L1"
    for k in chosen:
        path = tmp_path / f"feet_{k:04d}.vtu"
        path.write_bytes(files[f"feet_{k:04d}.vtu"])
        mesh = meshio.read(path)
        force = mesh.point_data["ground_force"]
        assert np.array_equal(force, result.ground_force[k])
        stance = np.array([bool(c.in_stance(result.times[k])) for c in model.contacts])
        assert np.array_equal(mesh.point_data["stance"], stance)
        assert np.all(force[~stance] == 0.0)
        for c, contact in enumerate(model.contacts):  # the foot point, on the ground in stance
            foot = joint_origin(model, result.q[k], model.joints[contact.joint])[0]
            assert np.allclose(mesh.points[c], foot, atol=1e-9)
        assert np.allclose(mesh.points[stance, 2], 0.0, atol=1e-9)
