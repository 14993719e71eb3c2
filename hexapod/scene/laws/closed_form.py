"""Laws in closed form: a polynomial, a harmonic series (a constant is in ``base``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hexapod.scene.laws.base import (
    Law,
    _derivative,
    _finite,
    _horner,
    _size_problem,
)


@dataclass(frozen=True)
class Polynomial(Law):
    """``f(t) = sum_k c_k (t - t0)^k``, coefficients in ascending powers.

    Parameters
    ----------
    coefficients : sequence of float
        ``c_0, c_1, ...``, in the law's unit per s^k.
    t0 : float
        The time origin, s.
    """

    coefficients: tuple[float, ...]
    t0: float = 0.0
    kind = "polynomial"

    def __post_init__(self):
        object.__setattr__(self, "coefficients", tuple(float(c) for c in self.coefficients))

    def evaluate(self, t):
        s = np.asarray(t, dtype=float) - self.t0
        coef = self.coefficients if self.coefficients else (0.0,)
        d1 = _derivative(coef)
        d2 = _derivative(d1)
        return _horner(s, coef), _horner(s, d1), _horner(s, d2)

    def symbolic(self, t):
        coef = self.coefficients if self.coefficients else (0.0,)
        d1 = _derivative(coef)
        d2 = _derivative(d1)
        s = t - self.t0

        def horner(a):
            out = 0 * t + a[-1]
            for x in a[-2::-1]:
                out = out * s + x
            return out

        return horner(coef), horner(d1), horner(d2)

    def _scaled(self, factor):
        return Polynomial(tuple(c * factor for c in self.coefficients), self.t0)

    def problems(self):
        out = []
        if not self.coefficients:
            out.append("coefficients are empty")
        if not _finite(self.coefficients) or not math.isfinite(self.t0):
            out.append("coefficients or t0 are not finite")
        else:
            out.append(_size_problem(self.coefficients, self.t0))
        return [problem for problem in out if problem]


@dataclass(frozen=True)
class Harmonic(Law):
    """``f(t) = offset + sum_k a_k cos(k w (t - t0)) + b_k sin(k w (t - t0))``, w = 2 pi frequency.

    ``cos[k-1]`` and ``sin[k-1]`` are the amplitudes of harmonic ``k``; ``frequency`` in Hz.

    Parameters
    ----------
    offset : float
        The mean value, in the law's unit.
    cos, sin : sequence of float
        The amplitudes of harmonics 1, 2, ..., in the law's unit.
    frequency : float
        The fundamental frequency, Hz (positive).
    t0 : float
        The time origin, s.
    """

    offset: float = 0.0
    cos: tuple[float, ...] = ()
    sin: tuple[float, ...] = ()
    frequency: float = 1.0
    t0: float = 0.0
    kind = "harmonic"

    def __post_init__(self):
        object.__setattr__(self, "cos", tuple(float(a) for a in self.cos))
        object.__setattr__(self, "sin", tuple(float(b) for b in self.sin))

    def evaluate(self, t):
        s = np.asarray(t, dtype=float) - self.t0
        a, b, kw = _harmonic_arrays(self.cos, self.sin, 2.0 * np.pi * self.frequency)
        if not kw.size:
            return np.full_like(s, self.offset), np.zeros_like(s), np.zeros_like(s)
        # all harmonics at once: one cos and one sin of the (samples x harmonics) angles
        angle = np.multiply.outer(s, kw)
        c, n = np.cos(angle), np.sin(angle)
        f = self.offset + c @ a + n @ b
        fd = n @ (-a * kw) + c @ (b * kw)
        fdd = -(c @ (a * kw**2) + n @ (b * kw**2))
        return f, fd, fdd

    def cycle_time(self):
        return 1.0 / self.frequency if (self.cos or self.sin) else None

    def symbolic(self, t):
        import casadi as ca

        a, b, kw = _harmonic_arrays(self.cos, self.sin, 2.0 * np.pi * self.frequency)
        if not kw.size:
            return self.offset + 0 * t, 0 * t, 0 * t
        # all harmonics as one vector expression (a series of hundreds of terms stays cheap)
        angle = ca.DM(kw) * (t - self.t0)
        c, n = ca.cos(angle), ca.sin(angle)

        def dot(weights, x):
            return ca.dot(ca.DM(weights), x)

        return (self.offset + dot(a, c) + dot(b, n), dot(b * kw, c) - dot(a * kw, n),
                -(dot(a * kw**2, c) + dot(b * kw**2, n)))

    def _scaled(self, factor):
        return Harmonic(self.offset * factor, tuple(a * factor for a in self.cos),
                        tuple(b * factor for b in self.sin), self.frequency, self.t0)

    def problems(self):
        out = []
        if not _finite([self.offset, self.frequency, self.t0, *self.cos, *self.sin]):
            out.append("offset, amplitudes, frequency or t0 are not finite")
        elif self.frequency <= 0:
            out.append(f"frequency must be positive, got {self.frequency}")
        else:
            out.append(_size_problem([self.offset, self.frequency, self.t0, *self.cos,
                                      *self.sin]))
        return [problem for problem in out if problem]


def _harmonic_arrays(cos, sin, rate: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cosine and sine amplitudes padded to one length, and the harmonics' rates k * rate."""
    n = max(len(cos), len(sin))
    a, b = np.zeros(n), np.zeros(n)
    a[:len(cos)], b[:len(sin)] = cos, sin
    return a, b, rate * np.arange(1, n + 1)
