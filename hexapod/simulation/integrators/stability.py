"""Linear stability of the explicit methods: the largest step they can take on a linear mode.

A linearised mechanism (see :mod:`hexapod.simulation.diagnostics`) has modes ``exp(lambda t)``. An
explicit method advances the test equation ``y' = lambda y`` by ``y_n+1 = R(h lambda) y_n``; it is
stable on that mode while ``|R(h lambda)| <= 1``. Along the ray of ``lambda`` the stability region
of a Runge-Kutta method ends at a radius ``r(arg lambda)``, so the largest stable step on the mode
is ``r / |lambda|``, and on the mechanism the smallest of these over its modes (Hairer and Wanner,
*Solving ODEs II*, IV.2). Modes that grow physically (``Re lambda > 0``: an inverted pendulum)
set no limit: no step makes them decay.

Methods that are not Runge-Kutta on a first-order ODE (RATTLE's kick-drift-kick) give their
one-step map of the damped oscillator ``x'' + c x' + k x = 0`` instead; its spectral radius
plays the part of ``|R|``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

#: growth per step tolerated as "stable": 1e-7 per step is a factor 1.01 over 1e5 steps; the
#: polynomials of high-order methods touch 1 near the imaginary axis by far less than that
GROWTH_TOLERANCE = 1e-7
#: modes whose real part is below this fraction of their magnitude count as undamped
#: oscillations (linearisation round-off must not turn them into growing ones)
IMAGINARY_SLACK = 1e-6


def runge_kutta_stability(A: np.ndarray, b: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """``R(z) = 1 + z b^T (I - z A)^-1 1`` of an explicit tableau, as a polynomial in ``z``
    (``A`` strictly lower triangular, so the series stops after ``len(b)`` terms)."""
    A = np.asarray(A, dtype=float)
    b = np.asarray(b, dtype=float)
    coefficients = [1.0]
    power = np.ones(len(b))  # A^k 1
    for _ in range(len(b)):
        coefficients.append(float(b @ power))
        power = A @ power
    polynomial = np.polynomial.Polynomial(coefficients)
    return lambda z: polynomial(np.asarray(z, dtype=complex))


def oscillator_modes(eigenvalues: np.ndarray) -> list[complex]:
    """The modes that limit an explicit step: one of each conjugate pair, growing modes left out,
    near-imaginary ones put on the imaginary axis, zero modes (free motions) left out."""
    lam = np.asarray(eigenvalues, dtype=complex)
    if lam.size == 0:
        return []
    size = np.abs(lam)
    keep = size > 1e-12 * size.max()
    modes = []
    for value in lam[keep]:
        value = complex(value.real, abs(value.imag))
        if value.real > IMAGINARY_SLACK * abs(value):
            continue  # physically growing
        if value.real > -IMAGINARY_SLACK * abs(value):
            value = complex(0.0, value.imag) if value.imag else complex(0.0, 0.0)
        if value != 0:
            modes.append(value)
    return sorted(set(modes), key=abs, reverse=True)


def ray_radius(growth: Callable[[complex], float], direction: complex,
               largest: float = 20.0) -> float:
    """The distance from 0 along ``direction`` (unit complex) to where ``growth(z)`` first
    exceeds ``1 + GROWTH_TOLERANCE``: a fine scan, then bisection."""
    s = np.linspace(0.0, largest, 4001)[1:]
    values = np.array([growth(x * direction) for x in s])
    unstable = np.nonzero(values > 1.0 + GROWTH_TOLERANCE)[0]
    if unstable.size == 0:
        return float("inf")
    k = unstable[0]
    low, high = (s[k - 1] if k else 0.0), s[k]
    for _ in range(50):
        mid = 0.5 * (low + high)
        if growth(mid * direction) > 1.0 + GROWTH_TOLERANCE:
            high = mid
        else:
            low = mid
    return low


def largest_stable_step(growth: Callable[[complex], float], eigenvalues) -> float:
    """The largest ``h`` with ``growth(h lambda) <= 1`` on every mode (inf when none limits)."""
    best = float("inf")
    for mode in oscillator_modes(eigenvalues):
        radius = ray_radius(growth, mode / abs(mode))
        best = min(best, radius / abs(mode))
    return best


def oscillator_parameters(z: complex) -> tuple[float, float]:
    """``(k, c)`` (times ``h^2`` and ``h``) of the oscillator ``x'' + c x' + k x = 0`` whose
    characteristic roots are ``z`` and its conjugate (``z = h lambda``)."""
    return abs(z) ** 2, -2.0 * z.real
