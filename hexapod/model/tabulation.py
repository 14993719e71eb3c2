"""Costly time laws tabulated once for a forward simulation.

An integrator asks for every law at every stage of every step. Most laws cost a microsecond;
a law marked :attr:`~hexapod.scene.laws.Law.costly` (a walking leg's joint, whose value is the
leg's inverse kinematics solved by Newton's method) costs milliseconds a call, more than the
constrained step itself. Such laws are evaluated once, on a grid over one period when they
repeat (over the run otherwise), uniform between the laws' changes of regime, which are among
its times, and read by quintic Hermite interpolation of their values, rates and accelerations,
all of them in one call (:class:`~hexapod.scene.laws.table.LawTable`: C2, exact at the grid's
times).

**Accuracy.** The grid is halved until the interpolant agrees with the exact laws at the
midpoint of every interval (where a Hermite interpolant's error is near its largest) to
``tolerance`` relative to each law's largest value, rate and acceleration over the run: a
simulation asks for a hundredth of its relative tolerance (:data:`TOLERANCE_PER_RTOL`), so the
table moves the result by far less than the integrator's own error. The last grid is not
checked at all its midpoints, which would cost as much as the table itself: its error is
predicted from the grid before's (measured everywhere) and the fall the last halving showed,
and measured around the places where the grid before's was largest; a prediction or a
measurement that misses is followed by the full check. The acceleration's error
falls as ``h^4``; when it no longer falls (round-off in the exact values, amplified by
``1 / h^2``, has taken over) or the grid would pass :data:`MOST_INTERVALS`, the laws are
evaluated exactly, and the run says so. The table and the error it reached are recorded in the
result's options (``laws``).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from hexapod.model.law_values import evaluate_together, law_breaks
from hexapod.model.model import Model
from hexapod.scene.laws.base import Law, Rate
from hexapod.scene.laws.closed_form import Polynomial
from hexapod.scene.laws.table import LawTable
from hexapod.scene.laws.tabulated import Hermite

#: The table's tolerance, relative to the run's relative tolerance.
TOLERANCE_PER_RTOL = 1e-2
#: The first grid's intervals, and the most a grid may have.
FIRST_INTERVALS = 64
MOST_INTERVALS = 2**15


def tabulated_model(model: Model, t0: float, t_end: float,
                    tolerance: float) -> tuple[Model, dict | None]:
    """``model`` with its costly laws tabulated over ``[t0, t_end]`` to ``tolerance``, and
    what was done (a dict for the run's record; None when no law is costly). Laws that share
    a period are tabulated over one period from 0 and repeat, whatever the run: the table is
    built once per model and tolerance, and every run (a window of a long motion, a sweep of
    starts) reuses it and what the twin has built. Other laws are tabulated over the run, once
    per span. When no table reaches ``tolerance``, the model itself, and the record says why."""
    costly = [i for i, law in enumerate(model.laws) if law.costly]
    if not costly:
        return model, None
    period = shared_period([model.laws[i] for i in costly])
    start, span = (0.0, period) if period is not None else (float(t0), float(t_end - t0))
    return model.built_once(("tabulated laws", start, span, period, float(tolerance)),
                            lambda m: _tabulate(m, costly, start, span, period, tolerance))


def shared_period(laws) -> float | None:
    """The period the laws share (each repeats after it), or None (none given included)."""
    cycles = [law.cycle_time() for law in laws]
    if not cycles or any(c is None for c in cycles):
        return None
    longest = max(cycles)
    ratios = [longest / c for c in cycles]
    return longest if all(abs(r - round(r)) <= 1e-12 * r for r in ratios) else None


def first_grid(start: float, span: float, breaks: np.ndarray) -> np.ndarray:
    """About :data:`FIRST_INTERVALS` intervals over ``[start, start + span]``, uniform between
    the laws' ``breaks``, which are grid times: no interval then straddles a change of regime,
    where a polynomial converges slowly (the walking robot's table needs half the times)."""
    inside = breaks[(breaks > start + 1e-9 * span) & (breaks < start + span * (1 - 1e-9))]
    edges = np.concatenate([[start], inside, [start + span]])
    pieces = [np.linspace(a, b, max(1, round(FIRST_INTERVALS * (b - a) / span)) + 1)[:-1]
              for a, b in zip(edges[:-1], edges[1:], strict=True)]
    return np.concatenate(pieces + [[start + span]])


def _tabulate(model: Model, costly: list[int], start: float, span: float,
              period: float | None, tolerance: float):
    laws = [model.laws[i] for i in costly]
    record = {"tabulated": len(laws), "tolerance": tolerance, "period_s": period}
    breaks = law_breaks(laws, start - 1e-9 * span, start + span)
    times = first_grid(start, span, breaks)
    intervals = times.size - 1
    table = evaluate_together(laws, times)
    errors = None
    while True:
        middle = 0.5 * (times[:-1] + times[1:])
        exact = evaluate_together(laws, middle)
        per_interval = _midpoint_errors(times, table, middle, exact)
        previous, errors = errors, per_interval.max(axis=1)
        record.update(intervals=intervals, error=_error_record(errors))
        if errors.max() <= tolerance:
            break
        stalled = previous is not None and errors.max() > 0.5 * previous.max()
        if stalled or 2 * intervals > MOST_INTERVALS:
            record["exact"] = (f"no table reached the tolerance {tolerance:.2g} (the error "
                               f"{'stopped falling' if stalled else 'was still falling'} at "
                               f"{errors.max():.2g} with {intervals} intervals): the laws were "
                               "evaluated exactly")
            return model, record
        times = np.insert(times, np.arange(1, times.size), middle)
        table = np.insert(table, np.arange(1, table.shape[2]), exact, axis=2)
        intervals *= 2
        if previous is not None:
            checked = _checked_by_prediction(laws, times, table, per_interval, previous,
                                             tolerance)
            if checked is not None:
                record.update(intervals=intervals, error=_error_record(checked[0]),
                              checked=checked[1])
                break
    columns = LawTable(times, table, period, breaks).laws()
    replaced = list(model.laws)
    tabulated = {}
    for i, column in zip(costly, columns, strict=True):
        tabulated[id(replaced[i])] = column
        replaced[i] = column
    # the rate of a costly law (a controller's target speed) as the rate of its table: else
    # each step would solve the costly law again for its rate alone
    for i, law in enumerate(replaced):
        if isinstance(law, Rate) and id(law.law) in tabulated:
            replaced[i] = Rate(tabulated[id(law.law)])
    digest = (hashlib.sha256(f"{model.digest}/laws".encode() + times.tobytes() + table.tobytes())
              .hexdigest() if model.digest else "")
    return model.with_laws(tuple(replaced), digest), record


#: How fast the error of a quintic Hermite interpolant falls when its grid is halved, at most:
#: its values, rates and accelerations (``h^6``, ``h^5``, ``h^4``).
HALVING_GAINS = np.array([64.0, 32.0, 16.0])
#: The intervals of the grid before (either side of its largest error) whose halves the
#: prediction is checked on: a window of 34 midpoints, moved inside the grid at its ends. A
#: shorter one cost more: the guides' kinematics solves fewer than 32 times one by one (26 of
#: the on-ground robot's at 12 ms each, against 34 in 0.08 s by its plans).
CHECKED_EITHER_SIDE = 8


def _midpoint_errors(times, table, middle, exact) -> np.ndarray:
    """Per time of ``middle`` (3, k; the intervals' midpoints): the largest error over the
    laws of the interpolant of ``table`` on ``times`` against their ``exact`` values there,
    for the values, rates and accelerations, each relative to the law's largest."""
    scale = np.maximum(np.abs(table).max(axis=2), np.abs(exact).max(axis=2))  # (3, laws)
    interpolated = LawTable(times, table).evaluate(middle)
    return (np.abs(interpolated - exact) / np.maximum(scale, np.finfo(float).tiny)[:, :, None]
            ).max(axis=1)


def _error_record(errors) -> dict:
    return {"value": float(errors[0]), "rate": float(errors[1]),
            "acceleration": float(errors[2])}


def _checked_by_prediction(laws, times, table, coarse, previous, tolerance):
    """Whether the grid ``times`` just halved meets ``tolerance`` without the laws solved at
    all its midpoints (half the cost of a table): its error predicted from the grid before's
    (``coarse``, per interval), divided by the fall the last halving showed (never more than
    :data:`HALVING_GAINS`), and measured where it is largest, at the midpoints of the halves
    of the intervals around the grid before's largest error of each kind. Returns the errors
    (the larger of predicted and measured) and how they were found, or None when the
    prediction or the measurement misses (the full check then follows)."""
    errors = coarse.max(axis=1)
    gains = np.minimum(previous / np.maximum(errors, np.finfo(float).tiny), HALVING_GAINS)
    predicted = errors / np.maximum(gains, 1.0)
    if predicted.max() > tolerance:
        return None
    fine = set()
    width = min(2 * CHECKED_EITHER_SIDE + 1, coarse.shape[1])
    for worst in np.argmax(coarse, axis=1):  # per kind, the halves of the intervals around
        low = min(max(0, worst - CHECKED_EITHER_SIDE), coarse.shape[1] - width)
        fine.update(range(2 * low, 2 * (low + width)))
    fine = np.array(sorted(fine))
    middle = 0.5 * (times[fine] + times[fine + 1])
    # each window in a call of its own: a costly law solves its times by continuation from
    # one to the next, and a gap between windows costs it more than a window does
    runs = np.split(np.arange(fine.size), np.flatnonzero(np.diff(fine) > 1) + 1)
    exact = np.concatenate([evaluate_together(laws, middle[run]) for run in runs], axis=2)
    measured = _midpoint_errors(times, table, middle, exact).max(axis=1)
    if measured.max() > tolerance:
        return None
    return np.maximum(predicted, measured), (
        f"predicted from the grid of {coarse.shape[1]} intervals and the fall of its error "
        f"({', '.join(f'{g:.3g}' for g in gains)} for values, rates and accelerations), and "
        f"measured at {fine.size} midpoints around its largest errors")


def sampled_laws(times: np.ndarray, values: np.ndarray, rates: np.ndarray,
                 accelerations: np.ndarray) -> list:
    """Laws exact at the samples ``times`` (N,): one per row of ``values``, ``rates``,
    ``accelerations`` (each (K, N)), the quintic Hermite interpolant (C2) of a motion file, or
    for a single sample its second-order Taylor polynomial."""
    if times.size == 1:
        return [Polynomial((y[0], r[0], a[0] / 2), t0=float(times[0]))
                for y, r, a in zip(values, rates, accelerations, strict=True)]
    times = np.asarray(times, dtype=float)  # one array for all: they are read together
    return [Hermite(times, y, r, a) for y, r, a in zip(values, rates, accelerations, strict=True)]


@dataclass(frozen=True, eq=False)
class ComputedLaw(Law):
    """Row ``index`` of a motion another computation gives: ``solve(t)`` returns the values,
    rates and accelerations (3, k, n) of ``k`` laws at the times ``t`` (n,), sorted. Costly:
    a simulation tabulates it once. It repeats with ``period`` (None: it does not) and changes
    regime where the laws ``regimes`` do (a guided joint's motion: its guides' laws)."""

    solve: Callable[[np.ndarray], np.ndarray]
    index: int
    period: float | None = None
    regimes: tuple = ()
    kind = "computed"
    costly = True

    def evaluate(self, t):
        values = type(self).evaluate_batch([self], t)
        return values[0, 0], values[1, 0], values[2, 0]

    def batch_key(self):
        return id(self.solve)

    @classmethod
    def evaluate_batch(cls, laws, t):
        t = np.asarray(t, dtype=float)
        flat = np.atleast_1d(t).ravel()
        order = np.argsort(flat, kind="stable")
        values = np.empty((3, len(laws), flat.size))
        values[:, :, order] = laws[0].solve(flat[order])[:, [law.index for law in laws]]
        return values.reshape((3, len(laws)) + t.shape)

    def cycle_time(self):
        return self.period

    def breaks(self, start, stop):
        found = [law.breaks(start, stop) for law in self.regimes]
        return np.unique(np.concatenate(found)) if found else np.zeros(0)
