"""The ground's shape under scheduled feet: a plane of any slope, with steps.

The ground rises at ``slope`` degrees towards ``heading`` (degrees from world ``x`` about
``z``). Along that direction, the distance ``d = cos(heading) x + sin(heading) y`` from the
origin; each **step** ``(at, rise)`` is a riser across the heading at distance ``at`` that
raises the ground beyond it (``d >= at``) by ``rise`` (negative: a step down). The height of
the ground under a point is ``tan(slope) d`` plus the rises behind it; its treads are parallel
to the plane, so the normal (out of the ground) is the plane's everywhere a foot stands.

A scheduled contact (:class:`~hexapod.scene.joints.Contact`) stands on this ground: the height
of the ground under its foothold is added to the foothold's own ``z`` (its height above the
ground), and its friction cone is about the ground's normal. The flat ground ``z = 0`` (the
default) changes nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

#: The steepest slope a ground may have (degrees): beyond it a foot's friction cone of any
#: usual coefficient is far outside the vertical, and the plane's tangent grows without bound.
STEEPEST = 60.0


@dataclass(frozen=True)
class Terrain:
    """A plane rising at ``slope`` degrees towards ``heading`` (degrees), with ``steps``
    (``(at, rise)`` pairs, lengths in the scene's unit); see the module's description.

    Parameters
    ----------
    slope : float
        The plane's inclination, degrees, in ``(-60, 60)``.
    heading : float
        The direction of steepest ascent, degrees from world ``x`` about ``z``.
    steps : tuple of (float, float)
        Risers: the distance along the heading and the rise beyond it.
    """

    slope: float = 0.0
    heading: float = 0.0
    steps: tuple = ()

    @property
    def flat(self) -> bool:
        """Whether this is the ground ``z = 0``."""
        return self.slope == 0.0 and not self.steps

    @property
    def direction(self) -> np.ndarray:
        """The heading as a unit vector of the horizontal plane (world)."""
        angle = np.radians(self.heading)
        return np.array([np.cos(angle), np.sin(angle), 0.0])

    def distance(self, x: ArrayLike, y: ArrayLike) -> np.ndarray:
        """The distance along the heading of the points ``(x, y)``."""
        direction = self.direction
        return direction[0] * np.asarray(x, dtype=float) + direction[1] * np.asarray(y, dtype=float)

    def height(self, x: ArrayLike, y: ArrayLike) -> np.ndarray:
        """The ground's height under the points ``(x, y)`` (world, scene units).

        Parameters
        ----------
        x, y : array_like
            Horizontal world coordinates (broadcast together).

        Returns
        -------
        ndarray
            ``tan(slope) d`` plus the rises of the steps at or behind ``d``.
        """
        d = self.distance(x, y)
        out = np.tan(np.radians(self.slope)) * d
        for at, rise in self.steps:
            out = out + rise * (d >= at)
        return out

    def normal(self) -> np.ndarray:
        """The unit normal out of the ground (world)."""
        angle = np.radians(self.slope)
        return np.array([0.0, 0.0, np.cos(angle)]) - np.sin(angle) * self.direction

    def axes(self) -> np.ndarray:
        """The contact axes as rows ``(t_1, t_2, n)``: ``t_1`` up the slope along the heading
        (world ``x`` on flat ground), ``t_2 = n x t_1``, ``n`` the normal; the identity on flat
        ground."""
        n = self.normal()
        angle = np.radians(self.slope)
        t1 = np.cos(angle) * self.direction + np.array([0.0, 0.0, np.sin(angle)])
        return np.array([t1, np.cross(n, t1), n])

    def scaled(self, length: float) -> Terrain:
        """The terrain with its steps' lengths multiplied by ``length`` (unit conversion)."""
        return Terrain(self.slope, self.heading,
                       tuple((at * length, rise * length) for at, rise in self.steps))

    def problems(self) -> list[tuple[str, str]]:
        """What is wrong with the numbers, as ``(key, message)`` pairs (empty when fine)."""
        out = []
        for key in ("slope", "heading"):
            value = getattr(self, key)
            if not isinstance(value, (int, float)) or not np.isfinite(value):
                out.append((key, f"must be a finite number of degrees, got {value!r}"))
        if not out and not abs(self.slope) < STEEPEST:
            out.append(("slope", f"must be less than {STEEPEST:g} degrees either way, got "
                        f"{self.slope:g}"))
        for k, step in enumerate(self.steps):
            numbers = np.asarray(step, dtype=object).ravel()
            if len(numbers) != 2 or not all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v)
                    for v in numbers):
                out.append((f"steps[{k}]", f"must be two finite numbers [at, rise], got "
                            f"{step!r}"))
        return out
