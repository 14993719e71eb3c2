"""The model's time laws evaluated, and checked: a law that cannot be computed, is not finite,
or drives a joint faster than any machine moves ends the computation with an error naming the
law and the time (a simulation then ends as failed, saying them)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hexapod._support.recent import Recent
from hexapod.errors import HexapodError
from hexapod.scene.laws.base import Rate

#: The fastest a driver may move a joint or a coordinate, rad/s or m/s (SI): the largest speed
#: and angular rate a scene may hold (``hexapod.scene.scene.LARGEST``). A law beyond it is
#: singular (``1 / (t - 0.1)``) or exploding (``exp(exp(exp(10 t)))``), and a simulation would
#: otherwise shrink its step towards the singular time for ever.
FASTEST_DRIVER = 1e6


def law_name(model, i: int) -> str:
    """Law ``i`` of ``model`` as a user knows it: by the driver it prescribes, else its kind."""
    driver = next((d.name for d in model.drivers if d.law == i), None)
    return (f"the law of driver '{driver}'" if driver is not None else
            f"law {i} ({getattr(model.laws[i], 'kind', type(model.laws[i]).__name__)})")


def _arithmetic(error: ArithmeticError) -> str:
    """What a Python arithmetic error means, in a user's words."""
    if isinstance(error, ZeroDivisionError):
        return "a division by zero"
    return f"a value beyond the floating-point range ({error or type(error).__name__})"


class RecentLaws(Recent):
    """The law values of a model's last :attr:`size` single times (a pure function of the
    time): an adaptive step asks for its end's four or five times (its projection, its rates
    there, the saved state's multipliers, the next step's contact set), half of a walking
    run's evaluations. Copies go in and out."""

    def __init__(self):
        super().__init__(4)

    def get(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        values = super().get(t)
        return None if values is None else tuple(x.copy() for x in values)

    def keep(self, t: float, values: tuple) -> None:
        super().keep(t, tuple(np.array(x, dtype=float) for x in values))


def _driven(model) -> np.ndarray:
    """The indices of the laws that drivers follow."""
    return np.array(sorted({d.law for d in model.drivers if d.law >= 0}), dtype=int)


class LawBatches(NamedTuple):
    """How a list of laws is evaluated (:func:`batches`): ``groups``, the indices and laws of
    each batch evaluated in one call, and ``rates``, pairs ``(i, j)`` of a
    :class:`~hexapod.scene.laws.base.Rate` ``i`` of law ``j`` of the same list, read from
    ``j``'s values (a controller's target speed is its target's rate: evaluated once)."""

    groups: list[tuple[np.ndarray, list]]
    rates: np.ndarray


def batches(laws) -> LawBatches:
    """``laws`` grouped for evaluation: the laws of one class and one
    :meth:`~hexapod.scene.laws.Law.batch_key` together, a law without one alone, and the rates
    of laws in the list read from theirs."""
    position = {id(law): i for i, law in enumerate(laws)}
    groups: dict = {}
    rates = []
    for i, law in enumerate(laws):
        if isinstance(law, Rate) and (inner := position.get(id(law.law))) is not None:
            rates.append((i, inner))
            continue
        key = law.batch_key()
        groups.setdefault(i if key is None else (type(law), key), []).append(i)
    return LawBatches([(np.array(indices), [laws[i] for i in indices])
                       for indices in groups.values()],
                      np.array(rates, dtype=int).reshape(-1, 2))


def law_breaks(laws, start: float, stop: float) -> np.ndarray:
    """The times in ``(start, stop)`` where any of ``laws`` changes regime
    (:meth:`~hexapod.scene.laws.Law.breaks`), sorted, those closer than a billionth of the
    span merged."""
    times = np.sort(np.concatenate([np.zeros(0)] + [law.breaks(start, stop) for law in laws]))
    if times.size == 0:
        return times
    close = np.diff(times) <= 1e-9 * max(stop - start, abs(stop), 1e-300)
    return times[np.concatenate([[True], ~close])]


def evaluate_together(laws, t, grouped: LawBatches | None = None) -> np.ndarray:
    """Values, rates and accelerations of ``laws`` at ``t``, (3, len(laws), *t.shape), each
    batch in one call (``grouped``: their :func:`batches`, when already made)."""
    t = np.asarray(t, dtype=float)
    out = np.empty((3, len(laws)) + t.shape)
    grouped = batches(laws) if grouped is None else grouped
    for indices, batch in grouped.groups:
        if len(batch) == 1:  # most laws: their own evaluation, no batch array
            out[0, indices[0]], out[1, indices[0]], out[2, indices[0]] = batch[0].evaluate(t)
        else:
            out[:, indices] = type(batch[0]).evaluate_batch(batch, t)
    if grouped.rates.size:  # as Rate.evaluate gives them: its own rate's rate is zero
        rate, law = grouped.rates.T
        out[0, rate], out[1, rate], out[2, rate] = out[1, law], out[2, law], 0.0
    return out


def evaluate_laws(model, t: np.ndarray, w: np.ndarray, wd: np.ndarray, wdd: np.ndarray) -> None:
    """Fill ``w``, ``wd``, ``wdd`` (n_w,) or (n_w, len(t)) with the values, rates and
    accelerations of ``model``'s laws at ``t``.

    Raises
    ------
    HexapodError
        A law cannot be computed (a division by zero), is not finite, or a driver's rate passes
        :data:`FASTEST_DRIVER`; the message names the law and the time.
    """
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        try:
            w[...], wd[...], wdd[...] = evaluate_together(
                model.laws, t, model.built_once(("law batches",), lambda m: batches(m.laws)))
        except ArithmeticError as error:  # Python's floats: 1 / 0, 10.0 ** 400
            i = _culprit(model.laws, t)
            raise HexapodError(f"model '{model.name}': {law_name(model, i)} cannot be "
                               f"computed at t = {float(t.flat[0]):.6g} s: "
                               f"{_arithmetic(error)}") from None
        if np.isfinite(w.sum() + wd.sum() + wdd.sum()):
            driven = model.built_once(("driven laws",), _driven)
            if not driven.size or np.abs(wd[driven]).max() <= FASTEST_DRIVER:
                return
        _refuse(model, t, w, wd, wdd)


def _culprit(laws, t: np.ndarray) -> int:
    """The index of the first law that cannot be evaluated alone at ``t``."""
    for i, law in enumerate(laws):
        try:
            law.evaluate(t)
        except ArithmeticError:
            return i
    return 0


def _refuse(model, t: np.ndarray, w, wd, wdd) -> None:
    """Raise the error naming the first law at fault and the time (a sum overflowed or a rate
    passed the bound: perhaps none is at fault)."""
    driven = {d.law for d in model.drivers}
    times = np.atleast_1d(t)
    for i in range(model.n_w):
        for what, values in (("value", w[i]), ("rate", wd[i]), ("acceleration", wdd[i])):
            values = np.atleast_1d(values)
            bad = np.flatnonzero(~np.isfinite(values))
            if bad.size:
                raise HexapodError(
                    f"model '{model.name}': {law_name(model, i)} has a non-finite {what} "
                    f"({values[bad[0]]}) at t = {float(times[bad[0]]):.6g} s: a division by "
                    "zero, or a value beyond the floating-point range")
            if what == "rate" and i in driven:
                bad = np.flatnonzero(np.abs(values) > FASTEST_DRIVER)
                if bad.size:
                    raise HexapodError(
                        f"model '{model.name}': {law_name(model, i)} moves at {values[bad[0]]:.3g}"
                        f" (rad/s or m/s) at t = {float(times[bad[0]]):.6g} s, faster than any "
                        f"machine (at most {FASTEST_DRIVER:.0e}): the law is singular or "
                        "overflows there")
