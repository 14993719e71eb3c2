"""Cockroach leg and body data at natural scale, and the 20:1 scaling of the robot of Dumitru,
Marin and Margine.

Every value is tagged with its source: [S] from a cited source, [D] derived by a stated
calculation, [E] an estimate to be replaced by measured values.

* Segment lengths, radii and masses: a working table ([E], built around measured hind-leg masses,
  Kram, Wong & Full 1997, and effective leg lengths, Bender et al. 2011).
  Layout A fuses trochanter and femur: length and mass add, the femur's radius is kept ([D]).
* Segments are solid cylinders with the centre of mass at mid-length (transverse and axial
  moments of inertia I_t, I_a).
* Rest poses: estimated for the front leg ([E]); the middle and hind legs' are ours ([E]).
* Thorax-coxa points and the trunk: estimates ([E]).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

#: Geometric scale of the experimental model of Dumitru, Marin and Margine.
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

    def stretched(self, factor: float) -> Segment:
        """The segment with its length multiplied by ``factor``, same cross-section and density:
        its mass follows the length (its inertias follow from :meth:`scaled`). Itself for 1."""
        if factor == 1.0:
            return self
        return replace(self, length_mm=self.length_mm * factor, mass_mg=self.mass_mg * factor)


def _fused(trochanter: Segment, femur: Segment) -> Segment:
    """Layout A's "trochanter + femur as one body" [D]."""
    return Segment("femur", trochanter.length_mm + femur.length_mm, femur.radius_mm,
                   trochanter.mass_mg + femur.mass_mg)


#: Segments of layout A (coxa, trochanter + femur, tibia, tarsus), from the working table.
SEGMENTS = {
    "front": (Segment("coxa", 5.0, 1.00, 11.98),
              _fused(Segment("trochanter", 1.5, 0.50, 1.33), Segment("femur", 6.0, 0.55, 10.12)),
              Segment("tibia", 5.0, 0.35, 2.66), Segment("tarsus", 5.0, 0.20, 0.53)),
    "middle": (Segment("coxa", 5.0, 1.10, 20.60),
               _fused(Segment("trochanter", 1.5, 0.55, 2.29),
                      Segment("femur", 8.0, 0.60, 17.39)),
               Segment("tibia", 8.0, 0.40, 4.58), Segment("tarsus", 7.0, 0.22, 0.92)),
    "hind": (Segment("coxa", 6.0, 1.30, 36.00),
             _fused(Segment("trochanter", 2.0, 0.60, 4.00), Segment("femur", 10.0, 0.70, 30.40)),
             Segment("tibia", 12.0, 0.45, 8.00), Segment("tarsus", 9.0, 0.25, 1.60)),
}

#: The zero-length links of the three-axis thorax-coxa joint: 1 % of the coxa mass with the
#: inertia of a sphere of radius 0.5 mm (natural scale), a placeholder.
def bracket(leg: str) -> Segment:
    return Segment("bracket", 0.0, 0.5, 0.01 * SEGMENTS[leg][0].mass_mg)


#: Rest poses: the leg plane turned forward of lateral by ``plane_forward`` (negative: backward),
#: segment inclinations below the horizontal (deg). Front: an estimate [E]; the tarsus angle, the
#: middle and the hind legs are our estimates [E] (the hind leg reaches back).
REST_POSE_DEG = {
    "front": {"plane_forward": 40.0, "coxa": 40.0, "femur": 0.0, "tibia": 60.0, "tarsus": 20.0},
    "middle": {"plane_forward": 0.0, "coxa": 35.0, "femur": 0.0, "tibia": 65.0, "tarsus": 20.0},
    "hind": {"plane_forward": -40.0, "coxa": 30.0, "femur": 0.0, "tibia": 70.0, "tarsus": 20.0},
}

#: Thorax-coxa points from the body's centre of mass (x forward, y left, z up), mm at natural scale,
#: left side (the right mirrors y) [E].
THC_POINT_MM = {"front": (12.0, 4.0, -2.0), "middle": (6.0, 4.0, -2.0), "hind": (0.0, 4.5, -2.0)}

#: The trunk without legs at natural scale: mass (g) and principal moments (kg m^2) of the uniform
#: ellipsoid [E].
TRUNK = {"mass_g": 2.30, "inertia": (0.218 / 3.2e6, 1.055 / 3.2e6, 1.226 / 3.2e6)}

#: Tripod-gait joint laws for the joints J1 ... J6 of layout A: amplitude (deg) and shape of
#: q_i = A h(phase), phase 0 at lift-off, pi at touch-down [E]. Used for every leg.
GAIT_LAWS = (
    ("thc_protraction", 25.0, "-cos"),
    ("thc_levation", 8.0, "sin"),
    ("coxa_rotation", 10.0, "sin"),
    ("ctr", 20.0, "sin"),
    ("fti", 25.0, "-cos"),
    ("tita", 10.0, "-cos"),
)

#: One stride in the 0-0.5 s window of Fig. 7 of Dumitru, Marin and Margine (Froude-scaled
#: 9 Hz -> 2 Hz) [D].
STRIDE_PERIOD = 0.5

#: The stride seen from the trunk, natural scale (mm): the foot's travel in stance, duty factor
#: times stride length, 11.6-13.5 mm over the range of running speeds considered [D]; its lift in
#: swing, 2-3 mm [E]; the ground's height in the trunk frame [E, ours: the rest poses' feet lie
#: 11-19 mm below the centre of mass].
STANCE_LENGTH_MM = 13.0
FOOT_LIFT_MM = 2.5
GROUND_Z_MM = -14.0

#: Fore-aft offset of each leg's stance line (its middle) from the rest pose's foot, mm [E,
#: ours]: the front leg's rest pose reaches far forward, so its stride is centred further back,
#: where the whole of it is reachable with the joints well inside their ranges.
STANCE_OFFSET_MM = {"front": -10.0, "middle": -1.0, "hind": 1.0}
