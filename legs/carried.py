"""A trunk motion two feet can carry: the trunk's sway corrected so that, wherever only two feet
are on the ground, the whole robot's momentum needs no moment about the line through them.

Two point feet push the robot with forces whose moment about the line through them is zero.
The rate of change of the robot's angular momentum about that line, less gravity's moment
about it (from every body's motion: :func:`tipping`), must then vanish at every instant of a
trot's, a pace's or a bound's two-feet phases: one equation of motion in the trunk's position
across the line, not a polygon to stay in. It is an inverted pendulum's, unstable forward in
time, so it is solved as a boundary-value problem on each two-feet phase: the trunk's sway
along one horizontal axis (``y`` for a line along the walk, a trot's or a pace's; ``x`` for a
bound's: :func:`free_axis`) is the planned sway (:mod:`legs.trunk_path`) plus a correction
``d(t)``, a polynomial of degree :data:`DEGREE` on each phase given by its values at the
phase's Chebyshev-Lobatto points, such that the tipping moment vanishes at the interior points
(collocation: the moment at a point depends on the trunk's motion there only). Newton's method
(the chord method while it gains a digit a step) solves them, the partial derivatives in
``d``, ``d'`` and ``d''`` found by the guides' kinematics with the correction moved at every
point at once. The polynomial converges spectrally: the moment between the points is checked
(below :data:`BETWEEN`), else the degree is raised.

Each phase's end values are free (two per phase); they are chosen so that the quintics that
join the phases where more feet are down (value, rate and acceleration continuous: the motion
is C2) are the least accelerated, the least integral of ``d''^2`` over them, to first order in
the phases' homogeneous solutions, then the equations are solved again with them. (Ends held
at zero instead made the joins swing the trunk hard enough for the quadruped's feet to pull.)
The correction is one period's, repeated (:class:`TrunkSway`).

The inverse dynamics takes the accelerations of the motion the two feet leave free (the trunk
tipping about their line) from the dynamics, and checks that they are the guides' to 1e-6
(:data:`hexapod.algorithms.sample_inverse.FOLLOWED_TOL`); with the moment at :data:`BETWEEN`
of the weight times the height they differ by about 1e-7 m/s^2.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, replace

import numpy as np

from hexapod.scene import Harmonic, Hermite, Law

#: The correction's degree on each two-feet phase at first, and at most.
DEGREE, HIGHEST_DEGREE = 48, 96
#: The tipping moment left at the nodes, and between them, as a share of the robot's weight
#: times its height.
TOLERANCE, BETWEEN = 1e-9, 1e-8
#: Newton's iterations at most.
ITERATIONS = 8
#: m, m/s, m/s^2: the steps of the partial derivatives' differences.
STEPS = (1e-6, 1e-5, 1e-4)


def sway_design_parameter(bounds: tuple, key: str, swaying: bool = False) -> None:
    """A trunk's sway as a design parameter sees it (:meth:`hexapod.scene.Law.
    design_parameter`): corrected (``bounds``), it depends on every gait parameter through
    the whole motion (the two feet must carry it), which is not derived; ``swaying`` (its
    series not zero), it is planned from the feet's schedule and paths and the gait's period
    (its centre of pressure sees the accelerations), which the duty factor, the step height
    and the period change."""
    if bounds and key.startswith("gait."):
        raise ValueError("the trunk's sway is corrected so that two feet carry the robot, a "
                         f"solve over the whole motion whose derivative with respect to {key} "
                         "is not derived (a gait with three feet down or more has no "
                         "correction)")
    if swaying and key in ("gait.duty", "gait.step_height", "gait.period", "gait.stride"):
        raise ValueError("the trunk's sway is planned from the feet's schedule and paths over "
                         f"the stride, a solve whose derivative with respect to {key} is not "
                         "derived (a level trunk, the gait's trunk = \"level\", has none)")


@dataclass(frozen=True, eq=False)
class TrunkSway(Law):
    """One horizontal coordinate of the trunk (m): ``start + speed t`` plus its planned sway
    ``sum_k cos[k-1] cos(k w t) + sin[k-1] sin(k w t)`` (``w = 2 pi / period``), plus the
    correction that lets two feet carry it (none when ``bounds`` is empty): over each
    two-feet phase ``[bounds[2j], bounds[2j + 1]]`` (s, within a period from ``bounds[0]``) the
    polynomial through its share of ``values`` (m) at the phase's Chebyshev-Lobatto points,
    between phases the quintic that joins them (value, rate and acceleration continuous),
    repeated every period."""

    start: float = 0.0
    speed: float = 0.0
    cos: tuple = ()
    sin: tuple = ()
    period: float = 1.0
    bounds: tuple = ()
    values: tuple = ()
    _series: object = field(default=None, init=False, repr=False, compare=False)
    _pieces: object = field(default=None, init=False, repr=False, compare=False)
    kind = "trunk-sway"

    def design_parameter(self, key):
        """The gait's parameters (:func:`sway_design_parameter`); ``gait.stride`` on a level
        trunk: its speed, ``stride / period``."""
        sway_design_parameter(self.bounds, key, any(self.cos) or any(self.sin))
        if key == "gait.stride" and self.speed:
            return self.speed * self.period, TrunkSway(speed=1.0 / self.period,
                                                       period=self.period)
        return None

    def __post_init__(self):
        for key in ("cos", "sin", "bounds", "values"):
            object.__setattr__(self, key, tuple(float(x) for x in np.ravel(getattr(self, key))))
        object.__setattr__(self, "_series", Harmonic(self.start, self.cos, self.sin,
                                                     1.0 / self.period if self.period else 0.0))
        if self.bounds and not self.problems():
            object.__setattr__(self, "_pieces", _correction_pieces(self))

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        value, rate, acceleration = self._series.evaluate(t)
        out = [value + self.speed * t, rate + self.speed, acceleration]
        if self._pieces is not None:
            tau = self.bounds[0] + np.mod(t - self.bounds[0], self.period)
            for (a, b), closed, piece in self._pieces:
                inside = ((tau >= a) & (tau <= b)) if closed else ((tau > a) & (tau < b))
                if inside.any():
                    for m, x in enumerate(piece(np.where(inside, tau, a))):
                        out[m] = out[m] + np.where(inside, x, 0.0)
        return tuple(out)

    def cycle_time(self):
        return self.period if self.speed == 0.0 else None

    def symbolic(self, t):  # a closed form without a correction: the series and the drift
        if self.bounds:
            return None
        value, rate, acceleration = self._series.symbolic(t)
        return value + self.speed * t, rate + self.speed, acceleration

    def problems(self):
        out = []
        if not (np.isfinite(self.period) and self.period > 0):
            out.append(f"period must be positive, got {self.period}")
        if len(self.cos) != len(self.sin):
            out.append("cos and sin must be as long as each other")
        numbers = (self.start, self.speed, *self.cos, *self.sin, *self.bounds, *self.values)
        if not all(np.isfinite(v) for v in numbers):
            out.append("start, speed, cos, sin, bounds and values must be finite")
        elif self.bounds:
            bounds = np.array(self.bounds)
            phases = bounds.size // 2
            if bounds.size % 2 or np.any(np.diff(bounds) <= 0) or (
                    bounds[-1] - bounds[0] >= self.period):
                out.append("bounds must be pairs (start, stop) of phases in time order "
                           "within a period")
            elif len(self.values) % phases or len(self.values) // phases < 3:
                out.append(f"values must hold as many (at least 3) for each of the {phases} "
                           "phases")
        return out


def _correction_pieces(sway: TrunkSway) -> list:
    """The correction of ``sway`` as ``((start, stop), closed, piece)`` over one period from
    ``bounds[0]``, ``piece(t)`` its value, rate and acceleration: the phases' polynomials (on
    closed intervals) and the quintics that join them (open)."""
    from numpy.polynomial import chebyshev

    bounds = np.array(sway.bounds).reshape(-1, 2)
    values = np.array(sway.values).reshape(len(bounds), -1)
    out, ends = [], []
    for (a, b), y in zip(bounds, values, strict=True):
        x = _unit_lobatto(y.size - 1)
        c = chebyshev.chebfit(x, y, y.size - 1)
        scale = 2.0 / (b - a)
        series = (c, chebyshev.chebder(c) * scale, chebyshev.chebder(c, 2) * scale**2)

        def piece(t, a=a, series=series, scale=scale):
            x = (t - a) * scale - 1.0
            return tuple(chebyshev.chebval(x, s) for s in series)

        out.append(((a, b), True, piece))
        ends.append((piece(np.array(a)), piece(np.array(b))))
    starts = np.r_[bounds[1:, 0], bounds[0, 0] + sway.period]
    for j, (b, a_next) in enumerate(zip(bounds[:, 1], starts, strict=True)):
        stop, begin = ends[j][1], ends[(j + 1) % len(ends)][0]
        join = Hermite((b, a_next), (float(stop[0]), float(begin[0])),
                       (float(stop[1]), float(begin[1])),
                       (float(stop[2]), float(begin[2])))
        out.append(((b, a_next), False, join.evaluate))
    return out


def two_feet_phases(phases: dict[str, float], duty: float, period: float) -> list[tuple]:
    """The phases of a period with exactly two feet on the ground, ``(start, stop, (foot,
    foot))`` (s), in time order from the first's start (a phase's times may pass the period's
    end). Raises ``ValueError`` where one foot alone, or none, holds the robot, and for two
    feet down where the load passes from one pair to another with no time for it (a duty
    factor of one half or less)."""
    events = np.unique(np.mod([(p - d) * period for p in phases.values() for d in (0.0, duty)],
                              period))
    spans = list(zip(events, np.r_[events[1:], events[0] + period], strict=True))
    downs = []
    for start, stop in spans:
        middle = (start + stop) / 2
        down = tuple(f for f, p in phases.items()
                     if np.mod(middle / period - p, 1.0) >= 1.0 - duty)
        if len(down) < 2:
            raise ValueError(f"between t = {start:.4g} s and {stop:.4g} s "
                             f"{'only ' + down[0] + ' is' if down else 'no foot is'} on the "
                             "ground: point feet cannot hold the trunk there (a longer duty "
                             "factor keeps two feet down)")
        downs.append(down)
    for k, down in enumerate(downs):  # cyclic: the last span hands over to the first
        before = downs[k - 1]
        if len(downs) > 1 and len(down) == len(before) == 2 and down != before:
            raise ValueError(f"at t = {spans[k][0]:.4g} s the feet {' and '.join(before)} "
                             f"hand the robot to {' and '.join(down)} with no time with more "
                             "feet down: give the gait a duty factor above 0.5")
    return [(float(a), float(b), down) for (a, b), down in zip(spans, downs, strict=True)
            if len(down) == 2]


def free_axis(phases: list[tuple], feet: dict, rate: float = 0.0) -> int:
    """The trunk's horizontal axis (0: ``x``, 1: ``y``, its own) that moves it most across
    every two-feet phase's line (``feet``: per foot, its path's ``(x, y, z)`` laws; the trunk
    turning at ``rate``, rad/s, from yaw zero)."""
    worst = np.ones(2)
    for start, stop, (a, b) in phases:
        t = (start + stop) / 2
        world = np.array([feet[b][i](t) - feet[a][i](t) for i in (0, 1)])
        c, s = np.cos(rate * t), np.sin(rate * t)
        along = np.array([c * world[0] + s * world[1], -s * world[0] + c * world[1]])
        across = np.abs(along[::-1]) / np.linalg.norm(along)
        worst = np.minimum(worst, across)
    return int(np.argmax(worst))


def tipping(model, result, lines: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """The moment (N m) about each sample's line (``lines``: a point and a unit vector, each
    (N, 3)) of every body's momentum rate less its weight, for the motion of ``result`` (the
    guides' kinematics): zero where two point feet on that line can carry the motion."""
    from legs.balance import momentum_rates

    force, moment = momentum_rates(model, result)
    point, unit = lines
    return np.einsum("ni,ni->n", moment - np.cross(point, force), unit)


def _unit_lobatto(degree: int) -> np.ndarray:
    """The Chebyshev-Lobatto points of ``[-1, 1]`` in increasing order (``degree + 1``)."""
    return -np.cos(np.pi * np.arange(degree + 1) / degree)


def lobatto(a: float, b: float, degree: int) -> np.ndarray:
    """The Chebyshev-Lobatto points of ``[a, b]`` in time order (``degree + 1``)."""
    return a + (b - a) * (_unit_lobatto(degree) + 1.0) / 2.0


def differentiation(a: float, b: float, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """The first and second derivatives at the :func:`lobatto` points of the polynomial
    through values there, as matrices on the values (as :class:`TrunkSway` evaluates it)."""
    from numpy.polynomial import chebyshev

    x = _unit_lobatto(degree)
    fit = chebyshev.chebfit(x, np.eye(degree + 1), degree)  # columns: each value's series
    scale = 2.0 / (b - a)
    return tuple(chebyshev.chebval(x, chebyshev.chebder(fit, m)).T * scale**m for m in (1, 2))


def carry(kinematics, sways: dict, phases: list[tuple], feet: dict, scale: float,
          degree: int = DEGREE) -> dict:
    """``sways``, the laws of the trunk's guides in the guides' ``kinematics`` model that hold
    the correction (``trunk/x`` or ``trunk/y`` walking straight, both turning), corrected so
    that the robot's motion has no tipping moment about the two feet's line wherever only two
    are down (see the module's notes).

    Parameters
    ----------
    kinematics : Model
        The walking scene's guides' kinematics (``hexapod.assemble(scene).guidance.kinematics``).
    sways : dict of str to Law
        The laws without a correction by their guides' names (:class:`TrunkSway`, or
        :class:`legs.turning.TurnedSway`: laws with ``bounds`` and ``values``).
    phases : list of (float, float, (str, str))
        The two-feet phases of a period (:func:`two_feet_phases`).
    feet : dict of str to (Law, Law, Law)
        Each foot's path (world ``x, y, z``).
    scale : float
        N m: the robot's weight times its height, the measure of the tipping moment.
    degree : int
        The correction's degree on each phase; raised by half until the moment between the
        nodes is below :data:`BETWEEN` of ``scale`` too.

    Raises
    ------
    HexapodError
        Newton's method does not bring the moment below :data:`TOLERANCE` of ``scale`` at the
        nodes, or it stays above :data:`BETWEEN` between them at the highest degree.
    """
    from hexapod import HexapodError

    while True:
        problem = _Collocation(kinematics, sways, phases, feet, scale, degree)
        d, _ = problem.solve(np.zeros(problem.nodes.size))
        d, worst = problem.solve(problem.gentle_ends(d))
        middles = np.concatenate([(g[1:] + g[:-1]) / 2 for g in problem.grids])
        between = float(np.abs(problem.tipping(middles, d, "between")).max())
        if worst < TOLERANCE and between < BETWEEN:
            return problem.laws(d)
        if degree >= HIGHEST_DEGREE or worst >= TOLERANCE:
            raise HexapodError(
                f"model '{kinematics.name}': the trunk's motion two feet can carry was not "
                f"found: the tipping moment about their line is {worst:.3g} of the weight "
                f"times the height at the nodes and {between:.3g} between them, at degree "
                f"{degree}")
        degree = min(HIGHEST_DEGREE, int(degree * 1.5))


class _Collocation:
    """The correction's equations at one degree: the tipping moment at each phase's
    interior Lobatto points (the ends' values given), by Newton's method."""

    def __init__(self, kinematics, sways, phases, feet, scale, degree):
        self.kinematics, self.sways, self.phases, self.feet = kinematics, sways, phases, feet
        self.scale, self.degree = scale, degree
        self.period = next(iter(sways.values())).period
        self.slots = {name: next(d.law for d in kinematics.drivers if d.name == name)
                      for name in sways}
        self.grids = [lobatto(a, b, degree) for a, b, _ in phases]
        self.nodes = np.concatenate(self.grids)
        self.matrices = [differentiation(a, b, degree) for a, b, _ in phases]
        self.since = np.concatenate([g - g[0] for g in self.grids])  # from each phase's start
        self.spans = [slice(j * (degree + 1), (j + 1) * (degree + 1))
                      for j in range(len(phases))]
        self.jacobians = None

    def laws(self, d: np.ndarray) -> dict:
        """The guides' laws with the correction's values ``d`` at the nodes."""
        bounds = tuple(x for a, b, _ in self.phases for x in (a, b))
        return {name: replace(law, bounds=bounds, values=tuple(d))
                for name, law in self.sways.items()}

    def tipping(self, times: np.ndarray, d: np.ndarray, tag) -> np.ndarray:
        """The tipping moment (a share of the scale) at ``times`` with the correction's values
        ``d`` at the nodes."""
        import hexapod as hx

        laws = list(self.kinematics.laws)
        for name, law in self.laws(d).items():
            laws[self.slots[name]] = law
        digest = hashlib.sha256(repr((self.kinematics.digest, "carried", self.degree, tag,
                                      d.tobytes())).encode()).hexdigest()
        model = self.kinematics.with_laws(tuple(laws), digest, share_built=True)
        result = hx.inverse_dynamics(model, times, check_limits=False)
        return tipping(model, result, _lines(self.feet, self.phases, times)) / self.scale

    def solve(self, d: np.ndarray) -> tuple[np.ndarray, float]:
        """The values at the nodes that zero the moment inside each phase, from ``d`` (whose
        values at the phases' ends are kept), and the largest moment left inside."""
        d = d.copy()
        inner = np.ones(d.size, dtype=bool)
        inner[::self.degree + 1] = inner[self.degree::self.degree + 1] = False
        last = np.inf
        for iteration in range(ITERATIONS + 1):
            r = self.tipping(self.nodes, d, iteration)
            worst = float(np.abs(r[inner]).max())
            if worst < TOLERANCE or iteration == ITERATIONS:
                return d, worst
            if self.jacobians is None or worst > 0.1 * last:  # the chord method while it
                self.jacobians = self._partials(d, r)        # gains a digit a step
            last = worst
            for k, jacobian in zip(self.spans, self.jacobians, strict=True):
                d[k][1:-1] -= np.linalg.solve(jacobian[1:-1, 1:-1], r[k][1:-1])
        return d, worst

    def _partials(self, d: np.ndarray, r: np.ndarray) -> list[np.ndarray]:
        """Each phase's Jacobian of the moment at its nodes on the values there. The moment at
        a node depends on the correction's value, rate and acceleration there only: their
        partial derivatives come from moving them at every node at once."""
        s = self.since
        moved = [(self.tipping(self.nodes, d + step * s**m / (1, 1, 2)[m], ("partial", m))
                  - r) / step for m, step in enumerate(STEPS)]
        p0 = moved[0]
        p1 = moved[1] - s * p0
        p2 = moved[2] - s * p1 - s**2 / 2 * p0
        return [np.diag(p0[k]) + p1[k, None] * d1 + p2[k, None] * d2
                for k, (d1, d2) in zip(self.spans, self.matrices, strict=True)]

    def gentle_ends(self, d: np.ndarray) -> np.ndarray:
        """``d`` with the phases' end values that make the joins between phases least
        accelerated (the least ``sum of the integral of d''^2`` over them, and a little of the
        end values' squares), to first order: each phase's solution moves with its end values
        along the homogeneous solutions of its linearised equations."""
        n, phases = len(self.phases), self.phases
        ends, moves, grids = [], [], []  # per phase: (value, rate, acceleration) at its
        # start and stop; how they move with its end values; its homogeneous solutions
        for k, jacobian, (d1, d2) in zip(self.spans, self.jacobians, self.matrices,
                                         strict=True):
            def at(y, d1=d1, d2=d2):  # value, rate and acceleration at the phase's ends
                return np.array([[y[i], (d1 @ y)[i], (d2 @ y)[i]] for i in (0, -1)])

            grid = _homogeneous(jacobian)
            grids.append(grid)
            ends.append(at(d[k]))
            moves.append([at(grid[:, 0]), at(grid[:, 1])])
        rows, rhs = [], []
        for j in range(n):  # the join from phase j's stop to phase j + 1's start
            length = (phases[(j + 1) % n][0] + (self.period if j == n - 1 else 0.0)
                      - phases[j][1])
            root = _bending(length)
            block = np.zeros((6, 2 * n))
            for e in (0, 1):
                block[:3, 2 * j + e] = moves[j][e][1]
                block[3:, 2 * ((j + 1) % n) + e] = moves[(j + 1) % n][e][0]
            rows.append(root @ block)
            rhs.append(-root @ np.r_[ends[j][1], ends[(j + 1) % n][0]])
        weight = 1e-3 * float(np.abs(np.vstack(rows)).max())
        rows.append(weight * np.eye(2 * n))
        rhs.append(-weight * np.concatenate([[end[0][0], end[1][0]] for end in ends]))
        shift = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]
        out = d.copy()
        for j, (k, grid) in enumerate(zip(self.spans, grids, strict=True)):
            out[k] = out[k] + grid @ shift[2 * j:2 * j + 2]
        return out


def _homogeneous(jacobian: np.ndarray) -> np.ndarray:
    """The two solutions (columns) of the linearised equations ``jacobian`` inside a phase
    that are 1 at its start and 0 at its stop, and the other way round."""
    size = jacobian.shape[0]
    grid = np.zeros((size, 2))
    grid[0, 0] = grid[-1, 1] = 1.0
    grid[1:-1] = -np.linalg.solve(jacobian[1:-1, 1:-1], jacobian[1:-1][:, [0, -1]])
    return grid


def _bending(length: float) -> np.ndarray:
    """The Gram matrix of the quintic Hermite basis's second derivatives over an interval of
    ``length`` (s), on the data ``(y0, y0', y0'', y1, y1', y1'')`` (the join's ``integral
    of y''^2``), as its square root ``R`` (``R^T R``: semi-definite, lines bend not)."""
    x, w = np.polynomial.legendre.leggauss(8)
    t = (x + 1.0) * length / 2.0
    second = np.array([Hermite((0.0, length), *np.eye(6)[i].reshape(2, 3).T).evaluate(t)[2]
                       for i in range(6)])
    values, vectors = np.linalg.eigh((second * w) @ second.T * length / 2.0)
    return (vectors * np.sqrt(np.clip(values, 0.0, None))).T


def _lines(feet: dict, phases: list[tuple], times: np.ndarray) -> tuple:
    """The two-feet line at each of ``times`` (within the ``phases``): a point on it and its
    unit vector, each (N, 3)."""
    points, units = np.zeros((times.size, 3)), np.zeros((times.size, 3))
    for start, stop, (a, b) in phases:
        k = (times >= start) & (times <= stop)
        t = times[k]
        pa = np.column_stack([np.broadcast_to(feet[a][i](t), t.shape) for i in range(3)])
        pb = np.column_stack([np.broadcast_to(feet[b][i](t), t.shape) for i in range(3)])
        points[k] = pa
        units[k] = (pb - pa) / np.linalg.norm(pb - pa, axis=1)[:, None]
    return points, units
