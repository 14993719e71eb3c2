"""The law contract, what the laws share (checks of their numbers, polynomials), and the laws
made of other laws."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike


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

    def breaks(self, start: float, stop: float) -> np.ndarray:
        """The times in ``(start, stop)`` where the law changes regime (a foot touching down
        or lifting off): a derivative jumps there, the law's third or a lower one. An
        adaptive integrator ends a step at each instead of stepping over it and letting its
        error control find it by rejected steps. Sampled laws do not list their samples.
        Default: none."""
        return np.zeros(0)

    def unscaled(self) -> tuple[Law, float]:
        """The law before a unit conversion and the factor applied (itself and 1)."""
        return self, 1.0

    def design_parameter(self, key: str) -> tuple[float, Law] | None:
        """The design parameter ``key`` (a scene key, e.g. ``gait.step_height``) as this law
        holds it: its value, and the law's derivative with respect to it (value, rate and
        acceleration per unit of it, a law of time), for design sensitivities
        (:mod:`hexapod.algorithms.law_tangents`); None when the law does not depend on it
        (the default).

        Raises
        ------
        ValueError
            The law depends on it in a way not derived (a trunk's sway solved from the whole
            motion); the message says how.
        """
        return None

    def symbolic(self, t):
        """Value, first and second derivatives as CasADi expressions of the symbol ``t`` (SX or
        MX), for integrators whose time loop runs in compiled code; None when the law has no
        closed form to offer (such an integrator then calls :meth:`evaluate`)."""
        return None

    #: True when evaluating the law costs far more than interpolating a table of it (a gait's
    #: inverse kinematics solved at every call): a forward simulation, which asks for the
    #: laws at every stage of every step, evaluates such laws once on a grid and interpolates
    #: them to well within its tolerance (:mod:`hexapod.model.tabulation`).
    costly = False

    def batch_key(self):
        """A key shared by the laws of this class that :meth:`evaluate_batch` evaluates
        together at less cost than one by one (the contacts' gates, the columns of one table);
        None (the default): evaluated alone."""
        return None

    @classmethod
    def evaluate_batch(cls, laws, t) -> np.ndarray:
        """Values, rates and accelerations of ``laws`` (of this class, one batch key) at ``t``:
        an array (3, len(laws), *t.shape). The default evaluates them one by one."""
        t = np.asarray(t, dtype=float)
        out = np.empty((3, len(laws)) + t.shape)
        for k, law in enumerate(laws):
            for m, values in enumerate(law.evaluate(t)):
                out[m, k] = values
        return out


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


@dataclass(frozen=True, eq=False)
class DesignShift(Law):
    """A design parameter's change from the scene's value, zero at every time, but a symbol of
    the model where a :class:`Constant` is folded in as a number: the model's Functions then
    depend on it and can be differentiated with respect to it (a joint's frame moved along a
    direction, :func:`hexapod.model.assemble.assemble`'s ``moved_frames``). Compared by
    identity: each is its own parameter."""

    name: str = ""
    kind = "design-shift"

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        return np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)

    def symbolic(self, t):
        return 0 * t, 0 * t, 0 * t

    def design_parameter(self, key):
        """Its own parameter (``key``: its name): the value zero, the derivative one."""
        return (0.0, Constant(1.0)) if key == self.name else None


@dataclass(frozen=True)
class Constant(Law):
    """``f(t) = value``.

    Parameters
    ----------
    value : float
        In the unit of what the law gives (rad, L, N, N m).
    """

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

    def unscaled(self):
        return self.law, self.factor

    def cycle_time(self):
        return self.law.cycle_time()

    def breaks(self, start, stop):
        return self.law.breaks(start, stop)

    def symbolic(self, t):
        inner = self.law.symbolic(t)
        return None if inner is None else tuple(self.factor * x for x in inner)

    def problems(self):
        return self.law.problems()


@dataclass(frozen=True)
class Rate(Law):
    """The first time derivative of ``law``, for elements that read a law's rate as a value (a
    joint controller's target velocity). Its own rate is the law's second derivative; its
    second derivative, which no force element reads, is given as zero."""

    law: Law
    kind = "rate"

    def evaluate(self, t):
        _, fd, fdd = self.law.evaluate(t)
        return fd, fdd, np.zeros_like(np.asarray(fdd, dtype=float))

    def batch_key(self):  # the rates of laws evaluated together (a table's columns): together
        inner = self.law.batch_key()
        return None if inner is None else (type(self.law), inner)

    @classmethod
    def evaluate_batch(cls, laws, t):
        inner = type(laws[0].law).evaluate_batch([law.law for law in laws], t)
        return np.stack([inner[1], inner[2], np.zeros_like(inner[2])])

    def cycle_time(self):
        return self.law.cycle_time()

    def breaks(self, start, stop):
        return self.law.breaks(start, stop)

    def problems(self):
        return self.law.problems()


def rate_of(law: Law) -> Law:
    """``law``'s first time derivative as a law (zero for a constant)."""
    return Constant(0.0) if isinstance(law, Constant) else Rate(law)


def as_law(value) -> Law:
    """A law from a law or a number (a number is a :class:`Constant`)."""
    if isinstance(value, Law):
        return value
    return Constant(float(value))


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


def cycle_breaks(period: float, phases: ArrayLike, start: float, stop: float) -> np.ndarray:
    """The times in ``(start, stop)`` at the fractions ``phases`` of each cycle of ``period``
    (``(k + phase) period`` for every integer ``k``): a periodic law's
    :meth:`Law.breaks`.

    Parameters
    ----------
    period : float
        s.
    phases : array_like
        Fractions of the period (any real numbers: taken modulo 1).
    start, stop : float
        The open window, s.

    Returns
    -------
    ndarray
        The times, sorted, each once (s).
    """
    phases = np.mod(np.asarray(phases, dtype=float), 1.0)
    first, last = math.floor(start / period) - 1, math.ceil(stop / period) + 1
    times = ((np.arange(first, last + 1)[:, None] + phases[None, :]) * period).ravel()
    return np.unique(times[(times > start) & (times < stop)])
