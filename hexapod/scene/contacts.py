"""Feet on the ground: the stance schedule of a contact, its footholds, the load-sharing
weights, and the policy that shares the ground forces among the feet.

A :class:`~hexapod.scene.joints.Contact` is in stance on ``[(lift_off + k - duty) T,
(lift_off + k) T)`` (stance ``k``, period ``T``). Its rows are ``gate (r_foot - a_k)``: the gate
is 1 in stance and 0 in swing, ``a_k`` the foothold of stance ``k``. Both are piecewise constant
in time and enter the model as law values (:class:`StanceGate`, :class:`Foothold`), so one
model serves every contact set and a change of contact set costs nothing.

**Load sharing** (:func:`stance_weight`): a foot's weight in the ground-force policy is
``S(min(s, 1 - s) / ramp)``, clipped to 1, with ``s`` the stance progress (0 at touch-down, 1 at
lift-off) and ``S(u) = u^3 (10 - 15 u + 6 u^2)`` the quintic smooth step: 0 at touch-down and
lift-off, 1 over the middle of the stance, C2 in time. The policies add to their objective
``(1 / w - 1) |F l / tau_ref|^2`` per foot (:mod:`hexapod.algorithms.ground`), so a foot's
force grows from zero after touch-down and falls to zero before lift-off; a foot of weight zero
carries nothing.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import lru_cache
from types import SimpleNamespace

import numpy as np

from hexapod._support import limits
from hexapod.catalog import MAX_FACES, POLICIES
from hexapod.errors import Problem
from hexapod.scene.laws import Law
from hexapod.scene.laws.base import Constant, cycle_breaks
from hexapod.scene.terrain import Terrain


def _cycle(contact, t):
    """Cycle fraction from lift-off (0 at lift-off, ``1 - duty`` at touch-down) and the index
    of the stance in progress or to come."""
    x = np.asarray(t, dtype=float) / contact.period - contact.lift_off
    k = np.floor(x) + 1.0
    return x - np.floor(x), k


def in_stance(contact, t) -> np.ndarray:
    """Whether the contact's foot is on the ground at ``t`` (touch-down included, lift-off
    not)."""
    tau, _ = _cycle(contact, t)
    return tau >= 1.0 - contact.duty - 1e-12


def stance_progress(contact, t) -> np.ndarray:
    """0 at touch-down to 1 at lift-off in stance; NaN in swing."""
    tau, _ = _cycle(contact, t)
    s = (tau - (1.0 - contact.duty)) / contact.duty
    return np.where(in_stance(contact, t), np.clip(s, 0.0, 1.0), np.nan)


def stance_weight(contact, t) -> np.ndarray:
    """The foot's weight in the ground-force policy: 0 in swing, at touch-down and lift-off, 1
    over the middle of the stance, a quintic smooth step over ``ramp`` of the stance at each
    end (C2)."""
    s = stance_progress(contact, t)
    u = np.clip(np.minimum(s, 1.0 - s) / contact.ramp, 0.0, 1.0)
    weight = np.where(np.isnan(s), 0.0, u**3 * (10 - 15 * u + 6 * u**2))
    return np.where(contact.duty >= 1.0, 1.0, weight)  # always on the ground: 1


def schedule_arrays(contacts) -> SimpleNamespace:
    """The schedules of ``contacts`` as arrays (one entry per contact: ``period``,
    ``lift_off``, ``duty``, ``ramp``), on which :func:`in_stance` and :func:`stance_weight`
    give every contact's value at a time in one pass, the same arithmetic as each one's."""
    return SimpleNamespace(**{key: np.array([float(getattr(c, key)) for c in contacts])
                              for key in ("period", "lift_off", "duty", "ramp")})


def stance_weight_rate(contact, t) -> np.ndarray:
    """The derivative of :func:`stance_weight` at ``t`` with respect to the duty factor, the
    lift-off kept (the design parameter ``gait.duty``): the stance progress ``s`` grows by
    ``(1 - s) / duty`` per unit of duty."""
    s = stance_progress(contact, t)
    if contact.duty >= 1.0:
        return np.zeros_like(np.asarray(t, dtype=float))
    u = np.minimum(s, 1.0 - s) / contact.ramp
    along = np.where(s < 0.5, 1.0, -1.0) * (1.0 - s) / (contact.duty * contact.ramp)
    ramping = ~np.isnan(s) & (u < 1.0)
    return np.where(ramping, 30.0 * u**2 * (1.0 - u) ** 2 * along, 0.0)


def stance_intervals(contact, start: float, stop: float) -> list[tuple[float, float]]:
    """The contact's stances (touch-down to lift-off) that overlap ``[start, stop]``, clipped
    to it."""
    if contact.duty >= 1.0:
        return [(start, stop)]
    period = contact.period
    limits.check_steps(2.0 * (stop - start) / period, f"the stances of contact '{contact.name}' "
                       f"(period {period:g} s) over {stop - start:g} s, a phase each,",
                       "give the contact a longer period, or ask for a shorter window",
                       option=None)
    first = int(np.floor(start / period - contact.lift_off)) - 1
    out = []
    for k in range(first, first + int(np.ceil((stop - start) / period)) + 3):
        up = (contact.lift_off + k) * period
        down = up - contact.duty * period
        if up > start and down < stop:
            out.append((max(down, start), min(up, stop)))
    return out


@dataclass(frozen=True, eq=False)
class StanceGate(Law):
    """1 while the contact is in stance, 0 in swing (a switch, not a motion: its derivatives
    are zero)."""

    contact: object
    kind = "stance-gate"

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        gate = in_stance(self.contact, t).astype(float)
        return gate, np.zeros_like(t), np.zeros_like(t)

    def cycle_time(self):
        return self.contact.period

    def breaks(self, start, stop):
        c = self.contact
        if c.duty >= 1.0:
            return np.zeros(0)
        return cycle_breaks(c.period, (c.lift_off, c.lift_off - c.duty), start, stop)

    def batch_key(self):
        return "gate"

    @classmethod
    def evaluate_batch(cls, laws, t):
        t = np.asarray(t, dtype=float)
        gate = in_stance(_schedules(tuple(laws), t.ndim), t).astype(float)
        return np.array([gate, np.zeros_like(gate), np.zeros_like(gate)])


@lru_cache(maxsize=64)  # an integrator asks for the same laws' batch at every stage
def _schedules(laws: tuple, ndim: int) -> SimpleNamespace:
    """The schedules of the laws' contacts as arrays (k, 1, ...) that broadcast against times
    of ``ndim`` dimensions: the same arithmetic as one contact's, for all at once; and, for
    footholds, their first positions and advances per stance (``foothold``, ``advance``) and the
    laws whose footholds turn or are raised by the ground (``apart``: each evaluated alone)."""
    shape = (len(laws),) + (1,) * ndim
    arrays = {key: value.reshape(shape) for key, value in
              vars(schedule_arrays([law.contact for law in laws])).items()}
    if all(hasattr(law, "axis") for law in laws):
        for key in ("foothold", "advance"):
            arrays[key] = np.array([getattr(law.contact, key)[law.axis]
                                    for law in laws]).reshape(shape)
        arrays["apart"] = [i for i, law in enumerate(laws) if not law.straight]
    return SimpleNamespace(**arrays)


def foothold_point(contact, k) -> tuple:
    """The world foothold ``(x, y, z)`` of the contact's stance ``k`` (an array of indices):
    ``foothold + k advance``, turned by ``k turn`` about the vertical through ``centre``, its
    ``z`` raised by the ground's height under it."""
    c, k = contact, np.asarray(k, dtype=float)
    x, y, z = (c.foothold[i] + k * c.advance[i] for i in range(3))
    if c.turn:
        angle = np.radians(c.turn) * k
        dx, dy = c.foothold[0] - c.centre[0], c.foothold[1] - c.centre[1]
        x = c.centre[0] + np.cos(angle) * dx - np.sin(angle) * dy + k * c.advance[0]
        y = c.centre[1] + np.sin(angle) * dx + np.cos(angle) * dy + k * c.advance[1]
    if c.terrain is not None and not c.terrain.flat:
        z = z + c.terrain.height(x, y)
    return x, y, z


@dataclass(frozen=True, eq=False)
class Foothold(Law):
    """One world component of the contact's foothold in the stance in progress (or to come)."""

    contact: object
    axis: int
    kind = "foothold"

    @property
    def straight(self) -> bool:
        """Whether the component is ``foothold + k advance`` (no turn; for ``z``, flat)."""
        c = self.contact
        if self.axis == 2:
            return c.terrain is None or c.terrain.flat
        return not c.turn

    def design_parameter(self, key):
        """The stances kept centred on the footholds' times, as the walking builders place
        them: ``gait.duty``, each foothold moves back by half the ``advance`` per unit of duty
        (a constant); ``gait.stride`` (footholds advancing along ``x``), the footholds are
        ``rest + stride (lift_off - duty / 2 + k)`` along ``x``. Refused where the footholds
        turn or the ground is not flat."""
        c = self.contact
        if key not in ("gait.duty", "gait.stride") or c.duty >= 1.0:
            return None
        if not self.straight:
            raise ValueError(f"contact '{c.name}': footholds that turn, or on a ground that "
                             f"is not flat: their dependence on {key} is not derived")
        if key == "gait.duty":
            return float(c.duty), Constant(-0.5 * float(c.advance[self.axis]))
        if np.any(c.advance[1:]):
            raise ValueError(f"contact '{c.name}': footholds advancing otherwise than along "
                             "x: their dependence on the stride is not derived")
        if self.axis != 0:
            return None
        along = replace(c, foothold=np.array([c.lift_off - c.duty / 2, 0.0, 0.0]),
                        advance=np.array([1.0, 0.0, 0.0]))
        return float(c.advance[0]), Foothold(along, 0)

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        _, k = _cycle(self.contact, t)
        value = foothold_point(self.contact, k)[self.axis]
        return value * np.ones_like(t), np.zeros_like(t), np.zeros_like(t)

    def breaks(self, start, stop):  # the next stance's foothold from lift-off
        c = self.contact
        return np.zeros(0) if c.duty >= 1.0 else cycle_breaks(c.period, (c.lift_off,), start,
                                                               stop)

    def batch_key(self):
        return "foothold"

    @classmethod
    def evaluate_batch(cls, laws, t):
        t = np.asarray(t, dtype=float)
        schedules = _schedules(tuple(laws), t.ndim)
        _, k = _cycle(schedules, t)
        value = schedules.foothold + k * schedules.advance
        for i in schedules.apart:  # footholds that turn, or on a ground that is not flat
            value[i] = foothold_point(laws[i].contact, k[i])[laws[i].axis]
        return np.array([value, np.zeros_like(value), np.zeros_like(value)])


#: The keys of ``[ground]`` that give the ground's shape (the others, its forces' policy).
SHAPE_KEYS = ("slope", "heading", "steps")


@dataclass
class GroundForces:
    """How the ground forces are shared among the feet when they are statically indeterminate
    (three or more feet down).

    Attributes
    ----------
    policy : {"min-wrench", "min-effort", "friction"}
        ``min-wrench``: the least sum of ``|F|^2 + |T / l|^2`` over every joint's wrench, the
        contacts' included (the engine's unit-free default); ``min-effort``: the least sum of
        ``(tau_j / reference_effort_j)^2`` over the actuator efforts; ``friction``: the same
        least effort with every foot's normal force at least ``weight * min_normal`` and its
        tangential force inside the friction cone of ``mu``.
    reference_efforts : dict
        Reference effort per driven joint (N m, or N for a prismatic joint), by joint name;
        ``default_reference`` for the others.
    mu : float
        Friction coefficient (``friction``; also the denominator of the reported friction ratio
        ``|F_t| / (mu F_n)``).
    faces : int
        The friction cone as a pyramid of this many faces inscribed in it (so the pyramid never
        leaves the cone); 0 for the exact (quadratic) cone.
    min_normal : float
        Least normal force of a foot in full stance (N), scaled by its weight near touch-down
        and lift-off.
    default_reference : float
        The reference effort of the driven joints ``reference_efforts`` leaves out (N m, or N).
    slope, heading, steps :
        The ground's shape under the feet (:class:`~hexapod.scene.terrain.Terrain`): a plane
        rising at ``slope`` degrees towards ``heading`` (degrees from world ``x``), with risers
        ``(at, rise)`` (scene units); flat ``z = 0`` by default.
    source : str
        Where the settings were written (the scene file's ``[ground]``), named in messages.
    """

    policy: str = "min-wrench"
    reference_efforts: dict = field(default_factory=dict)
    default_reference: float = 1.0
    mu: float = 0.8
    faces: int = 8
    min_normal: float = 0.0
    slope: float = 0.0
    heading: float = 0.0
    steps: tuple = ()
    source: str = ""

    def reference(self, joint: str) -> float:
        return float(self.reference_efforts.get(joint, self.default_reference))

    @property
    def terrain(self) -> Terrain:
        """The ground's shape under the feet."""
        steps = self.steps if isinstance(self.steps, (list, tuple)) else (self.steps,)
        return Terrain(self.slope, self.heading, tuple(
            tuple(step) if isinstance(step, (list, tuple, np.ndarray)) else step
            for step in steps))

    def scaled(self, length: float) -> GroundForces:
        """The settings with the steps' lengths multiplied by ``length`` (unit conversion)."""
        return replace(self, steps=self.terrain.scaled(length).steps) if self.steps else self

    def problems(self) -> list[Problem]:
        def problem(key, message):
            return Problem("ground", message, f"{self.source}.{key}" if self.source else key)

        out = []
        if self.policy not in POLICIES:
            out.append(problem("policy", f"must be one of {', '.join(POLICIES)}, got "
                               f"{self.policy!r}"))
        numbers = {"mu": self.mu, "min_normal": self.min_normal,
                   "default_reference": self.default_reference,
                   **{f"reference_efforts.{k}": v for k, v in self.reference_efforts.items()}}
        for key, value in numbers.items():
            try:
                number = float(value)
            except (TypeError, ValueError):
                out.append(problem(key, f"must be a number, got {value!r}"))
                continue
            if not np.isfinite(number):
                out.append(problem(key, f"must be finite, got {value!r}"))
            elif key == "min_normal" and number < 0:
                out.append(problem(key, f"must not be negative, got {value!r}"))
            elif key != "min_normal" and number <= 0:
                out.append(problem(key, f"must be positive, got {value!r}"))
        out.extend(problem(key, message) for key, message in self.terrain.problems())
        if not isinstance(self.faces, int) or isinstance(self.faces, bool) or not (
                self.faces == 0 or 3 <= self.faces <= MAX_FACES):
            out.append(problem("faces", f"must be 0 (the exact cone) or at least 3 (at most "
                               f"{MAX_FACES}), got {self.faces!r}"))
        return out
