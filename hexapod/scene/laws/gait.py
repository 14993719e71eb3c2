"""A gait's periodic joint law: stance and swing joined by smooth steps."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.scene.laws.base import SHORTEST_PERIOD, Law, _finite, _size_problem
from hexapod.scene.laws.closed_form import _harmonic_arrays


def _smootherstep(u):
    """Quintic smooth step on [0, 1]: 0 to 1 with zero first and second derivatives at both
    ends (so a rate blended with it is C2 and its integral, the phase, C3)."""
    return u**3 * (10 - 15 * u + 6 * u**2)


def _smootherstep_integral(u):
    return u**4 * (2.5 - 3 * u + u**2)


def _smootherstep_slope(u):
    return 30 * u**2 * (1 - u) ** 2


@dataclass(frozen=True)
class Gait(Law):
    """A harmonic series in a duty-factor-warped phase: the joint laws of a gait.

    ``f(t) = offset + sum_k cos[k-1] cos(k phi) + sin[k-1] sin(k phi)``. The phase ``phi`` runs
    from 0 to 2 pi over each ``period``: through (0, pi) during swing, a fraction
    ``1 - duty`` of the period, and through (pi, 2 pi) during stance, the fraction ``duty``. The
    cycle starts (``phi = 0``, lift-off) at ``t = -shift * period`` (modulo the period), so legs
    differ by their ``shift``. The phase rate changes from its swing value to its stance value
    over ``blend`` (a fraction of the period) around each switch with a quintic smooth step, so
    the law is C2; the two rates are chosen so that the phase is exactly pi at touch-down and
    2 pi at lift-off. With ``duty = 0.5`` the phase is uniform (``blend`` plays no part).

    Parameters
    ----------
    offset : float
        The mean value, in the law's unit (rad for a joint angle).
    cos, sin : sequence of float
        The amplitudes of harmonics 1, 2, ... of the warped phase, in the law's unit.
    period : float
        The gait's period, s.
    duty : float
        The stance's fraction of the period.
    shift : float
        The leg's phase shift, a fraction of the period.
    blend : float
        The width of the phase rate's change around each switch, a fraction of the period.
    """

    offset: float = 0.0
    cos: tuple[float, ...] = ()
    sin: tuple[float, ...] = ()
    period: float = 1.0
    duty: float = 0.5
    shift: float = 0.0
    blend: float = 0.1
    kind = "gait"

    def __post_init__(self):
        object.__setattr__(self, "cos", tuple(float(a) for a in self.cos))
        object.__setattr__(self, "sin", tuple(float(b) for b in self.sin))

    def _pieces(self) -> tuple[float, float]:
        """The swing share of the cycle and the blends' half-width."""
        return 1.0 - self.duty, self.blend / 2

    def _rates(self) -> tuple[float, float]:
        """Swing and stance rates (per cycle) that give phase pi at tau = a and 2 pi at 1."""
        a, d = self._pieces()
        # the phase at a: swing rate over [d, a - d], the blends' halves around 0 and a
        # contribute (per unit of rate) the integrals of the smooth step over their parts
        half = _smootherstep_integral(0.5)  # integral of the step over [0, 1/2]
        # over [0, d]: rate = stance + (swing - stance) S(u), u from 1/2 to 1
        # over [a - d, a]: rate = swing + (stance - swing) S(u), u from 0 to 1/2
        swing_at_a = (a - 2 * d) + 2 * d * (0.5 - half) + 2 * d * (0.5 - half)
        stance_at_a = 2 * d * half + 2 * d * half
        # over the whole cycle each rate holds for its own share
        A = np.array([[swing_at_a, stance_at_a], [a, 1.0 - a]])
        return tuple(np.linalg.solve(A, [np.pi, 2 * np.pi]))

    def phase(self, t):
        """The warped phase, its first and second time derivatives (unwrapped: 2 pi per cycle)."""
        t = np.asarray(t, dtype=float)
        x = t / self.period + self.shift
        cycles = np.floor(x)
        tau = x - cycles
        if self.duty == 0.5:
            return (2 * np.pi * x, np.full_like(x, 2 * np.pi / self.period), np.zeros_like(x))
        a, d = self._pieces()
        swing, stance = self._rates()
        step, integral, slope = _smootherstep, _smootherstep_integral, _smootherstep_slope
        # breakpoints of the rate over the cycle and the phase reached at each
        edges = [0.0, d, a - d, a + d, 1.0 - d, 1.0]
        rate = np.zeros_like(tau)
        rate_d = np.zeros_like(tau)
        phi = np.zeros_like(tau)
        start = 0.0
        for k in range(5):
            lo, hi = edges[k], edges[k + 1]
            inside = (tau >= lo) & (tau < hi) if k < 4 else (tau >= lo)
            s = tau[inside] - lo
            if k in (1, 3):  # constant rate
                r0 = swing if k == 1 else stance
                rate[inside], phi[inside] = r0, start + r0 * s
                start += r0 * (hi - lo)
                continue
            # blends: from r0 to r1 over a width 2d; pieces 0 and 4 are its halves
            r0, r1 = (stance, swing) if k in (0, 4) else (swing, stance)
            u0 = {0: 0.5, 2: 0.0, 4: 0.0}[k]
            u = u0 + s / (2 * d)
            rate[inside] = r0 + (r1 - r0) * step(u)
            rate_d[inside] = (r1 - r0) * slope(u) / (2 * d)
            phi[inside] = start + r0 * s + (r1 - r0) * 2 * d * (integral(u) - integral(u0))
            u_end = u0 + (hi - lo) / (2 * d)
            start += r0 * (hi - lo) + (r1 - r0) * 2 * d * (integral(u_end) - integral(u0))
        return (2 * np.pi * cycles + phi, rate / self.period, rate_d / self.period**2)

    def evaluate(self, t):
        phi, phi_d, phi_dd = self.phase(t)
        a, b, k = _harmonic_arrays(self.cos, self.sin, 1.0)
        if not k.size:
            return np.full_like(phi, self.offset), np.zeros_like(phi), np.zeros_like(phi)
        angle = np.multiply.outer(phi, k)
        c, n = np.cos(angle), np.sin(angle)
        value_d = n @ (-a * k) + c @ (b * k)  # d/dphi
        value_dd = -(c @ (a * k**2) + n @ (b * k**2))
        return (self.offset + c @ a + n @ b, value_d * phi_d,
                value_dd * phi_d**2 + value_d * phi_dd)

    def cycle_time(self):
        return self.period if (self.cos or self.sin) else None

    def _scaled(self, factor):
        return Gait(self.offset * factor, tuple(a * factor for a in self.cos),
                    tuple(b * factor for b in self.sin), self.period, self.duty, self.shift,
                    self.blend)

    def problems(self):
        values = [self.offset, self.period, self.duty, self.shift, self.blend, *self.cos,
                  *self.sin]
        if not _finite(values):
            return ["offset, amplitudes, period, duty, shift or blend are not finite"]
        if _size_problem(values):
            return [_size_problem(values)]
        out = []
        if not self.period >= SHORTEST_PERIOD:
            out.append(f"period must be at least {SHORTEST_PERIOD:g} s, got {self.period}")
        if not 0 < self.duty < 1:
            out.append(f"duty must be between 0 and 1, got {self.duty}")
        elif not 0 < self.blend <= min(self.duty, 1 - self.duty):
            out.append(f"blend must be positive and at most the shorter of swing and stance "
                       f"({min(self.duty, 1 - self.duty):.3g} of the period), got {self.blend}")
        elif self.duty != 0.5 and min(self._rates()) <= 0:
            out.append("the phase would run backwards: use a smaller blend")
        return out


#: The quintic Hermite basis on [0, 1], ascending powers: the polynomials with value, first and
#: second derivative 1 for one end quantity and 0 for the five others, in the order
#: (y0, y0', y0'', y1, y1', y1'').
