"""Gaits: which legs swing together, for how long, and the laws that follow from it.

A gait gives each leg a **lift-off time** (a fraction of the period) and all legs one **duty
factor** (the fraction of the cycle in stance); a leg's law leads by ``shift = -lift_off``
(modulo 1). Each joint then follows ``q_i = A_i h_i(phi)`` in the duty-factor-warped phase
``phi`` of :class:`hexapod.Gait` (0 at lift-off, pi at touch-down, C2; the laws of
section 7.3 of the leg note).

================  ====  ==============================================================
gait              duty  lift-off times (fraction of the period)
================  ====  ==============================================================
tripod            1/2   L1, R2, L3 at 0; R1, L2, R3 at 1/2 (Delcomyn 1971)
tetrapod          2/3   L3, R2 at 0; L2, R1 at 1/3; L1, R3 at 2/3: back to front
wave (ripple)     5/6   one leg at a time, back to front: L3 0, L2 1/6, L1 2/6, R3 3/6,
                        R2 4/6, R1 5/6
================  ====  ==============================================================

**Stance loads** (seed 001's "variation laws of the generalized forces"): the ground's reaction
on a foot during stance, ``sin^2`` of the stance progress times its peak, zero in swing. The
peak makes the legs in stance carry the weight on average: ``W / (6 duty) / (1/2)``. Front legs
brake, hind legs propel and middle legs do both (Full, Blickhan & Ting 1991): a fore-aft part of
20 % of the vertical one [E]. The loads are periodic quintic splines through 120 samples per
period (C4; a load need not be smoother than that).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod import Gait, Spline
from legs.cockroach import GAIT_LAWS, STRIDE_PERIOD

LEG_NAMES = ("L1", "L2", "L3", "R1", "R2", "R3")
_POSITION = {"1": "front", "2": "middle", "3": "hind"}


def leg_of(name: str) -> tuple[str, str]:
    """``"L2"`` -> (``"middle"``, ``"L"``)."""
    return _POSITION[name[1]], name[0]


@dataclass(frozen=True)
class GaitPattern:
    name: str
    duty: float
    lift_off: dict[str, float]  # fraction of the period
    blend: float = 0.1  # the phase rate's switch width, a fraction of the period

    def shift(self, leg: str) -> float:
        return (-self.lift_off[leg]) % 1.0

    def joint_laws(self, leg: str = "L1", period: float = STRIDE_PERIOD) -> dict:
        """The drivers' laws of one leg's six joints (joint name -> law)."""
        laws = {}
        for joint, amplitude, shape in GAIT_LAWS:
            a = np.radians(amplitude)
            harmonic = {"sin": {"sin": [a]}, "-cos": {"cos": [-a]}}[shape]
            laws[joint] = Gait(period=period, duty=self.duty, shift=self.shift(leg),
                               blend=self.blend, **harmonic)
        return laws

    def phase_law(self, leg: str, period: float = STRIDE_PERIOD) -> Gait:
        """The leg's phase as a law (``sin`` of it): for the stance test of the phases."""
        return Gait(period=period, duty=self.duty, shift=self.shift(leg), blend=self.blend,
                    sin=[1.0])

    def in_stance(self, leg: str, t, period: float = STRIDE_PERIOD) -> np.ndarray:
        """True where the leg is in stance (phase in [pi, 2 pi) modulo 2 pi)."""
        phi = self.phase_law(leg, period).phase(t)[0] % (2 * np.pi)
        return phi >= np.pi

    def stance_load(self, leg: str, weight: float, period: float = STRIDE_PERIOD,
                    samples: int = 120) -> tuple[Spline, Spline, Spline]:
        """The ground's reaction on the leg's foot (world x, y, z, N) as periodic laws."""
        t = np.linspace(0.0, period, samples + 1)
        phi = self.phase_law(leg, period).phase(t)[0] % (2 * np.pi)
        stance = phi >= np.pi
        progress = np.where(stance, (phi - np.pi) / np.pi, 0.0)
        peak = weight / (6 * self.duty) / 0.5
        vertical = np.where(stance, peak * np.sin(np.pi * progress) ** 2, 0.0)
        position, _ = leg_of(leg)
        fore_aft = {"front": -0.2 * vertical, "hind": 0.2 * vertical,
                    "middle": -0.2 * peak * np.where(stance, np.sin(2 * np.pi * progress),
                                                     0.0)}[position]
        vertical[-1], fore_aft[-1] = vertical[0], fore_aft[0]  # exactly periodic
        laws = [Spline(t, values, degree=5, boundary="periodic")
                for values in (fore_aft, np.zeros_like(t), vertical)]
        return laws[0], laws[1], laws[2]


GAITS = {
    "tripod": GaitPattern("tripod", 0.5, {"L1": 0.0, "R2": 0.0, "L3": 0.0,
                                          "R1": 0.5, "L2": 0.5, "R3": 0.5}),
    "tetrapod": GaitPattern("tetrapod", 2 / 3, {"L3": 0.0, "R2": 0.0, "L2": 1 / 3,
                                                "R1": 1 / 3, "L1": 2 / 3, "R3": 2 / 3}),
    "wave": GaitPattern("wave", 5 / 6, {"L3": 0.0, "L2": 1 / 6, "L1": 2 / 6, "R3": 3 / 6,
                                        "R2": 4 / 6, "R1": 5 / 6}, blend=0.08),
}
