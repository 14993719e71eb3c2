"""Foot paths of a walking leg, and the joint laws that make the foot follow them.

Seen from the trunk, which moves forward at a constant speed, a foot in **stance** stays on the
ground: it moves backwards along a straight line parallel to the body's axis, at the walking
speed, over ``STANCE_LENGTH_MM`` in the stance time (the duty factor of the period). In
**swing** it returns forwards, lifted by up to ``FOOT_LIFT_MM``. The swing's fore-aft motion
leaves and rejoins the stance line with the stance's velocity and zero second to fourth
derivatives (a ninth-degree smooth step: the foot reverses smoothly, overshooting the line's
ends a little); its lift is ``1024 u^5 (1 - u)^5`` of the swing's progress ``u``. The path is
C4. Every leg walks on the same ground at the same speed, so the feet in stance do not slip
against each other, whatever the gait.

The joints: ``thc_levation`` and ``coxa_rotation`` rise and fall with the foot's lift, ``tita``
follows its fore-aft position, with the amplitudes of ``legs.cockroach.GAIT_LAWS``;
``thc_protraction``, ``ctr`` and ``fti`` are solved (inverse kinematics, Newton's method for all
samples of the cycle at once) so that the foot is on its path. Each joint's angle is then a
periodic function of time, fitted by least squares with ``HARMONICS`` harmonics
(:class:`hexapod.scene.Harmonic`, C-infinity), the three prescribed ones first so that the solved
ones compensate exactly what the fit makes of them. ``scripts/studies/gait_paths.py`` measures how
closely the feet then follow their paths. Angles do not depend on the scale, so the fit is done
once per leg position, duty factor and segment lengths, at natural scale, and serves both sides
(the right leg's axes mirror the left's, see :mod:`legs.leg`).

**Segment lengths** (``lengths``: factors of the coxa, femur, tibia and tarsus lengths, see
:func:`legs.leg.leg_geometry`): the foot path keeps its definition in terms of the rest pose of
the leg *with the new lengths*: the stance line lies ``STANCE_OFFSET_MM`` fore-aft of the new
rest pose's foot, at its lateral distance, on the same ground (``GROUND_Z_MM`` below the
trunk's centre of mass), with the same stride length and lift. A leg whose lengths cannot reach
that path raises ``ValueError`` naming the leg and the factors.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from hexapod.scene import Law, cycle_breaks
from legs.cockroach import (
    FOOT_LIFT_MM,
    GAIT_LAWS,
    GROUND_Z_MM,
    STANCE_LENGTH_MM,
    STANCE_OFFSET_MM,
    THC_POINT_MM,
)
from legs.leg import (
    JOINTS,
    SEGMENT_NAMES,
    LegGeometry,
    describe_lengths,
    leg_geometry,
    length_factors,
)

#: The joints placed by inverse kinematics (protraction swings the leg, CTr and FTi set its
#: reach and height); the others are prescribed.
SOLVED_JOINTS = ("thc_protraction", "ctr", "fti")
HARMONICS = 64
SAMPLES = 720  # over one cycle, for the inverse kinematics and the fit


def _smooth_step(u):
    """0 to 1 on [0, 1] with zero first to fourth derivatives at both ends."""
    return u**5 * (126 - 420 * u + 540 * u**2 - 315 * u**3 + 70 * u**4)


def foot_path(tau, duty: float, length: float, lift: float) -> tuple[np.ndarray, np.ndarray]:
    """The foot's fore-aft position from the stance line's middle and its height above the
    ground, at cycle fractions ``tau`` (0 at lift-off; swing until ``1 - duty``)."""
    tau = np.asarray(tau, dtype=float) % 1.0
    swing_share = 1.0 - duty
    fore_aft, height = np.empty_like(tau), np.zeros_like(tau)
    stance = tau >= swing_share
    fore_aft[stance] = length / 2 - length * (tau[stance] - swing_share) / duty
    u = tau[~stance] / swing_share
    rate = -length * swing_share / duty  # the stance velocity, per unit of swing progress
    fore_aft[~stance] = -length / 2 + rate * u + (length - rate) * _smooth_step(u)
    height[~stance] = lift * 1024 * u**5 * (1 - u) ** 5
    return fore_aft, height


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross products of (n, 3) arrays (NumPy's cross costs several times more on
    these shapes: it moves axes and checks them at every call)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def _rodrigues(axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each unit axis's cross-product matrix ``K`` and its square (k, 3, 3): the rotation by
    an angle is then ``I + sin K + (1 - cos) K^2`` (Rodrigues)."""
    K = np.zeros((axes.shape[0], 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -axes[:, 2], axes[:, 1], -axes[:, 0]
    K -= K.transpose(0, 2, 1)
    return K, K @ K


def chain_state(geometry: LegGeometry, angles: np.ndarray):
    """The foot (n, 3), and every joint's axis and point (n, 6, 3) as moved by the joints
    before it, at joint angles (n, 6), in the leg's frame (the thorax-coxa point, trunk axes).
    Product of exponentials: each joint turns everything beyond it about its rest-pose axis
    and point, the proximal joint last; the transforms ``x -> A x + b`` of the joints up to
    ``k`` are composed from the trunk outwards, their rotations as matrices (3, 3, n: the
    samples last, so that each product is a few long vector operations)."""
    rest_axes, rest_points = np.array(geometry.axes), np.array(geometry.points)
    K, K2 = _rodrigues(rest_axes)
    c, s = np.cos(angles).T, np.sin(angles).T  # (6, n): samples last, contiguous
    n = angles.shape[0]
    axes, points = np.empty((6, 3, n)), np.empty((6, 3, n))
    A, b = np.repeat(np.eye(3)[:, :, None], n, axis=2), np.zeros((3, n))  # x -> A x + b
    for k in range(6):
        axes[k] = np.einsum("ijn,j->in", A, rest_axes[k])
        points[k] = np.einsum("ijn,j->in", A, rest_points[k]) + b
        rotation = (np.eye(3)[:, :, None] + K[k][:, :, None] * s[k]
                    + K2[k][:, :, None] * (1 - c[k]))
        A = np.einsum("ijn,jkn->ikn", A, rotation)
        b = points[k] - np.einsum("ijn,j->in", A, rest_points[k])
    foot = np.einsum("ijn,j->in", A, rest_points[6]) + b
    return (np.ascontiguousarray(foot.T), axes.transpose(2, 0, 1).copy(),
            points.transpose(2, 0, 1).copy())


def foot_position(geometry: LegGeometry, angles: np.ndarray,
                  state=None) -> tuple[np.ndarray, np.ndarray]:
    """The foot (n, 3) at joint angles (n, 6), in the leg's frame, and its Jacobian (n, 3, 6):
    column ``k`` is the moved axis of joint ``k`` crossed with the arm to the foot. ``state``:
    :func:`chain_state` at these angles, when already computed."""
    foot, axes, points = chain_state(geometry, angles) if state is None else state
    return foot, _cross(axes, foot[:, None, :] - points).transpose(0, 2, 1)


def foot_bias(geometry: LegGeometry, angles: np.ndarray, rates: np.ndarray,
              state=None) -> np.ndarray:
    """The foot's acceleration (n, 3) at zero joint accelerations (the ``J_dot theta_dot``
    term): ``sum_k theta_dot_k (theta_dot_k a_k + 2 omega_k) x c_k``, with ``c_k`` the
    Jacobian's column ``a_k x (foot - p_k)`` and ``omega_k`` the angular velocity of the body
    before joint ``k``. ``state``: :func:`chain_state` at ``angles``, when already computed."""
    foot, axes, points = chain_state(geometry, angles) if state is None else state
    columns = _cross(axes, foot[:, None, :] - points)
    out = np.zeros_like(foot)
    omega = np.zeros_like(foot)
    for k in range(6):
        spin = rates[:, k, None] * axes[:, k]
        out += rates[:, k, None] * _cross(spin + 2 * omega, columns[:, k])
        omega = omega + spin
    return out


def solve_joints(geometry: LegGeometry, targets: np.ndarray, angles: np.ndarray,
                 solved: tuple[int, ...], steps: int = 10, tol: float = 1e-14) -> np.ndarray:
    """Angles (n, 6) placing the foot at ``targets`` (n, 3): the joints ``solved`` found, the
    others as given in ``angles``. Newton's method for all samples at once, continued from the
    rest pose (all angles zero) in ``steps``, so that every sample stays on the rest pose's
    branch (the knee bent the same way).

    Raises
    ------
    ValueError
        When a target is out of reach (the message names the leg and its length factors).
    """
    solved = list(solved)
    fixed = [k for k in range(6) if k not in solved]
    rest_foot = geometry.points[6]
    tolerance = tol * np.abs(geometry.points[6]).max()
    current = np.zeros_like(angles)
    for s in np.linspace(0.0, 1.0, steps + 1)[1:]:
        goal = rest_foot + s * (targets - rest_foot)
        current[:, fixed] = s * angles[:, fixed]
        for _ in range(30):
            foot, jacobian = foot_position(geometry, current)
            residual = foot - goal
            if np.abs(residual).max() <= tolerance:
                break
            try:
                step = np.linalg.solve(jacobian[:, :, solved], residual[..., None])[..., 0]
            except np.linalg.LinAlgError:
                raise ValueError(f"{_leg_label(geometry)}: the foot path is out of reach (the "
                                 "leg is stretched straight)") from None
            current[:, solved] -= step
        else:
            worst = float(np.abs(residual).max() / np.linalg.norm(rest_foot))
            raise ValueError(f"{_leg_label(geometry)}: the foot path is out of reach (missed "
                             f"by {worst:.2g} of the leg's reach)")
    return current


@cache
def _unit_geometry(position: str, lengths: tuple[float, float, float, float]) -> LegGeometry:
    """The left ``position`` leg at natural scale (built once: the laws ask at every call)."""
    return leg_geometry(position, "L", scale=1.0, lengths=lengths)


def _leg_label(geometry: LegGeometry) -> str:
    """``"front leg"``, with its length factors when they are not all 1."""
    if all(f == 1.0 for f in geometry.length_factors):
        return f"{geometry.leg} leg"
    return f"{geometry.leg} leg ({describe_lengths(geometry.length_factors)})"


def _fourier_basis(tau: np.ndarray, harmonics: int) -> np.ndarray:
    """Columns 1, cos(2 pi k tau), sin(2 pi k tau) for k = 1 ... ``harmonics``."""
    k = np.arange(1, harmonics + 1)
    x = 2 * np.pi * tau
    return np.hstack([np.ones((tau.size, 1)), np.cos(np.outer(x, k)), np.sin(np.outer(x, k))])


def _harmonic_start(harmonics: dict, joints, tau: np.ndarray) -> np.ndarray:
    """The harmonic series of ``joints`` (k, n) at cycle fractions ``tau``, by Horner's rule in
    ``z = exp(2 pi i tau)``: ``offset + Re sum_k (a_k - i b_k) z^k``, off by a few hundred
    units of round-off (Newton's method's start, which it then corrects)."""
    z = np.exp(2j * np.pi * tau)
    coefficients = np.array([np.array(harmonics[j][1]) - 1j * np.array(harmonics[j][2])
                             for j in joints])  # (k, harmonics)
    total = np.zeros((len(joints), tau.size), dtype=complex)
    for c in coefficients.T[::-1]:
        total = (total + c[:, None]) * z
    return np.array([harmonics[j][0] for j in joints])[:, None] + total.real


def path_targets(position: str, tau: np.ndarray, duty: float,
                 scale: float = 1.0, lengths=None) -> np.ndarray:
    """Where the foot of a left ``position`` leg should be at cycle fractions ``tau``, in the
    leg's frame (m at ``scale``; the right leg's is the mirror image, y negated): the stance
    line from the rest pose of the leg with its segment ``lengths`` (see the module's notes)."""
    geometry = (_unit_geometry(position, length_factors(lengths)) if scale == 1.0 else
                leg_geometry(position, "L", scale, lengths))
    mm = 1e-3 * scale
    fore_aft, height = foot_path(tau, duty, STANCE_LENGTH_MM * mm, FOOT_LIFT_MM * mm)
    rest_foot = geometry.points[6]
    ground = (GROUND_Z_MM - THC_POINT_MM[position][2]) * mm
    return np.column_stack([rest_foot[0] + STANCE_OFFSET_MM[position] * mm + fore_aft,
                            np.full_like(fore_aft, rest_foot[1]), ground + height])


def stepping_harmonics(position: str, duty: float, harmonics: int = HARMONICS,
                       lengths=None) -> dict[str, tuple]:
    """The harmonics ``(offset, cos, sin)`` in the cycle fraction (0 at lift-off) of every joint
    of a ``front``, ``middle`` or ``hind`` leg walking with ``duty``, its segments' lengths
    multiplied by ``lengths`` (coxa, femur, tibia, tarsus; None: all 1), such that the foot
    follows :func:`foot_path`. Computed once per leg, duty, harmonics and length factors
    (``stepping_harmonics.cache_clear()`` forgets them).

    Raises
    ------
    ValueError
        The leg cannot reach its path (the message names the leg and the factors).
    """
    return _stepping_harmonics(position, duty, harmonics, length_factors(lengths))


@cache
def _stepping_harmonics(position: str, duty: float, harmonics: int,
                        lengths: tuple[float, float, float, float]) -> dict[str, tuple]:
    geometry = leg_geometry(position, "L", scale=1.0, lengths=lengths)
    tau = np.arange(SAMPLES) / SAMPLES
    fore_aft, height = foot_path(tau, duty, 1.0, 1.0)  # shapes: unit stride and lift
    amplitude = {joint: np.radians(a) for joint, a, _ in GAIT_LAWS}
    prescribed = {"thc_levation": amplitude["thc_levation"] * height,
                  "coxa_rotation": amplitude["coxa_rotation"] * height,
                  "tita": amplitude["tita"] * 2 * fore_aft}
    basis = _fourier_basis(tau, harmonics)
    coefficients = {}
    angles = np.zeros((SAMPLES, 6))
    for joint, values in prescribed.items():
        coefficients[joint] = np.linalg.lstsq(basis, values, rcond=None)[0]
        angles[:, JOINTS.index(joint)] = basis @ coefficients[joint]
    solved = tuple(JOINTS.index(j) for j in SOLVED_JOINTS)
    angles = solve_joints(geometry, path_targets(position, tau, duty, lengths=lengths), angles,
                          solved)
    fitted = np.linalg.lstsq(basis, angles[:, list(solved)], rcond=None)[0]
    coefficients.update({joint: fitted[:, k] for k, joint in enumerate(SOLVED_JOINTS)})
    return {joint: (float(c[0]), tuple(c[1:harmonics + 1].tolist()),
                    tuple(c[harmonics + 1:].tolist()))
            for joint, c in ((j, coefficients[j]) for j in JOINTS)}


stepping_harmonics.cache_clear = _stepping_harmonics.cache_clear


# ------------------------------------------------------------------ the exact gait

_STEP9 = np.polynomial.Polynomial([0, 0, 0, 0, 0, 126, -420, 540, -315, 70])
_BUMP = np.polynomial.Polynomial([0, 1]) ** 5 * np.polynomial.Polynomial([1, -1]) ** 5 * 1024
#: the swing's fore-aft smooth step and its lift (unit shapes of its progress), each with its
#: first and second derivatives: every walking foot's path is made of them
STEP_RATES = tuple(_STEP9.deriv(m) for m in range(3))
LIFT_RATES = tuple(_BUMP.deriv(m) for m in range(3))


def foot_path_rates(tau, duty: float, length: float, lift: float):
    """:func:`foot_path` and its first and second derivatives in the cycle fraction ``tau``:
    ``(fore_aft, height)`` each as a tuple (value, d/dtau, d2/dtau2)."""
    tau = np.asarray(tau, dtype=float) % 1.0
    a = 1.0 - duty
    stance = tau >= a
    u = np.where(stance, 0.0, tau / a)
    rate = -length * a / duty
    step = [p(u) for p in STEP_RATES]
    bump = [p(u) for p in LIFT_RATES]
    fore_aft = (
        np.where(stance, length / 2 - length * (tau - a) / duty,
                 -length / 2 + rate * u + (length - rate) * step[0]),
        np.where(stance, -length / duty, (rate + (length - rate) * step[1]) / a),
        np.where(stance, 0.0, (length - rate) * step[2] / a**2),
    )
    height = tuple(np.where(stance, 0.0, lift * b / a**m) for m, b in enumerate(bump))
    return fore_aft, height


def exact_leg_motion(position: str, duty: float, tau,
                     lengths=None) -> tuple[np.ndarray, ...]:
    """The joint angles of a left ``position`` leg (n, 6) at cycle fractions ``tau``, and their
    first and second derivatives in ``tau``, such that the foot is on its path to round-off:
    the prescribed joints follow the path's lift and fore-aft position exactly, the solved
    ones are Newton's solution of the foot's position (started from the harmonic fit of
    :func:`stepping_harmonics`), their rates and accelerations from the foot's Jacobian. The
    leg's segments have their lengths multiplied by ``lengths`` (coxa, femur, tibia, tarsus;
    None: all 1).

    Raises
    ------
    ValueError
        Newton's method does not put the foot on its path (the message names the leg and the
        factors).
    """
    tau = np.atleast_1d(np.asarray(tau, dtype=float)) % 1.0
    lengths = length_factors(lengths)
    geometry = _unit_geometry(position, lengths)
    mm = 1e-3
    (fa, fa1, fa2), (h, h1, h2) = foot_path_rates(tau, duty, 1.0, 1.0)  # unit shapes
    n = tau.size
    angles, rates, accelerations = prescribed_motion(duty, tau)
    harmonics = stepping_harmonics(position, duty, HARMONICS, lengths)
    solved = [JOINTS.index(j) for j in SOLVED_JOINTS]
    free = [k for k in range(6) if k not in solved]
    angles[:, solved] = _harmonic_start(harmonics, SOLVED_JOINTS, tau).T
    length, lift = STANCE_LENGTH_MM * mm, FOOT_LIFT_MM * mm
    target = path_targets(position, tau, duty, scale=1.0, lengths=lengths)
    target_rate = np.column_stack([fa1 * length, np.zeros(n), h1 * lift])
    target_acceleration = np.column_stack([fa2 * length, np.zeros(n), h2 * lift])
    reach = np.linalg.norm(geometry.points[6])
    tolerance = 1e-15 * reach
    with np.errstate(divide="ignore", invalid="ignore"):  # a stretched leg: NaN, said below
        for _ in range(8):
            state = chain_state(geometry, angles)
            foot, jacobian = foot_position(geometry, angles, state)
            residual = foot - target
            if np.abs(residual).max() <= tolerance:
                break
            angles[:, solved] -= _solve3(jacobian[:, :, solved], residual)
        else:
            state = chain_state(geometry, angles)
            foot, jacobian = foot_position(geometry, angles, state)
    missed = float(np.abs(foot - target).max()) / reach
    if not missed <= 1e-12:  # NaN included
        raise ValueError(f"{_leg_label(geometry)}: the foot cannot follow its path (Newton's "
                         f"method missed it by {missed:.2g} of the leg's reach)")
    Js, Jp = jacobian[:, :, solved], jacobian[:, :, free]
    rhs = target_rate - np.einsum("nij,nj->ni", Jp, rates[:, free])
    rates[:, solved] = _solve3(Js, rhs)
    rhs = (target_acceleration - np.einsum("nij,nj->ni", Jp, accelerations[:, free])
           - foot_bias(geometry, angles, rates, state))
    accelerations[:, solved] = _solve3(Js, rhs)
    return angles, rates, accelerations


def prescribed_motion(duty: float, tau) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The angles (n, 6) at cycle fractions ``tau`` and their first and second derivatives in
    ``tau`` of the joints the gait prescribes (``legs.cockroach.GAIT_LAWS``: the levation and
    the coxa's rotation follow the foot's lift, the tita its fore-aft position); zero for the
    joints :data:`SOLVED_JOINTS`."""
    tau = np.atleast_1d(np.asarray(tau, dtype=float)) % 1.0
    (fa, fa1, fa2), (h, h1, h2) = foot_path_rates(tau, duty, 1.0, 1.0)  # unit shapes
    amplitude = {joint: np.radians(a) for joint, a, _ in GAIT_LAWS}
    prescribed = {"thc_levation": (h, h1, h2), "coxa_rotation": (h, h1, h2),
                  "tita": (2 * fa, 2 * fa1, 2 * fa2)}
    out = np.zeros((3, tau.size, 6))
    for joint, shapes in prescribed.items():
        for m, x in enumerate(shapes):
            out[m, :, JOINTS.index(joint)] = amplitude[joint] * x
    return out[0], out[1], out[2]


def _solve3(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``x`` with ``A x = b`` for (n, 3, 3) and (n, 3), by the adjugate: the inverse's columns
    are the cross products of ``A``'s rows over its determinant (NaN or infinite where ``A`` is
    singular). Several times cheaper than a batched LU on 3 x 3 systems."""
    r0, r1, r2 = A[:, 0], A[:, 1], A[:, 2]
    c0, c1, c2 = _cross(r1, r2), _cross(r2, r0), _cross(r0, r1)
    determinant = np.einsum("ni,ni->n", r0, c0)[:, None]
    return (c0 * b[:, :1] + c1 * b[:, 1:2] + c2 * b[:, 2:]) / determinant


_MOTIONS: dict = {}


def _cached_motion(leg: str, duty: float, tau: np.ndarray):
    """:func:`exact_leg_motion` of a :class:`Stepping` law's ``leg`` (its position and length
    factors), kept for the last few requests: the six laws of a leg ask for the same samples
    one after the other."""
    key = (leg, duty, tau.tobytes())
    if key not in _MOTIONS:
        if len(_MOTIONS) > 32:
            _MOTIONS.clear()
        position, lengths = parse_leg(leg)
        _MOTIONS[key] = exact_leg_motion(position, duty, tau, lengths)
    return _MOTIONS[key]


def leg_spec(position: str, lengths=None) -> str:
    """The ``position`` of a :class:`Stepping` law: the leg (``front``, ``middle`` or
    ``hind``), followed by those of its length factors that are not 1, as
    ``"front femur_length=1.2 tibia_length=0.9"`` (just ``"front"`` for the cockroach's
    proportions)."""
    return " ".join([position] + [f"{name}_length={factor!r}" for name, factor in
                                  zip(SEGMENT_NAMES, length_factors(lengths), strict=True)
                                  if factor != 1.0])


def parse_leg(spec: str) -> tuple[str, tuple[float, float, float, float]]:
    """``"front femur_length=1.2"`` -> ``("front", (1.0, 1.2, 1.0, 1.0))``: the inverse of
    :func:`leg_spec`.

    Raises
    ------
    ValueError
        Not a leg, or a malformed, unknown, repeated or non-positive factor.
    """
    words = str(spec).split()
    if not words or words[0] not in ("front", "middle", "hind"):
        raise ValueError(f"position must be front, middle or hind (then length factors such as "
                         f"femur_length=1.2), got {spec!r}")
    factors = dict.fromkeys(SEGMENT_NAMES, 1.0)
    seen = set()
    for word in words[1:]:
        key, _, value = word.partition("=")
        name = key.removesuffix("_length")
        if not key.endswith("_length") or name not in factors or name in seen:
            raise ValueError(f"position {spec!r}: {word!r} is not one of "
                             f"{', '.join(n + '_length=<factor>' for n in SEGMENT_NAMES)} "
                             "(each at most once)")
        try:
            factors[name] = float(value)
        except ValueError:
            raise ValueError(f"position {spec!r}: {key} must be a number, got {value!r}") \
                from None
        seen.add(name)
    return words[0], length_factors(tuple(factors.values()))


class OnSchedule:
    """What the laws of a walking foot's schedule share (``period``, s; ``duty`` and
    ``lift_off``, fractions of it): they repeat every period and change regime at lift-off and
    touch-down, where the path's pieces join."""

    def cycle_time(self):
        return self.period

    def breaks(self, start, stop):
        return cycle_breaks(self.period, (self.lift_off, self.lift_off + 1.0 - self.duty),
                            start, stop)

    def schedule_problems(self, lowest_duty: float = 0.0) -> list[str]:
        """What is wrong with the schedule: a period that is not positive, a duty outside
        ``(lowest_duty, 1)`` (``[lowest_duty, 1)`` when it is not 0)."""
        out = []
        if not (np.isfinite(self.period) and self.period > 0):
            out.append(f"period must be positive, got {self.period}")
        inside = lowest_duty < self.duty < 1 if lowest_duty == 0.0 else (
            lowest_duty <= self.duty < 1)
        if not inside:
            bracket = "(" if lowest_duty == 0.0 else "["
            out.append(f"duty must be in {bracket}{lowest_duty:g}, 1), got {self.duty}")
        return out


def _position_problems(position: str) -> list[str]:
    """What is wrong with a leg's ``position`` (:func:`parse_leg`), as a list."""
    try:
        parse_leg(position)
    except ValueError as error:
        return [str(error)]
    return []


@dataclass(frozen=True)
class Stepping(OnSchedule, Law):
    """The law of one joint of a leg walking with its foot exactly on its path
    (:func:`exact_leg_motion`): a ``front``, ``middle`` or ``hind`` leg, the gait's ``duty``
    factor and ``period`` (s), the leg's ``lift_off`` (a fraction of the period). The same
    angles serve the left and the right leg (their axes are mirror images).

    A leg whose segments' lengths differ from the cockroach's names its length factors in
    ``position`` after the leg (:func:`leg_spec`: ``"front femur_length=1.2"``), so that a
    scene file written with the cockroach's proportions has no key more than it had, and one
    written with other proportions reads back the same law. :attr:`leg` and :attr:`lengths`
    give the two parts."""

    position: str = "front"
    joint: str = "thc_protraction"
    duty: float = 0.5
    period: float = 1.0
    lift_off: float = 0.0
    kind = "stepping"
    costly = True  # Newton's method on the leg at every call

    def evaluate(self, t):
        values = type(self).evaluate_batch([self], t)
        return values[0, 0], values[1, 0], values[2, 0]

    def batch_key(self):
        return (self.position, self.duty, self.joint in SOLVED_JOINTS)

    @classmethod
    def evaluate_batch(cls, laws, t):
        """The laws of legs of one shape and duty in one solve: each leg's phase (its period
        and lift-off) gives its cycle fractions, and the foot paths of all are solved
        together (Newton's method costs little more for more samples). The prescribed
        joints' laws are closed forms of the path (no solve)."""
        t = np.asarray(t, dtype=float)
        phases = sorted({(law.period, law.lift_off) for law in laws})
        taus = [(np.atleast_1d(t) / period - lift_off) % 1.0 for period, lift_off in phases]
        solve = (_cached_motion if laws[0].joint in SOLVED_JOINTS
                 else lambda _, duty, tau: prescribed_motion(duty, tau))
        motion = solve(laws[0].position, laws[0].duty, np.concatenate(taus))
        size = taus[0].size
        out = np.empty((3, len(laws)) + t.shape)
        for i, law in enumerate(laws):
            p = phases.index((law.period, law.lift_off))
            k = JOINTS.index(law.joint)
            for m in range(3):
                out[m, i] = motion[m][p * size:(p + 1) * size, k].reshape(t.shape) / law.period**m
        return out

    @property
    def leg(self) -> str:
        """``front``, ``middle`` or ``hind``."""
        return parse_leg(self.position)[0]

    @property
    def lengths(self) -> tuple[float, float, float, float]:
        """The factors of the coxa, femur, tibia and tarsus lengths."""
        return parse_leg(self.position)[1]

    def problems(self):
        out = _position_problems(self.position)
        if self.joint not in JOINTS:
            out.append(f"joint must be one of {', '.join(JOINTS)}, got {self.joint!r}")
        return out + self.schedule_problems(lowest_duty=0.5)


@dataclass(frozen=True)
class FootPath(OnSchedule, Law):
    """One coordinate (m) of a walking leg's foot on its path (:func:`path_targets`), in the
    trunk's frame of :func:`legs.robot.hexapod_scene` (from the trunk's origin: the leg's
    thorax-coxa point plus the path, mirrored on the right): a guide's law, so that the engine
    places the leg's joints (:mod:`hexapod.scene.laws.guided`). ``position`` names the leg and
    its length factors as :class:`Stepping`'s; ``side`` ``L`` or ``R``; ``axis`` 0, 1, 2 (x
    forward, y left, z up); the gait's ``duty``, ``period`` (s) and the leg's ``lift_off`` (a
    fraction of the period); ``scale`` the robot's."""

    position: str = "front"
    side: str = "L"
    axis: int = 0
    duty: float = 0.5
    period: float = 1.0
    lift_off: float = 0.0
    scale: float = 1.0
    kind = "foot-path"

    def evaluate(self, t):
        from legs.cockroach import THC_POINT_MM

        t = np.asarray(t, dtype=float)
        tau = (np.atleast_1d(t) / self.period - self.lift_off) % 1.0
        leg, lengths = parse_leg(self.position)
        sign = -1.0 if (self.side == "R" and self.axis == 1) else 1.0
        # the path is linear in the scale: solved at natural scale, where its geometry is kept
        value = (path_targets(leg, tau, self.duty, 1.0, lengths)[:, self.axis]
                 + 1e-3 * THC_POINT_MM[leg][self.axis]) * sign * self.scale
        length, lift = (1e-3 * self.scale * x for x in (STANCE_LENGTH_MM, FOOT_LIFT_MM))
        (_, fa1, fa2), (_, h1, h2) = foot_path_rates(tau, self.duty, length, lift)
        rate, acceleration = {0: (fa1, fa2), 1: (0 * tau, 0 * tau), 2: (h1, h2)}[self.axis]
        return (value.reshape(t.shape), (rate / self.period).reshape(t.shape),
                (acceleration / self.period**2).reshape(t.shape))

    def problems(self):
        out = _position_problems(self.position)
        if self.side not in ("L", "R") or self.axis not in (0, 1, 2):
            out.append(f"side must be L or R and axis 0, 1 or 2, got {self.side!r}, "
                       f"{self.axis!r}")
        for name in ("period", "scale"):
            if not (np.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                out.append(f"{name} must be positive, got {getattr(self, name)}")
        if not 0 < self.duty < 1:
            out.append(f"duty must be in (0, 1), got {self.duty}")
        return out
