"""Gaits: which legs swing together, for how long, and the laws that follow from it.

A gait gives each leg a **lift-off time** (a fraction of the period) and all legs one **duty
factor** (the fraction of the cycle in stance). A leg's cycle fraction ``tau = t / T - lift_off``
(modulo 1) runs through swing, ``[0, 1 - duty)``, then stance; its joints follow the laws of
:mod:`legs.stepping`, which put its foot on the ground in stance, moving backwards at the walking
speed, and lift it in swing (the laws are harmonic series in time, C-infinity, started at the
leg's lift-off time).

================  ====  ==============================================================
gait              duty  lift-off times (fraction of the period)
================  ====  ==============================================================
tripod            1/2   L1, R2, L3 at 0; R1, L2, R3 at 1/2 (Delcomyn 1971)
tetrapod          2/3   L3, R2 at 0; L2, R1 at 1/3; L1, R3 at 2/3: back to front
wave (ripple)     5/6   one leg at a time, back to front: L3 0, L2 1/6, L1 2/6, R3 3/6,
                        R2 4/6, R1 5/6
================  ====  ==============================================================

**Stance loads** (the "variation laws of the generalized forces" of Dumitru, Marin and Margine): the
ground's reaction on a foot during stance, ``sin^2`` of the stance progress times its peak, zero in
swing. The peak makes the legs in stance carry the weight on average: ``W / (6 duty) / (1/2)``.
Front legs brake, hind legs propel and middle legs do both (Full, Blickhan & Ting 1991): a fore-aft
part of 20 % of the vertical one [E]. The loads are periodic quintic splines through 120 samples per
period (C4; a load need not be smoother than that).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.scene import Harmonic, Spline
from legs.cockroach import MODEL_SCALE, STANCE_LENGTH_MM, STRIDE_PERIOD, THC_POINT_MM
from legs.stepping import path_targets, stepping_harmonics

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

    def cycle_fraction(self, leg: str, t, period: float = STRIDE_PERIOD) -> np.ndarray:
        """Where the leg is in its cycle at ``t``: 0 at lift-off, 1 - duty at touch-down."""
        return (np.asarray(t, dtype=float) / period - self.lift_off[leg]) % 1.0

    def in_stance(self, leg: str, t, period: float = STRIDE_PERIOD) -> np.ndarray:
        return self.cycle_fraction(leg, t, period) >= 1.0 - self.duty

    def walking_speed(self, period: float = STRIDE_PERIOD, scale: float = MODEL_SCALE) -> float:
        """The trunk's speed over the ground, the feet's in stance relative to it (m/s)."""
        return STANCE_LENGTH_MM * 1e-3 * scale / (self.duty * period)

    def period_for_speed(self, speed: float, scale: float = MODEL_SCALE) -> float:
        """The stride period (s) at which the trunk walks at ``speed`` (m/s): the inverse of
        :meth:`walking_speed` (inversely proportional to the period)."""
        return self.walking_speed(1.0, scale) / speed

    def least_duty(self, feet: int = 3) -> float:
        """The smallest duty factor that keeps at least ``feet`` feet on the ground at every
        instant (a foot touching down as another lifts off counts as down): the number of feet
        down is least just after a lift-off."""
        need = []
        for leg in LEG_NAMES:
            # leg k is in stance at leg's lift-off when (l - l_k) mod 1 >= 1 - duty
            gaps = sorted(1.0 - (self.lift_off[leg] - self.lift_off[k]) % 1.0
                          for k in LEG_NAMES if k != leg)
            need.append(gaps[feet - 1])
        return max(need)

    def foot_targets(self, t, period: float = STRIDE_PERIOD, scale: float = MODEL_SCALE,
                     lengths=None) -> dict[str, np.ndarray]:
        """Where each foot is designed to be at times ``t`` (N, 3 per leg; m, in the trunk
        frame of :func:`legs.robot.hexapod_scene`): its leg's path, mirrored on the right,
        from its thorax-coxa point; the legs' segment ``lengths`` as in
        :func:`legs.stepping.path_targets`."""
        out = {}
        for leg in LEG_NAMES:
            position, side = leg_of(leg)
            path = path_targets(position, self.cycle_fraction(leg, t, period), self.duty, scale,
                                lengths)
            thc = np.array(THC_POINT_MM[position]) * 1e-3 * scale
            if side == "R":
                path[:, 1], thc[1] = -path[:, 1], -thc[1]
            out[leg] = path + thc
        return out

    def joint_laws(self, leg: str = "L1", period: float = STRIDE_PERIOD, lengths=None) -> dict:
        """The drivers' laws of one leg's six joints (joint name -> law): its foot follows its
        path (:mod:`legs.stepping`); the leg's segment ``lengths`` (a tuple of the four factors,
        None: all 1)."""
        position, _ = leg_of(leg)
        return {joint: Harmonic(offset, cos, sin, frequency=1.0 / period,
                                t0=self.lift_off[leg] * period)
                for joint, (offset, cos, sin) in stepping_harmonics(position, self.duty,
                                                                    lengths=lengths).items()}

    def stance_load(self, leg: str, weight: float, period: float = STRIDE_PERIOD,
                    samples: int = 120) -> tuple[Spline, Spline, Spline]:
        """The ground's reaction on the leg's foot (world x, y, z, N) as periodic laws."""
        t = np.linspace(0.0, period, samples + 1)
        tau = self.cycle_fraction(leg, t, period)
        stance = tau >= 1.0 - self.duty
        progress = np.where(stance, (tau - (1.0 - self.duty)) / self.duty, 0.0)
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
                                        "R2": 4 / 6, "R1": 5 / 6}),
}
