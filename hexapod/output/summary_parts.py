"""Small pieces of the reports' summaries: a peak with its time, Markdown tables, counts and
numbers."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Peak:
    """The largest magnitude of a quantity over the samples and the time it occurs (s)."""

    value: float
    time: float

    @classmethod
    def of(cls, times: np.ndarray, x: np.ndarray) -> Peak:
        k = int(np.argmax(np.abs(x)))
        return cls(float(np.abs(x[k])), float(times[k]))


def count(n: int, noun: str, plural: str | None = None) -> str:
    """``n noun``, the noun in the plural unless ``n`` is 1."""
    return f"{n} {noun if n == 1 else plural or noun + 's'}"


def g4(x: float) -> str:
    """A number to four significant digits."""
    return f"{x:.4g}"


def markdown_table(header: list[str], rows: list[list[str]]) -> list[str]:
    """The lines of a Markdown table."""
    return ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"] + [
        "| " + " | ".join(row) + " |" for row in rows]


def time_integral(times: np.ndarray, x: np.ndarray) -> float:
    """Integral over the samples' span by the trapezoidal rule (0 for one sample)."""
    return float(np.sum((x[1:] + x[:-1]) * np.diff(times)) / 2)


def time_rms(times: np.ndarray, x: np.ndarray) -> float:
    """Root mean square over time (trapezoidal rule; the value itself for one sample)."""
    if times.size < 2:
        return float(np.abs(x).max(initial=0.0))
    return float(np.sqrt(time_integral(times, x**2) / (times[-1] - times[0])))


def true_runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """The runs of consecutive true samples of ``flags`` (a 1-D bool array): each as the
    indices of its first and last sample."""
    edges = np.diff(np.concatenate([[0], np.asarray(flags, dtype=int), [0]]))
    return [(int(a), int(b)) for a, b in zip(np.flatnonzero(edges == 1),
                                             np.flatnonzero(edges == -1) - 1, strict=True)]
