"""Scalar functions of time for drivers and loads: value, first and second derivative.

The model's CasADi functions never see ``t``: they take the values and derivatives of every law as
inputs (see :mod:`hexapod.model.assemble`), so a law can be anything that returns ``f, f', f''`` for
an array of times. Drivers need laws that are at least C2 (a prescribed motion enters through its
second derivative).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache

import numpy as np


class Law:
    """Base class: a scalar function of time, C2 at least."""

    #: Short name used in scene files (``type = "..."``).
    kind: str = ""

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Value, first and second time derivatives at ``t`` (scalar or array), shaped like t."""
        raise NotImplementedError

    def __call__(self, t):
        return self.evaluate(t)[0]

    def scaled(self, factor: float) -> Law:
        """The law multiplied by ``factor`` (unit conversion); the law itself for 1."""
        return self if factor == 1.0 else self._scaled(factor)

    def _scaled(self, factor: float) -> Law:
        return Scaled(self, factor)

    def problems(self) -> list[str]:
        """What is wrong with the law's own numbers (empty when it is fine)."""
        return []

    def cycle_time(self) -> float | None:
        """The time after which the law repeats itself, None when it does not (or when it is
        constant, which repeats at any time)."""
        return None

    def symbolic(self, t):
        """Value, first and second derivatives as CasADi expressions of the symbol ``t`` (SX or
        MX), for integrators whose time loop runs in compiled code; None when the law has no
        closed form to offer (such an integrator then calls :meth:`evaluate`)."""
        return None


def _finite(values) -> bool:
    return bool(np.all(np.isfinite(np.asarray(values, dtype=float))))


#: The largest magnitude of a law's numbers: a force of 1e15 N, an angle of 1e15 rad or a time
#: of 1e15 s is nothing a legged machine meets, and products of a few stay far from overflow.
LARGEST_NUMBER = 1e15
#: The closest two samples of a table may be, as a fraction of its span and never below a
#: nanosecond: the derivatives are differences over the spacing (its square for accelerations),
#: so closer samples make them 1e18 times the values, nothing but round-off.
CLOSEST_SAMPLES = 1e-9
#: The shortest period of a gait, s: its accelerations go as 1 / period^2.
SHORTEST_PERIOD = 1e-6


def _size_problem(*groups) -> str:
    """A number of ``groups`` beyond :data:`LARGEST_NUMBER` in magnitude, or ''."""
    largest = max(float(np.max(np.abs(np.asarray(g, dtype=float)), initial=0.0)) for g in groups)
    return (f"holds a number of magnitude {largest:.3g}, beyond the 1e15 a law may hold"
            if largest > LARGEST_NUMBER else "")


def _spacing_problem(times) -> str:
    """Samples too close together for their derivatives to mean anything, or ''."""
    times = np.asarray(times, dtype=float)
    if times.size < 2:
        return ""
    spacing = np.diff(times)
    span = times[-1] - times[0]
    closest = CLOSEST_SAMPLES * max(span, 1.0)
    if spacing.min() < closest:
        k = int(np.argmin(spacing))
        return (f"the samples cannot be interpolated: times {float(times[k])!r} and "
                f"{float(times[k + 1])!r} s are {spacing[k]:.3g} s apart, closer than "
                f"{closest:.3g} s (a billionth of the span, at least a nanosecond), where the "
                "derivatives would be meaningless")
    return ""


def _derivative(coefficients) -> tuple[float, ...]:
    """The coefficients (ascending powers) of a polynomial's derivative, as NumPy's ``polyder``
    computes them (``(0.0,)`` for a constant)."""
    return tuple(k * float(coefficients[k]) for k in range(1, len(coefficients))) or (0.0,)


def _horner(s, coefficients):
    """The polynomial of ``coefficients`` (ascending powers) at ``s``, by Horner's rule in the
    order of NumPy's ``polyval`` (the same numbers to the last bit, without loading
    ``numpy.polynomial``: 7 ms of a command's start)."""
    out = coefficients[-1] + s * 0.0
    for a in coefficients[-2::-1]:
        out = a + out * s
    return out


@dataclass(frozen=True)
class Constant(Law):
    """``f(t) = value``."""

    value: float
    kind = "constant"

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        return np.full_like(t, self.value), np.zeros_like(t), np.zeros_like(t)

    def symbolic(self, t):
        return self.value + 0 * t, 0 * t, 0 * t

    def _scaled(self, factor):
        return Constant(self.value * factor)

    def problems(self):
        if not math.isfinite(self.value):
            return [f"value is not finite: {self.value}"]
        size = _size_problem(self.value)
        return [size] if size else []


@dataclass(frozen=True)
class Polynomial(Law):
    """``f(t) = sum_k c_k (t - t0)^k``, coefficients in ascending powers."""

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


_BOUNDARY = {"not-a-knot": None, "natural": "natural", "clamped": "clamped",
             "periodic": "periodic"}


@dataclass(frozen=True)
class Spline(Law):
    """Interpolating spline through tabulated samples ``(times, values)``.

    ``degree`` 3 (C2, the default) or 5 (C4); ``boundary`` one of ``not-a-knot``, ``natural``,
    ``clamped`` (zero end slopes) or ``periodic`` (values at both ends must be equal). Outside the
    table the end polynomials are continued (periodic splines repeat).
    """

    times: tuple[float, ...]
    values: tuple[float, ...]
    degree: int = 3
    boundary: str = "not-a-knot"
    _spline: object = field(default=None, init=False, repr=False, compare=False)
    _failure: str = field(default="", init=False, repr=False, compare=False)
    kind = "spline"

    def __post_init__(self):
        object.__setattr__(self, "times", tuple(float(x) for x in self.times))
        object.__setattr__(self, "values", tuple(float(y) for y in self.values))
        if not self._sample_problems():
            object.__setattr__(self, "_spline", self._fit())

    def _fit(self):
        from scipy.interpolate import make_interp_spline

        bc = _BOUNDARY[self.boundary]
        if self.degree == 5 and bc in ("natural", "clamped"):
            # quintic ends: clamped fixes the 1st and 2nd derivatives, natural the 3rd and 4th
            order = 1 if bc == "clamped" else 3
            ends = [(order, 0.0), (order + 1, 0.0)]
            bc = (ends, ends)
        try:
            spline = make_interp_spline(self.times, self.values, k=self.degree, bc_type=bc)
        except (ValueError, ArithmeticError, np.linalg.LinAlgError) as error:
            object.__setattr__(self, "_failure", f"the samples cannot be interpolated ({error})")
            return None
        if not np.all(np.isfinite(spline.c)):
            object.__setattr__(self, "_failure", "the samples cannot be interpolated (times "
                               "too close together for floating point)")
            return None
        if self.boundary == "periodic":
            spline.extrapolate = "periodic"
        return spline

    def evaluate(self, t):
        if self._spline is None:
            raise ValueError("spline law is invalid: " + "; ".join(self.problems()))
        t = np.asarray(t, dtype=float)
        s = self._spline
        return s(t), s(t, nu=1), s(t, nu=2)

    def cycle_time(self):
        return self.times[-1] - self.times[0] if self.boundary == "periodic" else None

    def _scaled(self, factor):
        return Spline(self.times, tuple(v * factor for v in self.values), self.degree,
                      self.boundary)

    def problems(self):
        return self._sample_problems() or ([self._failure] if self._failure else [])

    def _sample_problems(self):
        out = []
        if self.degree not in (3, 5):
            out.append(f"degree must be 3 or 5 (C2 at least), got {self.degree}")
            return out
        if self.boundary not in _BOUNDARY:
            out.append(f"boundary must be one of {', '.join(_BOUNDARY)}, got {self.boundary!r}")
            return out
        if len(self.times) != len(self.values):
            out.append(f"{len(self.times)} times but {len(self.values)} values")
            return out
        if len(self.times) < self.degree + 1:
            out.append(f"a degree-{self.degree} spline needs at least {self.degree + 1} samples,"
                       f" got {len(self.times)}")
        if not _finite(self.times) or not _finite(self.values):
            out.append("times or values are not finite")
        elif np.any(np.diff(self.times) <= 0):
            out.append("times must be strictly increasing")
        elif self.boundary == "periodic" and self.values[0] != self.values[-1]:
            out.append("a periodic spline needs equal first and last values")
        else:
            out.append(_size_problem(self.times, self.values) or _spacing_problem(self.times))
        return [problem for problem in out if problem]


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
_QUINTIC_HERMITE = (
    (1, 0, 0, -10, 15, -6), (0, 1, 0, -6, 8, -3), (0, 0, 0.5, -1.5, 1.5, -0.5),
    (0, 0, 0, 10, -15, 6), (0, 0, 0, -4, 7, -3), (0, 0, 0, 0.5, -1, 0.5),
)
#: Each basis polynomial with its first and second derivatives.
_QUINTIC_HERMITE_RATES = tuple((tuple(map(float, c)), _derivative(c), _derivative(_derivative(c)))
                               for c in _QUINTIC_HERMITE)


@dataclass(frozen=True, eq=False)
class Hermite(Law):
    """Tabulated values with their first and second derivatives: the quintic Hermite
    interpolant, C2, equal to the given values, rates and accelerations at every sample (a
    motion file with exact derivatives). Outside the table the end polynomials are continued."""

    times: np.ndarray
    values: np.ndarray
    rates: np.ndarray
    accelerations: np.ndarray
    _table: object = field(default=None, init=False, repr=False, compare=False)
    kind = "hermite"

    def __post_init__(self):
        for key in ("times", "values", "rates", "accelerations"):  # arrays: motions are long
            object.__setattr__(self, key, np.asarray(getattr(self, key), dtype=float).ravel())
        if not self.problems():
            object.__setattr__(self, "_table", np.array(
                [self.times, self.values, self.rates, self.accelerations]))

    def evaluate(self, t):
        """On each interval ``[t0, t1]`` of length ``h``, with ``s = (t - t0) / h``, the quintic
        ``sum_k f_k H_k(s)`` through the end values ``(y, h y', h^2 y'')`` (the standard quintic
        Hermite basis); outside the table the end interval's polynomial continues."""
        if self._table is None:
            raise ValueError("hermite law is invalid: " + "; ".join(self.problems()))
        times, y, yd, ydd = self._table
        t = np.asarray(t, dtype=float)
        i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, times.size - 2)
        h = times[i + 1] - times[i]
        s = (t - times[i]) / h
        ends = (y[i], h * yd[i], h * h * ydd[i], y[i + 1], h * yd[i + 1], h * h * ydd[i + 1])
        f = fd = fdd = 0.0
        for (c, c1, c2), end in zip(_QUINTIC_HERMITE_RATES, ends, strict=True):
            f = f + end * _horner(s, c)
            fd = fd + end * _horner(s, c1) / h
            fdd = fdd + end * _horner(s, c2) / h**2
        return f, fd, fdd

    def _scaled(self, factor):
        return Hermite(self.times, self.values * factor, self.rates * factor,
                       self.accelerations * factor)

    def problems(self):
        n = self.times.size
        if any(getattr(self, k).size != n for k in ("values", "rates", "accelerations")):
            return [f"{n} times but {len(self.values)} values, {len(self.rates)} rates and "
                    f"{len(self.accelerations)} accelerations"]
        if n < 2:
            return ["needs at least 2 samples"]
        if not all(_finite(getattr(self, k)) for k in ("times", "values", "rates",
                                                        "accelerations")):
            return ["times, values, rates or accelerations are not finite"]
        if np.any(np.diff(self.times) <= 0):
            return ["times must be strictly increasing"]
        numbers = (_size_problem(self.times, self.values, self.rates, self.accelerations)
                   or _spacing_problem(self.times))
        return [numbers] if numbers else []


@dataclass(frozen=True)
class Expression(Law):
    """``f(t)`` written as an expression of ``t``, e.g. ``asin(r*sin(w*t))``.

    The grammar (numbers, ``t``, ``pi``, ``e``, the law's constants, ``+ - * / ^``, functions
    and ``if_else``) is that of :mod:`hexapod.scene.expression`; the text is parsed by our own
    parser, never evaluated by Python. The derivatives are exact: CasADi differentiates the
    expression twice, and the three are compiled once per law into one function.

    Parameters
    ----------
    expression : str
        The expression.
    constants : mapping or sequence of (name, value) pairs
        Named numbers the expression uses; stored as pairs sorted by name.
    period : float, optional
        The time after which the law repeats, as the user asserts it (not checked): the
        duration of one cycle of a report or a simulation.

    Notes
    -----
    The expression is checked when the law is, not evaluated: a value outside a function's
    domain (``asin`` of more than 1, ``log`` of a negative number) gives NaN at the times it
    occurs, and a run that meets it fails as non-finite. A driver needs a law that is C2:
    ``abs``, ``min``, ``max`` and ``if_else`` give kinks and jumps unless the pieces meet with
    equal values and first and second derivatives.
    """

    expression: str
    constants: tuple[tuple[str, float], ...] = ()
    period: float | None = None
    _function: object = field(default=None, init=False, repr=False, compare=False)
    _problems: tuple[str, ...] | None = field(default=None, init=False, repr=False,
                                              compare=False)
    kind = "expression"

    def __post_init__(self):
        pairs = (self.constants.items() if isinstance(self.constants, Mapping)
                 else self.constants)
        object.__setattr__(self, "constants", tuple(sorted(
            ((name, float(value)) for name, value in pairs), key=lambda pair: str(pair[0]))))
        if self.period is not None:
            object.__setattr__(self, "period", float(self.period))

    def __getstate__(self):
        # a compiled CasADi function stays behind: scenes are pickled to worker processes
        return {**self.__dict__, "_function": None}

    def _compiled(self):
        """The CasADi function ``t -> (f, f', f'')``, built on first use."""
        if self._function is None:
            problems = self.problems()
            if problems:
                raise ValueError("expression law is invalid: " + "; ".join(problems))
            import casadi as ca

            from hexapod.scene.expression import parse, to_casadi

            constants = dict(self.constants)
            t = ca.SX.sym("t")
            f = to_casadi(parse(self.expression, constants), t, constants)
            fd = ca.jacobian(f, t)
            object.__setattr__(self, "_function",
                               ca.Function("law", [t], [f, fd, ca.jacobian(fd, t)]))
        return self._function

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        function = self._compiled()
        if t.ndim == 0:
            return tuple(np.array(float(x)) for x in function(float(t)))
        if t.size == 0:
            return np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)
        # all samples in one call of the function mapped over them
        out = function.map(t.size)(t.reshape(1, -1))
        return tuple(x.full().reshape(t.shape) for x in out)

    def symbolic(self, t):
        return tuple(self._compiled()(t))

    def cycle_time(self):
        return self.period

    def _scaled(self, factor):
        return Expression(f"{float(factor)!r}*({self.expression})", self.constants, self.period)

    def problems(self):
        if self._problems is None:
            object.__setattr__(self, "_problems", tuple(self._find_problems()))
        return list(self._problems)

    def _find_problems(self) -> list[str]:
        # the parser is loaded by the scenes that use it: a leg driven by a motion file starts
        # without it
        from hexapod.scene.expression import (
            MOST_CONSTANTS,
            ExpressionError,
            constant_problem,
            parse,
        )

        out = []
        if len(self.constants) > MOST_CONSTANTS:
            out.append(f"constants: {len(self.constants)} given, at most {MOST_CONSTANTS}")
            names = []
        else:
            names = [name for name, _ in self.constants if not constant_problem(name)]
            out += [f"constants: {constant_problem(name)}" for name, _ in self.constants
                    if constant_problem(name)]
            out += [f"constants: '{name}' is given twice"
                    for name, count in Counter(names).items() if count > 1]
            for name, value in self.constants:
                if not math.isfinite(value):
                    out.append(f"constants: {name!r} is not finite: {value}")
                elif _size_problem(value):
                    out.append(f"constants: {name!r} {_size_problem(value)}")
        if self.period is not None and not (math.isfinite(self.period) and self.period > 0):
            out.append(f"period must be positive and finite, got {self.period}")
        elif self.period is not None and _size_problem(self.period):
            out.append(f"period {_size_problem(self.period)}")
        if not isinstance(self.expression, str):
            out.append(f"expression must be a string, got {self.expression!r}")
        else:
            try:
                parse(self.expression, names, largest=LARGEST_NUMBER)
            except ExpressionError as error:
                out.append(f"expression: {error}")
        return out


@dataclass(frozen=True)
class Scaled(Law):
    """``factor * law(t)``."""

    law: Law
    factor: float
    kind = "scaled"

    def evaluate(self, t):
        f, fd, fdd = self.law.evaluate(t)
        return self.factor * f, self.factor * fd, self.factor * fdd

    def _scaled(self, factor):
        return Scaled(self.law, self.factor * factor)

    def cycle_time(self):
        return self.law.cycle_time()

    def symbolic(self, t):
        inner = self.law.symbolic(t)
        return None if inner is None else tuple(self.factor * x for x in inner)

    def problems(self):
        return self.law.problems()


def as_law(value) -> Law:
    """A law from a law or a number (a number is a :class:`Constant`)."""
    if isinstance(value, Law):
        return value
    return Constant(float(value))


#: Law classes by the ``type`` used in scene files.
LAW_TYPES: dict[str, type[Law]] = {
    cls.kind: cls for cls in (Constant, Polynomial, Harmonic, Spline, Hermite, Gait,
                              Expression)
}


@cache
def law_types() -> dict[str, type[Law]]:
    """The law classes by the ``type`` of scene files: the engine's (:data:`LAW_TYPES`), and
    those installed packages register in the entry-point group ``hexapod.laws`` (the ``legs``
    package registers its exact gait laws there), so that a scene written with them reads
    back. Looked up once per process (a scene file has a law per driver)."""
    from importlib.metadata import entry_points

    out = dict(LAW_TYPES)
    for entry in entry_points(group="hexapod.laws"):
        if entry.name not in out:
            out[entry.name] = entry.load()
    return out


class LawOnJoint:
    """What an element driven by one time law along one joint's coordinate shares (a joint
    driver, a joint effort): ``law`` taken as a :class:`Law`, its problems reported under the key
    ``law``, scaled with the element (the scene passes the unit factor of the coordinate or the
    effort, 1 for angles and forces) and the joint's name prefixed when attached."""

    def __post_init__(self):
        self.law = as_law(self.law)

    def problems(self):
        return [self.problem("law", message) for message in self.law.problems()]

    def scaled(self, length):
        out = super().scaled(length)
        out.law = self.law.scaled(length)
        return out

    def attached(self, attachment):
        out = super().attached(attachment)
        out.joint = attachment.name(self.joint)
        return out
