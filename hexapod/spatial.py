"""Rotations, Euler parameters and frames, written once for CasADi SX and for numbers.

Conventions (those of docs/scene-format.md): Euler parameters ``p = (e0, e1, e2, e3)`` are stored
**scalar first**; ``A(p)`` maps body to global components; ``G(p)`` and ``E(p)`` are Haug's 3 x 4
matrices with ``omega' = 2 G(p) p_dot`` (body frame) and ``omega = 2 E(p) p_dot`` (global frame).

The matrix-valued functions accept a NumPy array or a CasADi SX/MX vector and return the same kind,
so the model's residuals and the numerical helpers share one formula.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

#: Public as ``hexapod.spatial``: the frame and the rotation helpers a scene is written with.
__all__ = ["Placement", "euler_parameters_from_rotation", "rotation_about_axis",
           "rotation_from_euler_parameters", "rotation_from_rpy", "rpy_from_rotation"]

_SYMBOLIC = (ca.SX, ca.MX, ca.DM)


def _is_symbolic(*xs) -> bool:
    return any(isinstance(x, _SYMBOLIC) for x in xs)


def _matrix(rows, symbolic: bool):
    """Build a matrix from nested lists of scalars, as CasADi or NumPy."""
    if symbolic:
        return ca.vertcat(*[ca.horzcat(*row) for row in rows])
    return np.array(rows, dtype=float)


def _inlined(formula):
    """Evaluate ``formula`` on numbers directly; on CasADi symbols through an SX Function built
    once from it, whose call inlines the whole formula in one step (building it operation by
    operation from Python costs far more when models have many bodies)."""
    cache: dict = {}

    @functools.wraps(formula)
    def wrapper(*args):
        if not _is_symbolic(*args):
            return formula(*args)
        sizes = tuple(int(a.numel()) for a in args)
        if sizes not in cache:
            symbols = [ca.SX.sym(f"x{k}", n) for k, n in enumerate(sizes)]
            cache[sizes] = ca.Function(formula.__name__, symbols, [formula(*symbols)])
        return cache[sizes](*args)

    return wrapper


def skew(w):
    """Cross-product matrix: ``skew(w) @ x == cross(w, x)``."""
    w0, w1, w2 = w[0], w[1], w[2]
    return _matrix([[0.0, -w2, w1], [w2, 0.0, -w0], [-w1, w0, 0.0]], _is_symbolic(w))


@_inlined
def rotation_from_euler_parameters(p: ArrayLike | ca.SX | ca.MX) -> np.ndarray | ca.SX | ca.MX:
    """``A(p) = (2 e0^2 - 1) I + 2 (e e^T + e0 ~e)``, body -> global (unit ``p`` assumed).

    Parameters
    ----------
    p : array_like, shape (4,), or a CasADi SX or MX vector
        Euler parameters ``(e0, e1, e2, e3)``, scalar first.

    Returns
    -------
    ndarray, shape (3, 3), or a CasADi matrix
        The rotation matrix, of the kind of ``p``.
    """
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    return _matrix(
        [
            [2 * (e0 * e0 + e1 * e1) - 1, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)],
            [2 * (e1 * e2 + e0 * e3), 2 * (e0 * e0 + e2 * e2) - 1, 2 * (e2 * e3 - e0 * e1)],
            [2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), 2 * (e0 * e0 + e3 * e3) - 1],
        ],
        _is_symbolic(p),
    )


@_inlined
def g_matrix(p):
    """Haug's ``G(p) = [-e, -~e + e0 I]`` (3 x 4): ``omega' = 2 G(p) p_dot``."""
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    return _matrix(
        [[-e1, e0, e3, -e2], [-e2, -e3, e0, e1], [-e3, e2, -e1, e0]], _is_symbolic(p)
    )


@_inlined
def e_matrix(p):
    """Haug's ``E(p) = [-e, ~e + e0 I]`` (3 x 4): ``omega = 2 E(p) p_dot``."""
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    return _matrix(
        [[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]], _is_symbolic(p)
    )


def rotation_2d(angle):
    """Planar rotation matrix of ``angle`` (rad)."""
    if _is_symbolic(angle):
        c, s = ca.cos(angle), ca.sin(angle)
        return _matrix([[c, -s], [s, c]], True)
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


@_inlined
def quaternion_product(p, q):
    """Hamilton product, scalar first: ``A(p * q) = A(p) A(q)``; row-wise for (n, 4) arrays,
    or of two CasADi 4-vectors."""
    if _is_symbolic(p, q):
        s = p[0] * q[0] - ca.dot(p[1:4], q[1:4])
        return ca.vertcat(s, p[0] * q[1:4] + q[0] * p[1:4] + ca.cross(p[1:4], q[1:4]))
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    # by components: NumPy's sum and cross cost three times the arithmetic on a few bodies
    out = np.empty(np.broadcast_shapes(p.shape, q.shape))
    for k, part in enumerate(_product_components([p[..., k] for k in range(4)],
                                                 [q[..., k] for k in range(4)])):
        out[..., k] = part
    return out


def _product_components(p, q) -> list:
    """The Hamilton product's four components from the factors' (sequences of four: arrays
    of many quaternions' components, or CasADi vectors of them)."""
    p0, p1, p2, p3 = p
    q0, q1, q2, q3 = q
    return [p0 * q0 - (p1 * q1 + p2 * q2 + p3 * q3),
            p0 * q1 + q0 * p1 + (p2 * q3 - p3 * q2),
            p0 * q2 + q0 * p2 + (p3 * q1 - p1 * q3),
            p0 * q3 + q0 * p3 + (p1 * q2 - p2 * q1)]


def retract_symbolic(q, dv, lin_q, lin_v, quat_q, omega_v):
    """``q (+) dv`` on CasADi SX symbols (:meth:`hexapod.model.model.Model.integrate`
    evaluates it on numbers): coordinates ``lin_q`` move by the velocity-space entries
    ``lin_v``, and each spatial body's Euler parameters (the rows of ``quat_q``) turn by the
    body-frame rotation vector at ``omega_v``, ``p <- p * exp(dpi'/2)``, renormalised. Written
    on the vectors of all bodies' components at once (a few dozen operations to build, whatever
    the bodies: the body-by-body writing took 10 ms to build for 19 bodies)."""
    out = ca.SX(q)
    if len(lin_q):
        out[[int(i) for i in lin_q]] = q[[int(i) for i in lin_q]] + dv[[int(j) for j in lin_v]]
    if not len(quat_q):
        return out
    theta = [dv[[int(j) for j in omega_v[:, a]]] for a in range(3)]
    angle2 = theta[0] * theta[0] + theta[1] * theta[1] + theta[2] * theta[2]
    small = angle2 < 1e-16
    angle = ca.sqrt(ca.if_else(small, 1.0, angle2))
    # sin(x/2)/x with its series near zero (no 0/0 in the branch not taken)
    k = ca.if_else(small, 0.5 - angle2 / 48.0, ca.sin(angle / 2) / angle)
    c = ca.if_else(small, 1.0 - angle2 / 8.0, ca.cos(angle / 2))
    p = [q[[int(i) for i in quat_q[:, a]]] for a in range(4)]
    product = _product_components(p, [c, *(k * t for t in theta)])
    norm = ca.sqrt(sum(x * x for x in product))
    for a in range(4):
        out[[int(i) for i in quat_q[:, a]]] = product[a] / norm
    return out


# ---------------------------------------------------------------- numbers only

def quaternion_exp(rotation_vector) -> np.ndarray:
    """Unit quaternion of the rotation ``rotation_vector`` (axis times angle, rad); row-wise for
    (n, 3) arrays."""
    theta = np.asarray(rotation_vector, dtype=float)
    angle = np.linalg.norm(theta, axis=-1, keepdims=True)
    small = angle < 1e-8
    # sin(x/2)/x, with its series near zero so that the result stays smooth and unit
    k = np.where(small, 0.5 - angle**2 / 48.0, np.sin(angle / 2) / np.where(small, 1.0, angle))
    return np.concatenate([np.cos(angle / 2), k * theta], axis=-1)


def quaternion_log(p) -> np.ndarray:
    """Rotation vector of unit Euler parameters (the shorter way round: ``p`` and ``-p`` give
    the same); row-wise for (n, 4) arrays. Inverse of :func:`quaternion_exp`."""
    p = np.asarray(p, dtype=float)
    p = p * np.where(p[..., :1] < 0, -1.0, 1.0)
    s = np.linalg.norm(p[..., 1:], axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(s, p[..., :1])
    k = np.where(s > 1e-12, angle / np.where(s > 1e-12, s, 1.0), 2.0)
    return k * p[..., 1:]


def euler_parameters_from_rotation(R: ArrayLike) -> np.ndarray:
    """Unit Euler parameters (scalar first, ``e0 >= 0``) of a rotation matrix (Shepperd).

    Parameters
    ----------
    R : array_like, shape (3, 3)
        A rotation matrix.

    Returns
    -------
    ndarray, shape (4,)
        ``(e0, e1, e2, e3)``.
    """
    R = np.asarray(R, dtype=float)
    trace = np.trace(R)
    candidates = np.array([trace, R[0, 0], R[1, 1], R[2, 2]])
    k = int(np.argmax(candidates))
    if k == 0:
        e0 = 0.5 * np.sqrt(1.0 + trace)
        p = [e0, (R[2, 1] - R[1, 2]) / (4 * e0), (R[0, 2] - R[2, 0]) / (4 * e0),
             (R[1, 0] - R[0, 1]) / (4 * e0)]
    elif k == 1:
        e1 = 0.5 * np.sqrt(1.0 + 2 * R[0, 0] - trace)
        p = [(R[2, 1] - R[1, 2]) / (4 * e1), e1, (R[0, 1] + R[1, 0]) / (4 * e1),
             (R[0, 2] + R[2, 0]) / (4 * e1)]
    elif k == 2:
        e2 = 0.5 * np.sqrt(1.0 + 2 * R[1, 1] - trace)
        p = [(R[0, 2] - R[2, 0]) / (4 * e2), (R[0, 1] + R[1, 0]) / (4 * e2), e2,
             (R[1, 2] + R[2, 1]) / (4 * e2)]
    else:
        e3 = 0.5 * np.sqrt(1.0 + 2 * R[2, 2] - trace)
        p = [(R[1, 0] - R[0, 1]) / (4 * e3), (R[0, 2] + R[2, 0]) / (4 * e3),
             (R[1, 2] + R[2, 1]) / (4 * e3), e3]
    p = np.array(p)
    p /= np.linalg.norm(p)
    return -p if p[0] < 0 else p


def rotation_about_axis(axis: ArrayLike, angle: float) -> np.ndarray:
    """Rodrigues' formula: rotation by ``angle`` (rad) about the unit direction of ``axis``.

    Parameters
    ----------
    axis : array_like, shape (3,)
        The axis (any nonzero length).
    angle : float
        rad, positive counter-clockwise about ``axis``.

    Returns
    -------
    ndarray, shape (3, 3)
    """
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    K = skew(a)
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)


def rotation_from_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF convention: ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (fixed axes x, y, z).

    Parameters
    ----------
    roll, pitch, yaw : float
        rad.

    Returns
    -------
    ndarray, shape (3, 3)
    """
    return (
        rotation_about_axis([0, 0, 1], yaw)
        @ rotation_about_axis([0, 1, 0], pitch)
        @ rotation_about_axis([1, 0, 0], roll)
    )


def rpy_from_rotation(R: ArrayLike) -> np.ndarray:
    """``(roll, pitch, yaw)`` with ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (URDF), accurate to
    round-off everywhere (pitch from ``atan2``, not ``arcsin``, which loses half the digits near
    +-90 degrees). At gimbal lock the whole turn about z is put in yaw.

    Parameters
    ----------
    R : array_like, shape (3, 3)
        A rotation matrix.

    Returns
    -------
    ndarray, shape (3,)
        ``(roll, pitch, yaw)``, rad.
    """
    R = np.asarray(R, dtype=float)
    pitch = np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0]))
    if np.hypot(R[0, 0], R[1, 0]) < 1e-12:
        return np.array([0.0, pitch, np.arctan2(-R[0, 1], R[1, 1])])
    return np.array([np.arctan2(R[2, 1], R[2, 2]), pitch, np.arctan2(R[1, 0], R[0, 0])])


def orthonormal_complement(axis) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``u, w`` with ``(u, w, a)`` right-handed orthonormal, ``a = axis / |axis|``.

    Deterministic: ``u`` is the normalised component of the coordinate axis least aligned with
    ``a``, so a joint's rows do not change from one run to the next.
    """
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    e = np.eye(3)[int(np.argmin(np.abs(a)))]
    u = e - (e @ a) * a
    u /= np.linalg.norm(u)
    return u, np.cross(a, u)


def is_rotation(R, tol: float = 1e-6) -> bool:
    """True for a proper rotation matrix: ``|R^T R - I| <= tol`` entrywise and ``det R > 0``.

    The tolerance admits matrices written with six or more significant digits."""
    R = np.asarray(R, dtype=float)
    if R.shape not in ((2, 2), (3, 3)) or not np.all(np.isfinite(R)):
        return False
    n = R.shape[0]
    return bool(np.max(np.abs(R.T @ R - np.eye(n))) <= tol and np.linalg.det(R) > 0)


@dataclass(frozen=True)
class Placement:
    """A frame given in another frame: origin ``position`` and ``rotation`` (local -> outer axes).

    In space ``position`` has 3 entries and ``rotation`` is 3 x 3; in the plane, 2 and 2 x 2.
    Compose with ``@``: ``a @ b`` is frame ``b`` (given in ``a``) expressed in ``a``'s outer
    frame.

    Parameters
    ----------
    position : array_like, shape (3,) or (2,)
        The frame's origin in the outer frame (m, or the scene's length unit).
    rotation : array_like, shape (3, 3) or (2, 2), or float, optional
        Its axes in the outer frame (local -> outer); in the plane also an angle (rad).
        Default: the identity.
    """

    position: np.ndarray
    rotation: np.ndarray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self):
        position = np.array(self.position, dtype=float).reshape(-1)
        n = position.size
        rotation = np.eye(n) if self.rotation is None else self.rotation
        rotation = np.array(rotation, dtype=float)
        if rotation.ndim == 0 and n == 2:
            rotation = rotation_2d(float(rotation))
        object.__setattr__(self, "position", position)
        object.__setattr__(self, "rotation", rotation)

    @classmethod
    def identity(cls, dimension: int = 3) -> Placement:
        return cls(np.zeros(dimension))

    @property
    def dimension(self) -> int:
        return self.position.size

    @property
    def angle(self) -> float:
        """Rotation angle of a planar placement (rad)."""
        return float(np.arctan2(self.rotation[1, 0], self.rotation[0, 0]))

    def __matmul__(self, other: Placement) -> Placement:
        return Placement(self.position + self.rotation @ other.position,
                         self.rotation @ other.rotation)

    def inverse(self) -> Placement:
        return Placement(-self.rotation.T @ self.position, self.rotation.T)

    def transform_point(self, x) -> np.ndarray:
        return self.position + self.rotation @ np.asarray(x, dtype=float)

    def scaled(self, factor: float) -> Placement:
        """The same frame with lengths multiplied by ``factor`` (unit conversion)."""
        return Placement(self.position * factor, self.rotation)
