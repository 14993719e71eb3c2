"""A trunk motion the feet can carry: the trunk's sway planned so that the centre of pressure
stays inside the support polygon.

Point feet push, they do not pull: the ground's forces on a robot whose centre of mass moves
level at constant speed can only balance it while the centre of pressure (the point about which
the ground's forces have no horizontal moment, the ZMP) lies inside the polygon of the feet on
the ground. This module plans the trunk's horizontal offset from its constant-speed path, a
periodic Fourier series of ``harmonics`` terms in each axis, so that the centre of pressure of a
lumped model keeps the largest margin inside the polygon of the loaded feet over the stride.

**The lumped model.** The trunk's mass at its height ``h``, each leg's at the middle of its hip
(the trunk's point above the foot's rest position) and its foot, moving with them: the centre of
pressure of point masses on flat ground, ``p = sum m_i (x_i (z_i'' + g) - z_i x_i'') /
sum m_i (z_i'' + g)`` (on a slope, in its plane: ``g`` its normal part, and
``- z_i (x_i'' - g_t)`` with ``g_t`` gravity's part along it), is then ``(a T - b T'' + c) /
den`` with ``a, b, c, den`` known from the feet's paths: linear in the trunk's horizontal
position ``T`` and so in the series'
coefficients (the swinging legs' weight and inertia count).

**The plan** is two linear programs (SciPy's HiGHS): the largest margin ``s`` such that, at
``samples`` times of the stride, ``p`` is at least ``s`` inside every edge of the polygon of the
feet whose load-sharing weight is at least ``loaded`` (a foot near touch-down or lift-off
carries little: :mod:`hexapod.scene`'s ramps); then, keeping ``0.9 s``, the least sway (the sum
of the coefficients' magnitudes weighted by their harmonic's square, the offsets by one: an
offset left free was any the solver met, centimetres on a hexapod). With two feet loaded the
polygon is their segment: ``p`` must lie on it (a trot's diagonal). Given the friction
coefficient ``mu``, the ground's total tangential force in the lumped model (the trunk's and
the legs' accelerations, gravity's part along the ground) stays within
:data:`FRICTION_SHARE` of ``mu`` times its normal force along each axis: the largest margin
alone swung Solo12's trunk up 10 degrees hard enough for its feet to slip.
Where the ground cannot give that (a slope steeper than the share), the excess is held as
small as it can be, and the inverse dynamics says which feet slip.

The margin is that of the lumped model; ``correction`` adds the whole robot's centre of pressure
less the lumped one's, where it is known (:mod:`legs.balance`); the inverse dynamics then gives
the real ground forces and says where a foot would still pull.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: The share of the friction coefficient the ground's total tangential force may use along each
#: axis (a pyramid inside the cone, with room for the feet's unequal loads).
FRICTION_SHARE = 0.5


@dataclass(frozen=True)
class TrunkPlan:
    """The planned sway: the trunk's offset from its constant-speed path is
    ``offset + sum_k cos[k-1] cos(k w t) + sin[k-1] sin(k w t)`` in ``x`` and in ``y``
    (``w = 2 pi / period``), and the lumped model's smallest margin (m; negative: the centre of
    pressure leaves the polygon by that much somewhere)."""

    x: tuple[float, tuple, tuple]
    y: tuple[float, tuple, tuple]
    period: float
    margin: float
    pressure: np.ndarray | None = field(default=None, compare=False, repr=False)

    @classmethod
    def level(cls, period: float) -> TrunkPlan:
        """No sway: the trunk straight at constant speed (its margin not computed: NaN)."""
        return cls((0.0, (), ()), (0.0, (), ()), period, float("nan"))


def _stance_weights(phases, duty: float, t: np.ndarray, ramp: float) -> np.ndarray:
    """Each foot's load-sharing weight (feet, n): 0 in swing, the quintic ramp over ``ramp`` of
    the stance at each end (as the scene's contacts share the ground forces)."""
    tau = (t[None, :] - np.array(phases)[:, None]) % 1.0
    s = (tau - (1.0 - duty)) / duty
    u = np.clip(np.minimum(s, 1.0 - s) / ramp, 0.0, 1.0)
    return np.where(tau >= 1.0 - duty, u**3 * (10 - 15 * u + 6 * u**2), 0.0)


def _edges(points: np.ndarray) -> list[tuple[np.ndarray, float, bool]]:
    """The polygon of ``points`` (k, 2) as half-planes ``n . p <= d`` (n unit), each marked
    whether the margin applies (False: the two sides of a segment, on which ``p`` must lie)."""
    if len(points) >= 3:
        from scipy.spatial import ConvexHull

        hull = ConvexHull(points)
        return [(eq[:2], -eq[2], True) for eq in hull.equations]
    if len(points) == 2:
        a, b = points
        along = (b - a) / np.linalg.norm(b - a)
        normal = np.array([-along[1], along[0]])
        return [(normal, normal @ a, False), (-normal, -normal @ a, False),
                (along, along @ b, True), (-along, -along @ a, True)]
    return [(np.array(e), float(np.array(e) @ points[0]), False)
            for e in ((1, 0), (-1, 0), (0, 1), (0, -1))]


def plan_trunk(feet: dict, phases: dict[str, float], duty: float, period: float,
               stride: float, height: float, masses: tuple[float, float], *,
               samples: int = 240, harmonics: int = 8, loaded: float = 0.5,
               ramp: float = 0.1, gravity: float = 9.81,
               slope: tuple[float, float] = (0.0, 0.0),
               correction: np.ndarray | None = None, mu: float | None = None) -> TrunkPlan:
    """The trunk's sway for a robot walking along ``x`` (see the module's notes).

    Parameters
    ----------
    feet : dict of str to (Law, Law, array)
        Per foot, its world ``x`` and ``z`` paths (laws) and its rest position relative to the
        trunk (x, y; m); its ``y`` is the rest's.
    phases : dict of str to float
        Lift-off fractions by foot.
    duty, period, stride, height : float
        The gait's duty factor, period (s), stride (m) and the trunk's height (m).
    masses : (float, float)
        The trunk's and all the legs' mass (kg).
    correction : ndarray (samples, 2), optional
        Added to the lumped model's centre of pressure at the samples (m).
    mu : float, optional
        The ground's friction coefficient: the total tangential force's bound (see the
        module's notes); None: no bound.
    slope : (float, float)
        The ground's slope and heading (degrees): heights are then above the ground's plane
        (the feet's ``z`` paths their lift above it), and gravity has a component along the
        plane, which moves the centre of pressure downhill by the heights times the slope's
        tangent (horizontal coordinates stand for the plane's: a stretch of ``1 / cos``).

    Returns
    -------
    TrunkPlan
    """
    from scipy.optimize import linprog

    t = np.arange(samples) * period / samples
    names = list(feet)
    trunk_mass, legs_mass = masses
    leg = legs_mass / len(names)
    # p = (a T - b T'' + c) / den, T the trunk's horizontal position (see the module's notes)
    angle, heading = np.radians(slope)
    along = -gravity * np.sin(angle) * np.array([np.cos(heading), np.sin(heading)])
    gravity = gravity * np.cos(angle)  # across the ground's plane; along it, ``along``
    a = np.full(samples, trunk_mass * gravity)
    b = np.full(samples, trunk_mass * height)
    c = np.tile(trunk_mass * height * along, (samples, 1))
    den = np.full(samples, trunk_mass * gravity)
    # the ground's tangential force: push T'' + pushed, T'' the trunk's acceleration
    push = trunk_mass + legs_mass / 2
    pushed = np.tile(-(trunk_mass + legs_mass) * along, (samples, 1))
    for name in names:
        x_law, z_law, rest = feet[name]
        f = np.column_stack([x_law(t), np.full(samples, rest[1])])
        f_dd = np.column_stack([x_law.evaluate(t)[2], np.zeros(samples)])
        z, _, z_dd = z_law.evaluate(t)
        lift = z_dd / 2 + gravity  # the leg's middle: its weight and vertical inertia
        a += leg * lift / 2
        b += leg * (height + z) / 4
        den += leg * lift
        c += leg * ((rest + f) * (lift / 2)[:, None]
                    - ((height + z) / 4)[:, None] * (f_dd - 2 * along))
        pushed += leg * f_dd / 2
    nominal = np.column_stack([stride / period * t, np.zeros(samples)])
    fixed = (a[:, None] * nominal + c) / den[:, None]  # p without the sway
    if correction is not None:  # the whole body's centre of pressure less the lumped one's
        fixed = fixed + correction
    k = np.arange(1, harmonics + 1)
    phase = 2 * np.pi * np.outer(t / period, k)
    gain = (a[:, None] + b[:, None] * (2 * np.pi * k / period) ** 2) / den[:, None]
    basis = np.hstack([(a / den)[:, None], gain * np.cos(phase), gain * np.sin(phase)])
    m = basis.shape[1]
    weights = _stance_weights([phases[n] for n in names], duty, t / period, ramp)
    rows, bounds_b = [], []
    for j in range(samples):
        points = np.array([[feet[n][0](t[j]), feet[n][2][1]]
                           for i, n in enumerate(names) if weights[i, j] >= loaded])
        if not len(points):  # the load passes between feet (duty 0.5): nothing to hold to
            continue
        for normal, d, with_margin in _edges(points):
            # unknowns: the x and y coefficients, the margin s, the slack e of the sides of
            # a segment (on which p must lie: held to zero as far as it can be)
            rows.append(np.r_[normal[0] * basis[j], normal[1] * basis[j],
                              (1.0, 0.0) if with_margin else (0.0, -1.0)])
            bounds_b.append(d - normal @ fixed[j])
    rows = [np.r_[row, 0.0] for row in rows]  # the last unknown: the friction's slack
    if mu is not None:  # |F_x|, |F_y| <= share mu F_n for the ground's total force
        w = 2 * np.pi * k / period
        accelerate = np.hstack([np.zeros((samples, 1)), -w**2 * np.cos(phase),
                                -w**2 * np.sin(phase)]) * (push / den)[:, None]
        zero = np.zeros_like(accelerate)
        for axis, block in ((0, (accelerate, zero)), (1, (zero, accelerate))):
            for sign in (1.0, -1.0):
                rows.extend(np.c_[sign * block[0], sign * block[1], np.zeros((samples, 2)),
                                  -np.ones(samples)])
                bounds_b.extend(FRICTION_SHARE * mu - sign * pushed[:, axis] / den)
    A, b = np.array(rows), np.array(bounds_b)
    box = [(-stride, stride)] * (2 * m) + [(None, stride), (0.0, None), (0.0, None)]
    slack_cost = 100.0  # per metre of a segment's side, per unit of friction: before margin
    first = linprog(np.r_[np.zeros(2 * m), -1.0, slack_cost, slack_cost], A_ub=A, b_ub=b,
                    bounds=box, method="highs")
    if not first.success:
        raise ValueError(f"the trunk's path cannot be planned: {first.message}")
    margin, slack, friction = (float(x) for x in first.x[-3:])
    # then the least sway keeping nine tenths of the margin and the slacks found
    cost = np.r_[np.zeros(2 * m + 3), np.tile(np.r_[1.0, k**2, k**2], 2)]  # offsets too
    A2 = np.vstack([np.hstack([A, np.zeros((len(A), 2 * m))]),
                    np.hstack([np.eye(2 * m), np.zeros((2 * m, 3)), -np.eye(2 * m)]),
                    np.hstack([-np.eye(2 * m), np.zeros((2 * m, 3)), -np.eye(2 * m)])])
    b2 = np.r_[b, np.zeros(4 * m)]
    keep = [(margin - 0.1 * abs(margin), None), (0.0, slack + 1e-9), (0.0, friction + 1e-9)]
    second = linprog(cost, A_ub=A2, b_ub=b2, bounds=box[:2 * m] + keep + [(0, None)] * (2 * m),
                     method="highs")
    coefficients = (second if second.success else first).x[:2 * m]
    margin_rows = A[:, 2 * m] == 1.0
    margin = float(np.min((b - A[:, :2 * m] @ coefficients)[margin_rows]))
    x, y = coefficients[:m], coefficients[m:]
    split_series = [(float(c[0]), tuple(c[1:harmonics + 1].tolist()),
                     tuple(c[harmonics + 1:].tolist())) for c in (x, y)]
    pressure = fixed + np.column_stack([basis @ x, basis @ y])
    return TrunkPlan(split_series[0], split_series[1], period, margin, pressure)
