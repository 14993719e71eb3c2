"""The ground's reaction on each foot of the walking robot, as loads for a single leg.

A leg of the walking robot (:func:`legs.robot.hexapod_scene` with ``trunk="free"``) sees its
trunk move straight ahead at constant speed, level: an inertial frame. The same leg on a fixed
trunk, driven by the same laws, with its foot loaded by the ground's reaction the robot's
policy gives it, therefore transmits exactly the same joint wrenches. The single-leg scenes
(:func:`legs.front_leg.walking_leg_scene`) are built so, with the reactions of the robot's
inverse dynamics at ``SAMPLES`` instants of the stride, with their first and second derivatives
(central differences of the robot's reactions, five points ``DELTA`` apart), interpolated by
quintic Hermite polynomials: each interval's polynomial depends on its two ends only, so the
loads are exactly zero in swing and C2 everywhere.

The robot's inverse dynamics costs seconds, so the reactions of the built-in gaits are kept in
``legs/data/`` (``legs/data/make_walking_loads.py`` writes them; a test recomputes some samples).
"""

from __future__ import annotations

import csv
from functools import cache
from pathlib import Path

import numpy as np

from hexapod import assemble, inverse_dynamics
from hexapod.scene import Hermite
from legs.cockroach import MODEL_SCALE, STRIDE_PERIOD
from legs.gait import LEG_NAMES
from legs.robot import hexapod_scene

#: Samples of the ground reactions over one stride.
SAMPLES = 200
#: Spacing of the central differences (s): truncation (DELTA^4) and round-off (1e-13 / DELTA^2)
#: errors both about 1e-6 of the reactions' second derivative.
DELTA = 2e-4
TABLES = Path(__file__).parent / "data"


def table_path(gait: str) -> Path:
    return TABLES / f"{gait}-ground-reactions.csv"


def computed_reactions(gait: str = "tripod", period: float = STRIDE_PERIOD,
                       scale: float = MODEL_SCALE, samples: int = SAMPLES,
                       times=None) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Times (s) and each foot's ground reaction (N, 3, 3: value, rate and acceleration of the
    x, y, z components; N, world axes) of the walking robot with the least-wrench policy."""
    if times is None:
        times = np.arange(samples) * period / samples
    times = np.asarray(times, dtype=float)
    offsets = np.array([-2, -1, 0, 1, 2]) * DELTA
    model = assemble(hexapod_scene(gait, period, scale, trunk="free"))
    result = inverse_dynamics(model, (times[:, None] + offsets).ravel())
    force = result.ground_force.reshape(times.size, 5, len(result.contacts), 3)
    value = force[:, 2]
    rate = (force[:, 0] - 8 * force[:, 1] + 8 * force[:, 3] - force[:, 4]) / (12 * DELTA)
    acceleration = (-force[:, 0] + 16 * force[:, 1] - 30 * force[:, 2] + 16 * force[:, 3]
                    - force[:, 4]) / (12 * DELTA**2)
    # a foot that carries nothing (swing, touch-down, lift-off) has a load flat to second
    # order (its weight rises as the cube of time): its differences there are round-off
    idle = np.all(np.abs(value) <= 1e-12 * np.abs(value).max(), axis=2)
    value[idle], rate[idle], acceleration[idle] = 0.0, 0.0, 0.0
    stacked = np.stack([value, rate, acceleration], axis=2)  # (N, C, 3 orders, 3 axes)
    return times, {name.split("/")[0]: stacked[:, k]
                   for k, name in enumerate(result.contacts)}


def write_table(gait: str = "tripod", path: Path | None = None) -> Path:
    """Compute the reactions of ``gait`` at the built-in scale and period and write them."""
    times, forces = computed_reactions(gait)
    path = path or table_path(gait)
    orders = ("", "_d", "_dd")
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["t"] + [f"GR{axis}{order}:{leg}" for leg in LEG_NAMES
                                 for order in orders for axis in "xyz"])
        for k, t in enumerate(times):
            writer.writerow([repr(float(t))] + [repr(float(x)) for leg in LEG_NAMES
                                                for x in forces[leg][k].ravel()])
    return path


@cache
def tabulated_reactions(gait: str = "tripod") -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The reactions kept for ``gait`` (built-in scale and period), shaped as
    :func:`computed_reactions` gives them."""
    data = np.loadtxt(table_path(gait), delimiter=",", skiprows=1, ndmin=2)
    return data[:, 0], {leg: data[:, 1 + 9 * k:10 + 9 * k].reshape(-1, 3, 3)
                        for k, leg in enumerate(LEG_NAMES)}


def ground_load_laws(leg: str, gait: str = "tripod", period: float = STRIDE_PERIOD,
                     scale: float = MODEL_SCALE) -> tuple[Hermite, Hermite, Hermite]:
    """The ground's reaction on ``leg``'s foot (world x, y, z, N) as periodic laws: from the
    kept table for the built-in scale and period, else computed."""
    if period == STRIDE_PERIOD and scale == MODEL_SCALE and table_path(gait).is_file():
        times, forces = tabulated_reactions(gait)
    else:
        times, forces = computed_reactions(gait, period, scale)
    t = np.append(times, period)
    table = np.concatenate([forces[leg], forces[leg][:1]])  # closed: periodic
    laws = [Hermite(t, table[:, 0, axis], table[:, 1, axis], table[:, 2, axis], periodic=True)
            for axis in range(3)]
    return laws[0], laws[1], laws[2]
