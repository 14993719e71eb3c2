"""The efforts of the walking hexapod's inverse dynamics as laws of time, for its forward twin
(:mod:`legs.replay`).

The inverse efforts are smooth between the times :func:`effort_breaks` lists and lose
smoothness there: each foot's touch-down and lift-off (its rows and its path switch) and the
ends of its load ramps (the load-sharing weight, a quintic smooth step clipped to 1, is C2
there). Each effort is therefore a separate quintic spline (not-a-knot, the interpolant of
:class:`hexapod.scene.Spline` of degree 5) on each interval between consecutive breaks, exact at
every sample (:class:`EffortTable`). Close to a switch the efforts change fast but smoothly;
uniform samples would need some 0.2 ms steps all along, so :func:`adaptive_inverse` instead
bisects, round after round, the intervals whose midpoint the spline misses, until each joint's
effort is within ``tol`` of its largest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import hexapod as hx
from hexapod import Scene
from hexapod.scene import Contact, Law, cycle_breaks

#: Degree of the effort splines (C4; 5 is the largest :class:`hexapod.scene.Spline` offers).
EFFORT_DEGREE = 5
#: Mean step of the first samples of :func:`adaptive_inverse` (s).
EFFORT_SPACING = 10e-3
#: Default relative accuracy of the effort splines (each joint's, of its largest effort).
EFFORT_TOL = 3e-6
#: Fewest intervals per piece (a quintic not-a-knot spline needs at least 6 samples).
MIN_INTERVALS = 6


# ------------------------------------------------------------------ the schedule

def _contacts(source) -> list:
    """The contact schedules of a scene (its :class:`hexapod.scene.Contact` joints) or of a model
    (the schedules of ``model.contacts``, in SI)."""
    if isinstance(source, Scene):
        return [j for j in source.joints.values() if isinstance(j, Contact)]
    return [c.schedule for c in source.contacts]


def _times(contact, fractions, t0: float, t1: float) -> list[float]:
    """The times ``(lift_off + k - f) period`` inside ``[t0, t1]`` for each ``f`` of
    ``fractions`` (fractions of the period before lift-off) and every cycle ``k``."""
    tol = 1e-12 * max(1.0, abs(t0), abs(t1))
    times = cycle_breaks(contact.period, [contact.lift_off - f for f in fractions],
                         t0 - tol, t1 + tol)
    return [min(max(float(t), t0), t1) for t in times]


def _unique(times, tol: float) -> list[float]:
    """Sorted times, those closer than ``tol`` to the one before taken as one."""
    out: list[float] = []
    for t in sorted(times):
        if not out or t - out[-1] > tol:
            out.append(t)
    return out


def _merge(times, t0: float, t1: float, tol: float) -> np.ndarray:
    """Sorted times in ``[t0, t1]``, those closer than ``tol`` taken as one, with both ends."""
    out = _unique([t0, t1, *times], tol)
    out[0], out[-1] = t0, t1
    if len(out) > 1 and out[-1] - out[-2] <= tol:
        out.pop(-2)
    return np.array(out)


def switch_times(source, t0: float, t1: float) -> np.ndarray:
    """``t0``, every touch-down and lift-off of the contacts of a scene or model inside
    ``(t0, t1)``, and ``t1``: the ends of the phases in which the set of feet on the ground is
    constant (s)."""
    times = []
    for c in _contacts(source):
        if c.duty < 1.0:
            times += _times(c, (0.0, c.duty), t0, t1)
    return _merge(times, t0, t1, 1e-12 * max(1.0, abs(t1)))


def lift_off_times(source, t0: float, t1: float) -> np.ndarray:
    """Every lift-off of the contacts of a scene or model in ``[t0, t1]`` (s), sorted, each
    once."""
    times = [t for c in _contacts(source) if c.duty < 1.0 for t in _times(c, (0.0,), t0, t1)]
    return np.array(_unique(times, 1e-12 * max(1.0, abs(t1))))


def effort_breaks(source, t0: float, t1: float) -> np.ndarray:
    """The times of :func:`switch_times` and the ends of every foot's load ramps (touch-down
    plus, lift-off minus ``ramp duty period``), between ``t0`` and ``t1`` and including them:
    between two of them the efforts of a walking scene are smooth (s)."""
    times = list(switch_times(source, t0, t1))
    for c in _contacts(source):
        if c.duty < 1.0:
            times += _times(c, (c.ramp * c.duty, c.duty * (1.0 - c.ramp)), t0, t1)
    return _merge(times, t0, t1, 1e-12 * max(1.0, abs(t1)))


def sample_times(source, t0: float, t1: float, spacing: float = EFFORT_SPACING,
                 min_intervals: int = MIN_INTERVALS) -> np.ndarray:
    """The first samples of :func:`adaptive_inverse`: every break of :func:`effort_breaks`, and
    between two consecutive breaks ``a, b`` the Chebyshev-Lobatto
    points ``a + (b - a) (1 - cos(pi k / m)) / 2``, ``k = 0 ... m``, with ``m`` the larger of
    ``min_intervals`` and ``(b - a) / spacing`` (so ``spacing`` is about the mean step). They
    crowd towards the breaks (the first step is some ``(pi / 2 m)^2`` of the interval), where
    the efforts change fastest: a foot's load leaves it over the last few milliseconds before
    lift-off and reaches it over the first few after touch-down."""
    breaks = effort_breaks(source, t0, t1)
    pieces = []
    for a, b in zip(breaks[:-1], breaks[1:], strict=True):
        m = max(min_intervals, int(np.ceil((b - a) / spacing - 1e-9)))
        x = (1.0 - np.cos(np.pi * np.arange(m + 1) / m)) / 2
        x[0], x[-1] = 0.0, 1.0
        pieces.append(a + (b - a) * x)
    pieces = [p if k == len(pieces) - 1 else p[:-1] for k, p in enumerate(pieces)]
    return np.concatenate(pieces)


# ------------------------------------------------------------------ the effort laws

class EffortTable:
    """The efforts of several joints (``values``, N x J, at ``times``) as splines of time joined
    end to end: piece ``k``, on ``[breaks[k], breaks[k + 1]]``, is the not-a-knot spline of
    ``degree`` (the interpolant of :class:`hexapod.scene.Spline`) through the samples in that
    interval, both ends included (neighbouring pieces share their end sample). Outside
    ``[breaks[0], breaks[-1]]`` the end pieces are continued. Exact at every sample; inside each
    piece as smooth as the spline, continuous at the breaks.

    All joints are evaluated together (one spline with J columns per piece) and the values at
    the last time asked for are kept: an integrator asks for every law at the same time, one
    law after the other. With ``periodic``, the efforts of one cycle ``[breaks[0],
    breaks[-1]]`` repeat (a periodic gait's: its first and last samples then agree)."""

    def __init__(self, times, values, breaks, degree: int = EFFORT_DEGREE,
                 periodic: bool = False):
        from scipy.interpolate import make_interp_spline

        times = np.asarray(times, dtype=float).ravel()
        values = np.asarray(values, dtype=float).reshape(times.size, -1)
        breaks = np.asarray(breaks, dtype=float).ravel()
        if breaks.size < 2 or np.any(np.diff(breaks) <= 0):
            raise ValueError("breaks must be at least two increasing times")
        if np.any(np.diff(times) <= 0) or not np.all(np.isfinite(values)):
            raise ValueError("times must increase and values be finite")
        tol = 1e-9 * max(1.0, float(np.abs(times).max()))
        self.breaks, self.degree, self.columns = breaks, degree, values.shape[1]
        self.period = float(breaks[-1] - breaks[0]) if periodic else None
        self.pieces = []
        for a, b in zip(breaks[:-1], breaks[1:], strict=True):
            inside = (times >= a - tol) & (times <= b + tol)
            ends = times[inside][[0, -1]] if inside.any() else (np.nan, np.nan)
            if abs(ends[0] - a) > tol or abs(ends[1] - b) > tol:
                raise ValueError(f"the breaks {a:.9g} s and {b:.9g} s must be sample times")
            if inside.sum() < degree + 1:
                raise ValueError(f"{inside.sum()} samples from {a:.9g} s to {b:.9g} s: a "
                                 f"spline of degree {degree} needs {degree + 1}")
            self.pieces.append(make_interp_spline(times[inside], values[inside], k=degree))
        self._last: tuple[float, np.ndarray] | None = None

    def _piece(self, t: np.ndarray) -> np.ndarray:
        return np.clip(np.searchsorted(self.breaks, t, side="right") - 1, 0,
                       len(self.pieces) - 1)

    def evaluate(self, t) -> np.ndarray:
        """Values and first and second derivatives, shape ``(3,) + t.shape + (J,)``."""
        t = np.asarray(t, dtype=float)
        if self.period is not None:  # into the cycle tabulated
            t = self.breaks[0] + np.mod(t - self.breaks[0], self.period)
        if t.ndim == 0:
            if self._last is None or self._last[0] != float(t):
                spline = self.pieces[int(self._piece(t))]
                self._last = (float(t), np.array([spline(t, nu=m) for m in range(3)]))
            return self._last[1]
        flat = t.ravel()
        index = self._piece(flat)
        out = np.zeros((3, flat.size, self.columns))
        for k in np.unique(index):
            at = index == k
            out[:, at] = [self.pieces[k](flat[at], nu=m) for m in range(3)]
        return out.reshape((3,) + t.shape + (self.columns,))


@dataclass(frozen=True, eq=False)
class TabulatedEffort(Law):
    """Column ``column`` of an :class:`EffortTable`: one joint's effort as a law of time."""

    table: EffortTable
    column: int
    kind = "tabulated-effort"

    def evaluate(self, t):
        values = self.table.evaluate(t)[..., self.column]
        return values[0], values[1], values[2]

    def batch_key(self):  # the columns of one table: one spline evaluation for all
        return id(self.table)

    @classmethod
    def evaluate_batch(cls, laws, t):
        values = laws[0].table.evaluate(t)[..., [law.column for law in laws]]
        return np.moveaxis(values, -1, 1)

    def breaks(self, start, stop):  # where the splines join (each cycle's, when periodic)
        inside = self.table.breaks
        if self.table.period is not None:
            return cycle_breaks(self.table.period, inside[:-1] / self.table.period, start,
                                stop)
        return inside[(inside > start) & (inside < stop)]

    def cycle_time(self):
        return self.table.period


# ------------------------------------------------------------------ adaptive sampling

def _effort_columns(result) -> np.ndarray:
    """The joints whose efforts ``result`` reports (driven revolute and prismatic joints)."""
    return np.flatnonzero(np.all(np.isfinite(result.effort), axis=0))


@dataclass
class Sampling:
    """What :func:`adaptive_inverse` did: the number of samples after each round, the largest
    interpolation error found at the samples each round added (each joint's error relative to
    its largest effort, ``effort_scale``), and whether every interval passed."""

    samples: list[int]
    errors: list[float]
    tol: float
    effort_scale: np.ndarray
    converged: bool


def adaptive_inverse(model, source, t0: float, t1: float, *, tol: float = EFFORT_TOL,
                     spacing: float = EFFORT_SPACING, min_intervals: int = MIN_INTERVALS,
                     degree: int = EFFORT_DEGREE, max_rounds: int = 10):
    """Inverse dynamics of ``model`` at times chosen so that the efforts' splines
    (:class:`EffortTable`) are accurate to ``tol``, each joint's relative to its own largest
    effort (a light joint turns as much under a small error as a heavy one under a large).

    Starts from :func:`sample_times` at ``spacing`` (``source``: the scene or model whose
    contacts give the breaks), then, round after round, computes the efforts at the midpoint
    of every interval still to check (in one run with the samples so far, solved again),
    compares them with the spline through the samples so far, keeps them as samples, and
    marks the two halves of every interval whose midpoint missed by more than ``2^(degree +
    1) tol`` to be checked next round (an adaptive bisection, as adaptive quadrature does):
    halving an interval divides the error of a spline of ``degree`` by about
    ``2^(degree + 1)``, so the spline through the midpoint too is then within about ``tol``
    there. Stops when no interval is left to check.

    Returns the last round's :class:`hexapod.InverseResult` (every sample) and a
    :class:`Sampling`.
    """
    breaks = effort_breaks(source, t0, t1)
    result = hx.inverse_dynamics(model, sample_times(source, t0, t1, spacing, min_intervals))
    columns = _effort_columns(result)
    scale = np.abs(result.effort[:, columns]).max(axis=0)
    scale = np.maximum(scale, 1e-9 * scale.max())  # a joint that carries nothing: absolute
    pending = list(zip(result.times[:-1], result.times[1:], strict=True))
    sampling = Sampling([result.times.size], [], tol, scale, False)
    for _ in range(max_rounds):
        if not pending:
            break
        table = EffortTable(result.times, result.effort[:, columns], breaks, degree)
        middles = np.array([(a + b) / 2 for a, b in pending])
        # the samples so far solved again with the midpoints among them, so that the motion is
        # followed from sample to sample: midpoints alone lie in scattered clusters, and every
        # gap between them cost a walking robot exact solves and its guides' kinematics solved
        # again to check that no joint had jumped to another solution across it
        result = hx.inverse_dynamics(model, np.union1d(result.times, middles))
        added = result.effort[np.searchsorted(result.times, middles)][:, columns]
        miss = (np.abs(table.evaluate(middles)[0] - added) / scale).max(axis=1)
        sampling.errors.append(float(miss.max()))
        sampling.samples.append(result.times.size)
        # halving an interval divides a spline's error by about 2^(degree + 1): the spline
        # through the midpoint too is good enough when the miss is below that many tol
        pending = [half for (a, b), m, e in zip(pending, middles, miss, strict=True)
                   if e > tol * 2.0 ** (degree + 1) for half in ((a, m), (m, b))]
    sampling.converged = not pending
    return result, sampling


# ------------------------------------------------------------------ the forward twin
