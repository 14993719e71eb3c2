"""The left front leg (L1) of seed 001's hexapod at 20:1: six revolute joints, layout A.

Element and joint numbering (so that ``F21`` is the wrench at joint 2 exerted by element 1 on
element 2, reported in element 2's joint frame):

===  ====================  ==========================  ==========================================
 k   joint (parent -> child)                            axis in the rest pose
===  ====================  ==========================  ==========================================
 1   ``thc_protraction``   ground (pronotum) -> E1     body vertical z, through the ThC point
 2   ``thc_levation``      E1 -> E2                    horizontal, normal to the leg plane
 3   ``coxa_rotation``     E2 -> E3 (``coxa``)         along the coxa
 4   ``ctr``               E3 -> E4 (``femur``)        normal to the leg plane
 5   ``fti``               E4 -> E5 (``tibia``)        normal to the leg plane
 6   ``tita``              E5 -> E6 (``tarsus``)       normal to the leg plane
===  ====================  ==========================  ==========================================

E1 and E2 (``thc_link_1``, ``thc_link_2``) are the zero-length links of the three-axis
thorax-coxa joint; E4 is trochanter and femur as one body. The world frame is the pronotum frame
at the thorax-coxa point: x forward, y left, z up. Every joint frame has its z axis along the
joint axis, and all joint angles are zero in the rest pose; positive rotations about the
leg-plane normal raise the distal part.
"""

from __future__ import annotations

import numpy as np

from hexapod import GROUND, Harmonic, JointDriver, Revolute, Scene, SpatialBody
from legs.cockroach import (
    BRACKET,
    FRONT_LEG,
    GAIT_LAWS,
    MODEL_SCALE,
    REST_POSE_DEG,
    STRIDE_PERIOD,
)

JOINTS = tuple(name for name, _, _ in GAIT_LAWS)
ELEMENTS = ("thc_link_1", "thc_link_2", "coxa", "femur", "tibia", "tarsus")


def _frame(x, z) -> np.ndarray:
    """Rotation with the given unit x and z axes (columns x, y = z cross x, z)."""
    x = np.asarray(x, dtype=float)
    z = np.asarray(z, dtype=float)
    return np.column_stack([x, np.cross(z, x), z])


def gait_law(amplitude_deg: float, shape: str, period: float, phase: float = 0.0) -> Harmonic:
    """``A h(2 pi t / T + phase)`` with ``h`` = ``sin`` or ``-cos`` (section 7.3 of the note)."""
    a = np.radians(amplitude_deg)
    # A h(w t + phase) as a cos/sin series in w t
    c, s = np.cos(phase), np.sin(phase)
    if shape == "sin":
        cos_amp, sin_amp = a * s, a * c
    elif shape == "-cos":
        cos_amp, sin_amp = -a * c, a * s
    else:
        raise ValueError(f"unknown gait law shape {shape!r}")
    return Harmonic(offset=0.0, cos=[cos_amp], sin=[sin_amp], frequency=1.0 / period)


def front_leg_scene(scale: float = MODEL_SCALE, gait: bool = True, phase: float = 0.0,
                    period: float = STRIDE_PERIOD, name: str = "front-leg") -> Scene:
    """The L1 leg as a scene hanging from a fixed pronotum.

    Parameters
    ----------
    scale : float
        Geometric scale (20 for seed 001's model; 1 for the insect).
    gait : bool
        Drive all six joints with the tripod-gait laws (inverse dynamics); otherwise the leg is
        free (6 degrees of freedom).
    phase : float
        Phase of this leg in the gait (rad): 0 for L1, R2, L3; pi for R1, L2, R3.
    period : float
        Stride period (s).
    """
    pose = {k: np.radians(v) for k, v in REST_POSE_DEG.items()}
    up = np.array([0.0, 0.0, 1.0])
    lateral = np.array([np.sin(pose["plane_forward"]), np.cos(pose["plane_forward"]), 0.0])
    normal = np.cross(lateral, up)  # positive rotation about it raises the leg

    def direction(key):
        return np.cos(pose[key]) * lateral - np.sin(pose[key]) * up

    scene = Scene(name, dimension=3, length_unit="m")
    _, m_bracket, _, _ = BRACKET.scaled(scale)
    r_bracket = BRACKET.radius_mm * 1e-3 * scale
    i_bracket = 0.4 * m_bracket * r_bracket**2
    for body in ELEMENTS[:2]:
        scene.add(SpatialBody(body, m_bracket, [i_bracket] * 3))

    point = np.zeros(3)
    joint_points = [point.copy()] * 3
    for segment in FRONT_LEG:
        length, mass, transverse, axial = segment.scaled(scale)
        u = direction(segment.name)
        scene.add(SpatialBody(segment.name, mass, [axial, transverse, transverse],
                              com=[length / 2, 0.0, 0.0], position=point,
                              rotation=_frame(u, normal),
                              markers={"distal": [length, 0.0, 0.0]}))
        point = point + length * u
        joint_points.append(point.copy())

    joint_frames = [
        _frame(lateral, up),  # J1: about the vertical
        _frame(lateral, normal),  # J2: about the leg-plane normal
        _frame(normal, direction("coxa")),  # J3: about the coxa
        *[_frame(direction(s.name), normal) for s in FRONT_LEG[1:]],  # J4-J6
    ]
    parents = (GROUND,) + ELEMENTS[:-1]
    for k, joint in enumerate(JOINTS):
        scene.add(Revolute(joint, parents[k], ELEMENTS[k], origin=joint_points[k],
                           rotation=joint_frames[k]))
    if gait:
        for joint, amplitude, shape in GAIT_LAWS:
            scene.add(JointDriver(f"drive_{joint}", joint,
                                  gait_law(amplitude, shape, period, phase)))
    return scene
