"""The foot contact: a point held at its foothold while in stance, by a gait's schedule."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.scene.contacts import Foothold, StanceGate
from hexapod.scene.element import Attachment, check_finite
from hexapod.scene.joints.base import NUMBER, VECTOR3, Joint, register
from hexapod.scene.joints.geometry import LENGTH

#: The shortest period of a contact's schedule, s, as for a gait law: each stance is a phase of
#: the inverse dynamics, and a shorter period is no gait (1e-12 s gave 2e12 phases a second).
SHORTEST_PERIOD = 1e-6


@register
@dataclass(eq=False)
class Contact(Joint):
    """A foot on the ground by a gait's schedule: while the foot is in **stance** its point (the
    child frame's origin) stays at its **foothold** (3 rows, world axes: no slip); in **swing**
    the rows vanish. The parent is the ground, whose normal is world ``z``.

    The schedule repeats every ``period`` (s): the foot lifts off at ``lift_off`` (a fraction of
    the period) and is on the ground for the fraction ``duty`` before that, so stance ``k``
    lasts from ``(lift_off + k - duty) period`` to ``(lift_off + k) period``. Its foothold is
    ``foothold + k advance`` (world, scene units): ``foothold`` is where the foot stands in the
    stance that ends at ``t = lift_off period``, ``advance`` how far the footholds move each
    cycle (the stride, for a robot walking straight). A robot turning at a constant rate sets
    ``turn``: the footholds then also turn by ``k turn`` (degrees) about the vertical through
    ``centre``, ``centre + Rz(k turn) (foothold - centre) + k advance``.

    A foot's share of the ground forces grows from zero at touch-down and falls to zero at
    lift-off over ``ramp`` (a fraction of the stance), so the forces are continuous in time
    (:mod:`hexapod.scene.contacts`).

    Rows: ``x, y, z`` of ``gate (r_foot - foothold)``, world axes, where the gate (1 in stance,
    0 in swing) and the foothold are time laws, so the contact set and the footholds change
    without rebuilding anything.

    Parameters
    ----------
    name, parent, child, parent_frame, child_frame, origin, rotation, source :
        As for every joint (:class:`~hexapod.scene.joints.base.Joint`).
    period : float
        The gait's period, s (default 1).
    duty : float
        The fraction of the period the foot is on the ground, in (0, 1] (default 0.5).
    lift_off : float
        When the foot lifts off, a fraction of the period in [0, 1) (default 0).
    foothold : array_like, shape (3,), optional
        Where the foot stands in the stance that ends at ``t = lift_off period``, world (L);
        default the origin.
    advance : array_like, shape (3,), optional
        How far the footholds move each cycle, world (L); default zero.
    turn : float
        How far the footholds turn about the vertical through ``centre`` each cycle, degrees
        (default 0).
    centre : array_like, shape (3,), optional
        A point of the vertical axis the footholds turn about, world (L); default the origin.
    ramp : float
        The fraction of the stance over which the foot's share of the ground forces grows
        from or falls to zero, in (0, 0.5] (default 0.1).
    terrain : Terrain, optional
        The ground's shape (:class:`~hexapod.scene.terrain.Terrain`), set by the model from
        the scene's ``[ground]``: the ground's height under each foothold is added to its
        ``z``, and the friction cone is about the ground's normal. None: flat ``z = 0``.
    """

    period: float = 1.0
    duty: float = 0.5
    lift_off: float = 0.0
    foothold: np.ndarray | None = None
    advance: np.ndarray | None = None
    turn: float = 0.0
    centre: np.ndarray | None = None
    ramp: float = 0.1
    terrain: object = None
    kind = "contact"
    plane_hint = "a point-on-plane joint (contacts are spatial)"

    def __post_init__(self):
        super().__post_init__()
        self.foothold = np.zeros(3) if self.foothold is None else np.array(
            self.foothold, dtype=float).reshape(-1)
        self.advance = np.zeros(3) if self.advance is None else np.array(
            self.advance, dtype=float).reshape(-1)
        self.centre = np.zeros(3) if self.centre is None else np.array(
            self.centre, dtype=float).reshape(-1)

    def problems(self):
        out = super().problems()
        if self.parent != "ground":
            out.append(self.problem("parent", f"a contact's parent is the ground, got "
                                    f"'{self.parent}'"))
        for key in ("foothold", "advance", "centre"):
            value = getattr(self, key)
            if check_finite(self, key, value, out) and value.size != 3:
                out.append(self.problem(key, f"needs 3 numbers, got {value.size}"))
        numbers = {k: getattr(self, k) for k in ("period", "duty", "lift_off", "ramp", "turn")}
        if not all(check_finite(self, k, v, out) for k, v in numbers.items()):
            return out
        if not self.period >= SHORTEST_PERIOD:
            out.append(self.problem("period", f"must be at least {SHORTEST_PERIOD:g} s (a "
                                    f"microsecond), got {self.period}"))
        if not 0 < self.duty <= 1:
            out.append(self.problem("duty", f"must be in (0, 1], got {self.duty}"))
        if not 0 <= self.lift_off < 1:
            out.append(self.problem("lift_off", f"must be in [0, 1), got {self.lift_off}"))
        if not 0 < self.ramp <= 0.5:
            out.append(self.problem("ramp", f"must be in (0, 0.5], got {self.ramp}"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        out.foothold = self.foothold * length
        out.advance = self.advance * length
        out.centre = self.centre * length
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        if attachment.base != "ground":  # footholds are in the world
            out.parent = "ground"
        T = attachment.transform
        out.foothold = T.transform_point(self.foothold)
        out.advance = T.rotation @ self.advance
        out.centre = T.transform_point(self.centre)
        return out

    @classmethod
    def file_keys(cls, dimension):
        # footholds are world points, 3 numbers (contacts exist in space only)
        return {"period": (NUMBER, False), "duty": (NUMBER, False),
                "lift_off": (NUMBER, False), "foothold": (VECTOR3, False),
                "advance": (VECTOR3, False), "turn": (NUMBER, False),
                "centre": (VECTOR3, False), "ramp": (NUMBER, False)}

    def rows(self, g, laws):
        gate = laws.value(StanceGate(self), f"{self.name}/gate", ("gate", self.name))[0]
        point = g.child.point(g.child_frame.position)
        return [(axis, gate * (point[i] - g.scale * laws.value(
            Foothold(self, i), f"{self.name}/{axis}0", ("foothold", self.name, i))[0]), LENGTH)
                for i, axis in enumerate("xyz")]
