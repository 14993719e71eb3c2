"""Several laws tabulated on one grid of times, with their rates and accelerations, and read by
quintic Hermite interpolation (C2), all of them in one evaluation: what a forward simulation
puts in place of laws that cost far more to evaluate than to interpolate
(:mod:`hexapod.model.tabulation`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.scene.laws.base import Law, cycle_breaks
from hexapod.scene.laws.tabulated import quintic_pieces, read_pieces


class LawTable:
    """Values, rates and accelerations of ``k`` laws at ``N`` times, interpolated by quintic
    Hermite polynomials (:func:`~hexapod.scene.laws.tabulated.quintic_pieces`), formed once.

    Parameters
    ----------
    times : array_like, shape (N,)
        Strictly increasing, s.
    table : array_like, shape (3, k, N)
        The laws' values, rates and accelerations at ``times``.
    period : float, optional
        The laws repeat with this period, s: a time ``t`` is read at ``times[0] + (t -
        times[0]) mod period`` (the table then spans one period). None: the end intervals'
        polynomials continue outside the table.
    breaks : array_like, optional
        The tabulated laws' own :meth:`~hexapod.scene.laws.Law.breaks` within the table's
        span, s (repeated with the period).
    """

    def __init__(self, times, table, period: float | None = None, breaks=()):
        self.times = np.asarray(times, dtype=float)
        self.table = np.asarray(table, dtype=float)
        self.period = period
        self.breaks = np.asarray(breaks, dtype=float)
        if self.table.shape[0] != 3 or self.table.shape[-1] != self.times.size:
            raise ValueError(f"a table of {self.times.size} times needs values, rates and "
                             f"accelerations of shape (3, k, {self.times.size}), got "
                             f"{self.table.shape}")
        self._pieces = quintic_pieces(self.times, self.table)

    def __len__(self) -> int:
        return self.table.shape[1]

    def evaluate(self, t) -> np.ndarray:
        """Values, rates and accelerations of every law at ``t``: (3, k, *t.shape)."""
        t = np.asarray(t, dtype=float)
        if self.period is not None:
            t = self.times[0] + np.mod(t - self.times[0], self.period)
        return read_pieces(self.times, self._pieces, t)

    def laws(self) -> list[TableColumn]:
        """One law per column, evaluated together."""
        return [TableColumn(self, k) for k in range(len(self))]


@dataclass(frozen=True, eq=False)
class TableColumn(Law):
    """Law ``column`` of a :class:`LawTable`; the columns of one table are evaluated in one
    interpolation."""

    table: LawTable
    column: int
    kind = "table-column"

    def evaluate(self, t):
        f, fd, fdd = self.table.evaluate(t)[:, self.column]
        return f, fd, fdd

    def cycle_time(self):
        return self.table.period

    def breaks(self, start, stop):
        table = self.table
        if table.period is None:
            inside = table.breaks
        else:
            inside = cycle_breaks(table.period, (table.breaks - table.times[0]) / table.period,
                                  start - table.times[0], stop - table.times[0]) + table.times[0]
        return inside[(inside > start) & (inside < stop)]

    def batch_key(self):
        return id(self.table)

    @classmethod
    def evaluate_batch(cls, laws, t):
        return laws[0].table.evaluate(t)[:, [law.column for law in laws]]
