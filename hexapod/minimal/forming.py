"""Three methods of forming ``W(q) q_dd = P + V(q, q_d)`` for open chains and trees.

Vukobratović and Potkonjak (Mech. Mach. Theory 14 (1979) 179-188) form the model of an open chain by
three methods and compare their efficiency. **Our copy holds Part I only** (the method of basic
theorems, implemented in :mod:`hexapod.minimal.chain`); the Lagrange and Gibbs-Appell algorithms of
Part II and its operation counts are missing. This module is a **reconstruction from the
literature**, not a transcription of Part II:

* M. Vukobratovic, V. Potkonjak, "Scientific Fundamentals of Robotics 1: Dynamics of
  Manipulation Robots", Springer 1982, ch. 2 (the computer-oriented methods: general theorems,
  Lagrange equations, Appell equations, on the same recurrent kinematic relations for the
  coefficients ``Omega``, ``Gamma`` and the free terms);
* J. M. Hollerbach, "A recursive Lagrangian formulation of manipulator dynamics and a
  comparative study of dynamics formulation complexity", IEEE Trans. SMC 10(11) (1980) 730-736
  (a Lagrangian with Christoffel symbols of the Uicker-Kahn kind costs O(n^4), against O(n)
  to O(n^3) for the others);
* E. P. Popov, A. F. Vereshchagin, S. L. Zenkevich, "Manipulation Robots: Dynamics and
  Algorithms" (in Russian), Nauka 1978, and K. Desoyer, P. Lugner, "Recursive formulation for
  the analytical or numerical application of the Gibbs-Appell method to the dynamics of
  robots", Robotica 7 (1989) 343-347 (Gibbs-Appell).

The bibliographic details are quoted from memory, not from the papers: check before citing.

All three methods share the recurrent kinematics of Part I (eqs. (11)-(14), (23)-(30)): the
coefficients of the generalized accelerations ``Omega_j`` (centre of mass ``j``; the Jacobian of
its position) and ``Gamma_j`` (angular acceleration; the Jacobian of the angular velocity:
column ``k`` is the world axis ``e_k`` of a revolute joint ``k`` on the path to ``j``, zero for a
prismatic one) and the free terms ``theta_j``, ``phi_j``:

``basic``
    the theorems of kinetic momentum and of the motion of the centre of mass applied to the
    part beyond every joint, projected on its axis (Part I; as :meth:`ChainModel.matrices`).

``lagrange``
    the kinetic energy ``T = 1/2 sum_j (m_j v_j.v_j + w_j.J_j w_j) = 1/2 q_d^T W q_d`` gives
    ``W_kl = sum_j (m_j Omega_jk.Omega_jl + Gamma_jk.J_j Gamma_jl)``, and
    ``V_k = -sum_lm (dW_kl/dq_m - 1/2 dW_lm/dq_k) q_d_l q_d_m + sum_j m_j Omega_jk.g``
    (Christoffel symbols of the first kind). The derivatives of ``W`` come from the recurrent
    relations, not from differencing: ``d Omega_jk / d q_m = Gamma_j,min(k,m) x
    Omega_j,max(k,m)`` (the earlier of the two joints on the path, a symmetric second
    derivative), ``d Gamma_jk / d q_m = Gamma_jm x Gamma_jk`` for ``m`` before ``k``, and
    ``d J_j / d q_m = [Gamma_jm] J_j - J_j [Gamma_jm]``. Forming ``V`` is O(n^4) for a chain.

``gibbs-appell``
    the acceleration energy ``G = 1/2 sum_j (m_j a_j.a_j + eps_j.J_j eps_j
    + 2 eps_j.(w_j x J_j w_j))`` with ``a_j = Omega_j q_dd + theta_j``,
    ``eps_j = Gamma_j q_dd + phi_j``; Appell's equations ``dG/dq_dd = P + Q_gravity`` are linear
    in ``q_dd``: their coefficients are ``W`` (the same as Lagrange's) and their free part
    ``V_k = -sum_j [m_j Omega_jk.(theta_j - g) + Gamma_jk.(J_j phi_j + w_j x J_j w_j)]``.

The functions are written in plain arithmetic on numpy arrays (``+ - *`` only, no BLAS), so that
they run unchanged on :class:`Counted` scalars (object arrays): the operation counts of
:func:`count_operations` come from running the methods, not from formulas. Products and sums of
constants (the geometry and inertia of the model) are precomputed and not counted; an operation
with a constant exact zero or one is skipped (structural zeros: the ground, prismatic columns of
``Gamma``). Sines and cosines are counted apart.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

METHODS = ("basic", "lagrange", "gibbs-appell")

# ---------------------------------------------------------------- the counting instrument


@dataclass
class OpCount:
    """Operations counted while a :func:`counting` block was active."""

    mul: int = 0  # multiplications and divisions
    add: int = 0  # additions and subtractions
    fun: int = 0  # sines and cosines

    def as_dict(self) -> dict:
        return {"mul": self.mul, "add": self.add, "fun": self.fun}


_NO_COUNT = OpCount()  # the tally outside a counting block (discarded)


def _is_const(x) -> bool:
    return isinstance(x, (int, float, np.floating, np.integer))


class Counted:
    """A float that counts the arithmetic done on it (``Counted.tally``).

    An operation between a ``Counted`` and a plain number is counted, except additions of an
    exact zero and multiplications by an exact zero or one (structural constants); operations
    between plain numbers are not counted (precomputed constants)."""

    __slots__ = ("v",)
    tally = _NO_COUNT

    def __init__(self, v):
        self.v = float(v)

    def __float__(self):
        return self.v

    def __repr__(self):
        return f"Counted({self.v!r})"

    def __add__(self, o):
        if not isinstance(o, Counted) and not _is_const(o):
            return NotImplemented
        if isinstance(o, Counted):
            Counted.tally.add += 1
            return Counted(self.v + o.v)
        if o == 0:
            return self
        Counted.tally.add += 1
        return Counted(self.v + o)

    __radd__ = __add__

    def __sub__(self, o):
        if not isinstance(o, Counted) and not _is_const(o):
            return NotImplemented
        if isinstance(o, Counted):
            Counted.tally.add += 1
            return Counted(self.v - o.v)
        if o == 0:
            return self
        Counted.tally.add += 1
        return Counted(self.v - o)

    def __rsub__(self, o):
        if not _is_const(o):
            return NotImplemented
        if o == 0:
            return Counted(-self.v)
        Counted.tally.add += 1
        return Counted(o - self.v)

    def __mul__(self, o):
        if not isinstance(o, Counted) and not _is_const(o):
            return NotImplemented
        if isinstance(o, Counted):
            Counted.tally.mul += 1
            return Counted(self.v * o.v)
        if o == 0:
            return 0.0
        if o == 1:
            return self
        if o == -1:
            return Counted(-self.v)
        Counted.tally.mul += 1
        return Counted(self.v * o)

    __rmul__ = __mul__

    def __truediv__(self, o):
        if not isinstance(o, Counted) and not _is_const(o):
            return NotImplemented
        Counted.tally.mul += 1
        return Counted(self.v / float(o))

    def __rtruediv__(self, o):
        Counted.tally.mul += 1
        return Counted(float(o) / self.v)

    def __neg__(self):
        return Counted(-self.v)

    def __pos__(self):
        return self


@contextmanager
def counting():
    """``with counting() as tally:`` counts the operations on :class:`Counted` scalars."""
    previous, Counted.tally = Counted.tally, OpCount()
    try:
        yield Counted.tally
    finally:
        Counted.tally = previous


def counted(x) -> np.ndarray:
    """An object array of :class:`Counted` with the values of ``x``."""
    x = np.asarray(x, dtype=float)
    out = np.empty(x.shape, dtype=object)
    for i, v in np.ndenumerate(x):
        out[i] = Counted(v)
    return out


def values(x) -> np.ndarray:
    """Floats from an array of :class:`Counted` (or of plain numbers)."""
    x = np.asarray(x)
    return np.vectorize(float, otypes=[float])(x) if x.size else x.astype(float)


def _cos(x):
    if isinstance(x, Counted):
        Counted.tally.fun += 1
        return Counted(math.cos(x.v))
    return math.cos(x)


def _sin(x):
    if isinstance(x, Counted):
        Counted.tally.fun += 1
        return Counted(math.sin(x.v))
    return math.sin(x)


# ---------------------------------------------------------------- plain arithmetic on 3-vectors
# (arrays whose last axis has length 3; floats or Counted)


def _dot(a, b):
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def _cross(a, b):
    a, b = np.broadcast_arrays(a, b)
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def _matvec(R, v):
    """``R v`` for a 3x3 ``R`` and vectors ``v`` (..., 3)."""
    return np.stack([_dot(R[i], v) for i in range(3)], axis=-1)


def _matmul(A, B):
    """``A B`` of two 3x3 matrices."""
    return np.stack([_matvec(A, B[:, j]) for j in range(3)], axis=-1)


def _inertia_world(R, inertia):
    """``R I R^T`` (symmetric: six entries computed)."""
    T = _matmul(R, inertia)
    out = np.empty((3, 3), dtype=object if object in (R.dtype, T.dtype) else float)
    for i in range(3):
        for j in range(i, 3):
            out[i, j] = out[j, i] = _dot(T[i], R[j])
    return out


def _array(shape, dtype):
    """Zeros: floats, or plain ``0.0`` in an object array (structural zeros, not counted)."""
    if dtype is object:
        return np.full(shape, 0.0, dtype=object)
    return np.zeros(shape, dtype=dtype)


# ---------------------------------------------------------------- constants of the chain


@dataclass
class _Link:
    kind: str
    parent: int
    coordinate: int
    mass: float
    inertia: np.ndarray
    p_pos: np.ndarray  # joint point in the parent's centre-of-mass frame
    b: np.ndarray  # the axis in the parent's centre-of-mass frame
    rel: tuple  # (M0, M1, M2): parent -> child rotation M0 + cos q M1 + sin q M2
    c_pos: np.ndarray  # joint point in the child's frame
    path: list = field(default_factory=list)  # links with a coordinate, root -> this link


@dataclass
class Layout:
    """The constants of a chain for the three methods (build once: :func:`layout`)."""

    links: list
    dof: int
    gravity: np.ndarray
    subtree: list  # links beyond each link (itself first)


def layout(chain) -> Layout:
    """Constants of a :class:`~hexapod.minimal.chain.ChainModel` (any object with ``links``,
    ``dof`` and ``gravity`` of that form)."""
    out = []
    for link in chain.links:
        a = np.asarray(link.axis, dtype=float)
        if link.kind != "fixed":
            a = a / np.linalg.norm(a)
        P, C = link.on_parent.rotation, link.on_child.rotation.T
        K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        aa = np.outer(a, a)
        if link.kind == "revolute":
            rel = (P @ aa @ C, P @ (np.eye(3) - aa) @ C, P @ K @ C)
        else:
            rel = (P @ C, None, None)
        path = [] if link.parent < 0 else list(out[link.parent].path)
        if link.coordinate >= 0:
            path.append(len(out))
        out.append(_Link(link.kind, link.parent, link.coordinate, float(link.mass),
                         np.asarray(link.inertia, dtype=float),
                         np.asarray(link.on_parent.position, dtype=float), P @ a, rel,
                         np.asarray(link.on_child.position, dtype=float), path))
    subtree = [[k] for k in range(len(out))]
    for k in reversed(range(len(out))):
        if out[k].parent >= 0:
            subtree[out[k].parent].extend(subtree[k])
    return Layout(out, int(chain.dof), np.asarray(chain.gravity, dtype=float), subtree)


# ---------------------------------------------------------------- recurrent kinematics


@dataclass
class _State:
    R: list
    r: list  # centres of mass
    A: list  # joint origins (on the child)
    e: list  # world axes
    omega: list = None
    phi: list = None  # free term of the angular acceleration
    theta: list = None  # free term of the acceleration of the centre of mass


def _kinematics(lay: Layout, q, q_d=None) -> _State:
    """Poses (and, with ``q_d``, angular velocities and free terms of the accelerations) of
    every link by the recurrent relations of Vukobratović and Potkonjak (1979), Part I."""
    n = len(lay.links)
    s = _State([None] * n, [None] * n, [None] * n, [None] * n)
    if q_d is not None:
        s.omega, s.phi, s.theta = [None] * n, [None] * n, [None] * n
    eye, zero = np.eye(3), np.zeros(3)
    for k, link in enumerate(lay.links):
        p = link.parent
        R_p, r_p = (eye, zero) if p < 0 else (s.R[p], s.r[p])
        arm_p = _matvec(R_p, link.p_pos)  # centre of mass of the parent -> joint point
        point = r_p + arm_p
        e = _matvec(R_p, link.b)
        c = link.coordinate
        qc = q[c] if c >= 0 else 0.0
        if link.kind == "revolute":
            M0, M1, M2 = link.rel
            cq, sq = _cos(qc), _sin(qc)
            R = _matmul(R_p, M0 + cq * M1 + sq * M2)
        else:
            R = _matmul(R_p, link.rel[0])
        origin = point + qc * e if link.kind == "prismatic" else point
        arm = -_matvec(R, link.c_pos)  # joint origin -> centre of mass
        s.R[k], s.r[k], s.A[k], s.e[k] = R, origin + arm, origin, e
        if q_d is None:
            continue
        w_p, phi_p, th_p = (zero, zero, zero) if p < 0 else (s.omega[p], s.phi[p], s.theta[p])
        qc_d = q_d[c] if c >= 0 else 0.0
        theta = th_p + _cross(phi_p, arm_p) + _cross(w_p, _cross(w_p, arm_p))
        omega, phi = w_p, phi_p
        if link.kind == "revolute":
            omega = w_p + qc_d * e
            phi = phi_p + qc_d * _cross(w_p, e)
        elif link.kind == "prismatic":
            w_e = _cross(w_p, e)
            theta = theta + 2.0 * qc_d * w_e + qc * (_cross(phi_p, e) + _cross(w_p, w_e))
        s.omega[k], s.phi[k] = omega, phi
        s.theta[k] = theta + _cross(phi, arm) + _cross(omega, _cross(omega, arm))
    return s


def _jacobians(lay: Layout, s: _State, j: int, dtype):
    """``Omega_j`` and ``Gamma_j`` restricted to the path of ``j``: arrays (p, 3)."""
    path = lay.links[j].path
    Om, Ga = _array((len(path), 3), dtype), _array((len(path), 3), dtype)
    for i, k in enumerate(path):
        if lay.links[k].kind == "revolute":
            Ga[i] = s.e[k]
            Om[i] = _cross(s.e[k], s.r[j] - s.A[k])
        else:
            Om[i] = s.e[k]
    return Om, Ga


def _mirror(W, done):
    """Fill ``W[b, a] = W[a, b]`` where only ``(a, b)`` was formed (``done``)."""
    for a, b in zip(*np.nonzero(done & ~done.T), strict=True):
        W[b, a] = W[a, b]
    return W


# ---------------------------------------------------------------- the three methods


def _basic(lay: Layout, q, q_d, dtype):
    """Theorems of kinetic momentum and of the centre of mass, per joint, on the part beyond;
    only the upper triangle of ``W`` is formed (the rest by symmetry)."""
    s = _kinematics(lay, q, q_d)
    dof, g = lay.dof, lay.gravity
    W, V = _array((dof, dof), dtype), _array(dof, dtype)
    done = np.zeros((dof, dof), dtype=bool)
    jac, J, force, moment = {}, {}, {}, {}
    for j, link in enumerate(lay.links):
        jac[j] = _jacobians(lay, s, j, dtype)
        J[j] = _inertia_world(s.R[j], link.inertia)
        force[j] = link.mass * (s.theta[j] - g)
        moment[j] = _matvec(J[j], s.phi[j]) + _cross(s.omega[j], _matvec(J[j], s.omega[j]))
    for k, link in enumerate(lay.links):
        c = link.coordinate
        if c < 0:
            continue
        e = s.e[k]
        for j in lay.subtree[k]:
            path = lay.links[j].path
            first = path.index(k)
            cols = [lay.links[i].coordinate for i in path[first:]]
            Om, Ga = jac[j][0][first:], jac[j][1][first:]
            m = lay.links[j].mass
            done[c, cols] = True
            if link.kind == "revolute":
                u = _cross(e, s.r[j] - s.A[k])  # e . (arm x f) = (e x arm) . f
                Je = _matvec(J[j], e)
                W[c, cols] = W[c, cols] + _dot(m * u, Om) + _dot(Je, Ga)
                V[c] = V[c] - (_dot(u, force[j]) + _dot(e, moment[j]))
            else:
                W[c, cols] = W[c, cols] + _dot(m * e, Om)
                V[c] = V[c] - _dot(e, force[j])
    return _mirror(W, done), V


def _w_of_jacobians(lay: Layout, s: _State, dtype):
    """``W_kl = sum_j m_j Omega_jk.Omega_jl + Gamma_jk.J_j Gamma_jl`` (k <= l), with the
    Jacobians and world inertias it used."""
    dof = lay.dof
    W = _array((dof, dof), dtype)
    done = np.zeros((dof, dof), dtype=bool)
    data = {}
    for j, link in enumerate(lay.links):
        path = link.path
        Om, Ga = _jacobians(lay, s, j, dtype)
        J = _inertia_world(s.R[j], link.inertia)
        JGa = _array((len(path), 3), dtype)
        for i, k in enumerate(path):
            if lay.links[k].kind == "revolute":
                JGa[i] = _matvec(J, Ga[i])
        data[j] = (Om, Ga, J, JGa)
        if not path:
            continue
        a, b = np.triu_indices(len(path))
        cols = np.array([lay.links[i].coordinate for i in path])
        done[cols[a], cols[b]] = True
        W[cols[a], cols[b]] = W[cols[a], cols[b]] + (_dot(Om[a], link.mass * Om[b])
                                                     + _dot(Ga[a], JGa[b]))
    return W, done, data


def _gibbs_appell(lay: Layout, q, q_d, dtype):
    """``W`` and ``V`` from ``dG/dq_dd`` of the acceleration energy ``G``."""
    s = _kinematics(lay, q, q_d)
    W, done, data = _w_of_jacobians(lay, s, dtype)
    V = _array(lay.dof, dtype)
    for j, link in enumerate(lay.links):
        if not link.path:
            continue
        Om, Ga, J, _ = data[j]
        force = link.mass * (s.theta[j] - lay.gravity)
        moment = _matvec(J, s.phi[j]) + _cross(s.omega[j], _matvec(J, s.omega[j]))
        cols = [lay.links[i].coordinate for i in link.path]
        V[cols] = V[cols] - (_dot(Om, force) + _dot(Ga, moment))
    return _mirror(W, done), V


def _lagrange(lay: Layout, q, q_d, dtype):
    """``W`` from the kinetic energy, ``V`` from its Christoffel symbols and gravity."""
    s = _kinematics(lay, q)
    W, done, data = _w_of_jacobians(lay, s, dtype)
    dof = lay.dof
    D = _array((dof, dof, dof), dtype)  # D[k, l, m] = dW_kl / dq_m, k <= l
    grav = _array(dof, dtype)
    for j, link in enumerate(lay.links):
        path = link.path
        p = len(path)
        if not p:
            continue
        Om, Ga, J, JGa = data[j]
        cols = np.array([lay.links[i].coordinate for i in path])
        grav[cols] = grav[cols] + _dot(Om, link.mass * lay.gravity)
        # d Omega_k / d q_m = Gamma_min(k,m) x Omega_max(k,m)
        a, b = np.triu_indices(p)
        H = _array((p, p, 3), dtype)
        H[a, b] = _cross(Ga[a], Om[b])
        H[b, a] = H[a, b]
        # d Gamma_k / d q_m = Gamma_m x Gamma_k for m before k
        dG = _array((p, p, 3), dtype)
        a1, b1 = np.triu_indices(p, 1)
        dG[b1, a1] = _cross(Ga[a1], Ga[b1])
        k, l = a, b  # pairs k <= l
        trans = _dot(H[k], Om[l][:, None]) + _dot(Om[k][:, None], H[l])
        rot = _dot(dG[k], JGa[l][:, None]) + _dot(JGa[k][:, None], dG[l])
        # Gamma_k . (dJ/dq_m) Gamma_l = Gamma_m . (J Gamma_l x Gamma_k + J Gamma_k x Gamma_l)
        sym = _cross(JGa[l], Ga[k]) + _cross(JGa[k], Ga[l])
        rot = rot + _dot(Ga[None, :, :], sym[:, None, :])
        block = link.mass * trans + rot  # (pairs, p)
        ck, cl = cols[k][:, None], cols[l][:, None]
        D[ck, cl, cols[None, :]] = D[ck, cl, cols[None, :]] + block
    _mirror(D, done)  # the other half by symmetry in (k, l)
    # sum_lm c_klm q_d_l q_d_m with c_klm = dW_kl/dq_m - 1/2 dW_lm/dq_k (symmetric part in l, m)
    Q = _array((dof, dof), dtype)
    for l in range(dof):
        Q[l, l:] = q_d[l] * q_d[l:]
        Q[l:, l] = Q[l, l:]
    E = D - 0.5 * D.transpose(2, 0, 1)  # E[k, l, m] = D[k, l, m] - D[l, m, k] / 2
    V = _array(dof, dtype)
    for k in range(dof):
        acc = E[k] * Q
        V[k] = grav[k] - np.add.reduce(acc.reshape(-1))
    return _mirror(W, done), V


_FORMERS = {"basic": _basic, "lagrange": _lagrange, "gibbs-appell": _gibbs_appell}


def form(lay: Layout, q, q_d, method: str = "basic") -> tuple[np.ndarray, np.ndarray]:
    """``W`` and ``V`` of ``W q_dd = P + V`` by ``method`` (one of :data:`METHODS`). ``q`` and
    ``q_d`` may be float arrays or object arrays of :class:`Counted`; the result has their kind."""
    if method not in _FORMERS:
        raise ValueError(f"unknown method '{method}': choose one of {', '.join(METHODS)}")
    q, q_d = np.asarray(q), np.asarray(q_d)
    dtype = object if object in (q.dtype, q_d.dtype) else float
    if dtype is float:
        q, q_d = q.astype(float), q_d.astype(float)
    return _FORMERS[method](lay, q, q_d, dtype)


def count_operations(lay: Layout, method: str, q=None, q_d=None) -> OpCount:
    """The operations of one forming of ``W`` and ``V`` by ``method``, counted by running it
    on :class:`Counted` scalars (at ``q``, ``q_d``: random when not given)."""
    rng = np.random.default_rng(0)
    q = rng.normal(size=lay.dof) if q is None else q
    q_d = rng.normal(size=lay.dof) if q_d is None else q_d
    with counting() as tally:
        form(lay, counted(q), counted(q_d), method)
    return tally
