"""Taylor jets: exact first and second derivatives of the references' kinematics.

A :class:`Jet` carries a value and its Taylor coefficients along the coordinates' unit
directions and along one motion, so that any composition of the operations here (arithmetic,
:func:`sin`, :func:`cos`, :func:`arcsin`, :func:`stack`, :func:`rotation`,
:func:`planar_rotation`) gives the Jacobian's columns, the velocity and the acceleration to
round-off: no finite differences, no symbolic algebra, no code shared with the engine.
"""

from __future__ import annotations

import numpy as np


class Jet:
    """A value and its Taylor coefficients along several directions of the coordinates:
    ``c0`` (the value, shape S), ``c1`` (first-order coefficients along each of m directions,
    shape (m,) + S) and ``c2`` (the second-order coefficient along the **last** direction,
    shape S). With ``q(t) = q + e_k t`` for the first n directions and ``q + qd t + qdd t^2 / 2``
    for the last, ``c1`` holds the Jacobian's columns and the velocity, and ``2 c2`` the
    acceleration: exact derivatives of any composition of the operations below."""

    __slots__ = ("c0", "c1", "c2")
    __array_priority__ = 1000

    def __init__(self, c0, c1, c2):
        self.c0, self.c1, self.c2 = c0, c1, c2

    @staticmethod
    def constant(value) -> Jet:
        value = np.asarray(value, dtype=float)
        return Jet(value, np.zeros((1,) + value.shape), np.zeros(value.shape))

    @staticmethod
    def variables(q, qd, qdd=None) -> Jet:
        """The coordinates: unit directions, then the motion's direction ``qd`` (and ``qdd``)."""
        q = np.asarray(q, dtype=float)
        c2 = np.zeros_like(q) if qdd is None else 0.5 * np.asarray(qdd, dtype=float)
        return Jet(q, np.vstack([np.eye(q.size), np.asarray(qd, dtype=float)]), c2)

    def __getitem__(self, index):
        index = index if isinstance(index, tuple) else (index,)
        return Jet(self.c0[index], self.c1[(slice(None),) + index], self.c2[index])

    def __neg__(self):
        return Jet(-self.c0, -self.c1, -self.c2)

    def __add__(self, other):
        other = _lift(other)
        ndim = max(self.c0.ndim, other.c0.ndim)
        return Jet(self.c0 + other.c0, _directions(self, ndim) + _directions(other, ndim),
                    self.c2 + other.c2)

    __radd__ = __add__

    def __sub__(self, other):
        return self + (-_lift(other))

    def __rsub__(self, other):
        return _lift(other) + (-self)

    def __mul__(self, other):
        return _product(self, _lift(other), np.multiply)

    __rmul__ = __mul__

    def __matmul__(self, other):
        return _product(self, _lift(other), np.matmul)

    def __rmatmul__(self, other):
        return _product(_lift(other), self, np.matmul)

    def __truediv__(self, other):
        return self * _reciprocal(_lift(other))

    def __rtruediv__(self, other):
        return _lift(other) * _reciprocal(self)


def _lift(x) -> Jet:
    return x if isinstance(x, Jet) else Jet.constant(x)


def _directions(a: Jet, ndim: int) -> np.ndarray:
    """``a.c1`` with its value axes padded on the left to ``ndim`` (elementwise broadcasting
    must not pair the direction axis with a value axis)."""
    return a.c1.reshape(a.c1.shape[:1] + (1,) * (ndim - a.c0.ndim) + a.c0.shape)


def _product(a: Jet, b: Jet, op) -> Jet:
    if op is np.matmul:
        # a vector's directions are stacked rows: multiply each as a column
        left = (np.matmul(a.c0, b.c1[..., None])[..., 0] if b.c0.ndim == 1
                else np.matmul(a.c0, b.c1))
        c1 = left + np.matmul(a.c1, b.c0)
    else:
        ndim = max(a.c0.ndim, b.c0.ndim)
        c1 = op(a.c0, _directions(b, ndim)) + op(_directions(a, ndim), b.c0)
    return Jet(op(a.c0, b.c0), c1, op(a.c0, b.c2) + op(a.c1[-1], b.c1[-1]) + op(a.c2, b.c0))


def _compose(a: Jet, f0, f1, f2) -> Jet:
    """``f(a)`` from ``f``'s value and first two derivatives at ``a.c0`` (elementwise)."""
    return Jet(f0, f1 * a.c1, f1 * a.c2 + 0.5 * f2 * a.c1[-1] ** 2)


def _reciprocal(a: Jet) -> Jet:
    x = a.c0
    return _compose(a, 1 / x, -1 / x**2, 2 / x**3)


def sin(a):
    a = _lift(a)
    s, c = np.sin(a.c0), np.cos(a.c0)
    return _compose(a, s, c, -s)


def cos(a):
    a = _lift(a)
    s, c = np.sin(a.c0), np.cos(a.c0)
    return _compose(a, c, -s, -c)


def arcsin(a):
    a = _lift(a)
    x = a.c0
    r = 1 / np.sqrt(1 - x * x)
    return _compose(a, np.arcsin(x), r, x * r**3)


def stack(items) -> Jet:
    items = [_lift(i) for i in items]
    m = max(i.c1.shape[0] for i in items)
    c1 = np.zeros((m, len(items)) + items[0].c0.shape)
    for k, item in enumerate(items):
        c1[:, k] = item.c1
    return Jet(np.array([i.c0 for i in items]), c1, np.array([i.c2 for i in items]))


def rotation(axis, angle) -> Jet:
    """Rotation by the jet ``angle`` about the constant unit ``axis`` (Rodrigues,
    ``I + sin K + (1 - cos) K^2``)."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    K2 = K @ K
    s, c = sin(angle), cos(angle)
    return Jet(np.eye(3) + s.c0 * K + (1.0 - c.c0) * K2,
                s.c1[:, None, None] * K - c.c1[:, None, None] * K2, s.c2 * K - c.c2 * K2)


def planar_rotation(cos_jet, sin_jet) -> Jet:
    """Rotation about z whose first column is ``(cos, sin, 0)`` (both jets)."""
    c, s = _lift(cos_jet), _lift(sin_jet)
    m = max(c.c1.shape[0], s.c1.shape[0])
    out = Jet(np.eye(3), np.zeros((m, 3, 3)), np.zeros((3, 3)))
    for coefficient, (cc, ss) in ((out.c0, (c.c0, s.c0)), (out.c2, (c.c2, s.c2))):
        coefficient[0, 0] = coefficient[1, 1] = cc
        coefficient[1, 0], coefficient[0, 1] = ss, -ss
    out.c1[:, 0, 0] = out.c1[:, 1, 1] = c.c1
    out.c1[:, 1, 0] = s.c1
    out.c1[:, 0, 1] = -s.c1
    return out


def vee(S: np.ndarray) -> np.ndarray:
    """The vector of a skew matrix (last two axes)."""
    return np.stack([S[..., 2, 1], S[..., 0, 2], S[..., 1, 0]], axis=-1)
