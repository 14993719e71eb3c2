"""Where steps end: at the run's end, and for an adaptive method at the breaks of the laws (a
foot's touch-down or lift-off, where the motion has a kink its error control would otherwise
find by rejected steps), a step that ends on one reading its laws before it.
:class:`StepEnds` is a part of :class:`~hexapod.simulation.integrators.base.Integrator` (a base
class of it), whose ``__init__`` sets ``t0``, ``t_bound``, ``t``, ``h`` and ``max_step``.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from hexapod.model.law_values import law_breaks


class StepEnds:
    """The step-end services of an integrator (see the module's description)."""

    def _at_end(self, t: float) -> bool:
        """Whether a step that reached ``t`` ends the run (``t_bound`` to round-off)."""
        return t >= self.t_bound - 1e-12 * max(1.0, abs(self.t_bound))

    def next_step(self, t: float | None = None) -> float:
        """The step to take now (or, for a fixed-step method, from ``t``): the method's current
        step, cut to end at ``t_bound`` or, for an adaptive method, at the laws' next break (a
        foot's touch-down: a kink its error control would otherwise find by rejected steps); a
        step that would leave a sliver of less than 1 % is stretched to the end."""
        if t is not None and self.adaptive:
            raise ValueError("an adaptive method's steps ahead are not known")
        remaining = self._next_stop() - (self.t if t is None else t)
        h = min(self.h, self.max_step)
        return remaining if h >= 0.99 * remaining else h

    def _next_stop(self) -> float:
        """``t_bound``, or for an adaptive method the first break of the laws after ``t``."""
        if not self.adaptive:
            return self.t_bound
        breaks = self._breaks
        k = np.searchsorted(breaks, self.t + self._break_tolerance, side="right")
        return float(breaks[k]) if k < breaks.size else self.t_bound

    @cached_property
    def _breaks(self) -> np.ndarray:
        """The laws' breaks after the start, one at the end included (the last step reads
        its laws before it too, :meth:`_laws_until`)."""
        return law_breaks(self.model.laws, self.t0, self.t_bound + 2 * self._break_tolerance)

    def _break_near(self, t: float) -> float | None:
        """The break of the laws ``t`` is on (to :attr:`_break_tolerance`), or None."""
        if not self._breaks.size:
            return None
        k = np.searchsorted(self._breaks, t)
        for near in self._breaks[max(k - 1, 0):k + 1]:
            if abs(near - t) <= self._break_tolerance:
                return float(near)
        return None

    def _on_break(self, t: float) -> float:
        """``t``, or the break it is on (a step cut to end at a break ends on it)."""
        near = self._break_near(t) if self.adaptive else None
        return t if near is None else near

    def _laws_until(self, t_end: float) -> float:
        """The latest time a step ending at ``t_end`` reads its laws at: ``t_end``, or just
        before it (:attr:`_break_tolerance`) where it is a break of the laws. A step that ends
        on a touch-down or lift-off integrates the regime before it, in which the compiled
        kernels were built; read at the break itself, a lifting foot's gate is already 0,
        its rows vanish, and the kernels refuse the last stages (the exact solve, a rank
        decision each, took them: 2 of the 10 ms such a step cost the walking robot)."""
        near = self._break_near(t_end) if self.adaptive else None
        return t_end if near is None else near - self._break_tolerance

    @cached_property
    def _break_tolerance(self) -> float:
        """How near a break a step's end counts as on it (the sum ``t + h`` rounds)."""
        return 1e-12 * max(1.0, abs(self.t0), abs(self.t_bound))
