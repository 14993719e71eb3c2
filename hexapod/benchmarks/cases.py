"""The extreme-case suite: every case of every category, at its default parameters."""

from __future__ import annotations

from hexapod.benchmarks.mass_ratios import mass_ratio, mass_ratio_pendulum
from hexapod.benchmarks.pendulums import large_step_pendulum, long_pendulum
from hexapod.benchmarks.redundant import bricard
from hexapod.benchmarks.reference import Case
from hexapod.benchmarks.singular import four_bar_dead_points, n_four_bar, stretched_leg
from hexapod.benchmarks.stiff import flyball_governor, stiff_slider, stiff_spring_pendulum


def suite() -> list[Case]:
    """Every case at its default parameters (the stiff slider at four stiffnesses)."""
    return [
        *(stiff_slider(k) for k in (1e3, 1e5, 1e7, 1e9)),
        stiff_spring_pendulum(),
        flyball_governor(),
        n_four_bar(),
        n_four_bar(dimension=3),
        bricard(),
        four_bar_dead_points(),
        four_bar_dead_points(driven=True),
        mass_ratio(),
        mass_ratio_pendulum(),
        stretched_leg(),
        stretched_leg(driven=True),
        long_pendulum(),
        large_step_pendulum(),
    ]
