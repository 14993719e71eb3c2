"""VTK files of a simulation or a liaison force report, for ParaView (``hexapod export``).

A result directory of ``hexapod simulate`` (``results.npz``) or ``hexapod report``
(``inverse.csv`` and ``summary.md``) is read back into a :class:`Recording`: the scene it was
run on (a scene file's absolute path or a built-in scene's name), the saved times and, for a
simulation, the saved states. With the scene's model, :func:`vtk_files` turns it into one
``bodies_NNNN.vtu`` and one ``joints_NNNN.vtu`` per saved instant and the time indices
``bodies.pvd`` and ``joints.pvd`` (ParaView Collection files):

- **bodies**: every body's solid, posed: a box centred on the centre of mass along the principal
  axes of inertia with the body's mass and moments of inertia (the equivalent box; a flat plate
  for a planar body, its long side towards the body's joints), a bar from the centre of mass to
  each joint origin and marker on the body, a small octahedron for a particle; or a mesh file
  given for the body (in its centre-of-mass frame, metres). Cell data ``body`` (the body's
  index in ``bodies.csv``) and ``part`` (0 box, 1 bar, 2 particle, 3 mesh).
- **joints**: one vertex per joint at its origin (world frame), with point data ``joint`` (the
  index in ``joints.csv``), ``force`` and ``moment`` (the wrench exerted by the parent on the
  child about the joint origin, world axes), ``force_joint_frame`` and ``moment_joint_frame``
  (the same in the child's joint frame, the report convention) and ``effort`` (NaN for joints
  without an axis).
- **feet** (a scene with foot contacts, a walking robot): one vertex per foot at its point
  (world frame), with point data ``foot`` (the index in ``feet.csv``), ``ground_force`` (the
  ground's force on the foot, world axes, N; zero in swing) and ``stance`` (1 in stance, 0 in
  swing, by the gait's schedule): ParaView's Glyph filter draws the forces as arrows.

A simulation's wrenches are computed here from the saved multipliers by
:func:`hexapod.algorithms.liaison.wrenches_from_multipliers` (and its ground forces by
:func:`hexapod.algorithms.ground.ground_reactions`); a report's are read from its CSV. A
report does not save positions: its scene prescribes the motion, so they are assembled again at
the CSV's times.
"""

from __future__ import annotations

import csv
import io
import json
import re
import tempfile
import warnings
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from hexapod.algorithms.ground import ground_reactions
from hexapod.algorithms.kinematics import assemble_positions, body_poses
from hexapod.algorithms.liaison import joint_origin, wrenches_from_multipliers
from hexapod.errors import HexapodError, InputFileError
from hexapod.model.model import Model
from hexapod.output.ground import GROUND_COMPONENTS, leg_name
from hexapod.output.report import inverse_columns

#: Values of the cell data ``part``.
PART_BOX, PART_BAR, PART_PARTICLE, PART_MESH = 0, 1, 2, 3


# ------------------------------------------------------------------ reading a result directory

@dataclass
class Recording:
    """What a result directory holds.

    Attributes
    ----------
    kind : str
        ``"simulation"`` or ``"report"``.
    directory : Path
    scene : str or None
        The scene it was run on (a file's path or a built-in scene's name), when it says.
    scene_file : str
        The file that says it (for messages).
    t : ndarray (N,)
    q, v, lam : ndarray or None
        Saved states of a simulation (None for a report).
    coordinates : list of str or None
        The coordinate names of a simulation.
    columns : list of str or None
        The CSV header of a report.
    table : ndarray or None
        The CSV rows of a report.
    frame : str
        Axes of a report's wrenches, ``"joint"`` or ``"world"``.
    """

    kind: str
    directory: Path
    scene: str | None
    scene_file: str
    t: np.ndarray
    q: np.ndarray | None = None
    v: np.ndarray | None = None
    lam: np.ndarray | None = None
    coordinates: list[str] | None = None
    columns: list[str] | None = None
    table: np.ndarray | None = None
    frame: str = "joint"


def read_recording(directory: str | Path) -> Recording:
    """Read the result directory of ``hexapod simulate`` or ``hexapod report``.

    Raises
    ------
    InputFileError
        The directory is missing, is not such a result, or a file in it cannot be read; the
        message names the file and the problem.
    """
    directory = Path(directory)
    if not directory.exists():
        raise InputFileError(f"{directory}: no such directory")
    if not directory.is_dir():
        raise InputFileError(f"{directory}: is a file, not a result directory of 'hexapod "
                             "simulate' or 'hexapod report'")
    if (directory / "results.npz").exists():
        return _read_simulation(directory)
    if (directory / "inverse.csv").exists():
        return _read_report(directory)
    raise InputFileError(f"{directory}: not a result directory of 'hexapod simulate' "
                         "(results.npz) or 'hexapod report' (inverse.csv)")


def _read_simulation(directory: Path) -> Recording:
    path = directory / "results.npz"
    try:
        with np.load(path, allow_pickle=False) as saved:
            arrays = {key: saved[key] for key in saved.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
        raise InputFileError(f"{path}: cannot read the file ({error})") from None
    for key in ("t", "q", "v", "lam", "coordinates"):
        if key not in arrays:
            raise InputFileError(f"{path}: no array '{key}': not written by 'hexapod simulate'")
    t = np.asarray(arrays["t"])
    n = t.shape[0] if t.ndim == 1 else -1
    for key in ("t", "q", "v", "lam"):
        array = arrays[key]
        if array.dtype.kind not in "fi" or array.ndim != (1 if key == "t" else 2) \
                or array.shape[0] != n:
            raise InputFileError(f"{path}: array '{key}' has shape {array.shape} "
                                 f"({array.dtype}), not one row per saved time")
        if not np.all(np.isfinite(array)):
            raise InputFileError(f"{path}: array '{key}' holds non-finite numbers")
    if n == 0:
        raise InputFileError(f"{path}: no saved state")
    scene, said_by = None, str(path)
    if "source" in arrays and arrays["source"].ndim == 0:
        scene = str(arrays["source"])
    else:  # written before results recorded their scene: a built-in scene's name may do
        stats = directory / "stats.json"
        try:
            name = json.loads(stats.read_text(encoding="utf-8")).get("scene")
        except (OSError, ValueError, AttributeError):
            name = None
        if isinstance(name, str) and name:
            scene, said_by = name, str(stats)
    return Recording("simulation", directory, scene, said_by, t.astype(float),
                     q=arrays["q"].astype(float), v=arrays["v"].astype(float),
                     lam=arrays["lam"].astype(float),
                     coordinates=[str(c) for c in arrays["coordinates"]])


_SCENE_LINE = re.compile(r"^Scene `([^`]*)`", re.M)


def _read_report(directory: Path) -> Recording:
    from hexapod._support.files import read_text

    path = directory / "inverse.csv"
    rows = list(csv.reader(io.StringIO(read_text(path, "report CSV"))))
    if not rows or not rows[0] or rows[0][0] != "t":
        raise InputFileError(f"{path}: line 1: the header does not start with 't': not the CSV "
                             "of 'hexapod report'")
    header = rows[0]
    table = []
    for number, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        if len(row) != len(header):
            raise InputFileError(f"{path}: line {number}: {len(row)} values for "
                                 f"{len(header)} columns")
        try:
            table.append([float(x) for x in row])
        except ValueError:
            raise InputFileError(f"{path}: line {number}: not a number in the row") from None
    if not table:
        raise InputFileError(f"{path}: no sample")
    values = np.array(table)
    if not np.all(np.isfinite(values[:, 0])):
        raise InputFileError(f"{path}: non-finite times")
    summary = directory / "summary.md"
    text = read_text(summary, "report summary")
    match = _SCENE_LINE.search(text)
    if match is None:
        raise InputFileError(f"{summary}: no line 'Scene `...`' naming the scene: not the "
                             "summary of 'hexapod report'")
    if "in world axes;" in text:
        frame = "world"
    elif "in the child's joint frame;" in text:
        frame = "joint"
    else:
        raise InputFileError(f"{summary}: does not say in which axes the wrenches are given")
    return Recording("report", directory, match.group(1), str(summary), values[:, 0],
                     columns=header, table=values, frame=frame)


# ------------------------------------------------------------------ states and wrenches

@dataclass
class Frames:
    """The saved instants, ready to draw: positions, and each joint's wrench (world axes and
    the child's joint frame) at every instant."""

    t: np.ndarray  # (N,)
    q: np.ndarray  # (N, n_q)
    force: np.ndarray  # (N, J, 3) world axes
    moment: np.ndarray
    force_joint: np.ndarray  # (N, J, 3) the child's joint frame
    moment_joint: np.ndarray
    effort: np.ndarray  # (N, J)
    ground_force: np.ndarray | None = None  # (N, C, 3) world axes, per foot contact


def frames(model: Model, recording: Recording) -> Frames:
    """Positions and wrenches at every saved instant of ``recording``, for ``model`` (the
    scene the results were computed on).

    Raises
    ------
    InputFileError
        The results do not fit the model (other coordinates, other joints).
    HexapodError
        A report's positions cannot be assembled again.
    """
    n, J = recording.t.size, len(model.joints)
    force, moment = np.zeros((n, J, 3)), np.zeros((n, J, 3))
    force_joint, moment_joint, effort = np.zeros((n, J, 3)), np.zeros((n, J, 3)), np.zeros((n, J))
    ground = np.zeros((n, len(model.contacts), 3))
    if recording.kind == "simulation":
        where = recording.directory / "results.npz"
        sizes = (recording.q.shape[1], recording.v.shape[1], recording.lam.shape[1])
        if tuple(recording.coordinates) != tuple(model.coordinate_names) or \
                sizes != (model.n_q, model.n_v, model.n_c):
            raise InputFileError(f"{where}: its coordinates are not those of scene "
                                 f"'{model.name}': not a run of this scene")
        q = recording.q
        for k in range(n):
            w, _, _ = model.law_values(recording.t[k])
            Phi_v = model.call("Phi_v", q=q[k], w=w)
            Q_across = (model.call("Q_across", q=q[k], v=recording.v[k], w=w)
                        if model.Q_across is not None else None)
            wrenches = wrenches_from_multipliers(model, q[k], recording.lam[k], Phi_v, Q_across)
            force_joint[k], moment_joint[k] = wrenches.force, wrenches.torque
            effort[k] = wrenches.effort
            if model.contacts:
                ground[k] = ground_reactions(model, recording.lam[k])
    else:
        where = recording.directory / "inverse.csv"
        if recording.columns != inverse_columns(model):
            raise InputFileError(f"{where}: its columns are not those of scene '{model.name}' "
                                 "(other joints or foot contacts): not a report of this "
                                 "scene")
        q = np.zeros((n, model.n_q))
        guess = model.q0
        data = model.create_data()
        for k, t in enumerate(recording.t):
            guess = q[k] = assemble_positions(model, data, float(t), guess)
        index = {name: c for c, name in enumerate(recording.columns)}
        for j, joint in enumerate(model.joints):
            c = index[f"Fx:{joint.name}"]
            force_joint[:, j] = recording.table[:, c:c + 3]
            moment_joint[:, j] = recording.table[:, c + 3:c + 6]
            tau = index.get(f"tau:{joint.name}")
            effort[:, j] = recording.table[:, tau] if tau is not None else np.nan
        for c, contact in enumerate(model.contacts):
            first = index[f"{GROUND_COMPONENTS[0]}:{leg_name(contact.name)}"]
            ground[:, c] = recording.table[:, first:first + 3]
    for k in range(n):
        for j, joint in enumerate(model.joints):
            _, R = joint_origin(model, q[k], joint)
            if recording.kind == "report" and recording.frame == "world":
                force[k, j], moment[k, j] = force_joint[k, j], moment_joint[k, j]
                force_joint[k, j], moment_joint[k, j] = R.T @ force[k, j], R.T @ moment[k, j]
            else:
                force[k, j], moment[k, j] = R @ force_joint[k, j], R @ moment_joint[k, j]
    return Frames(recording.t, q, force, moment, force_joint, moment_joint, effort,
                  ground if model.contacts else None)


# ------------------------------------------------------------------ shapes in the body frames

@dataclass
class Shape:
    """A body's solid in its centre-of-mass frame (3-D; planar bodies in z = 0): points (P, 3)
    and cell blocks ``(meshio cell type, connectivity (C, k), part)``."""

    points: np.ndarray
    cells: list[tuple[str, np.ndarray, int]]


_BOX = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                 [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float) / 2


def _embed(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float).reshape(-1)
    return np.concatenate([x, np.zeros(3 - x.size)])


def attachment_points(model: Model, body: int) -> np.ndarray:
    """The joint origins and markers on ``body``, in its centre-of-mass frame (P, 3)."""
    points = []
    for joint in model.joints:
        if joint.parent == body:
            points.append(_embed(joint.parent_frame.position))
        if joint.child == body:
            points.append(_embed(joint.child_frame.position))
    points += [_embed(m.position) for m in model.bodies[body].markers.values()]
    out: list[np.ndarray] = []
    for p in points:
        if all(np.linalg.norm(p - o) > 1e-12 for o in out):
            out.append(p)
    return np.array(out).reshape(-1, 3)


def _bar(end: np.ndarray, width: float, normal: np.ndarray | None = None) -> np.ndarray:
    """The 8 corners of a bar of square section ``width`` from the origin to ``end``."""
    axis = end / np.linalg.norm(end)
    if normal is None:
        trial = np.eye(3)[int(np.argmin(np.abs(axis)))]
        normal = np.cross(axis, trial)
    side = np.cross(axis, normal)
    side /= np.linalg.norm(side)
    normal = np.cross(side, axis)
    corners = [(0, -1, -1), (1, -1, -1), (1, 1, -1), (0, 1, -1),
               (0, -1, 1), (1, -1, 1), (1, 1, 1), (0, 1, 1)]
    return np.array([a * end + (b * side + c * normal) * width / 2 for a, b, c in corners])


def body_shape(model: Model, body: int, mesh=None) -> Shape:
    """The solid drawn for ``body``, in its centre-of-mass frame (see the module's help).
    ``mesh``: a meshio Mesh to draw instead (points in the centre-of-mass frame, metres)."""
    info = model.bodies[body]
    scale = model.characteristic_length
    smallest = 0.01 * scale
    if mesh is not None:
        points = np.zeros((len(mesh.points), 3))
        points[:, :mesh.points.shape[1]] = mesh.points
        return Shape(points, [(block.type, np.asarray(block.data, dtype=np.int64), PART_MESH)
                              for block in mesh.cells])
    if info.kind == "particle":
        r = 0.03 * scale
        points = np.array([[r, 0, 0], [0, r, 0], [-r, 0, 0], [0, -r, 0], [0, 0, r], [0, 0, -r]])
        return Shape(points, [("pyramid", np.array([[0, 1, 2, 3, 4], [0, 3, 2, 1, 5]]),
                               PART_PARTICLE)])
    mass = max(info.mass, np.finfo(float).tiny)
    ends = attachment_points(model, body)
    if info.kind == "spatial":
        moments, axes = np.linalg.eigh(np.asarray(info.inertia, dtype=float))
        squared = 6 * (moments.sum() - 2 * moments) / mass  # the box of the same inertia
        sides = np.maximum(np.sqrt(np.maximum(squared, 0.0)), smallest)
        if np.linalg.det(axes) < 0:
            axes[:, 2] = -axes[:, 2]
        normal = None
    else:  # a plate of the same moment of inertia, its long side towards the joints
        total = 12 * float(np.asarray(info.inertia).reshape(-1)[0]) / mass
        far = ends[np.argmax(np.linalg.norm(ends, axis=1))] if ends.size else np.zeros(3)
        if np.linalg.norm(far) > smallest:
            length, width = np.sqrt(total / 1.01), 0.1 * np.sqrt(total / 1.01)
            direction = far / np.linalg.norm(far)
        else:
            length = width = np.sqrt(total / 2)
            direction = np.array([1.0, 0.0, 0.0])
        axes = np.column_stack([direction, np.cross([0.0, 0.0, 1.0], direction), [0, 0, 1]])
        sides = np.maximum([length, width, width], smallest)
        normal = np.array([0.0, 0.0, 1.0])
    points = [(_BOX * sides) @ axes.T]
    cells = [("hexahedron", np.arange(8)[None, :], PART_BOX)]
    width = max(0.5 * sides.min(), 0.5 * smallest)
    bars = [end for end in ends if np.linalg.norm(end) > width]
    for k, end in enumerate(bars):
        points.append(_bar(end, width, normal))
        cells.append(("hexahedron", 8 * (k + 1) + np.arange(8)[None, :], PART_BAR))
    return Shape(np.vstack(points), cells)


# ------------------------------------------------------------------ the files

def _vtu_bytes(mesh, directory: Path) -> bytes:
    import meshio

    path = directory / "frame.vtu"
    meshio.write(path, mesh, file_format="vtu", binary=True, compression="zlib")
    return path.read_bytes()


def pvd_text(entries: list[tuple[float, str]]) -> str:
    """A ParaView Collection file: each (time, file) as a ``DataSet`` with its ``timestep``."""
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    lines += [f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(name)}/>'
              for t, name in entries]
    return "\n".join(lines + ["  </Collection>", "</VTKFile>", ""])


def _csv(header: list[str], rows: list[list]) -> bytes:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    return buffer.getvalue().encode()


def vtk_files(model: Model, frames: Frames, meshes: dict | None = None,
              every: int = 1) -> dict[str, bytes]:
    """Every file of the export, in memory: ``bodies_NNNN.vtu`` and ``joints_NNNN.vtu`` per
    saved instant (every ``every``-th, and the last), ``bodies.pvd`` and ``joints.pvd`` (no
    joint files for a scene without joints), and the index files ``bodies.csv`` and
    ``joints.csv``; with foot contacts also ``feet_NNNN.vtu``, ``feet.pvd`` and ``feet.csv``
    (the ground's force on each foot). ``meshes``: meshio Meshes by body name, drawn
    instead of the generated solids."""
    try:
        import meshio
    except ImportError:  # pragma: no cover - a declared dependency
        raise HexapodError("VTK export needs meshio: pip install meshio") from None
    meshes = meshes or {}
    unknown = sorted(set(meshes) - set(model.body_index))
    if unknown:
        raise InputFileError(f"--mesh: no body named {', '.join(unknown)} in scene "
                             f"'{model.name}'")
    shapes = [body_shape(model, b, meshes.get(body.name)) for b, body in enumerate(model.bodies)]
    n = frames.t.size
    chosen = list(range(0, n, every))
    if chosen[-1] != n - 1:
        chosen.append(n - 1)
    digits = max(4, len(str(n - 1)))
    position, rotation = body_poses(model, frames.q)
    files: dict[str, bytes] = {}
    bodies_pvd, joints_pvd, feet_pvd = [], [], []
    with tempfile.TemporaryDirectory(prefix="hexapod-export-") as scratch:
        scratch = Path(scratch)
        for k in chosen:
            points, blocks, body_data, part_data = [], [], [], []
            offset = 0
            for b, shape in enumerate(shapes):
                points.append(position[k, b] + shape.points @ rotation[k, b].T)
                for kind, connectivity, part in shape.cells:
                    blocks.append(meshio.CellBlock(kind, connectivity + offset))
                    body_data.append(np.full(len(connectivity), b, dtype=np.int32))
                    part_data.append(np.full(len(connectivity), part, dtype=np.int32))
                offset += len(shape.points)
            bodies = meshio.Mesh(np.vstack(points) if points else np.zeros((0, 3)), blocks,
                                 cell_data={"body": body_data, "part": part_data})
            name = f"bodies_{k:0{digits}d}.vtu"
            files[name] = _vtu_bytes(bodies, scratch)
            bodies_pvd.append((float(frames.t[k]), name))
            J = len(model.joints)
            if not J:  # nothing to draw (and meshio cannot read an empty VTU back)
                continue
            origins = np.array([joint_origin(model, frames.q[k], joint)[0]
                                for joint in model.joints])
            joints = meshio.Mesh(
                origins, [meshio.CellBlock("vertex", np.arange(J)[:, None])],
                point_data={"joint": np.arange(J, dtype=np.int32),
                            "force": frames.force[k], "moment": frames.moment[k],
                            "force_joint_frame": frames.force_joint[k],
                            "moment_joint_frame": frames.moment_joint[k],
                            "effort": frames.effort[k]})
            name = f"joints_{k:0{digits}d}.vtu"
            files[name] = _vtu_bytes(joints, scratch)
            joints_pvd.append((float(frames.t[k]), name))
            if model.contacts:
                name = f"feet_{k:0{digits}d}.vtu"
                files[name] = _vtu_bytes(_feet_mesh(model, frames, k), scratch)
                feet_pvd.append((float(frames.t[k]), name))
    files["bodies.pvd"] = pvd_text(bodies_pvd).encode()
    if joints_pvd:
        files["joints.pvd"] = pvd_text(joints_pvd).encode()
    if feet_pvd:
        files["feet.pvd"] = pvd_text(feet_pvd).encode()
        files["feet.csv"] = _csv(["foot", "contact", "leg"],
                                 [[c, contact.name, leg_name(contact.name)]
                                  for c, contact in enumerate(model.contacts)])
    files["bodies.csv"] = _csv(["body", "name", "kind", "mass"],
                               [[b.index, b.name, b.kind, repr(b.mass)] for b in model.bodies])
    names = ["ground"] + [b.name for b in model.bodies]
    files["joints.csv"] = _csv(["joint", "name", "kind", "parent", "child"],
                               [[j.index, j.name, j.kind, names[j.parent + 1],
                                 names[j.child + 1]] for j in model.joints])
    return files


def _feet_mesh(model: Model, frames: Frames, k: int):
    """The feet at saved instant ``k``: a vertex at each contact's foot point with the ground's
    force on it (``ground_force``, world axes, N) and whether it is in stance."""
    import meshio

    C = len(model.contacts)
    t = float(frames.t[k])
    feet = np.array([joint_origin(model, frames.q[k], model.joints[c.joint])[0]
                     for c in model.contacts])
    force = (frames.ground_force[k] if frames.ground_force is not None
             else np.zeros((C, 3))) + 0.0
    stance = np.array([bool(c.in_stance(t)) for c in model.contacts], dtype=np.int32)
    return meshio.Mesh(feet, [meshio.CellBlock("vertex", np.arange(C)[:, None])],
                       point_data={"foot": np.arange(C, dtype=np.int32),
                                   "ground_force": force, "stance": stance})


def scene_meshes(scene) -> dict:
    """The meshes the scene's bodies name (their ``mesh`` key), by body name: read, moved from
    the body's reference frame to its centre-of-mass frame and converted to metres."""
    base = Path(scene.source).parent if scene.source else Path.cwd()
    meshes = {}
    for name, body in scene.bodies.items():
        if body.mesh:
            try:
                mesh = read_mesh(base / body.mesh)
            except InputFileError as error:
                raise InputFileError(f"{scene.source or scene.name}: body '{name}', mesh: "
                                     f"{error}") from None
            points = np.array(mesh.points, dtype=float)
            com = getattr(body, "com", None)  # a particle's reference point is its mass
            if com is not None:
                width = min(points.shape[1], com.size)
                points[:, :width] -= com[:width]
            mesh.points = points * scene.unit
            meshes[name] = mesh
    return meshes


def read_mesh(path: str | Path):
    """A mesh file (any format meshio reads), or an :class:`InputFileError`."""
    import meshio

    path = Path(path)
    if not path.is_file():
        raise InputFileError(f"{path}: no such mesh file")
    try:
        with warnings.catch_warnings():  # numpy's, on reading garbage as a binary file
            warnings.simplefilter("ignore")
            mesh = meshio.read(path)
    except Exception as error:  # meshio raises many kinds for a bad file
        raise InputFileError(f"{path}: cannot read the mesh ({type(error).__name__}: "
                             f"{error})") from None
    if mesh.points.ndim != 2 or mesh.points.shape[1] not in (2, 3) or not mesh.cells:
        raise InputFileError(f"{path}: no points in 2-D or 3-D with cells")
    return mesh
