"""Cockroach leg data at natural scale, and the 20:1 scaling of seed 001's robot.

Source: the project's research note ``insect-legs.md`` (section 4.2, working table; section 6,
layout A). The lengths, radii and mass split are **estimates** there ([E]), built around measured
hind-leg masses (Kram, Wong & Full 1997) and effective leg lengths (Bender et al. 2011); replace
them when primary tables are available. Segments are solid cylinders with the centre of mass at
mid-length.
"""

from __future__ import annotations

from dataclasses import dataclass

#: Geometric scale of seed 001's experimental model.
MODEL_SCALE = 20.0


@dataclass(frozen=True)
class Segment:
    """A leg segment at natural scale: length and radius (mm), mass (mg)."""

    name: str
    length_mm: float
    radius_mm: float
    mass_mg: float

    def scaled(self, scale: float) -> tuple[float, float, float, float]:
        """Length (m), mass (kg), transverse and axial moments of inertia (kg m^2) at ``scale``,
        same density: lengths x s, masses x s^3 (inertias follow from them, x s^5)."""
        length = self.length_mm * 1e-3 * scale
        radius = self.radius_mm * 1e-3 * scale
        mass = self.mass_mg * 1e-6 * scale**3
        transverse = mass * (3 * radius**2 + length**2) / 12.0
        axial = mass * radius**2 / 2.0
        return length, mass, transverse, axial


#: Front leg, layout A: the trochanter is fused to the femur (one body, "trochanter + femur").
FRONT_LEG = (
    Segment("coxa", 5.0, 1.00, 11.98),
    Segment("femur", 7.5, 0.55, 11.45),
    Segment("tibia", 5.0, 0.35, 2.66),
    Segment("tarsus", 5.0, 0.20, 0.53),
)

#: The two zero-length links of the three-axis thorax-coxa joint: 1 % of the coxa mass with the
#: inertia of a sphere of radius 0.5 mm (natural scale), the placeholder of the note, section 6.
BRACKET = Segment("bracket", 0.0, 0.5, 0.01 * 11.98)

#: Rest pose (section 6): the leg plane turned 40 deg forward of lateral; segment inclinations
#: below the horizontal (deg). The tarsus angle is our estimate, chosen so the foot reaches
#: the ground about 9 mm below the thorax-coxa joint at natural scale.
REST_POSE_DEG = {"plane_forward": 40.0, "coxa": 40.0, "femur": 0.0, "tibia": 60.0,
                 "tarsus": 20.0}

#: Tripod-gait joint laws of section 7.3: amplitude (deg) and shape of q_i(t) = A h(w t + phase),
#: for the joints J1 ... J6 of layout A. Phase origin w t = 0 at lift-off.
GAIT_LAWS = (
    ("thc_protraction", 25.0, "-cos"),
    ("thc_levation", 8.0, "sin"),
    ("coxa_rotation", 10.0, "sin"),
    ("ctr", 20.0, "sin"),
    ("fti", 25.0, "-cos"),
    ("tita", 10.0, "-cos"),
)

#: One stride in the 0-0.5 s window of seed 001's Fig. 7 (Froude-scaled 9 Hz -> 2 Hz).
STRIDE_PERIOD = 0.5
