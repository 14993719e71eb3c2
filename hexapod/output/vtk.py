"""VTK files of a simulation or a liaison force report, for ParaView (``hexapod export``).

A result directory of ``hexapod simulate`` (``results.npz``) or ``hexapod report``
(``inverse.csv`` and ``summary.md``) is read back (:mod:`hexapod.output.recording`) into the
scene it was run on, the saved times and, for a simulation, the saved states. With the
scene's model, :func:`vtk_files` turns it into one ``bodies_NNNN.vtu`` and one
``joints_NNNN.vtu`` per saved instant and the time indices ``bodies.pvd`` and
``joints.pvd`` (ParaView Collection files):

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
- **contacts** (a contact scheme's run, a scene with ``ground-contact`` elements): one vertex
  per contact at its touching point (world frame), with point data ``contact`` (the index in
  ``contacts.csv``), ``ground_force`` (the ground's force on the body there, world axes, N, as
  the run saved it) and ``closed`` (1 where the ground pushes).
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

import contextlib
import csv
import io
import os
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from hexapod._support.files import check_input
from hexapod._support.limits import parse_size, size_text
from hexapod.algorithms.contact_frames import contact_frames, ground_contacts
from hexapod.algorithms.ground import ground_reactions
from hexapod.algorithms.kinematics import assemble_positions, body_poses
from hexapod.algorithms.liaison import joint_origin, wrenches_from_multipliers
from hexapod.errors import HexapodError, InputFileError
from hexapod.model.model import Model
from hexapod.model.units import leg_name
from hexapod.output.ground import GROUND_COMPONENTS
from hexapod.output.recording import Recording
from hexapod.output.report import inverse_columns
from hexapod.simulation.results import units_json

#: Values of the cell data ``part``.
PART_BOX, PART_BAR, PART_PARTICLE, PART_MESH = 0, 1, 2, 3


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
    contact_force: np.ndarray | None = None  # (N, m, 3) world axes, per unilateral contact


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
        q, data = recording.q, model.create_data()
        for k in range(n):
            w, _, _ = model.law_values(recording.t[k], data)
            Phi_v = model.call("Phi_v", data, q=q[k], w=w)
            Q_across = (model.call("Q_across", data, q=q[k], v=recording.v[k], w=w)
                        if model.Q_across is not None else None)
            wrenches = wrenches_from_multipliers(model, q[k], recording.lam[k], Phi_v, Q_across,
                                                 data=data)
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
    touching = None
    if recording.contact_forces is not None:
        touching = recording.contact_forces.reshape(n, -1, model.dimension)
        if touching.shape[1] != len(ground_contacts(model)):
            raise InputFileError(f"{recording.directory / 'results.npz'}: its contact forces "
                                 f"are not those of scene '{model.name}'")
        touching = np.concatenate([touching, np.zeros((n, touching.shape[1],
                                                       3 - model.dimension))], axis=2)
    return Frames(recording.t, q, force, moment, force_joint, moment_joint, effort,
                  ground if model.contacts else None, touching)


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
    (the ground's force on each foot); a contact scheme's run also ``contacts_NNNN.vtu``,
    ``contacts.pvd`` and ``contacts.csv`` (the ground's force at each unilateral contact).
    ``meshes``: meshio Meshes by body name, drawn
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
    bodies_pvd, joints_pvd, feet_pvd, contacts_pvd = [], [], [], []
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
            if frames.contact_force is not None and frames.contact_force.shape[1]:
                name = f"contacts_{k:0{digits}d}.vtu"
                files[name] = _vtu_bytes(_contacts_mesh(model, frames, k), scratch)
                contacts_pvd.append((float(frames.t[k]), name))
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
    if contacts_pvd:
        files["contacts.pvd"] = pvd_text(contacts_pvd).encode()
        files["contacts.csv"] = _csv(["contact", "name", "body"],
                                     [[c, f.name, model.bodies[f.bodies[0]].name]
                                      for c, f in enumerate(ground_contacts(model))])
    files["bodies.csv"] = _csv(["body", "name", "kind", "mass"],
                               [[b.index, b.name, b.kind, repr(b.mass)] for b in model.bodies])
    names = ["ground"] + [b.name for b in model.bodies]
    files["joints.csv"] = _csv(["joint", "name", "kind", "parent", "child"],
                               [[j.index, j.name, j.kind, names[j.parent + 1],
                                 names[j.child + 1]] for j in model.joints])
    tables = {name: columns for name, columns in TABLE_UNITS.items()
              if name in files or any(f.startswith(name.partition("*")[0]) for f in files)}
    files["units.json"] = units_json(tables).encode()
    return files


#: The units of the index tables and of the VTK files' data arrays (``bodies_*.vtu`` cell data,
#: ``joints_*.vtu`` and ``feet_*.vtu`` point data): SI, ``1`` for an index or a pure number,
#: ``None`` for text.
TABLE_UNITS = {
    "bodies.csv": {"body": ("1", "index of the body (cell data 'body')"),
                   "name": (None, "the body's name"), "kind": (None, "spatial, planar, particle"),
                   "mass": ("kg", "the body's mass")},
    "joints.csv": {"joint": ("1", "index of the joint (point data 'joint')"),
                   "name": (None, "the joint's name"), "kind": (None, "the joint's type"),
                   "parent": (None, "the parent body"), "child": (None, "the child body")},
    "contacts.csv": {"contact": ("1", "index of the contact (point data 'contact')"),
                     "name": (None, "the ground-contact element's name"),
                     "body": (None, "the body that touches")},
    "contacts_*.vtu": {"contact": ("1", "index in contacts.csv"),
                       "ground_force": ("N", "the ground's force on the body, world axes"),
                       "closed": ("1", "1 where the ground pushes, else 0"),
                       "points": ("m", "touching points, world frame")},
    "feet.csv": {"foot": ("1", "index of the foot (point data 'foot')"),
                 "contact": (None, "the contact's name"), "leg": (None, "the leg")},
    "bodies_*.vtu": {"body": ("1", "index in bodies.csv"),
                     "part": ("1", "0 box, 1 bar, 2 particle, 3 mesh"), "points": ("m", "")},
    "joints_*.vtu": {"joint": ("1", "index in joints.csv"),
                     "force": ("N", "by the parent on the child, world axes"),
                     "moment": ("N m", "about the joint origin, world axes"),
                     "force_joint_frame": ("N", "the same in the child's joint frame"),
                     "moment_joint_frame": ("N m", "the same in the child's joint frame"),
                     "effort": ("N m or N", "the joint's driver effort (revolute, prismatic)"),
                     "points": ("m", "joint origins, world frame")},
    "feet_*.vtu": {"foot": ("1", "index in feet.csv"),
                   "ground_force": ("N", "the ground's force on the foot, world axes"),
                   "stance": ("1", "1 in stance, 0 in swing"),
                   "points": ("m", "foot points, world frame")},
}


def _contacts_mesh(model: Model, frames: Frames, k: int):
    """The unilateral contacts at saved instant ``k``: a vertex at each touching point with
    the ground's force there (``ground_force``, world axes, N) and whether it pushes."""
    import meshio

    points = contact_frames(model, frames.q[k]).points
    points = np.array([_embed(p) for p in points])
    force = frames.contact_force[k] + 0.0
    m = len(points)
    return meshio.Mesh(points, [meshio.CellBlock("vertex", np.arange(m)[:, None])],
                       point_data={"contact": np.arange(m, dtype=np.int32),
                                   "ground_force": force,
                                   "closed": (np.linalg.norm(force, axis=1) > 0).astype(
                                       np.int32)})


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


#: the largest mesh file read for a body by default: some million triangles, far more than a
#: picture of a leg needs, and read into a few times as much memory
DEFAULT_MAX_MESH_BYTES = 256 * 1024**2


def max_mesh_bytes(given: int | None = None) -> int:
    """The size limit of a body's mesh file: ``given``, else the environment variable
    ``HEXAPOD_MAX_MESH_BYTES`` (``512M``, ``1G`` ...), else :data:`DEFAULT_MAX_MESH_BYTES`."""
    if given is not None:
        return int(given)
    text = os.environ.get("HEXAPOD_MAX_MESH_BYTES", "").strip()
    if not text:
        return DEFAULT_MAX_MESH_BYTES
    try:
        return parse_size(text)
    except ValueError as error:
        raise HexapodError(f"environment variable HEXAPOD_MAX_MESH_BYTES: {error}") from None


def scene_meshes(scene, limit: int | None = None) -> dict:
    """The meshes the scene's bodies name (their ``mesh`` key), by body name: read, moved from
    the body's reference frame to its centre-of-mass frame and converted to metres. ``limit``:
    see :func:`read_mesh`."""
    base = Path(scene.source).parent if scene.source else Path.cwd()
    meshes = {}
    for name, body in scene.bodies.items():
        if body.mesh:
            try:
                mesh = read_mesh(base / body.mesh, limit)
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


def _check_mesh_size(path: Path, limit: int) -> None:
    """Refuse a mesh file above ``limit`` bytes, or a binary STL whose header declares more
    triangles than the file holds, before meshio reads any of it."""
    size = path.stat().st_size
    if size > limit:
        said = (size_text(size), size_text(limit))
        if said[0] == said[1]:  # just above: in bytes
            said = (f"{size} bytes", f"{limit} bytes")
        raise InputFileError(f"{path}: {said[0]}, above the limit of {said[1]} for a body's "
                             "mesh (raise it with --max-mesh-size or HEXAPOD_MAX_MESH_BYTES)")
    if path.suffix.lower() == ".stl" and size >= 84:
        with path.open("rb") as stream:
            head = stream.read(84)
        triangles = int.from_bytes(head[80:84], "little")
        needed = 84 + 50 * triangles
        if not head.lstrip().startswith(b"solid") and needed != size:
            raise InputFileError(f"{path}: a binary STL whose header declares {triangles} "
                                 f"triangles ({size_text(needed)}) in {size_text(size)}")


def read_mesh(path: str | Path, limit: int | None = None):
    """A mesh file (any format meshio reads), or an :class:`InputFileError`.

    ``limit``: the largest file read, in bytes (default :func:`max_mesh_bytes`); its size is
    checked first (and a binary STL's triangle count against it). What meshio prints about a
    file it cannot read, and its ``sys.exit``, become the error's message.
    """
    import meshio

    path = Path(path)
    if not path.exists():
        raise InputFileError(f"{path}: no such mesh file")
    check_input(path, "mesh file")  # a pipe or a device: said, never waited on
    _check_mesh_size(path, max_mesh_bytes(limit))
    said = io.StringIO()
    try:
        with warnings.catch_warnings(), contextlib.redirect_stdout(said), \
                contextlib.redirect_stderr(said):
            warnings.simplefilter("ignore")  # numpy's, on reading garbage as a binary file
            mesh = meshio.read(path)
    except (Exception, SystemExit) as error:  # meshio raises many kinds, or exits
        what = " ".join(said.getvalue().split()) or f"{type(error).__name__}: {error}"
        raise InputFileError(f"{path}: cannot read the mesh ({what[:300]})") from None
    if mesh.points.ndim != 2 or mesh.points.shape[1] not in (2, 3) or not mesh.cells:
        raise InputFileError(f"{path}: no points in 2-D or 3-D with cells")
    return mesh
