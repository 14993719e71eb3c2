"""A cockroach leg of layout A (six revolute joints), for any leg and side, at any scale.

Element and joint numbering (so that ``F21`` is the wrench at joint 2 exerted by element 1 on
element 2, reported in element 2's joint frame):

===  ====================  =========================  ============================================
 k   joint                 parent -> child            axis in the rest pose (the joint frame's z)
===  ====================  =========================  ============================================
 1   ``thc_protraction``   trunk -> E1 ``thc_link_1``  vertical, pointing down on the left and up
                                                       on the right: positive protracts (forward)
 2   ``thc_levation``      E1 -> E2 ``thc_link_2``     horizontal, normal to the leg plane:
                                                       positive raises the leg
 3   ``coxa_rotation``     E2 -> E3 ``coxa``           along the coxa, pointing away from the body
                                                       on the left and towards it on the right
 4   ``ctr``               E3 -> E4 ``femur``          normal to the leg plane (as J2)
 5   ``fti``               E4 -> E5 ``tibia``          normal to the leg plane
 6   ``tita``              E5 -> E6 ``tarsus``         normal to the leg plane
===  ====================  =========================  ============================================

On the right, every axis is the mirror image of the left one's, reversed (axes are
pseudo-vectors), so equal angles give mirror-image motions. E1 and E2 are the zero-length links
of the three-axis thorax-coxa joint; E4 is trochanter and femur as one body. The scene's world
is the trunk frame at the thorax-coxa point (x forward, y left, z up); all joint angles are zero
in the rest pose. Each segment's reference frame sits at its proximal joint with x along the
segment and z along the leg plane's normal; markers ``distal`` (the next joint) and, on the
tarsus, ``foot``.

A design may change the segments' lengths (``lengths``: factors of the coxa, femur, tibia and
tarsus lengths, 1 for the cockroach's proportions): each segment keeps its cross-section and
density, so its mass follows its length and its inertias follow from both; the rest pose's
angles and the thorax-coxa brackets stay as they are.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hexapod import Scene
from hexapod.scene import GROUND, JointDriver, Revolute, SpatialBody
from legs.cockroach import GAIT_LAWS, MODEL_SCALE, REST_POSE_DEG, SEGMENTS, bracket

JOINTS = tuple(name for name, _, _ in GAIT_LAWS)
ELEMENTS = ("thc_link_1", "thc_link_2", "coxa", "femur", "tibia", "tarsus")
LEGS = ("front", "middle", "hind")
SIDES = {"L": 1.0, "R": -1.0}
#: The segments whose lengths a design may change, in the order of the length factors.
SEGMENT_NAMES = ("coxa", "femur", "tibia", "tarsus")
#: The cockroach's proportions: every length factor 1.
NOMINAL_LENGTHS = (1.0, 1.0, 1.0, 1.0)


def length_factors(lengths=None) -> tuple[float, float, float, float]:
    """``lengths`` (factors of the coxa, femur, tibia and tarsus lengths; None: all 1) as a
    tuple of four floats.

    Raises
    ------
    ValueError
        Not four finite positive numbers.
    """
    if lengths is None:
        return NOMINAL_LENGTHS
    factors = tuple(lengths)
    if len(factors) != 4:
        raise ValueError(f"lengths must be 4 factors ({', '.join(SEGMENT_NAMES)}), got "
                         f"{len(factors)}")
    out = []
    for name, factor in zip(SEGMENT_NAMES, factors, strict=True):
        if isinstance(factor, bool) or not isinstance(factor, (int, float, np.floating,
                                                               np.integer)) \
                or not (math.isfinite(factor) and factor > 0):
            raise ValueError(f"{name}_length must be a finite number > 0 (a factor of the "
                             f"segment's length), got {factor!r}")
        out.append(float(factor))
    return (out[0], out[1], out[2], out[3])


def describe_lengths(lengths=None) -> str:
    """``"coxa_length=1.0, femur_length=1.2, ..."``: the four factors, for messages."""
    return ", ".join(f"{name}_length={factor!r}"
                     for name, factor in zip(SEGMENT_NAMES, length_factors(lengths),
                                             strict=True))


def _frame(x, z) -> np.ndarray:
    """Rotation with the given unit x and z axes (columns x, y = z cross x, z)."""
    x = np.asarray(x, dtype=float)
    z = np.asarray(z, dtype=float)
    return np.column_stack([x, np.cross(z, x), z])


@dataclass(frozen=True)
class LegGeometry:
    """The rest pose of one leg: joint points, axes and frames (trunk frame at the ThC point),
    and the segments' lengths, masses and inertias at the model's scale."""

    leg: str
    side: str
    points: tuple[np.ndarray, ...]  # joint points J1 ... J6, then the foot
    frames: tuple[np.ndarray, ...]  # joint frames J1 ... J6 (z along the axis)
    segment_frames: tuple[np.ndarray, ...]  # reference frames of coxa ... tarsus
    lengths: tuple[float, ...]
    masses: tuple[float, ...]  # E1 ... E6
    inertias: tuple[np.ndarray, ...]  # principal moments in the segment frames, E1 ... E6
    length_factors: tuple[float, ...] = NOMINAL_LENGTHS  # coxa, femur, tibia, tarsus

    @property
    def axes(self) -> tuple[np.ndarray, ...]:
        return tuple(frame[:, 2] for frame in self.frames)


def leg_geometry(leg: str = "front", side: str = "L", scale: float = MODEL_SCALE,
                 lengths=None) -> LegGeometry:
    """The rest pose of a leg (``front``, ``middle`` or ``hind``; side ``L`` or ``R``), its
    segments' lengths multiplied by ``lengths`` (coxa, femur, tibia, tarsus; None: all 1)."""
    if leg not in LEGS or side not in SIDES:
        raise ValueError(f"leg must be one of {LEGS} and side L or R, got {leg!r}, {side!r}")
    factors = length_factors(lengths)
    sign = SIDES[side]
    pose = {k: np.radians(v) for k, v in REST_POSE_DEG[leg].items()}
    up = np.array([0.0, 0.0, 1.0])
    lateral = np.array([np.sin(pose["plane_forward"]), sign * np.cos(pose["plane_forward"]), 0.0])
    normal = np.cross(lateral, up)  # rotating the leg about it raises it

    def direction(name):
        return np.cos(pose[name]) * lateral - np.sin(pose[name]) * up

    segments = tuple(s.stretched(f) for s, f in zip(SEGMENTS[leg], factors, strict=True))
    _, m_bracket, _, _ = bracket(leg).scaled(scale)
    r_bracket = bracket(leg).radius_mm * 1e-3 * scale
    sphere = np.full(3, 0.4 * m_bracket * r_bracket**2)
    points, lengths, masses = [np.zeros(3)] * 3, [], [m_bracket, m_bracket]
    inertias = [sphere, sphere]
    segment_frames = []
    point = np.zeros(3)
    for segment in segments:
        length, mass, transverse, axial = segment.scaled(scale)
        segment_frames.append(_frame(direction(segment.name), normal))
        point = point + length * direction(segment.name)
        points.append(point)
        lengths.append(length)
        masses.append(mass)
        inertias.append(np.array([axial, transverse, transverse]))
    frames = (
        _frame(lateral, -sign * up),  # J1: down on the left, up on the right
        _frame(lateral, normal),  # J2
        _frame(normal, sign * direction("coxa")),  # J3: along the coxa, mirrored
        *segment_frames[1:],  # J4 ... J6: the femur's, tibia's and tarsus's frames
    )
    return LegGeometry(leg, side, tuple(points), tuple(frames), tuple(segment_frames),
                       tuple(lengths), tuple(masses), tuple(inertias), factors)


def leg_scene(leg: str = "front", side: str = "L", scale: float = MODEL_SCALE,
              laws: dict | None = None, name: str | None = None, lengths=None) -> Scene:
    """A leg hanging from a fixed trunk, its joints driven by ``laws`` (joint name -> law)
    when given (every joint, or some), otherwise free; its segments' lengths multiplied by
    ``lengths`` (see :func:`leg_geometry`)."""
    g = leg_geometry(leg, side, scale, lengths)
    scene = Scene(name or f"{leg}-leg", dimension=3, length_unit="m")
    for body in ELEMENTS[:2]:
        k = ELEMENTS.index(body)
        scene.add(SpatialBody(body, g.masses[k], g.inertias[k]))
    for k, body in enumerate(ELEMENTS[2:], start=2):
        length = g.lengths[k - 2]
        markers = {"distal": [length, 0.0, 0.0]}
        if body == "tarsus":
            markers["foot"] = [length, 0.0, 0.0]
        scene.add(SpatialBody(body, g.masses[k], g.inertias[k], com=[length / 2, 0.0, 0.0],
                              position=g.points[k], rotation=g.segment_frames[k - 2],
                              markers=markers))
    parents = (GROUND,) + ELEMENTS[:-1]
    for k, joint in enumerate(JOINTS):
        scene.add(Revolute(joint, parents[k], ELEMENTS[k], origin=g.points[k],
                           rotation=g.frames[k]))
    for joint, law in (laws or {}).items():
        scene.add(JointDriver(f"drive_{joint}", joint, law))
    return scene
