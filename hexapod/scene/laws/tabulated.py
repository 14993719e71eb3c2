"""Laws through samples: a cubic or quintic spline through values, and quintic Hermite
interpolation of values, rates and accelerations (C2 either way)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hexapod.scene.laws.base import (
    Law,
    _finite,
    _size_problem,
    _spacing_problem,
)

_BOUNDARY = {"not-a-knot": None, "natural": "natural", "clamped": "clamped",
             "periodic": "periodic"}


@dataclass(frozen=True)
class Spline(Law):
    """Interpolating spline through tabulated samples ``(times, values)``.

    ``degree`` 3 (C2, the default) or 5 (C4); ``boundary`` one of ``not-a-knot``, ``natural``,
    ``clamped`` (zero end slopes) or ``periodic`` (values at both ends must be equal). Outside the
    table the end polynomials are continued (periodic splines repeat).

    Parameters
    ----------
    times : sequence of float, shape (N,)
        Sample times, s, strictly increasing.
    values : sequence of float, shape (N,)
        The values there, in the law's unit.
    degree : {3, 5}
        The spline's degree.
    boundary : {"not-a-knot", "natural", "clamped", "periodic"}
        The end conditions.
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


_QUINTIC_HERMITE = (
    (1, 0, 0, -10, 15, -6), (0, 1, 0, -6, 8, -3), (0, 0, 0.5, -1.5, 1.5, -0.5),
    (0, 0, 0, 10, -15, 6), (0, 0, 0, -4, 7, -3), (0, 0, 0, 0.5, -1, 0.5),
)
#: The basis as a matrix: row ``e`` holds the coefficients of the polynomial that multiplies
#: end value ``e``.
_BASIS = np.array(_QUINTIC_HERMITE, dtype=float)
_POWERS = np.arange(6)
#: The basis polynomials (rows, ascending powers of s), their first and second derivatives.
_BASIS_RATES = np.vstack([_BASIS,
                          np.hstack([_BASIS[:, 1:] * _POWERS[1:], np.zeros((6, 1))]),
                          np.hstack([_BASIS[:, 2:] * _POWERS[2:] * _POWERS[1:-1],
                                     np.zeros((6, 2))])])


@dataclass(frozen=True, eq=False)
class Hermite(Law):
    """Tabulated values with their first and second derivatives: the quintic Hermite
    interpolant, C2, equal to the given values, rates and accelerations at every sample (a
    motion file with exact derivatives). Outside the table the end polynomials are continued,
    or, ``periodic``, the table repeats (its last sample must then equal its first: values,
    rates and accelerations).

    Parameters
    ----------
    times : array_like, shape (N,)
        Sample times, s, strictly increasing (at least 2).
    values, rates, accelerations : array_like, shape (N,)
        The values there, in the law's unit, and their first and second time derivatives (per
        s and per s^2).
    periodic : bool, optional
        The table repeats with the period ``times[-1] - times[0]`` (None: it does not).
    """

    times: np.ndarray
    values: np.ndarray
    rates: np.ndarray
    accelerations: np.ndarray
    periodic: bool | None = None
    _pieces: object = field(default=None, init=False, repr=False, compare=False)
    kind = "hermite"

    def __post_init__(self):
        for key in ("times", "values", "rates", "accelerations"):  # arrays: motions are long
            object.__setattr__(self, key, np.asarray(getattr(self, key), dtype=float).ravel())
        if not self.problems():
            object.__setattr__(self, "_pieces", quintic_pieces(
                self.times, np.array([self.values, self.rates, self.accelerations])))

    def evaluate(self, t):
        """On each interval ``[t0, t1]`` of length ``h``, with ``s = (t - t0) / h``, the quintic
        ``sum_k f_k H_k(s)`` through the end values ``(y, h y', h^2 y'')`` (the standard quintic
        Hermite basis); outside the table the end interval's polynomial continues."""
        if self._pieces is None:
            raise ValueError("hermite law is invalid: " + "; ".join(self.problems()))
        f, fd, fdd = read_pieces(self.times, self._pieces, self._in_table(t))
        return f, fd, fdd

    def _in_table(self, t):
        """``t``, or for a periodic table the same phase within its period."""
        if not self.periodic:
            return t
        start = self.times[0]
        return start + np.mod(np.asarray(t, dtype=float) - start, self.times[-1] - start)

    def batch_key(self):
        """Laws on one array of times (a motion's joints, :func:`~hexapod.model.tabulation.
        sampled_laws`) are read together: the basis at the times once, not once a law."""
        if self._pieces is None:
            return None
        return (self.times.__array_interface__["data"][0], self.times.size,
                bool(self.periodic))

    @classmethod
    def evaluate_batch(cls, laws, t):
        first = laws[0]
        return read_pieces(first.times, np.stack([law._pieces for law in laws]),
                           first._in_table(t))

    def cycle_time(self):
        return self.times[-1] - self.times[0] if self.periodic else None

    def _scaled(self, factor):
        return Hermite(self.times, self.values * factor, self.rates * factor,
                       self.accelerations * factor, self.periodic)

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
        if self.periodic and any(getattr(self, k)[0] != getattr(self, k)[-1]
                                 for k in ("values", "rates", "accelerations")):
            return ["a periodic table must end as it starts (values, rates and accelerations)"]
        numbers = (_size_problem(self.times, self.values, self.rates, self.accelerations)
                   or _spacing_problem(self.times))
        return [numbers] if numbers else []


def quintic_pieces(times: np.ndarray, table: np.ndarray) -> np.ndarray:
    """Each interval's quintic Hermite data (see :class:`Hermite`): its end values ``(y0, h y0',
    h^2 y0'', y1, h y1', h^2 y1'')``, for ``table`` (3, ..., N) holding the values, rates and
    accelerations at ``times`` (N,); returns (..., N - 1, 6). Formed once, read by
    :func:`read_pieces` at the cost of one small product whatever the number of laws."""
    y, yd, ydd = table
    h = np.diff(times)
    return np.stack([y[..., :-1], h * yd[..., :-1], h * h * ydd[..., :-1],
                     y[..., 1:], h * yd[..., 1:], h * h * ydd[..., 1:]], axis=-1)


def read_pieces(times: np.ndarray, pieces: np.ndarray, t) -> np.ndarray:
    """The values, rates and accelerations at ``t`` of the interpolant of ``pieces`` (..., N -
    1, 6) (:func:`quintic_pieces`): (3, ..., *t.shape). Outside ``times`` the end intervals'
    polynomials continue. At a sample the basis polynomials are exactly 0 or 1, so the
    tabulated values come back to the last bit."""
    t = np.asarray(t, dtype=float)
    # (np.clip costs 20 us on a scalar: more than the rest of the call)
    i = np.minimum(np.maximum(np.searchsorted(times, t, side="right") - 1, 0), times.size - 2)
    h = times[i + 1] - times[i]
    s = (t - times[i]) / h
    # the six basis polynomials and their first and second derivatives in s (exact integers
    # at s = 0 and 1), then in t: (3, *t.shape, 6). Sums are written out, never a matrix
    # product, so that a time gives the same bits alone or among others
    powers = np.ones((*t.shape, 6))
    powers[..., 1:] = np.multiply.accumulate(np.broadcast_to(s[..., None], (*t.shape, 5)),
                                             axis=-1)
    ones = (1,) * t.ndim
    basis = _sum_last(_BASIS_RATES.reshape((3, *ones, 6, 6)) * powers[None, ..., None, :])
    basis[1] /= h[..., None]
    basis[2] /= (h * h)[..., None]
    lead = (1,) * (pieces.ndim - 2)  # the laws' axes
    return _sum_last(pieces[..., i, :] * basis.reshape((3, *lead, *t.shape, 6)))


def _sum_last(x: np.ndarray) -> np.ndarray:
    """The sum over the last axis (of length 6), one term after the other: the order NumPy's
    own reduction takes for fewer than 8 terms, whatever the shape (the same bits), cheaper
    on these short rows (18 laws at 501 times: :func:`read_pieces` 0.99 -> 0.48 ms)."""
    total = x[..., 0] + x[..., 1]
    for k in range(2, x.shape[-1]):
        total += x[..., k]
    return total
