"""Read a URDF model into an absolute-coordinate scene.

Policy (stated here and in the scene reference):

* the **root link** (``base``, :data:`BASES`): by default, a root **with mass is a free body**
  (a floating base: a legged robot's trunk), and a **massless root is the ground** (an arm
  bolted down, Pinocchio's fixed-base models); ``base="fixed"`` welds a root with mass to the
  ground by a fixed joint ``<root>/ground`` (its mass counts, the weld's reaction is reported),
  ``base="free"`` insists on a free root (an error for a massless one: it would make the mass
  matrix singular). A root's mass is never dropped;
* each other link is a spatial body whose reference frame is the URDF link frame; its inertial
  (``<origin xyz rpy>``, ``<mass>``, ``<inertia ixx ixy ixz iyy iyz izz>``, the tensor about the
  centre of mass in the rotated inertial axes) gives ``com``, ``inertia_rotation``, ``inertia``;
* ``revolute`` and ``continuous`` joints become revolute joints, ``prismatic`` prismatic and
  ``fixed`` fixed joints (their wrenches are reported too). The **joint frame is the child link
  frame**; ``<origin xyz rpy>`` (``R = Rz(yaw) Ry(pitch) Rx(roll)``) places it in the parent link
  frame at zero joint coordinate; ``<axis xyz>`` (default x) is normalised; ``<limit lower
  upper>`` of a ``revolute`` or ``prismatic`` joint is the joint's range (``limits``: rad or m,
  as the file says, whatever its size; an attribute left out is URDF's default 0, a ``<limit>``
  without either gives no range, and ``lower`` must be below ``upper``; a ``continuous``
  joint has none); the ``<limit>``'s ``effort`` and ``velocity``, ``<dynamics>``,
  ``<mimic>``, visuals and collisions are ignored;
* a link **without an inertial** (or with zero mass) hanging from its parent by a fixed joint is
  **merged into the parent** as a frame: the joints below it hang from the parent; a massless
  link that moves would make the mass matrix singular, and is **rejected** with an error naming
  it (give it a mass, or attach it by a fixed joint).

Every problem is collected and reported in one :class:`~hexapod.errors.ModelError` naming the
file and the element.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hexapod._support.files import read_text
from hexapod.errors import InputFileError, ModelError, Problem
from hexapod.scene.bodies import SpatialBody
from hexapod.scene.element import GROUND
from hexapod.scene.joints import JOINT_TYPES, Joint, kinds_that
from hexapod.scene.scene import Scene
from hexapod.spatial import Placement, rotation_from_rpy, rpy_from_rotation


def _joint_types() -> dict[str, type[Joint]]:
    """The joint types by their URDF types (``continuous``: a revolute joint)."""
    return {urdf: cls for cls in JOINT_TYPES.values() for urdf in cls.urdf_types}


def _quoted(text: str, limit: int = 60) -> str:
    """An attribute value as a message shows it: in double quotes, cut short when long, with
    line breaks escaped (each problem stays on one line)."""
    text = text if len(text) <= limit else text[:limit - 3] + "..."
    return '"' + text.replace("\\", "\\\\").replace("\n", "\\n").replace("\r", "\\r") + '"'


def _tag(tag: str, name: str | None) -> str:
    """How messages name a link or a joint: as it is written, ``<joint name="knee">``."""
    return f"<{tag}>" if name is None else f"<{tag} name={_quoted(name)}>"


@dataclass
class _Link:
    name: str
    mass: float = 0.0
    com: Placement = field(default_factory=Placement.identity)
    inertia: np.ndarray = field(default_factory=lambda: np.zeros(6))


@dataclass
class _Joint:
    name: str
    kind: str
    parent: str
    child: str
    origin: Placement
    axis: np.ndarray
    limits: np.ndarray | None = None  # [lower, upper], revolute and prismatic joints only


#: The URDF joint types whose ``<limit lower upper>`` is a range of the coordinate (a
#: ``continuous`` joint has none).
_RANGED = ("revolute", "prismatic")


#: How the root link is attached (see the module's description).
BASES = ("auto", "free", "fixed")


class _UrdfReader:
    def __init__(self, path: Path, base: str = "auto"):
        self.path = path
        self.base = base
        self.problems: list[Problem] = []

    def add(self, element: str, message: str) -> None:
        self.problems.append(Problem(element, message, str(self.path)))

    def numbers(self, node, attribute: str, count: int, default, element: str):
        """The numbers of an attribute (``default`` when it is absent or wrong, and reported)."""
        text = node.get(attribute) if node is not None else None
        if text is None:
            return np.array(default, dtype=float)
        try:
            values = [float(x) for x in text.split()]
        except ValueError:
            values = []
        if len(values) != count or not all(math.isfinite(x) for x in values):
            wanted = "a finite number" if count == 1 else f"{count} finite numbers"
            self.add(element, f"<{node.tag}> {attribute}={_quoted(text)} must be {wanted}")
            return np.array(default, dtype=float)
        return np.array(values)

    def origin(self, node, element: str) -> Placement:
        origin = node.find("origin") if node is not None else None
        xyz = self.numbers(origin, "xyz", 3, [0, 0, 0], element)
        rpy = self.numbers(origin, "rpy", 3, [0, 0, 0], element)
        return Placement(xyz, rotation_from_rpy(*rpy))

    def link(self, node) -> _Link:
        name = node.get("name")
        link = _Link(name)
        inertial = node.find("inertial")
        if inertial is None:
            return link
        label = _tag("link", name)
        link.com = self.origin(inertial, label)
        mass = inertial.find("mass")
        link.mass = float(self.numbers(mass, "value", 1, [0.0], label)[0]) if mass is not None \
            else 0.0
        if link.mass < 0:
            self.add(label, f"<mass> value={_quoted(mass.get('value'))} must not be negative")
        inertia = inertial.find("inertia")
        if inertia is None:
            self.add(label, "<inertial> has no <inertia>")
        else:
            link.inertia = np.array([self.numbers(inertia, key, 1, [0.0], label)[0]
                                     for key in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")])
        return link

    def joint(self, node, links: dict) -> _Joint | None:
        name = node.get("name")
        label = _tag("joint", name)
        kind = node.get("type")
        types = _joint_types()
        if kind not in types:
            given = "has no type" if kind is None else f"type={_quoted(kind)} is not supported"
            self.add(label, f"{given} ({', '.join(types)})")
            return None
        ends = {}
        for end in ("parent", "child"):
            tag = node.find(end)
            ends[end] = tag.get("link") if tag is not None else None
            if ends[end] is None:
                self.add(label, f"has no <{end} link=\"...\"/>")
            elif ends[end] not in links:
                self.add(label, f"{end} link {_quoted(ends[end])} is not defined")
        if None in ends.values() or any(v not in links for v in ends.values()):
            return None
        if ends["parent"] == ends["child"]:
            self.add(label, f"joins link {_quoted(ends['child'])} to itself")
            return None
        axis = self.numbers(node.find("axis"), "xyz", 3, [1, 0, 0], label)
        # scaled by its largest component first, so that huge (finite) components do not
        # overflow the norm
        largest = float(np.max(np.abs(axis)))
        if types[kind].drivable and not largest > 1e-12:
            self.add(label, "<axis> has zero length")
        unit = axis / largest if largest > 1e-12 else np.array([1.0, 0.0, 0.0])
        return _Joint(name, kind, ends["parent"], ends["child"], self.origin(node, label),
                      unit / np.linalg.norm(unit),
                      self.limits(node.find("limit"), label) if kind in _RANGED else None)

    def limits(self, node, element: str) -> np.ndarray | None:
        """``[lower, upper]`` of a ``<limit>`` (an attribute left out: URDF's default 0); None
        without the element or both attributes, or when they are wrong (and reported)."""
        if node is None or (node.get("lower") is None and node.get("upper") is None):
            return None
        count = len(self.problems)
        values = np.array([self.numbers(node, key, 1, [0.0], element)[0]
                           for key in ("lower", "upper")])
        if len(self.problems) > count:
            return None
        if not values[0] < values[1]:
            self.add(element, f"<limit> lower={_quoted(node.get('lower', '0'))} upper="
                     f"{_quoted(node.get('upper', '0'))}: the lower limit must be below the "
                     "upper")
            return None
        return values

    def read(self, root_node) -> Scene:
        if root_node.tag != "robot":
            raise InputFileError(f"{self.path}: not a URDF file (the root element is "
                                 f"<{root_node.tag}>, not <robot>)")
        links: dict[str, _Link] = {}
        for node in root_node.findall("link"):
            name = node.get("name")
            if not name:
                self.add("<link>", "has no name")
            elif name in links:
                self.add(_tag("link", name), "is defined twice")
            else:
                links[name] = self.link(node)
        joints: list[_Joint] = []
        named = set()  # the names of the joints read
        for node in root_node.findall("joint"):
            if not node.get("name"):
                self.add("<joint>", "has no name")
                continue
            if node.get("name") in named:
                self.add(_tag("joint", node.get("name")), "is defined twice")
            joint = self.joint(node, links)
            if joint is not None:
                joints.append(joint)
                named.add(joint.name)
        scene = Scene(root_node.get("name") or self.path.stem, 3, "m", source=str(self.path))
        if not links:
            self.add("<robot>", "has no links")
        if self.problems:
            raise ModelError(f"URDF file {self.path}", self.problems)
        return self.build(scene, links, joints)

    def root_body(self, scene: Scene, link: _Link) -> str:
        """Add the root link to ``scene`` as the base policy says; the body its children hang
        from (the ground, or the root's own body)."""
        if link.mass <= 0:
            if self.base == "free":
                self.add(_tag("link", link.name), "is the root and has no mass: it cannot be a "
                         "free body (the mass matrix would be singular); give it an "
                         "<inertial>, or read the model with a fixed base")
            return GROUND
        scene.add(SpatialBody(link.name, link.mass, link.inertia, com=link.com.position,
                              inertia_rotation=link.com.rotation,
                              source=f"{self.path}, {_tag('link', link.name)} (the root)"))
        if self.base == "fixed":
            scene.add(_joint_types()["fixed"](f"{link.name}/ground", GROUND, link.name,
                                              parent_frame=Placement.identity(),
                                              child_frame=Placement.identity(),
                                              source=f"{self.path}, the fixed base"))
        return link.name

    def build(self, scene: Scene, links: dict, joints: list) -> Scene:
        parent_of = {}
        for joint in joints:
            if joint.child in parent_of:
                self.add(_tag("link", joint.child), "is the child of two joints (URDF is a "
                         "tree)")
            parent_of[joint.child] = joint
        roots = [name for name in links if name not in parent_of]
        if len(roots) != 1:
            self.add("<robot>", f"needs exactly one root link, found {len(roots)}: "
                     + ", ".join(roots) if roots else "the joints form a loop")
            raise ModelError(f"URDF file {self.path}", self.problems)
        root = roots[0]
        # link frames at zero joint coordinates, and the body (or ground) each link belongs to
        pose = {root: Placement.identity()}
        owner = {root: (self.root_body(scene, links[root]), Placement.identity())}
        below: dict[str, list[int]] = {}  # the joints hanging from each link, by file order
        for k, joint in enumerate(joints):
            below.setdefault(joint.parent, []).append(k)
        ordered, done = [], set()
        layer = below.get(root, [])  # link by link outwards from the root, each layer in file
        while layer:  # order (in linear time: a chain of 20,000 links has 20,000 layers)
            for k in layer:
                joint = joints[k]
                pose[joint.child] = pose[joint.parent] @ joint.origin
                ordered.append(joint)
            done.update(layer)
            layer = sorted({k for j in layer for k in below.get(joints[j].child, [])} - done)
        if len(ordered) < len(joints):
            self.add("<robot>", "some links are not connected to the root: "
                     + ", ".join(sorted({j.child for j in joints if j.child not in pose})))
            raise ModelError(f"URDF file {self.path}", self.problems)
        merged = set()
        for joint in ordered:  # parents first: a merged link's owner is known before its children
            link = links[joint.child]
            body, in_body = owner[joint.parent]
            if link.mass <= 0:
                if _joint_types()[joint.kind].drivable:
                    self.add(_tag("link", link.name), f"has no mass but moves (joint "
                             f"'{joint.name}' is {joint.kind}): the mass matrix would be "
                             "singular; give it an <inertial> or attach it by a fixed joint")
                owner[link.name] = (body, in_body @ joint.origin)  # merged into its parent
                merged.add(joint.name)
            else:
                owner[link.name] = (link.name, Placement.identity())
        for joint in joints:  # the file's order, for bodies, joints and output columns
            if joint.name in merged:
                continue
            link = links[joint.child]
            body, in_body = owner[joint.parent]
            scene.add(SpatialBody(link.name, link.mass, link.inertia, com=link.com.position,
                                  position=pose[link.name].position,
                                  rotation=pose[link.name].rotation,
                                  inertia_rotation=link.com.rotation,
                                  source=f"{self.path}, {_tag('link', link.name)}"))
            cls = _joint_types()[joint.kind]
            extra = {"axis": joint.axis} if "axis" in cls.file_keys(3) else {}
            if joint.limits is not None:
                extra["limits"] = joint.limits
            scene.add(cls(joint.name, body, link.name, parent_frame=in_body @ joint.origin,
                          child_frame=Placement.identity(),
                          source=f"{self.path}, {_tag('joint', joint.name)}", **extra))
        if self.problems:
            raise ModelError(f"URDF file {self.path}", self.problems)
        return scene


def read_urdf(path: str | Path, *, base: str = "auto") -> Scene:
    """Read a URDF file into a :class:`Scene` (metres, gravity -9.81 m/s^2 along z).

    Parameters
    ----------
    path : str or Path
        The URDF file.
    base : {"auto", "free", "fixed"}
        The root link: ``"auto"`` a free body when it has mass (a floating base), else the
        ground; ``"free"`` a free body (it must have mass); ``"fixed"`` welded to the ground
        (by a fixed joint ``<root>/ground`` when it has mass, else the ground itself).

    Returns
    -------
    Scene
        Each link but a massless root a spatial body (a massless link fixed to its parent
        merged into it), each URDF joint a joint whose frame is the child link's frame (the
        module's description).

    Raises
    ------
    InputFileError
        The file is missing, unreadable or not well-formed XML.
    ModelError
        The URDF is XML but not a model we can build; every problem is listed.
    """
    path = Path(path)
    text = read_text(path, "URDF file")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        raise InputFileError(f"{path}: not well-formed XML ({error})") from None
    if base not in BASES:
        raise ValueError(f"base must be one of {', '.join(BASES)}, got {base!r}")
    reader = _UrdfReader(path, base)
    with np.errstate(all="ignore"):  # huge values overflow in the checks, which report them
        scene = reader.read(root)
        problems = scene.problems()
    if problems:
        raise ModelError(f"URDF file {path}", problems)
    return scene


# ------------------------------------------------------------------ writing

def _xyz(x) -> str:
    return " ".join(repr(float(v)) for v in x)


def _rpy(R: np.ndarray) -> str:
    return _xyz(rpy_from_rotation(R))


def urdf_text(scene: Scene) -> str:
    """The URDF of a spatial tree of joints URDF has (revolute, prismatic and fixed: the types
    with ``urdf_types``) hanging from the ground, or from one free body (a floating base, the
    tree's root link: a walking robot's trunk); each link frame is its body's joint frame
    (URDF's rule; the root's, its reference frame), at the initial pose. A revolute or
    prismatic joint's ``<limit lower upper>`` is its range (``limits``), or -1e9 to 1e9 (which
    read back is a range no motion leaves) when it has none.

    Parameters
    ----------
    scene : Scene
        A valid spatial scene of such a tree.

    Returns
    -------
    str
        The URDF document, in metres.

    Raises
    ------
    ModelError
        The scene is invalid, or not a tree URDF can hold (every problem listed).
    """
    scene.validate()
    si = scene.in_si()
    problems = []
    if si.dimension != 3 or any(not isinstance(b, SpatialBody) for b in si.bodies.values()):
        problems.append(Problem("scene", "URDF holds spatial bodies only"))
    parent_joint = {}
    for joint in si.joints.values():
        if not joint.urdf_types:
            written = kinds_that(lambda t: bool(t.urdf_types))
            problems.append(Problem(joint.label, f"URDF has {written} joints only here"))
        if joint.child == GROUND or joint.child in parent_joint:
            problems.append(Problem(joint.label, "the joints do not form a tree hanging from "
                                    "the ground (a loop, or the ground as a child)"))
        parent_joint[joint.child] = joint
    missing = [b for b in si.bodies if b not in parent_joint]
    grounded = any(j.parent == GROUND for j in si.joints.values())
    floating = missing[0] if len(missing) == 1 and not grounded else None
    if missing and floating is None:
        problems.append(Problem("scene", "free bodies cannot be written (one may, as the root "
                                "of a tree no joint hangs from the ground): "
                                + ", ".join(missing)))
    if problems:
        raise ModelError(f"scene '{scene.name}'", problems)
    link_frame = {GROUND: Placement.identity()}  # world pose of every link frame
    if floating is not None:
        link_frame[floating] = si.pose(floating)
    for body, joint in parent_joint.items():
        link_frame[body] = si.pose(body) @ si.joint_frames(joint)[1]
    root = "ground" if floating is None else floating
    lines = ['<?xml version="1.0"?>', f'<robot name="{si.name}">',
             f"  <!-- written by hexapod; gravity of the scene: {_xyz(si.gravity)} m/s^2 -->"]
    if floating is None:
        lines.append(f'  <link name="{root}"/>')
    else:
        lines.append(f"  <!-- floating base: '{floating}', at {_xyz(link_frame[floating].position)}"
                     f" m, rpy {_rpy(link_frame[floating].rotation)} in the world -->")
    for name, body in si.bodies.items():
        frame = link_frame[name]
        centre = frame.inverse().transform_point(si.pose(name).transform_point(body.com))
        axes = frame.rotation.T @ body.rotation @ body.inertia_rotation
        J = body.inertia
        lines += [f'  <link name="{name}">', "    <inertial>",
                  f'      <origin xyz="{_xyz(centre)}" rpy="{_rpy(axes)}"/>',
                  f'      <mass value="{float(body.mass)!r}"/>',
                  "      <inertia " + " ".join(
                      f'{key}="{float(J[i, j])!r}"' for key, i, j in (
                          ("ixx", 0, 0), ("ixy", 0, 1), ("ixz", 0, 2), ("iyy", 1, 1),
                          ("iyz", 1, 2), ("izz", 2, 2))) + "/>",
                  "    </inertial>", "  </link>"]
    for name, joint in parent_joint.items():
        parent = root if joint.parent == GROUND else joint.parent
        on_parent = si.pose(joint.parent) @ si.joint_frames(joint)[0]
        origin = link_frame[joint.parent].inverse() @ on_parent
        lines += [f'  <joint name="{joint.name}" type="{joint.urdf_types[0]}">',
                  f'    <parent link="{parent}"/>', f'    <child link="{name}"/>',
                  f'    <origin xyz="{_xyz(origin.position)}" rpy="{_rpy(origin.rotation)}"/>']
        if joint.drivable:
            axis = np.asarray(joint.axis, dtype=float)
            # URDF asks for a <limit>: the joint's range, or one no motion leaves
            limits = ('lower="-1e9" upper="1e9"' if joint.limits is None else
                      'lower="{!r}" upper="{!r}"'.format(*map(float, joint.limits)))
            lines += [f'    <axis xyz="{_xyz(axis / np.linalg.norm(axis))}"/>',
                      f'    <limit {limits} effort="1e9" velocity="1e9"/>']
        lines += ["  </joint>"]
    lines.append("</robot>")
    return "\n".join(lines) + "\n"
