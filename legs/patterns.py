"""Gait patterns by the number of legs: which feet lift off together, and for how long they
stand (:mod:`legs.walker` walks them, :mod:`legs.description` checks a description's pattern
against them)."""

from __future__ import annotations

#: Lift-off phases (fractions of the period) by foot role, and the default duty factor, of
#: each pattern, by the number of legs. A trot, a pace and a bound have two feet down, whose
#: line the trunk's motion must not tip about (:mod:`legs.carried`), and four while the load
#: passes from one pair to the other: a duty factor above one half.
PATTERNS: dict[int, dict[str, tuple[dict[str, float], float]]] = {
    2: {"walk": ({"L": 0.0, "R": 0.5}, 0.6)},
    4: {"walk": ({"LH": 0.0, "LF": 0.25, "RH": 0.5, "RF": 0.75}, 0.75),
        "trot": ({"LF": 0.0, "RH": 0.0, "RF": 0.5, "LH": 0.5}, 0.6),
        "pace": ({"LF": 0.0, "LH": 0.0, "RF": 0.5, "RH": 0.5}, 0.6),
        "bound": ({"LF": 0.0, "RF": 0.0, "LH": 0.5, "RH": 0.5}, 0.6)},
    6: {"tripod": ({"L1": 0.0, "R2": 0.0, "L3": 0.0, "R1": 0.5, "L2": 0.5, "R3": 0.5}, 0.5),
        "tetrapod": ({"L3": 0.0, "R2": 0.0, "L2": 1 / 3, "R1": 1 / 3, "L1": 2 / 3,
                      "R3": 2 / 3}, 2 / 3),
        "wave": ({"L3": 0.0, "L2": 1 / 6, "L1": 2 / 6, "R3": 3 / 6, "R2": 4 / 6, "R1": 5 / 6},
                 5 / 6),
        "ripple": ({"L1": 0.0, "R2": 1 / 6, "L3": 2 / 6, "R1": 3 / 6, "L2": 4 / 6,
                    "R3": 5 / 6}, 2 / 3)},
}
