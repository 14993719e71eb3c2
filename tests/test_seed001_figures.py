"""scripts/papers/seed001_figures.py: Fig. 7 of Dumitru, Marin and Margine (the liaison force F21
of the left front leg) and the same figure for every joint. The curves drawn (read back from the
figures' axes) are checked against `hexapod report`'s CSV, against the engine's joint wrenches
recomputed apart (the saddle-point forward dynamics at single instants), and against the recursive
joint-coordinate model of Vukobratović and Potkonjak with the foot load added by hand, the last two
on a scene built here from ``legs`` rather than loaded by name."""

from __future__ import annotations

import numpy as np
import pytest
from script_loader import load_script

import hexapod as hx
from hexapod.minimal.chain import ChainModel
from legs import walking_leg_scene
from legs.leg import ELEMENTS, JOINTS
from legs.robot import robot_weight

PERIOD = 0.5
SAMPLES = 41  # 0.0125 s apart: the instants below, the stance peak at 0.375 s among them
INSTANTS = (0.05, 0.2, 0.275, 0.375, 0.45)  # swing, lift-off ... touch-down, stance
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
KEYS = {"file", "reproduces", "parameters", "caption", "joint", "wrench", "by_element",
        "on_element", "peak_force", "peak_time"}
PARAMETERS = {"scene", "gait", "leg", "start", "duration", "samples", "frame"}


figures_script = load_script("scripts/papers/seed001_figures.py")


@pytest.fixture(scope="module")
def drawn():
    """(entry, {label: (t, y)}) per figure, the curves read back from the drawn axes."""
    run = figures_script.liaison_forces(SAMPLES)
    out = []
    for entry, figure in figures_script.figures(run):
        (ax,) = figure.axes
        curves = {line.get_label(): line.get_xydata() for line in ax.get_lines()
                  if not line.get_label().startswith("_")}
        out.append((entry, figure, curves))
    return out


@pytest.fixture(scope="module")
def model():
    """The front leg walking, built here (not through the script's scene loading)."""
    return hx.assemble(walking_leg_scene("L1", "tripod", PERIOD))


def _per_joint(drawn):
    return {entry["joint"]: curves for entry, _, curves in drawn[1:]}


def _components(curves, k):
    """Drawn Fx, Fy, Fz at sample k, and the time."""
    return (np.array([curves[c][k, 1] for c in ("Fx", "Fy", "Fz")]), curves["Fx"][k, 0])


def _index(curves, t):
    k = int(np.argmin(np.abs(curves["Fx"][:, 0] - t)))
    assert curves["Fx"][k, 0] == pytest.approx(t, abs=1e-12), "an instant off the sample grid"
    return k


# ------------------------------------------------------------------ layout and files

def test_fig7_is_F21_at_thc_levation_on_one_axes(drawn):
    entry, figure, curves = drawn[0]
    assert entry["file"] == "fig7_F21.png" and "Fig. 7" in entry["reproduces"]
    assert (entry["wrench"], entry["joint"]) == ("F21", "thc_levation")
    assert (entry["by_element"], entry["on_element"]) == (1, 2)
    assert (entry["by_body"], entry["on_body"]) == ELEMENTS[:2]
    assert list(curves)[:4] == ["Fx", "Fy", "Fz", "|F|"]
    (ax,) = figure.axes
    assert ax.get_xlim() == pytest.approx((0.0, PERIOD))
    assert "time (s)" in ax.get_xlabel() and "(N)" in ax.get_ylabel()
    texts = " ".join(t.get_text() for t in figure.texts)
    assert "Liaison force variation F21" in texts
    for word in ("layout", "one axes", "f21", "element 1", "element 2",
                 f"{entry['peak_force']:.4g}"):
        assert word in entry["caption"].lower(), word
    parameters = entry["parameters"]
    assert (parameters["scene"], parameters["gait"], parameters["leg"]) == (
        "front-leg", "tripod", "L1")
    assert (parameters["start"], parameters["duration"], parameters["samples"]) == (
        0.0, PERIOD, SAMPLES)
    assert "child's joint frame" in parameters["frame"]


def test_one_figure_per_joint_naming_who_exerts_it_on_whom(drawn):
    entries = [entry for entry, _, _ in drawn[1:]]
    assert [e["joint"] for e in entries] == list(JOINTS)
    assert [e["file"] for e in entries] == [f"fig7_{j}.png" for j in JOINTS]
    bodies = ("trunk",) + ELEMENTS
    for k, (entry, figure, _) in enumerate(drawn[1:]):
        assert entry["wrench"] == f"F{k + 1}{k}"
        assert (entry["by_element"], entry["on_element"]) == (k, k + 1)
        assert entry["on_body"] == bodies[k + 1] and entry["by_body"].startswith(bodies[k])
        title = figure.axes[0].get_title()
        assert entry["joint"] in title and f"element {k} ({entry['by_body']}) on element " \
            f"{k + 1} ({entry['on_body']})" in title
    # the paper's figure and thc_levation's are the same curves
    paper, levation = drawn[0][2], _per_joint(drawn)["thc_levation"]
    for label in ("Fx", "Fy", "Fz", "|F|"):
        assert np.array_equal(paper[label], levation[label])


def test_make_writes_the_files_it_lists(tmp_path, capsys):
    entries = figures_script.make(tmp_path / "quick", samples=6)
    listed = [entry["file"] for entry in entries]
    assert sorted(listed) == sorted(p.name for p in (tmp_path / "quick").iterdir())
    assert listed == ["fig7_F21.png"] + [f"fig7_{j}.png" for j in JOINTS]
    for entry in entries:
        assert KEYS <= set(entry), KEYS - set(entry)
        assert PARAMETERS <= set(entry["parameters"]), PARAMETERS - set(entry["parameters"])
        assert entry["parameters"]["samples"] == 6
        assert (tmp_path / "quick" / entry["file"]).read_bytes().startswith(PNG_SIGNATURE)
    assert figures_script.main(["--out", str(tmp_path / "cli"), "--samples", "3"]) == 0
    assert sorted(p.name for p in (tmp_path / "cli").iterdir()) == sorted(listed)
    printed = capsys.readouterr().out.splitlines()
    assert [line.split(": ")[0] for line in printed] == [
        f"{tmp_path / 'cli'}/{name}" for name in listed]


# ------------------------------------------------------------------ the numbers drawn

def test_drawn_forces_are_hexapod_reports(drawn, tmp_path, capsys):
    """`hexapod report` on its default scene with the same samples: its CSV's force columns
    are the curves drawn (the same computation: to round-off, 1e-12 relative; CSV numbers have
    17 digits)."""
    from hexapod.cli import main

    assert main(["report", "--samples", str(SAMPLES), "--out", str(tmp_path / "report")]) == 0
    capsys.readouterr()
    lines = (tmp_path / "report" / "inverse.csv").read_text().splitlines()
    header, table = lines[0].split(","), np.array([line.split(",") for line in lines[1:]],
                                                  dtype=float)
    for joint, curves in _per_joint(drawn).items():
        assert np.array_equal(table[:, 0], curves["Fx"][:, 0])
        for c in ("Fx", "Fy", "Fz"):
            np.testing.assert_allclose(table[:, header.index(f"{c}:{joint}")], curves[c][:, 1],
                                       rtol=1e-12, atol=1e-9, err_msg=f"{joint} {c}")


def test_magnitude_is_the_norm_of_the_components(drawn):
    for entry, _, curves in drawn:
        components = np.column_stack([curves[c][:, 1] for c in ("Fx", "Fy", "Fz")])
        magnitude = curves["|F|"][:, 1]
        assert np.allclose(magnitude, np.linalg.norm(components, axis=1), rtol=1e-14, atol=0)
        assert np.array_equal(curves["|F|"][:, 0], curves["Fx"][:, 0])
        k = int(np.argmax(magnitude))
        assert (entry["peak_force"], entry["peak_time"]) == (magnitude[k], curves["Fx"][k, 0])


def test_drawn_forces_are_the_engines_wrenches_at_single_instants(drawn, model):
    """Saddle-point forward dynamics at each instant from a consistent state, then the joint
    wrenches from its multipliers: the driven scene's accelerations are its laws', so the
    multipliers are the liaison forces of the prescribed motion."""
    per_joint = _per_joint(drawn)
    scale = {j: np.abs(per_joint[j]["|F|"][:, 1]).max() for j in JOINTS}
    for t in INSTANTS:
        data = model.create_data()
        q = hx.assemble_positions(model, data, t)
        v = hx.solve_velocities(model, data, t, q)
        hx.forward_dynamics(model, data, t, q, v)
        wrenches = hx.joint_wrenches(model, data).as_dict()
        for joint in JOINTS:
            curves = per_joint[joint]
            force, _ = _components(curves, _index(curves, t))
            expected = np.array([wrenches[joint][c] for c in ("Fx", "Fy", "Fz")])
            assert np.abs(force - expected).max() <= 1e-9 * scale[joint], (joint, t)


def test_drawn_forces_are_the_recursive_models_with_the_foot_load(drawn, model):
    """The recursive model of Vukobratović and Potkonjak in joint coordinates (its own kinematics
    from the joint laws): the force on the part beyond a joint is the sum of m (a - g) over it, less
    the ground's reaction on the foot; turned into the child's joint frame."""
    chain = ChainModel.from_model(model)
    assert chain.names == JOINTS
    from legs.replay import joint_laws

    scene = walking_leg_scene("L1", "tripod", PERIOD)
    laws = joint_laws(scene)  # the foot's guides place three joints: the engine's kinematics
    load = scene.forces["ground_reaction"].force
    per_joint = _per_joint(drawn)
    for t in INSTANTS:
        q, q_d, q_dd = (np.array([float(laws[j].evaluate(t)[i]) for j in JOINTS])
                        for i in range(3))
        world, _ = chain.joint_wrenches(q, q_d, q_dd)
        foot = np.array([float(law(t)) for law in load])  # world axes, on the tarsus
        state = chain.kinematics(q, q_d)
        for k, joint in enumerate(JOINTS):
            R = state.R[k] @ chain.links[k].on_child.rotation  # joint frame -> world
            expected = R.T @ (world[k] - foot)
            curves = per_joint[joint]
            force, _ = _components(curves, _index(curves, t))
            scale = np.abs(curves["|F|"][:, 1]).max()
            assert np.abs(force - expected).max() <= 1e-9 * scale, (joint, t)
            if t == 0.375:  # in stance the foot load dominates: the frame matters
                assert np.abs(force - (world[k] - foot)).max() > 1.0, joint


def test_stance_carries_the_legs_share_of_the_weight(drawn):
    """The foot's load is the ground reaction the walking robot gives it (legs.loads): in stance
    (0.2 to 0.5 s) the tarsus joint carries it and a little more, in swing far less."""
    scene = walking_leg_scene("L1", "tripod", PERIOD)
    t = np.linspace(0.0, PERIOD, 2001)
    load = np.linalg.norm([law(t) for law in scene.forces["ground_reaction"].force], axis=0)
    assert 0.3 * robot_weight() < load.max() < 0.6 * robot_weight()  # a share of the weight
    for entry, _, curves in drawn:
        t, magnitude = curves["|F|"][:, 0], curves["|F|"][:, 1]
        assert entry["peak_time"] > 0.2  # in stance
        assert 0.9 * load.max() < entry["peak_force"] < 1.1 * load.max(), entry["joint"]
        assert magnitude[t < 0.19].max() < 0.15 * entry["peak_force"], entry["joint"]
