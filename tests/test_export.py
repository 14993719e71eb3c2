"""``hexapod export``: VTK files of a simulation or a report, read back with meshio and checked
against the engine's poses and joint wrenches."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms.inverse import inverse_dynamics
from hexapod.algorithms.liaison import joint_origin, wrenches_from_multipliers
from hexapod.cli import main
from hexapod.output.vtk import PART_BAR, PART_BOX, body_shape
from hexapod.scene.reader import read_scene
from hexapod.scene.writer import write_scene

ROOT = Path(__file__).resolve().parents[1]
PENDULUM = ROOT / "data" / "scenes" / "pendulum.toml"
FRONT_LEG = ROOT / "data" / "scenes" / "front_leg.toml"


def run(capsys, *args) -> tuple[int, str, str]:
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def pendulum_export(tmp_path_factory):
    """The pendulum of data/scenes simulated for 0.2 s, every step saved, then exported."""
    cwd = tmp_path_factory.mktemp("export")
    assert main(["simulate", str(PENDULUM), "--t-end", "0.2", "--out", str(cwd / "run")]) == 0
    assert main(["export", str(cwd / "run"), "--vtk", str(cwd / "vtk")]) == 0
    with np.load(cwd / "run" / "results.npz") as saved:
        arrays = {key: saved[key] for key in ("t", "q", "v", "lam")}
    return cwd, arrays, hx.assemble(read_scene(PENDULUM))


def read_pvd(path: Path) -> list[tuple[float, str]]:
    root = ET.parse(path).getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


def rotation(e: np.ndarray) -> np.ndarray:
    """Rotation matrix of unit Euler parameters (scalar first), written out here."""
    e0, e1, e2, e3 = e
    return 2 * np.array([
        [e0**2 + e1**2 - 0.5, e1 * e2 - e0 * e3, e1 * e3 + e0 * e2],
        [e1 * e2 + e0 * e3, e0**2 + e2**2 - 0.5, e2 * e3 - e0 * e1],
        [e1 * e3 - e0 * e2, e2 * e3 + e0 * e1, e0**2 + e3**2 - 0.5]])


def body_points(mesh: meshio.Mesh, body: int, part: int | None = None) -> np.ndarray:
    """The points of the cells of ``body`` (of one ``part``), in cell order."""
    rows = []
    for block, bodies, parts in zip(mesh.cells, mesh.cell_data["body"], mesh.cell_data["part"],
                                    strict=True):
        for cell, b, p in zip(block.data, bodies, parts, strict=True):
            if b == body and (part is None or p == part):
                rows.append(mesh.points[cell])
    return np.vstack(rows)


def test_one_vtu_per_saved_instant_and_the_pvd_lists_them_with_their_times(pendulum_export):
    cwd, saved, _ = pendulum_export
    t = saved["t"]
    files = {p.name for p in (cwd / "vtk").iterdir()}
    bodies = sorted(f for f in files if f.startswith("bodies_") and f.endswith(".vtu"))
    joints = sorted(f for f in files if f.startswith("joints_") and f.endswith(".vtu"))
    assert len(bodies) == len(joints) == t.size > 2
    assert files == set(bodies) | set(joints) | {"bodies.pvd", "joints.pvd", "bodies.csv",
                                                 "joints.csv", "units.json"}
    units = json.loads((cwd / "vtk" / "units.json").read_text())
    assert set(units) == {"bodies.csv", "joints.csv", "bodies_*.vtu", "joints_*.vtu"}
    assert units["joints_*.vtu"]["force"]["unit"] == "N"
    assert units["bodies.csv"]["mass"]["unit"] == "kg"
    assert read_pvd(cwd / "vtk" / "bodies.pvd") == list(zip(t.tolist(), bodies, strict=True))
    assert read_pvd(cwd / "vtk" / "joints.pvd") == list(zip(t.tolist(), joints, strict=True))
    assert (cwd / "vtk" / "bodies.csv").read_text().splitlines()[1].startswith("0,rod,spatial")
    assert not [p for p in cwd.iterdir() if p.name.startswith(".")]  # no staging left


def test_posed_shapes_are_the_body_frame_shapes_at_the_saved_poses(pendulum_export):
    """Each body's box is centred on its centre of mass (to 1e-9), every point is the pose of
    the saved state applied to the shape in the body frame, and the bar to the pivot ends at
    the joint origin the engine computes."""
    cwd, saved, model = pendulum_export
    shape = body_shape(model, 0)
    pvd = read_pvd(cwd / "vtk" / "bodies.pvd")
    rod = model.bodies[0]
    origins = []
    for k, (_, name) in enumerate(pvd):
        mesh = meshio.read(cwd / "vtk" / name)
        q = saved["q"][k]
        centre, R = q[rod.q][:3], rotation(q[rod.q][3:])
        box = body_points(mesh, 0, PART_BOX)
        assert box.shape == (8, 3)
        assert np.abs(box.mean(axis=0) - centre).max() < 1e-9
        assert np.abs(mesh.points - (centre + shape.points @ R.T)).max() < 1e-9
        bar = body_points(mesh, 0, PART_BAR)
        tip = bar[[1, 2, 5, 6]].mean(axis=0)  # the far face of the bar from the centre
        origin, _ = joint_origin(model, q, model.joints[0])
        assert np.abs(tip - origin).max() < 1e-9
        origins.append(origin)
    # the box has the rod's length and inertia: 1 m long, along the rod
    sides = np.sort(np.linalg.norm(shape.points[[1, 3, 4]] - shape.points[0], axis=1))
    assert sides[-1] == pytest.approx(np.sqrt(6 * (0.0833 + 0.0833 - 0.001)), rel=1e-12)
    assert np.allclose(origins, 0.0, atol=1e-12)  # the pivot stays put


def test_joint_vectors_are_the_engine_wrenches_at_each_state(pendulum_export):
    cwd, saved, model = pendulum_export
    for k, (t, name) in enumerate(read_pvd(cwd / "vtk" / "joints.pvd")):
        mesh = meshio.read(cwd / "vtk" / name)
        q, lam = saved["q"][k], saved["lam"][k]
        Phi_v = model.call("Phi_v", q=q)
        world = wrenches_from_multipliers(model, q, lam, Phi_v, frame="world")
        local = wrenches_from_multipliers(model, q, lam, Phi_v)
        data = mesh.point_data
        assert np.abs(data["force"] - world.force).max() < 1e-9
        assert np.abs(data["moment"] - world.torque).max() < 1e-9
        assert np.abs(data["force_joint_frame"] - local.force).max() < 1e-9
        assert np.abs(data["moment_joint_frame"] - local.torque).max() < 1e-9
        assert np.abs(data["effort"] - local.effort).max() < 1e-9
        assert np.abs(mesh.points[0] - joint_origin(model, q, model.joints[0])[0]).max() < 1e-12
        assert [b.type for b in mesh.cells] == ["vertex"] and list(data["joint"]) == [0]
        if k == 0:  # released at rest: the pivot holds up m (g - l theta_dd), the scene's 2.45 N
            g, m, l, inertia = 9.81, 1.0, 0.5, 0.0833 + 0.25
            lift = m * (g - l * m * g * l / inertia)
            assert t == 0.0
            assert data["force"][0] == pytest.approx([0.0, 0.0, lift], abs=1e-9)


def test_a_report_is_exported_with_its_csv_wrenches_at_its_poses(tmp_path, capsys):
    """A report in world axes: the poses assembled again agree with the report's inverse
    dynamics, and the vectors are the CSV's."""
    out = tmp_path / "report"
    code, _, err = run(capsys, "report", FRONT_LEG, "--samples", "4", "--frame", "world",
                       "--out", out)
    assert code == 0, err
    code, said, err = run(capsys, "export", out, "--vtk", tmp_path / "vtk")
    assert code == 0, err
    assert "4 instants of report" in said
    model = hx.assemble(read_scene(FRONT_LEG))
    lines = (out / "inverse.csv").read_text().splitlines()
    header, table = lines[0].split(","), np.array([[float(x) for x in line.split(",")]
                                                   for line in lines[1:]])
    result = inverse_dynamics(model, table[:, 0], frame="world")
    pvd = read_pvd(tmp_path / "vtk" / "bodies.pvd")
    assert [t for t, _ in pvd] == table[:, 0].tolist()
    for k, (_, name) in enumerate(pvd):
        mesh = meshio.read(tmp_path / "vtk" / name)
        for b, body in enumerate(model.bodies):
            centre = body_points(mesh, b, PART_BOX).mean(axis=0)
            assert np.abs(centre - result.q[k, body.q][:3]).max() < 1e-9
        joints = meshio.read(tmp_path / "vtk" / name.replace("bodies", "joints"))
        for j, joint in enumerate(model.joints):
            c = header.index(f"Fx:{joint.name}")
            assert np.array_equal(joints.point_data["force"][j], table[k, c:c + 3])
            assert np.array_equal(joints.point_data["moment"][j], table[k, c + 3:c + 6])


@pytest.mark.parametrize("case", ["missing", "file", "empty", "corrupt-npz", "bad-csv",
                                  "no-summary"])
def test_bad_results_give_one_message_and_write_nothing(tmp_path, capsys, case):
    results = tmp_path / "results"
    expected = str(results)
    if case == "file":
        results.write_text("t\n")
    elif case != "missing":
        results.mkdir()
    if case == "corrupt-npz":
        (results / "results.npz").write_bytes(b"PK\x03\x04 not a zip")
        expected = str(results / "results.npz")
    elif case in ("bad-csv", "no-summary"):
        (results / "inverse.csv").write_text("t,Fx:a\n0,1\n0.1,x\n" if case == "bad-csv"
                                             else "t,Fx:a\n0,1\n")
        expected = (f"{results / 'inverse.csv'}: line 3" if case == "bad-csv"
                    else f"{results / 'summary.md'}: no such file")
    before = sorted(p.name for p in tmp_path.iterdir())
    code, said, err = run(capsys, "export", results, "--vtk", tmp_path / "vtk")
    assert code == 1 and said == ""
    assert err.startswith(f"hexapod: error: {expected}") and err.count("\n") == 1, err
    assert "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # no vtk/, no staging


def test_the_scene_comes_from_the_results_or_from_scene(pendulum_export, tmp_path, capsys):
    """Results that do not name their scene (written before they did) need --scene; a scene
    that does not fit is refused; an output holding other files is left alone."""
    cwd, saved, _ = pendulum_export
    old = tmp_path / "old"
    old.mkdir()
    with np.load(cwd / "run" / "results.npz") as npz:
        assert str(npz["source"]) == str(PENDULUM)
        np.savez(old / "results.npz", **{k: npz[k] for k in npz.files if k != "source"})
    code, _, err = run(capsys, "export", old, "--vtk", tmp_path / "vtk")
    assert code == 1 and "does not say which scene" in err and "--scene" in err
    other = ROOT / "data" / "scenes" / "double_pendulum_planar.toml"
    code, _, err = run(capsys, "export", old, "--vtk", tmp_path / "vtk", "--scene", other)
    assert code == 1 and "not those of scene 'double-pendulum-planar'" in err
    busy = tmp_path / "busy"
    busy.mkdir()
    (busy / "notes.txt").write_text("keep")
    code, _, err = run(capsys, "export", old, "--vtk", busy, "--scene", PENDULUM)
    assert code == 1 and "holds other files (notes.txt)" in err
    assert [p.name for p in busy.iterdir()] == ["notes.txt"]
    code, said, err = run(capsys, "export", old, "--vtk", tmp_path / "vtk", "--scene", PENDULUM,
                          "--every", "4")
    assert code == 0, err
    n = saved["t"].size
    times = [t for t, _ in read_pvd(tmp_path / "vtk" / "bodies.pvd")]
    assert times == [saved["t"][k] for k in sorted({*range(0, n, 4), n - 1})]


def test_a_mesh_the_scene_names_is_drawn_at_the_body_pose(tmp_path, capsys):
    """A body's ``mesh`` (points in its reference frame, a path relative to the scene file) is
    drawn instead of its box: each point is the saved pose applied to the point less the
    centre of mass. The scene written back keeps the key."""
    triangle = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.1, 0.2]])
    meshio.write(tmp_path / "rod.vtu", meshio.Mesh(triangle, [("triangle", [[0, 1, 2]])]))
    text = PENDULUM.read_text().replace(
        'position = [0.5, 0.0, 0.0]', 'position = [0.5, 0.0, 0.0]\ncom = [0.1, 0.0, 0.0]\n'
        'mesh = "rod.vtu"', 1)
    scene_file = tmp_path / "pendulum.toml"
    scene_file.write_text(text)
    scene = read_scene(scene_file)
    assert scene.bodies["rod"].mesh == "rod.vtu"
    write_scene(scene, tmp_path / "again.toml")
    assert read_scene(tmp_path / "again.toml").bodies["rod"].mesh == "rod.vtu"
    assert run(capsys, "simulate", scene_file, "--t-end", "0.1", "--out", tmp_path / "run")[0] == 0
    assert run(capsys, "export", tmp_path / "run", "--vtk", tmp_path / "vtk")[0] == 0
    with np.load(tmp_path / "run" / "results.npz") as saved:
        q_all = saved["q"]
    model = hx.assemble(scene)
    rod = model.bodies[0]
    for k, (_, name) in enumerate(read_pvd(tmp_path / "vtk" / "bodies.pvd")):
        mesh = meshio.read(tmp_path / "vtk" / name)
        q = q_all[k]
        centre, R = q[rod.q][:3], rotation(q[rod.q][3:])
        drawn = body_points(mesh, 0)
        expected = centre + (triangle - [0.1, 0.0, 0.0]) @ R.T
        assert np.abs(drawn - expected).max() < 1e-9


def test_a_missing_scene_mesh_names_the_scene_the_body_and_the_file(tmp_path, capsys):
    text = PENDULUM.read_text().replace('position = [0.5, 0.0, 0.0]',
                                        'position = [0.5, 0.0, 0.0]\nmesh = "gone.stl"', 1)
    scene_file = tmp_path / "pendulum.toml"
    scene_file.write_text(text)
    assert run(capsys, "simulate", scene_file, "--t-end", "0.05", "--out", tmp_path / "run")[0] == 0
    code, _, err = run(capsys, "export", tmp_path / "run", "--vtk", tmp_path / "vtk")
    assert code == 1 and not (tmp_path / "vtk").exists()
    assert str(scene_file) in err and "body 'rod'" in err and "gone.stl" in err
    assert len(err.strip().splitlines()) == 1


def test_a_contact_schemes_run_exports_its_contact_forces_at_the_touching_points(tmp_path):
    """The block sliding down its incline (four corners, Moreau-Jean): each instant's
    ``contacts_NNNN.vtu`` has a vertex per corner on the incline (gap zero: ``n . p = 0``), the
    force the run saved there (pushing: ``closed`` 1, the incline's normal part equal to the
    weight's share across the slope in all), indexed by ``contacts.csv``."""
    scene = ROOT / "data" / "scenes" / "sliding-block.toml"
    assert main(["simulate", str(scene), "--t-end", "0.02", "--step", "1e-3", "--out",
                 str(tmp_path / "run")]) == 0
    assert main(["export", str(tmp_path / "run"), "--vtk", str(tmp_path / "vtk")]) == 0
    with np.load(tmp_path / "run" / "results.npz") as saved:
        t, forces = saved["t"], saved["contact_forces"]
    instants = read_pvd(tmp_path / "vtk" / "contacts.pvd")
    assert [time for time, _ in instants] == pytest.approx(list(t))
    normal = np.array([0.5, 0.0, np.sqrt(3) / 2])
    for k, (_, name) in enumerate(instants[1:], start=1):
        mesh = meshio.read(tmp_path / "vtk" / name)
        assert np.array_equal(mesh.point_data["ground_force"], forces[k])
        assert np.all(mesh.point_data["closed"] == 1)
        assert np.abs(mesh.points @ normal).max() < 1e-12
        assert mesh.point_data["ground_force"].sum(axis=0) @ normal == pytest.approx(
            9.81 * np.sqrt(3) / 2, rel=1e-9)
    index = (tmp_path / "vtk" / "contacts.csv").read_text().splitlines()
    assert index[0] == "contact,name,body" and index[1] == "0,corner-1,block"
