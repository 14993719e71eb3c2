"""Mechanisms of the extreme-case suite (issue 8), each with a reference independent of the engine.

Every builder returns a :class:`Case`: a :class:`~hexapod.scene.Scene`, how long to run it, what
is extreme about it, and an independent solution of its motion. The observable of a case is the
centre-of-mass position of some of its bodies (:meth:`Case.observable` reads it from an engine
state); :attr:`Case.reference` gives the same numbers at any times, and
:attr:`Case.accelerations` the centres of mass' accelerations at the start (a cheap, strong check
that the scene and the reference describe the same system).

====================================  ==========  =============================================
case                                  category    reference
====================================  ==========  =============================================
:func:`stiff_slider` (k = 1e3..1e9)   stiff       damped oscillator, closed form
:func:`stiff_spring_pendulum`         stiff       2-DOF Lagrange (theta, s) by hand, DOP853
:func:`flyball_governor` (A05)        stiff       symmetric reduction (Routh), Radau at 1e-12
:func:`n_four_bar` (A02)              singular /  1-DOF equation of the parallelogram chain,
                                      redundant   DOP853 at 1e-12
:func:`bricard` (A04)                 redundant   1-DOF Lagrange on the closed-form configuration
                                                  curve ``sin t1 + sin t2 + sin t1 sin t2 = 0``
:func:`four_bar_dead_points`          singular    1-DOF Lagrange on the anti-parallelogram's
                                                  rational branch (free or driven)
:func:`mass_ratio`                    mass-ratio  5-DOF joint-coordinate Lagrange (Kane)
:func:`mass_ratio_pendulum`           mass-ratio  double pendulum, Lagrange in closed form
:func:`stretched_leg`                 singular    1-DOF Lagrange by hand (free) or closed
                                                  form (driven)
:func:`long_pendulum`                 long        Jacobi elliptic functions
:func:`large_step_pendulum`           large-step  Jacobi elliptic functions
====================================  ==========  =============================================

The references never call the engine: they are written in minimal (joint) coordinates, in
closed form or as ordinary differential equations integrated by SciPy at ``rtol = 1e-12``.
Lagrange's equations of a mechanism given by its joint-coordinate kinematics are formed by
Kane's method, with the kinematics differentiated exactly (to round-off) by truncated Taylor
series (:class:`_Jet`): no finite differences, no symbolic algebra, no shared code with the
absolute-coordinate model. Where an ODE is integrated in a faster form (written out by hand,
or, for one degree of freedom, with its coefficients tabulated in Chebyshev series to
round-off: :class:`_OneDof`), Kane's equations of the same model remain the check
(``reference.model``). ODE references are solved once, when first asked for, and kept; their
precision is about 1e-11 of the motion's size.

This module is layer 2 of the engine: it builds scenes and imports nothing above
:mod:`hexapod.scene`. ``hexapod.benchmarks.references`` holds the same elliptic-function pendulum
for the studies; the formula is repeated here (a layer-2 module cannot import it).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from hexapod.scene import (
    Harmonic,
    JointDriver,
    Particle,
    PlanarBody,
    Polynomial,
    Prismatic,
    Revolute,
    Scene,
    SpatialBody,
    Spherical,
    SpringDamper,
)
from hexapod.spatial import rotation_about_axis

G = 9.81
CATEGORIES = ("stiff", "mass-ratio", "singular", "redundant", "long", "large-step")


# ------------------------------------------------------------------ the case


@dataclass
class Case:
    """One mechanism of the suite and its independent reference.

    Attributes
    ----------
    name, scene, t_end, description, category :
        ``description`` says in one line what is extreme about the case; ``category`` is one
        of :data:`CATEGORIES`.
    observed :
        Bodies whose centre-of-mass positions form the observable, in this order (2 numbers per
        body in a planar scene, 3 in a spatial one).
    reference :
        ``reference(times) -> (N, k)``: the observable of the exact or independent solution.
    accelerations :
        The reference's centre-of-mass accelerations at ``t = 0`` (body -> 2 or 3 numbers), to
        compare with the engine's ``v_dot`` at the initial state.
    length :
        Size of the motion (m), to make position errors relative.
    dof, counted_dof, dof_with_drivers, redundant :
        Numerical degrees of freedom of the joints at the initial pose, the Grubler-Kutzbach
        count, the numerical count with the drivers, and how many rows (joints and drivers)
        are redundant there.
    energy_conserved :
        Whether kinetic plus potential energy is a constant of the motion.
    source :
        Where the data come from.
    """

    name: str
    scene: Scene
    t_end: float
    description: str
    category: str
    observed: tuple[str, ...]
    reference: Callable[[np.ndarray], np.ndarray]
    accelerations: dict[str, np.ndarray]
    length: float
    dof: int
    counted_dof: int
    redundant: int = 0
    dof_with_drivers: int | None = None
    energy_conserved: bool = True
    source: str = "designed for the suite"
    notes: list[str] = field(default_factory=list)

    def __post_init__(self):
        if self.category not in CATEGORIES:
            raise ValueError(f"category must be one of {CATEGORIES}, got {self.category!r}")
        if self.dof_with_drivers is None:
            self.dof_with_drivers = self.dof

    def observable(self, model, q, v=None) -> np.ndarray:
        """The observed centres of mass at one state (``q`` (n_q,)) or many (``q`` (N, n_q)):
        shape (k,) or (N, k). ``model`` is the assembled scene."""
        q = np.asarray(q, dtype=float)
        width = model.dimension
        parts = []
        for name in self.observed:
            body = model.bodies[model.body_index[name]]
            parts.append(q[..., body.q.start:body.q.start + width])
        return np.concatenate(parts, axis=-1)

    def error(self, model, t, q) -> float:
        """Largest distance of an observed centre of mass from the reference over the samples
        ``(t, q)`` (a run's saved states), relative to :attr:`length`."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        diff = self.observable(model, np.atleast_2d(q)) - self.reference(t)
        width = model.dimension
        distances = np.linalg.norm(diff.reshape(t.size, -1, width), axis=2)
        return float(distances.max() / self.length)


# ------------------------------------------------------------------ Taylor jets


class _Jet:
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
    def constant(value) -> _Jet:
        value = np.asarray(value, dtype=float)
        return _Jet(value, np.zeros((1,) + value.shape), np.zeros(value.shape))

    @staticmethod
    def variables(q, qd, qdd=None) -> _Jet:
        """The coordinates: unit directions, then the motion's direction ``qd`` (and ``qdd``)."""
        q = np.asarray(q, dtype=float)
        c2 = np.zeros_like(q) if qdd is None else 0.5 * np.asarray(qdd, dtype=float)
        return _Jet(q, np.vstack([np.eye(q.size), np.asarray(qd, dtype=float)]), c2)

    def __getitem__(self, index):
        index = index if isinstance(index, tuple) else (index,)
        return _Jet(self.c0[index], self.c1[(slice(None),) + index], self.c2[index])

    def __neg__(self):
        return _Jet(-self.c0, -self.c1, -self.c2)

    def __add__(self, other):
        other = _lift(other)
        ndim = max(self.c0.ndim, other.c0.ndim)
        return _Jet(self.c0 + other.c0, _directions(self, ndim) + _directions(other, ndim),
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


def _lift(x) -> _Jet:
    return x if isinstance(x, _Jet) else _Jet.constant(x)


def _directions(a: _Jet, ndim: int) -> np.ndarray:
    """``a.c1`` with its value axes padded on the left to ``ndim`` (elementwise broadcasting
    must not pair the direction axis with a value axis)."""
    return a.c1.reshape(a.c1.shape[:1] + (1,) * (ndim - a.c0.ndim) + a.c0.shape)


def _product(a: _Jet, b: _Jet, op) -> _Jet:
    if op is np.matmul:
        # a vector's directions are stacked rows: multiply each as a column
        left = (np.matmul(a.c0, b.c1[..., None])[..., 0] if b.c0.ndim == 1
                else np.matmul(a.c0, b.c1))
        c1 = left + np.matmul(a.c1, b.c0)
    else:
        ndim = max(a.c0.ndim, b.c0.ndim)
        c1 = op(a.c0, _directions(b, ndim)) + op(_directions(a, ndim), b.c0)
    return _Jet(op(a.c0, b.c0), c1, op(a.c0, b.c2) + op(a.c1[-1], b.c1[-1]) + op(a.c2, b.c0))


def _compose(a: _Jet, f0, f1, f2) -> _Jet:
    """``f(a)`` from ``f``'s value and first two derivatives at ``a.c0`` (elementwise)."""
    return _Jet(f0, f1 * a.c1, f1 * a.c2 + 0.5 * f2 * a.c1[-1] ** 2)


def _reciprocal(a: _Jet) -> _Jet:
    x = a.c0
    return _compose(a, 1 / x, -1 / x**2, 2 / x**3)


def _sin(a):
    a = _lift(a)
    s, c = np.sin(a.c0), np.cos(a.c0)
    return _compose(a, s, c, -s)


def _cos(a):
    a = _lift(a)
    s, c = np.sin(a.c0), np.cos(a.c0)
    return _compose(a, c, -s, -c)


def _arcsin(a):
    a = _lift(a)
    x = a.c0
    r = 1 / np.sqrt(1 - x * x)
    return _compose(a, np.arcsin(x), r, x * r**3)


def _stack(items) -> _Jet:
    items = [_lift(i) for i in items]
    m = max(i.c1.shape[0] for i in items)
    c1 = np.zeros((m, len(items)) + items[0].c0.shape)
    for k, item in enumerate(items):
        c1[:, k] = item.c1
    return _Jet(np.array([i.c0 for i in items]), c1, np.array([i.c2 for i in items]))


def _rotation(axis, angle) -> _Jet:
    """Rotation by the jet ``angle`` about the constant unit ``axis`` (Rodrigues,
    ``I + sin K + (1 - cos) K^2``)."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    K2 = K @ K
    s, c = _sin(angle), _cos(angle)
    return _Jet(np.eye(3) + s.c0 * K + (1.0 - c.c0) * K2,
                s.c1[:, None, None] * K - c.c1[:, None, None] * K2, s.c2 * K - c.c2 * K2)


def _planar_rotation(cos_jet, sin_jet) -> _Jet:
    """Rotation about z whose first column is ``(cos, sin, 0)`` (both jets)."""
    c, s = _lift(cos_jet), _lift(sin_jet)
    m = max(c.c1.shape[0], s.c1.shape[0])
    out = _Jet(np.eye(3), np.zeros((m, 3, 3)), np.zeros((3, 3)))
    for coefficient, (cc, ss) in ((out.c0, (c.c0, s.c0)), (out.c2, (c.c2, s.c2))):
        coefficient[0, 0] = coefficient[1, 1] = cc
        coefficient[1, 0], coefficient[0, 1] = ss, -ss
    out.c1[:, 0, 0] = out.c1[:, 1, 1] = c.c1
    out.c1[:, 1, 0] = s.c1
    out.c1[:, 0, 1] = -s.c1
    return out


def _vee(S: np.ndarray) -> np.ndarray:
    """The vector of a skew matrix (last two axes)."""
    return np.stack([S[..., 2, 1], S[..., 0, 2], S[..., 1, 0]], axis=-1)


# ------------------------------------------------------------------ minimal coordinates


@dataclass
class _Spring:
    """A spring-damper between two points of the kinematics (names), or a fixed point (array)
    and a named one: tension ``k (L - free_length) + c dL/dt``."""

    a: str | np.ndarray
    b: str
    stiffness: float
    damping: float
    free_length: float


class _MinimalModel:
    """A mechanism in its own minimal coordinates ``x``: Kane's equations
    ``sum_i J_i^T (m_i a_i - f_i) + Jw_i^T (I_i alpha_i + w_i x I_i w_i - t_i) = 0``.

    ``kinematics(x)`` maps jets of the coordinates to ``(frames, points)``: each body's centre
    of mass and rotation (body -> world) as jets, and named points (for springs). ``bodies``
    gives each body's mass and inertia about its centre of mass in its own axes.
    """

    def __init__(self, kinematics, bodies: dict[str, tuple[float, np.ndarray]], gravity,
                 springs: tuple[_Spring, ...] = ()):
        self.kinematics = kinematics
        self.bodies = bodies
        self.gravity = np.asarray(gravity, dtype=float)
        self.springs = springs

    def equations(self, x, xd) -> tuple[np.ndarray, np.ndarray]:
        """Mass matrix and right-hand side ``f`` of ``M xdd = f``."""
        x = np.asarray(x, dtype=float)
        n = x.size
        frames, points = self.kinematics(_Jet.variables(x, xd))
        M, f = np.zeros((n, n)), np.zeros(n)
        for name, (mass, inertia) in self.bodies.items():
            p, R = frames[name]
            R0, R1 = R.c0, np.broadcast_to(R.c1, (n + 1, 3, 3))
            Jp = np.broadcast_to(p.c1, (n + 1, 3))[:n].T
            rates = _vee(R1 @ R0.T)  # (n + 1, 3): Jacobian's columns, then omega
            Jw, w = rates[:n].T, rates[n]
            Iw = R0 @ inertia @ R0.T
            bias = 2 * p.c2  # the acceleration at xdd = 0
            alpha = _vee(2 * R.c2 @ R0.T + R1[n] @ R1[n].T)
            M += mass * Jp.T @ Jp + Jw.T @ Iw @ Jw
            f += Jp.T @ (mass * (self.gravity - bias)) - Jw.T @ (Iw @ alpha
                                                                + np.cross(w, Iw @ w))
        for spring in self.springs:
            pb = points[spring.b]
            Jb = np.broadcast_to(pb.c1, (n + 1, 3))
            if isinstance(spring.a, str):
                pa = points[spring.a]
                Ja, ra = np.broadcast_to(pa.c1, (n + 1, 3)), pa.c0
            else:
                Ja, ra = np.zeros((n + 1, 3)), np.asarray(spring.a, dtype=float)
            d = pb.c0 - ra
            length = np.linalg.norm(d)
            u = d / length
            tension = (spring.stiffness * (length - spring.free_length)
                       + spring.damping * (u @ (Jb[n] - Ja[n])))
            f -= tension * (Jb[:n] - Ja[:n]) @ u
        return M, f

    def accelerations(self, x, xd) -> np.ndarray:
        M, f = self.equations(x, xd)
        return np.linalg.solve(M, f)

    def rates(self, _t, state) -> np.ndarray:
        n = state.size // 2
        return np.concatenate([state[n:], self.accelerations(state[:n], state[n:])])

    def com_positions(self, x) -> dict[str, np.ndarray]:
        x = np.asarray(x, dtype=float)
        frames, _ = self.kinematics(_Jet.variables(x, np.zeros_like(x)))
        return {name: frames[name][0].c0 for name in self.bodies}

    def com_accelerations(self, x, xd) -> dict[str, np.ndarray]:
        xdd = self.accelerations(x, xd)
        frames, _ = self.kinematics(_Jet.variables(x, xd, xdd))
        return {name: 2 * frames[name][0].c2 for name in self.bodies}

    def energy(self, x, xd) -> float:
        x = np.asarray(x, dtype=float)
        frames, points = self.kinematics(_Jet.variables(x, xd))
        total = 0.0
        for name, (mass, inertia) in self.bodies.items():
            p, R = frames[name]
            w = _vee(R.c1[-1] @ R.c0.T)  # a constant's single direction is zero as well
            total += 0.5 * mass * p.c1[-1] @ p.c1[-1] + 0.5 * w @ (R.c0 @ inertia @ R.c0.T) @ w
            total -= mass * self.gravity @ p.c0
        for spring in self.springs:
            ra = points[spring.a].c0 if isinstance(spring.a, str) else np.asarray(spring.a)
            length = np.linalg.norm(points[spring.b].c0 - ra)
            total += 0.5 * spring.stiffness * (length - spring.free_length) ** 2
        return float(total)


class _Trajectory:
    """The solution of ``rates`` from ``y0``, solved when first asked for (and again, further,
    when asked beyond the end), mapped to the observable by ``observe(y) -> (k,)``."""

    def __init__(self, rates, y0, t_end: float, observe, method: str = "DOP853",
                 rtol: float = 1e-12, atol: float = 1e-12, jacobian=None):
        self.rates, self.y0, self.t_end = rates, np.asarray(y0, dtype=float), t_end
        self.observe, self.method, self.rtol, self.atol = observe, method, rtol, atol
        self.jacobian = jacobian
        self.solution = None
        self.model: _MinimalModel | None = None

    def solve(self, t_end: float):
        from scipy.integrate import solve_ivp

        options = {"jac": self.jacobian} if self.jacobian is not None else {}
        solution = solve_ivp(self.rates, (0.0, t_end), self.y0, method=self.method,
                             rtol=self.rtol, atol=self.atol, dense_output=True, **options)
        if solution.status != 0:
            raise RuntimeError(f"reference integration failed: {solution.message}")
        self.solution, self.t_end = solution, t_end
        return solution

    def states(self, times) -> np.ndarray:
        """The state at ``times`` (N, 2 n)."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        if self.solution is None or times.max() > self.t_end:
            self.solve(max(self.t_end, float(times.max())))
        return self.solution.sol(times).T

    def __call__(self, times) -> np.ndarray:
        return np.array([self.observe(y) for y in self.states(times)])


def _minimal_reference(model: _MinimalModel, x0, xd0, t_end: float, observed, width: int,
                       rates=None, **options) -> tuple[_Trajectory, dict[str, np.ndarray]]:
    """The trajectory of a minimal model (observable: the observed centres of mass, ``width``
    coordinates each) and its initial centre-of-mass accelerations. ``rates``: the same
    equations in a faster form (written by hand, or :class:`_OneDof`), default the model's."""
    n = len(x0)

    def observe(y):
        positions = model.com_positions(y[:n])
        return np.concatenate([positions[b][:width] for b in observed])

    trajectory = _Trajectory(rates or model.rates, np.concatenate([x0, xd0]), t_end, observe,
                             **options)
    trajectory.model = model  # Kane's equations, to check faster forms of ``rates`` against
    accelerations = {name: a[:width] for name, a in model.com_accelerations(x0, xd0).items()}
    return trajectory, accelerations


class _OneDof:
    """A one-degree-of-freedom minimal model without springs, ``m(x) x'' = f0(x) + f2(x) x'^2``
    (``f2 = -m'/2``, ``f0 = -V'``), with ``m``, ``f0`` and ``f2`` interpolated at ``degree``
    Chebyshev points of ``[lo, hi]`` from the exact model: the same equation, evaluated a
    hundred times faster. The interpolation is checked against the model between the nodes
    (to 1e-13 relative) when built; outside ``[lo, hi]`` the model itself is used."""

    def __init__(self, model: _MinimalModel, lo: float, hi: float, degree: int = 128):
        if model.springs:
            raise ValueError("a tabulated model may not have springs (f is not quadratic)")
        self.model, self.lo, self.hi, self.degree = model, lo, hi, degree
        self.coefficients = None  # built at the first call

    def tabulate(self) -> np.ndarray:
        from numpy.polynomial import chebyshev

        degree = self.degree
        nodes = np.cos(np.pi * (np.arange(degree + 1) + 0.5) / (degree + 1))
        coefficients = chebyshev.chebfit(nodes, self._exact(self._x(nodes)), degree)
        check = np.cos(np.pi * np.arange(1, degree + 1) / (degree + 1))  # between the nodes
        exact = self._exact(self._x(check))
        error = float((np.abs(chebyshev.chebval(check, coefficients).T - exact)
                       / np.abs(exact).max(axis=0)).max())
        if error > 1e-13:
            raise ValueError(f"interpolation error {error:.1e} on [{self.lo}, {self.hi}]: "
                             "raise the degree")
        self.coefficients = coefficients
        return coefficients

    def _x(self, u):
        return 0.5 * (self.hi + self.lo) + 0.5 * (self.hi - self.lo) * u

    def _exact(self, xs) -> np.ndarray:
        out = []
        for x in xs:
            M, f0 = self.model.equations([x], [0.0])
            _, f1 = self.model.equations([x], [1.0])
            out.append([M[0, 0], f0[0], f1[0] - f0[0]])
        return np.array(out)

    def rates(self, _t, y) -> np.ndarray:
        x, xd = y
        if not self.lo <= x <= self.hi:
            return self.model.rates(_t, np.asarray(y, dtype=float))
        from numpy.polynomial.chebyshev import chebval

        coefficients = self.tabulate() if self.coefficients is None else self.coefficients
        m, f0, f2 = chebval((2 * x - self.lo - self.hi) / (self.hi - self.lo), coefficients)
        return np.array([xd, (f0 + f2 * xd * xd) / m])


def _rod_inertia(mass: float, length: float, axis: int, section: float = 0.0) -> np.ndarray:
    """Principal inertia (3 x 3) of a rod along body axis ``axis`` with a square section of
    side ``section`` (0: a slender rod)."""
    transverse = mass * (length**2 + section**2) / 12
    axial = mass * section**2 / 6
    moments = np.full(3, transverse)
    moments[axis] = axial
    return np.diag(moments)


# ------------------------------------------------------------------ stiff: the slider


def stiff_slider(k: float, c: float = 0.0, *, amplitude: float = 0.01, mass: float = 1.0,
                 t_end: float = 0.5, gravity: bool = True) -> Case:
    """A block on a vertical prismatic joint, hung from a spring-damper of stiffness ``k``
    (N/m) and damping ``c`` (N s/m) anchored 1 m above, released ``amplitude`` below its
    equilibrium (gravity along the slide when ``gravity``).

    Reference: ``m u'' + c u' + k u = 0`` in closed form (under-, critically or over-damped),
    ``u`` the block's distance from its static equilibrium. With ``k = 1e9`` the period is
    0.2 ms: 2500 periods in half a second."""
    free_length = 1.0
    g = G if gravity else 0.0
    y_eq = -(free_length + mass * g / k)
    y0 = y_eq - amplitude
    scene = Scene(f"stiff-slider-k{k:.0e}" + (f"-c{c:.0e}" if c else ""), dimension=2)
    scene.gravity = np.array([0.0, -g])
    scene.add(PlanarBody("block", mass, mass * 0.1**2 / 6, position=[0.0, y0]))
    scene.add(Prismatic("slide", "ground", "block", origin=[0.0, y0], axis=[0.0, 1.0]))
    scene.add(SpringDamper("spring", "ground", "block", point_a=[0.0, 0.0], stiffness=k,
                           damping=c, free_length=free_length))
    omega = np.sqrt(k / mass)
    zeta = c / (2 * np.sqrt(k * mass))
    u0 = -amplitude

    def displacement(t):
        t = np.asarray(t, dtype=float)
        if zeta < 1.0:
            wd = omega * np.sqrt(1 - zeta**2)
            return np.exp(-zeta * omega * t) * u0 * (np.cos(wd * t)
                                                    + zeta * omega / wd * np.sin(wd * t))
        if zeta == 1.0:
            return u0 * (1 + omega * t) * np.exp(-omega * t)
        root = np.sqrt(zeta**2 - 1)
        r1, r2 = -omega * (zeta - root), -omega * (zeta + root)
        return u0 * (r1 * np.exp(r2 * t) - r2 * np.exp(r1 * t)) / (r1 - r2)

    def reference(times):
        times = np.atleast_1d(np.asarray(times, dtype=float))
        return np.column_stack([np.zeros_like(times), y_eq + displacement(times)])

    period = 2 * np.pi / omega
    return Case(
        scene.name, scene, t_end,
        f"spring of {k:.0e} N/m on 1 kg: period {period:.2g} s, {t_end / period:.0f} periods"
        + (f", damping ratio {zeta:.3g}" if c else " undamped"),
        "stiff", ("block",), reference, {"block": np.array([0.0, -k * u0 / mass])},
        length=amplitude, dof=1, counted_dof=1, energy_conserved=(c == 0.0),
        source="closed form of the linear oscillator")


def stiff_spring_pendulum(k: float = 1e6, *, t_end: float = 2.0) -> Case:
    """A stiff spring inside a constrained mechanism: a 1 m arm (1 kg) swings about a pivot; a
    0.5 kg slider on it (prismatic joint along the arm) is held 0.6 m from the pivot by a
    spring of stiffness ``k``. Released horizontal at rest: the swing stretches the spring by
    micrometres while it vibrates at ``sqrt(k / 0.5)`` rad/s.

    Reference: Lagrange's equations in the arm's angle ``th`` and the slider's distance ``s``
    from the pivot, written out (``I_A`` the arm's inertia about the pivot, ``m, I`` the
    slider's),

        (I_A + I + m s^2) th'' + 2 m s s' th' = -g cos(th) (m_arm / 2 + m s)
        m s'' - m s th'^2 = -m g sin(th) - k (s - L0),

    integrated by DOP853 at 1e-12 (Kane's equations of the same system give the initial
    accelerations, and the tests check that both agree)."""
    arm_mass, slider_mass, free_length = 1.0, 0.5, 0.6
    scene = Scene(f"stiff-spring-pendulum-k{k:.0e}", dimension=2)
    scene.add(PlanarBody("arm", arm_mass, arm_mass / 12, com=[0.5, 0.0], position=[0.0, 0.0]))
    scene.add(PlanarBody("slider", slider_mass, 1e-3, position=[free_length, 0.0]))
    scene.add(Revolute("pivot", "ground", "arm", origin=[0.0, 0.0]))
    scene.add(Prismatic("slot", "arm", "slider", origin=[free_length, 0.0], axis=[1.0, 0.0]))
    scene.add(SpringDamper("spring", "arm", "slider", point_a=[0.0, 0.0], stiffness=k,
                           free_length=free_length))

    def kinematics(x):
        theta, s = x[0], x[1]
        c, si = _cos(theta), _sin(theta)
        R = _planar_rotation(c, si)
        zero = 0.0 * theta
        direction = _stack([c, si, zero])
        return ({"arm": (direction * 0.5, R), "slider": (direction * s, R)},
                {"slider": direction * s})

    model = _MinimalModel(kinematics, {"arm": (arm_mass, np.diag([0, 0, arm_mass / 12])),
                                       "slider": (slider_mass, np.diag([0, 0, 1e-3]))},
                          [0.0, -G, 0.0], (_Spring(np.zeros(3), "slider", k, 0.0, free_length),))
    observed = ("arm", "slider")
    inertia_arm = arm_mass / 12 + arm_mass * 0.25

    def rates(_t, y):
        th, s, thd, sd = y
        thdd = (-G * np.cos(th) * (0.5 * arm_mass + slider_mass * s)
                - 2 * slider_mass * s * sd * thd) / (inertia_arm + 1e-3 + slider_mass * s * s)
        sdd = s * thd * thd - G * np.sin(th) - k * (s - free_length) / slider_mass
        return np.array([thd, sd, thdd, sdd])

    reference, accelerations = _minimal_reference(model, [0.0, free_length], [0.0, 0.0], t_end,
                                                  observed, 2, rates=rates)
    return Case(scene.name, scene, t_end,
                f"spring of {k:.0e} N/m inside a swinging linkage: vibration at "
                f"{np.sqrt(k / slider_mass):.3g} rad/s on a 1 s swing", "stiff", observed,
                reference, accelerations, length=1.0, dof=2, counted_dof=2)


# ------------------------------------------------------------------ stiff: flyball governor

#: IFToMM / MBS benchmark A05 (stiff flyball governor), as implemented by the Padua group
#: (RehabEngGroup/MBSbenchmarksInOpenSim, src/A05-FlyballGovernor, after Gonzalez, Dopico,
#: Lugris & Cuadrado 2006): spindle and rods 1 x 0.01 x 0.01 m, sleeve 0.1 m cube, density
#: 3000 kg/m^3, 5 kg point masses at the rods' tips, spring-dampers 8e5 N/m, 4e4 N s/m, free
#: length 0.5 m, s = 0.5 m, alpha = 30 degrees, initial spin 2 pi rad/s, gravity 9.81 along
#: the spindle (down).
FLYBALL = dict(density=3000.0, rod=(1.0, 0.01), sleeve=0.1, ball=5.0, stiffness=8e5,
               damping=4e4, free_length=0.5, s=0.5, alpha=np.radians(30.0), spin=2 * np.pi,
               offset=0.05)


class _Flyball:
    """The governor reduced by its symmetries: both arms at the same angle ``beta`` from the
    spindle's upward axis (the mirror symmetry of the initial state is kept by the motion) and
    the spindle's angle cyclic (its angular momentum ``H`` about the axis is conserved, no
    torque acts). Routh's reduction leaves ``(s, beta)``:

        m_s s''           = -m_s g + 2 T cos(gamma)            (sleeve)
        2 I_p beta''      = -dV/dbeta + psi'^2 / 2 dI_z/dbeta - 2 T dL/dbeta
        psi'              = H / I_z(beta)

    with ``I_p`` the arm's inertia about its pin, ``I_z`` the whole governor's about the
    spindle, ``T = k (L - L0) + c L'`` each spring's tension and ``L(s, beta)`` its length
    (from the sleeve's edge to the arm's middle). Written by hand, independent of the 3-D
    model."""

    def __init__(self):
        p = FLYBALL
        length, side = p["rod"]
        self.m_rod = p["density"] * length * side**2
        self.m_sleeve = p["density"] * p["sleeve"] ** 3
        self.m_ball = p["ball"]
        self.I_t = self.m_rod * (length**2 + side**2) / 12  # rod transverse, about its centre
        self.I_a = self.m_rod * side**2 / 6
        self.I_spindle = self.m_rod * side**2 / 6  # about its own axis
        self.I_sleeve_z = self.m_sleeve * p["sleeve"] ** 2 / 6
        self.I_pin = self.I_t + self.m_rod * 0.25 + self.m_ball
        self.e = p["offset"]
        self.k, self.c, self.L0 = p["stiffness"], p["damping"], p["free_length"]

    def inertia_z(self, beta):
        """I_z and dI_z/dbeta."""
        sb, cb = np.sin(beta), np.cos(beta)
        rc, rb = self.e + 0.5 * sb, self.e + sb
        rod = self.I_t * sb**2 + self.I_a * cb**2 + self.m_rod * rc**2 + self.m_ball * rb**2
        d_rod = (2 * (self.I_t - self.I_a) * sb * cb + self.m_rod * rc * cb
                 + 2 * self.m_ball * rb * cb)
        return self.I_spindle + self.I_sleeve_z + 2 * rod, 2 * d_rod

    def spring(self, s, beta):
        """Length, dL/ds, dL/dbeta (sleeve edge (e, s) to arm middle, in the arm's plane)."""
        dx = 0.5 * np.sin(beta)
        dz = 1.0 + 0.5 * np.cos(beta) - s
        L = np.hypot(dx, dz)
        return L, -dz / L, (dx * 0.5 * np.cos(beta) - dz * 0.5 * np.sin(beta)) / L

    def rates(self, _t, y, H):
        s, beta, sd, bd = y[0], y[1], y[2], y[3]
        Iz, dIz = self.inertia_z(beta)
        psid = H / Iz
        L, dLs, dLb = self.spring(s, beta)
        tension = self.k * (L - self.L0) + self.c * (dLs * sd + dLb * bd)
        dV = -2 * G * (0.5 * self.m_rod + self.m_ball) * np.sin(beta)
        sdd = (-self.m_sleeve * G - 2 * tension * dLs) / self.m_sleeve
        bdd = (-dV + 0.5 * psid**2 * dIz - 2 * tension * dLb) / (2 * self.I_pin)
        return np.array([sd, bd, sdd, bdd, psid])


def flyball_governor(t_end: float = 10.0) -> Case:
    """IFToMM benchmark A05, the stiff flyball governor (data: :data:`FLYBALL`).

    A spindle turns freely about the vertical (revolute to the ground at its foot, initial spin
    2 pi rad/s); a sleeve slides on it (prismatic, turning with it); two arms hinge at its top,
    0.05 m either side, each carrying a 5 kg ball at its tip (a particle on a spherical joint);
    instead of rigid coupler rods, spring-dampers of 8e5 N/m and 4e4 N s/m join each side of
    the sleeve to the middle of its arm. Initially the arms make 30 degrees with the
    horizontal, the couplers are at their free length 0.5 m and the sleeve is 0.5 m above the
    spindle's foot. The dampers make eigenvalues near -1e4 1/s next to the seconds of the
    governor's motion.

    Reference: the symmetric reduction :class:`_Flyball` (Routh) integrated by Radau IIA at
    ``rtol = 1e-12``; the benchmark's published s(t) (Gonzalez et al. 2006) is not stored
    here. The observable is the sleeve and both balls."""
    p = FLYBALL
    length, side = p["rod"]
    m_rod = p["density"] * length * side**2
    m_sleeve = p["density"] * p["sleeve"] ** 3
    I_sleeve = m_sleeve * p["sleeve"] ** 2 / 6
    beta0 = np.pi / 2 + p["alpha"]  # arm direction from the spindle's upward axis
    spin = np.array([0.0, 0.0, p["spin"]])
    e = p["offset"]
    scene = Scene("flyball-governor", dimension=3)
    scene.gravity = np.array([0.0, 0.0, -G])
    spindle_inertia = _rod_inertia(m_rod, length, 2, side)
    scene.add(SpatialBody("spindle", m_rod, np.diag(spindle_inertia), position=[0, 0, 0.5],
                          angular_velocity=spin))
    scene.add(SpatialBody("sleeve", m_sleeve, [I_sleeve] * 3, position=[0, 0, p["s"]],
                          angular_velocity=spin))
    scene.add(Revolute("spindle_pin", "ground", "spindle", origin=[0, 0, 0], axis=[0, 0, 1]))
    scene.add(Prismatic("sleeve_slide", "spindle", "sleeve", origin=[0, 0, p["s"]],
                        axis=[0, 0, 1]))
    for k, sign in ((1, 1.0), (2, -1.0)):
        R = rotation_about_axis([0, 1, 0], sign * beta0)
        pivot = np.array([sign * e, 0.0, 1.0])
        centre, tip = pivot + R @ [0, 0, 0.5], pivot + R @ [0, 0, 1.0]
        scene.add(SpatialBody(f"arm_{k}", m_rod, np.diag(_rod_inertia(m_rod, length, 2, side)),
                              position=centre, rotation=R, angular_velocity=spin,
                              velocity=np.cross(spin, centre)))
        scene.add(Particle(f"ball_{k}", p["ball"], position=tip, velocity=np.cross(spin, tip)))
        scene.add(Revolute(f"arm_pin_{k}", "spindle", f"arm_{k}", origin=pivot,
                           axis=[0, 1, 0]))
        scene.add(Spherical(f"ball_joint_{k}", f"arm_{k}", f"ball_{k}", origin=tip))
        scene.add(SpringDamper(f"coupler_{k}", "sleeve", f"arm_{k}", point_a=[sign * e, 0, 0],
                               point_b=[0, 0, 0], stiffness=p["stiffness"],
                               damping=p["damping"], free_length=p["free_length"]))

    reduced = _Flyball()
    Iz0, _ = reduced.inertia_z(beta0)
    H = Iz0 * p["spin"]

    def observe(y):
        s, beta, psi = y[0], y[1], y[4]
        out = [np.array([0.0, 0.0, s])]
        turn = rotation_about_axis([0, 0, 1], psi)
        for sign in (1.0, -1.0):
            tip = np.array([sign * (e + np.sin(beta)), 0.0, 1.0 + np.cos(beta)])
            out.append(turn @ tip)
        return np.concatenate(out)

    def rates(t, y):
        return reduced.rates(t, y, H)

    def jacobian(t, y):
        # by central differences (Newton's matrix of Radau; the angle psi is cyclic)
        out = np.zeros((5, 5))
        for j in range(4):
            h = 1e-7 * max(1.0, abs(y[j]))
            up, down = y.copy(), y.copy()
            up[j] += h
            down[j] -= h
            out[:, j] = (rates(t, up) - rates(t, down)) / (2 * h)
        return out

    reference = _Trajectory(rates, [p["s"], beta0, 0.0, 0.0, 0.0], t_end, observe,
                            method="Radau", rtol=1e-12, atol=1e-12, jacobian=jacobian)
    full = _flyball_minimal(m_rod, m_sleeve, I_sleeve, spindle_inertia)
    x0, xd0 = np.array([0.0, p["s"], 0.0, 0.0]), np.array([p["spin"], 0.0, 0.0, 0.0])
    accelerations = full.com_accelerations(x0, xd0)
    return Case(scene.name, scene, t_end,
                "couplers replaced by 8e5 N/m, 4e4 N s/m spring-dampers: damped modes near "
                "-1e4 1/s on a 10 s motion", "stiff",
                ("sleeve", "ball_1", "ball_2"), reference, accelerations, length=1.0, dof=4,
                counted_dof=4, energy_conserved=False,
                source="IFToMM/MBS benchmark A05 (Gonzalez et al. 2006), data as in "
                       "RehabEngGroup/MBSbenchmarksInOpenSim src/A05-FlyballGovernor",
                notes=["the benchmark's reference s(t) is not stored: the reference is the "
                       "symmetric reduction (Routh), integrated by Radau IIA at 1e-12",
                       "balls are particles on spherical joints at the arms' tips (the "
                       "benchmark welds point masses)"])


def _flyball_minimal(m_rod, m_sleeve, I_sleeve, spindle_inertia) -> _MinimalModel:
    """The governor in its four joint coordinates (spindle angle, sleeve height, both arms'
    angles from the initial pose) by Kane's method: the full model, without symmetry."""
    p = FLYBALL
    beta0, e = np.pi / 2 + p["alpha"], p["offset"]
    rod = _rod_inertia(m_rod, p["rod"][0], 2, p["rod"][1])
    zero3 = np.zeros((3, 3))

    def kinematics(x):
        psi, s = x[0], x[1]
        R = _rotation([0, 0, 1], psi)
        frames = {"spindle": (R @ np.array([0.0, 0.0, 0.5]), R),
                  "sleeve": (_stack([0.0 * s, 0.0 * s, s]), R)}
        points = {}
        for k, sign in ((1, 1.0), (2, -1.0)):
            Ra = R @ _rotation([0, 1, 0], sign * (beta0 + x[1 + k]))
            pivot = R @ np.array([sign * e, 0.0, 1.0])
            frames[f"arm_{k}"] = (pivot + Ra @ np.array([0, 0, 0.5]), Ra)
            frames[f"ball_{k}"] = (pivot + Ra @ np.array([0, 0, 1.0]), Ra)
            points[f"arm_{k}"] = frames[f"arm_{k}"][0]
            points[f"edge_{k}"] = frames["sleeve"][0] + R @ np.array([sign * e, 0.0, 0.0])
        return frames, points

    bodies = {"spindle": (m_rod, spindle_inertia), "sleeve": (m_sleeve, np.eye(3) * I_sleeve),
              "arm_1": (m_rod, rod), "arm_2": (m_rod, rod),
              "ball_1": (p["ball"], zero3), "ball_2": (p["ball"], zero3)}
    springs = tuple(_Spring(f"edge_{k}", f"arm_{k}", p["stiffness"], p["damping"],
                            p["free_length"]) for k in (1, 2))
    return _MinimalModel(kinematics, bodies, [0.0, 0.0, -G], springs)


# ------------------------------------------------------------------ singular: N four-bar


def n_four_bar(n: int = 10, *, t_end: float = 10.0, dimension: int = 2) -> Case:
    """IFToMM benchmark A02, the N-four-bar mechanism: ``n`` parallelogram windows in a row,
    2 n + 1 uniform rods of 1 m and 1 kg (n + 1 cranks hinged to the ground 1 m apart, n
    couplers joining their tips), gravity 9.81 along -y. Initially the cranks are vertical
    (up) and the first crank's tip ``B0`` moves at 1 m/s along +x. The mechanism falls and
    turns over and over: twice per turn all rods lie on the ground line, where the joints'
    Jacobian loses n ranks (n + 1 instantaneous degrees of freedom) and each window may fold
    into an anti-parallelogram. With ``dimension=3`` the same chain of spatial bodies on
    revolute joints along z: 3 redundant rows per window (category "redundant").

    Reference: every crank turns by the same angle ``theta`` (clockwise from the vertical)
    and the couplers translate, so
    ``[(n + 1) m l^2 / 3 + n m l^2] theta'' = [(n + 1) m g l / 2 + n m g l] sin theta``,
    integrated by DOP853 at 1e-12. The observable is every rod's centre of mass, which shows
    a jump to another branch. The benchmark library's A02 has 40 windows (``n_four_bar(40)``),
    the OpenSim implementation 2; 10 s as there."""
    m, l = 1.0, 1.0
    scene = Scene(f"n-four-bar-{n}" + ("-3d" if dimension == 3 else ""), dimension=dimension)
    scene.gravity = np.array([0.0, -G] + ([0.0] if dimension == 3 else []))
    inertia = m * l**2 / 12

    def add_rod(name, centre, angle, velocity, omega):
        if dimension == 2:
            scene.add(PlanarBody(name, m, inertia, position=centre, angle=angle,
                                 velocity=velocity, angular_velocity=omega))
        else:
            scene.add(SpatialBody(name, m, [inertia * 1e-3, inertia, inertia],
                                  position=[*centre, 0.0],
                                  rotation=rotation_about_axis([0, 0, 1], angle),
                                  velocity=[*velocity, 0.0], angular_velocity=[0, 0, omega]))

    def at(p):
        return [*p, 0.0] if dimension == 3 else list(p)

    for i in range(n + 1):
        add_rod(f"crank_{i}", [i, 0.5], np.pi / 2, [0.5, 0.0], -1.0)
        if i < n:
            add_rod(f"coupler_{i}", [i + 0.5, 1.0], 0.0, [1.0, 0.0], 0.0)
    scene.add(Revolute("A_0", "ground", "crank_0", origin=at([0.0, 0.0])))
    for i in range(n):
        scene.add(Revolute(f"B_{i}", f"crank_{i}", f"coupler_{i}", origin=at([i, 1.0])))
        scene.add(Revolute(f"C_{i}", f"coupler_{i}", f"crank_{i + 1}", origin=at([i + 1, 1.0])))
        scene.add(Revolute(f"A_{i + 1}", "ground", f"crank_{i + 1}", origin=at([i + 1, 0.0])))
    inertia_total = (n + 1) * m * l**2 / 3 + n * m * l**2
    torque = (n + 1) * m * G * l / 2 + n * m * G * l
    rate = torque / inertia_total
    observed = tuple(f"{kind}_{i}" for i in range(n + 1) for kind in ("crank", "coupler")
                     if kind == "crank" or i < n)
    width = dimension

    def positions(theta):
        s, c = np.sin(theta), np.cos(theta)
        out = []
        for name in observed:
            kind, i = name.split("_")
            if kind == "crank":
                point = [int(i) + 0.5 * l * s, 0.5 * l * c]
            else:
                point = [int(i) + 0.5 + l * s, l * c]
            out.extend(point + [0.0] * (width - 2))
        return np.array(out)

    reference = _Trajectory(lambda _t, y: np.array([y[1], rate * np.sin(y[0])]), [0.0, 1.0],
                            t_end, lambda y: positions(y[0]))
    accelerations = {}
    theta_dd = 0.0  # sin(0) = 0: only the centripetal part at the start
    for name in observed:
        kind, _ = name.split("_")
        r = 0.5 * l if kind == "crank" else l
        # position (i + r sin theta, r cos theta): acceleration r (theta'' cos - theta'^2 sin,
        # -theta'' sin - theta'^2 cos) at theta = 0, theta' = 1
        accelerations[name] = np.array([r * theta_dd, -r] + [0.0] * (width - 2))
    counted = 1 if dimension == 2 else 6 * (2 * n + 1) - 5 * (3 * n + 1)
    return Case(scene.name, scene, t_end,
                f"{n} parallelogram windows pass through the flat pose where the Jacobian "
                f"loses {n} ranks" + (f"; {3 * n} redundant rows" if dimension == 3 else ""),
                "singular" if dimension == 2 else "redundant", observed, reference,
                accelerations, length=float(n + 1), dof=1, counted_dof=counted,
                redundant=0 if dimension == 2 else 3 * n,
                source="IFToMM/MBS benchmark A02 (Gonzalez et al. 2006; data as in "
                       "RehabEngGroup/MBSbenchmarksInOpenSim src/A02-NFourBarMechanism)")


# ------------------------------------------------------------------ redundant: Bricard

#: Bricard's mechanism, IFToMM benchmark A04, as in RehabEngGroup/MBSbenchmarksInOpenSim
#: (src/A04-BricardsMechanism): five bars of 1 m and 1 kg, square section 0.1 m, joined in a
#: loop with the ground by six revolute joints at O, P1 ... P5 (the corners of a unit cube
#: visited by the loop), each axis normal to both bars it joins; gravity 9.81 along -y,
#: released at rest, 10 s.
BRICARD_POINTS = np.array([[0, 0, 0], [1, 0, 0], [1, -1, 0], [1, -1, 1], [0, -1, 1],
                           [0, 0, 1]], dtype=float)
BRICARD_AXES = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]],
                        dtype=float)


def _bricard_minimal() -> _MinimalModel:
    """The Bricard loop in the angle ``t`` of its ground joint O. Opening the loop at P5, the
    chain's joint angles (from the initial pose) are ``(t, u, t, u, t)`` with
    ``sin t + sin u + sin t sin u = 0`` (found for this linkage by solving the closure
    numerically and checked to round-off; the threefold symmetry of the skew hexagon gives
    the repetition), so ``u = -arcsin(sin t / (1 + sin t))`` on the branch through the
    initial pose: valid for ``-pi/6 < t < 7 pi / 6``, which the motion from rest keeps to."""
    bars = np.diff(np.vstack([BRICARD_POINTS, BRICARD_POINTS[:1]]), axis=0)[:5]
    inertia = {}
    for k in range(5):
        axis = int(np.argmax(np.abs(bars[k])))
        inertia[f"bar_{k + 1}"] = (1.0, _rod_inertia(1.0, 1.0, axis, 0.1))

    def kinematics(x):
        t = x[0]
        s = _sin(t)
        u = -_arcsin(s / (1.0 + s))
        angles = (t, u, t, u, t)
        R = _Jet.constant(np.eye(3))
        start = _Jet.constant(np.zeros(3))
        frames, points = {}, {}
        for k in range(5):
            R = R @ _rotation(BRICARD_AXES[k], angles[k])
            end = start + R @ bars[k]
            frames[f"bar_{k + 1}"] = ((start + end) * 0.5, R)
            points[f"P{k + 1}"] = end
            start = end
        return frames, points

    return _MinimalModel(kinematics, inertia, [0.0, -G, 0.0])


def bricard(t_end: float = 10.0) -> Case:
    """IFToMM benchmark A04, Bricard's mechanism (data: :data:`BRICARD_POINTS`): five bars and
    the ground in a loop of six revolute joints. Grubler-Kutzbach counts 5 x 6 - 6 x 5 = 0
    degrees of freedom; the special axes leave one, so one row of the 30 is redundant at every
    pose (the engine names a row of the loop-closing joint P5).

    Reference: Lagrange's equation on the closed-form configuration curve
    (:func:`_bricard_minimal`, tabulated by :class:`_OneDof`), DOP853 at 1e-12. Observable:
    the five bars' centres of mass (the benchmark reports the point P3, the joint of bars 3
    and 4 here)."""
    scene = Scene("bricard", dimension=3)
    scene.gravity = np.array([0.0, -G, 0.0])
    names = [f"bar_{k}" for k in range(1, 6)]
    for k, name in enumerate(names):
        a, b = BRICARD_POINTS[k], BRICARD_POINTS[k + 1]
        axis = int(np.argmax(np.abs(b - a)))
        scene.add(SpatialBody(name, 1.0, np.diag(_rod_inertia(1.0, 1.0, axis, 0.1)),
                              position=(a + b) / 2))
    parents = ["ground"] + names
    children = names + ["ground"]
    labels = ["O", "P1", "P2", "P3", "P4", "P5"]
    for k in range(6):
        scene.add(Revolute(labels[k], parents[k], children[k], origin=BRICARD_POINTS[k],
                           axis=BRICARD_AXES[k]))
    model = _bricard_minimal()
    # released at rest at t = 0 it swings to t = pi and back (the potential is symmetric)
    reference, accelerations = _minimal_reference(model, [0.0], [0.0], t_end, tuple(names), 3,
                                                  rates=_OneDof(model, -0.15, np.pi + 0.15).rates)
    return Case(scene.name, scene, t_end,
                "over-constrained loop: Grubler counts 0 degrees of freedom, there is 1 and a "
                "redundant row at every pose", "redundant", tuple(names), reference,
                accelerations, length=1.0, dof=1, counted_dof=0, redundant=1,
                source="IFToMM/MBS benchmark A04 (Gonzalez et al. 2006), geometry as in "
                       "RehabEngGroup/MBSbenchmarksInOpenSim src/A04-BricardsMechanism",
                notes=["the benchmark's published P3(t) is not stored; the reference is the "
                       "1-DOF Lagrange equation on the closed-form configuration curve"])


# ------------------------------------------------------------------ singular: anti-parallelogram

#: The anti-parallelogram (crossed) four-bar: cranks AB = DC = 0.2 m, ground AD = coupler
#: BC = 0.5 m, uniform rods of 2 kg/m. A Grashof change-point linkage (0.2 + 0.5 = 0.2 + 0.5).
ANTI_PARALLELOGRAM = dict(crank=0.2, ground=0.5, density=2.0)


def _anti_parallelogram_points(theta):
    """B and C of the crossed branch at crank angle ``theta`` (jets or numbers): C is A
    mirrored in the perpendicular bisector of BD, ``C = (d^2 - a^2) (D - B) / |D - B|^2``."""
    a, d = ANTI_PARALLELOGRAM["crank"], ANTI_PARALLELOGRAM["ground"]
    if isinstance(theta, _Jet):
        B = _stack([a * _cos(theta), a * _sin(theta), 0.0 * theta])
        w = np.array([d, 0.0, 0.0]) - B
        C = w * ((d * d - a * a) / (w[0] * w[0] + w[1] * w[1]))
        return B, C
    B = a * np.array([np.cos(theta), np.sin(theta), 0.0])
    w = np.array([d, 0.0, 0.0]) - B
    return B, (d * d - a * a) * w / (w @ w)


def four_bar_dead_points(driven: bool = False, *, t_end: float | None = None) -> Case:
    """A four-bar that passes through its change points, where the Jacobian loses rank and a
    second branch crosses: the anti-parallelogram of :data:`ANTI_PARALLELOGRAM` (crank A-B,
    coupler B-C, rocker D-C, ground A-D), whose crossed configurations meet the parallelogram
    ones when all four joints are on the ground line (crank angle 0 and pi).

    Free (``driven=False``): released at rest with the crank vertical (theta = pi/2), under
    gravity; it swings through theta = 0 twice per period. Driven: the crank turns at 1
    revolution per second from pi/2 (a constant-rate driver) through pi and 2 pi.
    At those instants the two branches have different rocker rates, so the exact motion stays
    on the crossed branch; a method that lets the rank-deficient step choose can jump.

    Reference: on the crossed branch C(theta) is rational in cos and sin (see
    :func:`_anti_parallelogram_points`): the free motion by Lagrange's equation in theta
    (Kane, DOP853 at 1e-12), the driven one in closed form."""
    p = ANTI_PARALLELOGRAM
    a, d, rho = p["crank"], p["ground"], p["density"]
    theta0 = np.pi / 2
    omega = 2 * np.pi if driven else 0.0
    t_end = (1.0 if driven else 2.0) if t_end is None else t_end
    B, C = _anti_parallelogram_points(theta0)
    D = np.array([d, 0.0, 0.0])
    masses = {"crank": rho * a, "coupler": rho * d, "rocker": rho * a}
    scene = Scene("anti-parallelogram" + ("-driven" if driven else ""), dimension=2)

    def angle(u):
        return float(np.arctan2(u[1], u[0]))

    # initial velocities (driven: the crank's rate; the rest follows from the kinematics)
    x0 = np.array([theta0])
    model = _anti_parallelogram_minimal(masses)
    frames, _ = model.kinematics(_Jet.variables(x0, [omega]))
    for name, start, end in (("crank", np.zeros(3), B), ("coupler", B, C), ("rocker", D, C)):
        length = float(np.linalg.norm(end - start))
        p_jet, R = frames[name]
        w = _vee(R.c1[-1] @ R.c0.T)[2]
        scene.add(PlanarBody(name, masses[name], masses[name] * length**2 / 12,
                             position=((start + end) / 2)[:2], angle=angle(end - start),
                             velocity=p_jet.c1[-1][:2], angular_velocity=w))
    scene.add(Revolute("A", "ground", "crank", origin=[0.0, 0.0]))
    scene.add(Revolute("B", "crank", "coupler", origin=B[:2]))
    scene.add(Revolute("C", "coupler", "rocker", origin=C[:2]))
    scene.add(Revolute("D", "rocker", "ground", origin=D[:2]))
    observed = ("crank", "coupler", "rocker")
    if driven:
        scene.add(JointDriver("motor", "A", Polynomial([0.0, omega])))

        def reference(times):
            times = np.atleast_1d(np.asarray(times, dtype=float))
            out = []
            for t in times:
                positions = model.com_positions([theta0 + omega * t])
                out.append(np.concatenate([positions[b][:2] for b in observed]))
            return np.array(out)

        accelerations = {k: a_[:2] for k, a_ in _driven_accelerations(model, theta0,
                                                                      omega).items()}
    else:
        # from rest at pi/2 it swings down through 0 to about -0.3 rad and back
        reference, accelerations = _minimal_reference(
            model, x0, [0.0], t_end, observed, 2, rates=_OneDof(model, -1.0, 2.0).rates)
    return Case(scene.name, scene, t_end,
                "change-point four-bar: at theta = 0, pi the Jacobian loses a rank and the "
                "parallelogram branch crosses" + (" (crank driven)" if driven else ""),
                "singular", observed, reference, accelerations, length=d, dof=1,
                counted_dof=1, dof_with_drivers=0 if driven else 1,
                energy_conserved=not driven,
                source="designed for the suite (anti-parallelogram, Grashof change point)")


def _anti_parallelogram_minimal(masses) -> _MinimalModel:
    a, d = ANTI_PARALLELOGRAM["crank"], ANTI_PARALLELOGRAM["ground"]
    D = np.array([d, 0.0, 0.0])

    def kinematics(x):
        theta = x[0]
        B, C = _anti_parallelogram_points(theta)
        crank = _planar_rotation(_cos(theta), _sin(theta))
        u = (C - B) * (1.0 / d)
        r = (C - D) * (1.0 / a)
        frames = {"crank": (B * 0.5, crank),
                  "coupler": ((B + C) * 0.5, _planar_rotation(u[0], u[1])),
                  "rocker": ((C + D) * 0.5, _planar_rotation(r[0], r[1]))}
        return frames, {}

    bodies = {name: (mass, np.diag([0.0, 0.0, mass * length**2 / 12]))
              for (name, mass), length in zip(masses.items(), (a, d, a), strict=True)}
    return _MinimalModel(kinematics, bodies, [0.0, -G, 0.0])


def _driven_accelerations(model: _MinimalModel, x0: float, rate: float) -> dict:
    """Centre-of-mass accelerations of a 1-DOF model whose coordinate turns at a constant
    rate."""
    frames, _ = model.kinematics(_Jet.variables([x0], [rate]))
    return {name: 2 * frames[name][0].c2 for name in model.bodies}


# ------------------------------------------------------------------ mass ratio

#: The front leg's segments at 20:1 (lengths m, radii m, masses kg), from the project's leg
#: note (insect-legs.md, section 4.2, as in legs/cockroach.py: coxa 5 mm, 1 mm, 11.98 mg;
#: trochanter + femur 7.5 mm, 0.55 mm, 11.45 mg; tibia 5 mm, 0.35 mm, 2.66 mg; lengths x 20,
#: masses x 8000). Rest pose: coxa 40 degrees below the horizontal, femur horizontal, tibia 60
#: degrees below, in a vertical plane along +y.
LEG_SEGMENTS = {"coxa": (0.10, 0.020, 0.09584, 40.0), "femur": (0.15, 0.011, 0.09160, 0.0),
                "tibia": (0.10, 0.007, 0.02128, 60.0)}


def _cylinder(length, radius, mass) -> np.ndarray:
    """Principal inertia of a solid cylinder along x."""
    transverse = mass * (3 * radius**2 + length**2) / 12
    return np.array([mass * radius**2 / 2, transverse, transverse])


def _leg_geometry(ratio: float):
    """Rest-pose joint points and axes, bodies (mass, inertia in world axes at rest, centre of
    mass) of the chain ground -> link_1 -> link_2 -> coxa -> femur -> tibia."""
    def direction(deg):
        a = np.radians(deg)
        return np.array([0.0, np.cos(a), -np.sin(a)])

    points, frames, bodies = [np.zeros(3)] * 3, [], {}
    coxa_moments = _cylinder(*LEG_SEGMENTS["coxa"][:2], LEG_SEGMENTS["coxa"][2])
    tiny = (ratio * LEG_SEGMENTS["coxa"][2], np.diag(ratio * coxa_moments), np.zeros(3))
    bodies["link_1"] = bodies["link_2"] = tiny
    point = np.zeros(3)
    for name, (length, radius, mass, deg) in LEG_SEGMENTS.items():
        x = direction(deg)
        z = np.array([1.0, 0.0, 0.0])
        S = np.column_stack([x, np.cross(z, x), z])  # segment axes: x along it
        inertia = S @ np.diag(_cylinder(length, radius, mass)) @ S.T
        bodies[name] = (mass, inertia, point + 0.5 * length * x)
        frames.append(S)
        point = point + length * x
        points.append(point)
    axes = [np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), direction(40.0),
            np.array([1.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])]
    return points, axes, frames, bodies


def mass_ratio(ratio: float = 1e-6, *, t_end: float = 0.5) -> Case:
    """A cockroach front leg at 20:1 (:data:`LEG_SEGMENTS`) with its three-axis thorax-coxa
    joint made of two zero-length links whose mass and inertia are ``ratio`` times the
    coxa's: revolute joints about the vertical, the leg plane's normal and the coxa, then the
    coxa-trochanter and femur-tibia joints (normal to the leg plane). Released at rest under
    gravity from the rest pose, its five joints free.

    Reference: Lagrange's equations in the five joint angles (Kane, the rest pose's axes
    turned by the joints before them), DOP853 at 1e-12. The mass matrix of the absolute
    coordinates spans ``1 / ratio`` (x the coxa's own spread); the joint-coordinate one
    does not."""
    points, axes, frames, bodies = _leg_geometry(ratio)
    chain = ("link_1", "link_2", "coxa", "femur", "tibia")
    scene = Scene(f"mass-ratio-leg-{ratio:.0e}", dimension=3)
    scene.gravity = np.array([0.0, 0.0, -G])
    for k, name in enumerate(chain):
        mass, inertia, com = bodies[name]
        if k < 2:
            scene.add(SpatialBody(name, mass, np.diag(inertia), position=com))
        else:
            S = frames[k - 2]
            scene.add(SpatialBody(name, mass, np.diag(S.T @ inertia @ S), position=com,
                                  rotation=S))
    joints = ("thc_1", "thc_2", "thc_3", "ctr", "fti")
    parents = ("ground",) + chain[:-1]
    for k, joint in enumerate(joints):
        scene.add(Revolute(joint, parents[k], chain[k], origin=points[k], axis=axes[k]))

    def chain_kinematics(x):
        R_parent = _Jet.constant(np.eye(3))
        origin = _Jet.constant(np.zeros(3))
        frames_out = {}
        for k, name in enumerate(chain):
            if k > 0:
                origin = origin + R_parent @ (points[k] - points[k - 1])
            R = R_parent @ _rotation(axes[k], x[k])
            frames_out[name] = (origin + R @ (bodies[name][2] - points[k]), R)
            R_parent = R
        return frames_out, {}

    model = _MinimalModel(chain_kinematics, {n: bodies[n][:2] for n in chain}, [0.0, 0.0, -G])
    observed = ("coxa", "femur", "tibia")
    reference, accelerations = _minimal_reference(model, np.zeros(5), np.zeros(5), t_end,
                                                  observed, 3)
    return Case(scene.name, scene, t_end,
                f"two links of {ratio:.0e} times the coxa's mass and inertia in a 3-axis "
                "joint: a mass matrix spanning that ratio", "mass-ratio", observed, reference,
                accelerations, length=0.35, dof=5, counted_dof=5,
                source="cockroach front leg at 20:1 (insect-legs.md section 4.2, as "
                       "legs/cockroach.py); layout A's zero-length links")


def mass_ratio_pendulum(ratio: float = 1e-6, *, t_end: float = 5.0) -> Case:
    """A planar double pendulum of uniform rods, 1 m each: the upper one 1 kg, the lower
    ``ratio`` kg, released at rest from 1 rad and 2 rad (from the downward vertical).

    Reference: Lagrange's equations of the double pendulum written out by hand,
    ``M(th) th'' = f(th, th')``, DOP853 at 1e-12."""
    m1, m2, l1, l2 = 1.0, ratio, 1.0, 1.0
    I1, I2 = m1 * l1**2 / 12, m2 * l2**2 / 12
    th0 = np.array([1.0, 2.0])
    scene = Scene(f"mass-ratio-pendulum-{ratio:.0e}", dimension=2)
    elbow = l1 * np.array([np.sin(th0[0]), -np.cos(th0[0])])
    u2 = np.array([np.sin(th0[1]), -np.cos(th0[1])])
    scene.add(PlanarBody("upper", m1, I1, position=elbow / 2, angle=th0[0] - np.pi / 2))
    scene.add(PlanarBody("lower", m2, I2, position=elbow + u2 * l2 / 2,
                         angle=th0[1] - np.pi / 2))
    scene.add(Revolute("shoulder", "ground", "upper", origin=[0.0, 0.0]))
    scene.add(Revolute("elbow", "upper", "lower", origin=elbow))
    c1, c2 = l1 / 2, l2 / 2

    def accelerations_of(th, thd):
        d = th[0] - th[1]
        M = np.array([[I1 + m1 * c1**2 + m2 * l1**2, m2 * l1 * c2 * np.cos(d)],
                      [m2 * l1 * c2 * np.cos(d), I2 + m2 * c2**2]])
        f = np.array([-m2 * l1 * c2 * np.sin(d) * thd[1] ** 2 - (m1 * c1 + m2 * l1) * G
                      * np.sin(th[0]),
                      m2 * l1 * c2 * np.sin(d) * thd[0] ** 2 - m2 * c2 * G * np.sin(th[1])])
        return np.linalg.solve(M, f)

    def positions(th):
        e = l1 * np.array([np.sin(th[0]), -np.cos(th[0])])
        return np.concatenate([e / 2, e + l2 / 2 * np.array([np.sin(th[1]), -np.cos(th[1])])])

    reference = _Trajectory(lambda _t, y: np.concatenate([y[2:], accelerations_of(y[:2],
                                                                                 y[2:])]),
                            np.concatenate([th0, [0.0, 0.0]]), t_end, lambda y: positions(y[:2]))
    thdd = accelerations_of(th0, np.zeros(2))
    e1 = np.array([np.cos(th0[0]), np.sin(th0[0])])
    e2 = np.array([np.cos(th0[1]), np.sin(th0[1])])
    accelerations = {"upper": c1 * thdd[0] * e1, "lower": l1 * thdd[0] * e1 + c2 * thdd[1] * e2}
    return Case(scene.name, scene, t_end,
                f"double pendulum whose lower rod is {ratio:.0e} times lighter", "mass-ratio",
                ("upper", "lower"), reference, accelerations, length=2.0, dof=2, counted_dof=2)


# ------------------------------------------------------------------ singular: stretched leg

#: The hanging leg: thigh and shank 0.2 m (0.1 kg and 0.05 kg, uniform rods), trunk 1 kg.
STRETCHED_LEG = dict(length=0.2, thigh=0.1, shank=0.05, trunk=1.0)


def stretched_leg(driven: bool = False, *, theta0: float = 0.5,
                  t_end: float | None = None) -> Case:
    """A two-link leg through its fully stretched pose: an insect hanging from the ceiling.
    The foot is pinned to the ceiling at the origin; the trunk hangs below it on a vertical
    slider (x = 0); thigh (hip to knee) and shank (knee to foot) are equally long
    (:data:`STRETCHED_LEG`). With ``theta`` the shank's angle from the downward vertical, the
    knee is at ``l (sin theta, -cos theta)`` and the hip at ``(0, -2 l cos theta)``.

    At theta = 0 the leg is straight: the hip's height is stationary (second order in theta),
    the leg's foot-to-hip Jacobian is singular and the inverse kinematics (theta from the
    trunk's height) has infinite slope. The joints' Jacobian in absolute coordinates keeps
    full rank there (the knee may still move sideways). Free (default): released at rest with
    the knee bent by ``theta0``, it swings through the straight pose twice per period.
    Driven: the slider follows ``y(t) = -2 l cos(omega (t - t_end / 2))`` (omega = 2 pi rad/s,
    0.4 s: the knee from -72 to 72 degrees), which passes the straight pose at ``t_end / 2``;
    there the driver's row and the joints' become dependent (the knee's sideways motion is
    free for an instant) and the motion continues with the knee flipping to the other side,
    ``theta = omega (t - t_end / 2)`` (the only continuation with continuous velocities).

    Reference: free, Lagrange's equation in theta written out (DOP853 at 1e-12; Kane's
    equations give the initial accelerations, and the tests check both agree); driven, the
    closed form above."""
    p = STRETCHED_LEG
    l = p["length"]
    masses = {"trunk": p["trunk"], "thigh": p["thigh"], "shank": p["shank"]}
    omega = 2 * np.pi
    t_end = (0.4 if driven else 2.0) if t_end is None else t_end
    t_mid = t_end / 2
    if driven:
        theta0 = -omega * t_mid
    scene = Scene("stretched-leg" + ("-driven" if driven else ""), dimension=2)
    model = _stretched_leg_minimal(masses)
    rate0 = omega if driven else 0.0
    frames, _ = model.kinematics(_Jet.variables([theta0], [rate0]))
    inertias = {"trunk": 0.01, "thigh": p["thigh"] * l**2 / 12, "shank": p["shank"] * l**2 / 12}
    for name in ("trunk", "thigh", "shank"):
        pos, R = frames[name]
        scene.add(PlanarBody(name, masses[name], inertias[name], position=pos.c0[:2],
                             angle=float(np.arctan2(R.c0[1, 0], R.c0[0, 0])),
                             velocity=pos.c1[-1][:2],
                             angular_velocity=_vee(R.c1[-1] @ R.c0.T)[2]))
    hip = [0.0, -2 * l * np.cos(theta0)]
    knee = [l * np.sin(theta0), -l * np.cos(theta0)]
    scene.add(Prismatic("slider", "ground", "trunk", origin=hip, axis=[0.0, 1.0]))
    scene.add(Revolute("hip", "trunk", "thigh", origin=hip))
    scene.add(Revolute("knee", "thigh", "shank", origin=knee))
    scene.add(Revolute("foot", "shank", "ground", origin=[0.0, 0.0]))
    observed = ("trunk", "thigh", "shank")
    if driven:
        # slider displacement from the initial pose: -2 l cos(omega (t - t_mid)) - hip_y(0)
        scene.add(JointDriver("lift", "slider",
                              Harmonic(offset=-hip[1], cos=[-2 * l], frequency=1.0,
                                       t0=t_mid)))

        def reference(times):
            times = np.atleast_1d(np.asarray(times, dtype=float))
            out = []
            for t in times:
                positions = model.com_positions([omega * (t - t_mid)])
                out.append(np.concatenate([positions[b][:2] for b in observed]))
            return np.array(out)

        accelerations = {k: a[:2] for k, a in _driven_accelerations(model, theta0,
                                                                    omega).items()}
    else:
        mt, ms, M = p["thigh"], p["shank"], p["trunk"]
        inertia0 = (mt + ms) * l * l / 12 + (mt + ms) * l * l / 4  # both rods, at theta = 0
        potential = G * l * (2 * M + 1.5 * mt + 0.5 * ms)

        def rates(_t, y):
            # m(th) th'' + m'(th) th'^2 / 2 + V'(th) = 0, with
            # m = (m_t + m_s) l^2 / 12 + M (2 l s)^2 + m_t l^2 (c^2 / 4 + 9 s^2 / 4)
            #     + m_s l^2 / 4,  V = -g l c (2 M + 3 m_t / 2 + m_s / 2)
            th, thd = y
            sn, cs = np.sin(th), np.cos(th)
            m = inertia0 + (4 * M + 2 * mt) * l * l * sn * sn
            dm = 2 * (4 * M + 2 * mt) * l * l * sn * cs
            return np.array([thd, -(0.5 * dm * thd * thd + potential * sn) / m])

        reference, accelerations = _minimal_reference(model, [theta0], [0.0], t_end, observed,
                                                      2, rates=rates)
    return Case(scene.name, scene, t_end,
                "leg through its straight pose: the hip's height is stationary, the leg's "
                "Jacobian singular" + (" and the driven slider's row dependent" if driven
                                       else ""),
                "singular", observed, reference, accelerations, length=2 * l, dof=1,
                counted_dof=1, dof_with_drivers=0 if driven else 1,
                energy_conserved=not driven)


def _stretched_leg_minimal(masses) -> _MinimalModel:
    l = STRETCHED_LEG["length"]

    def kinematics(x):
        theta = x[0]
        s, c = _sin(theta), _cos(theta)
        zero = 0.0 * theta
        hip = _stack([zero, c * (-2 * l), zero])
        knee = _stack([s * l, c * (-l), zero])
        # thigh from knee to hip: direction (-sin, -cos); shank from foot to knee: (sin, -cos)
        frames = {"trunk": (hip, _Jet.constant(np.eye(3))),
                  "thigh": ((hip + knee) * 0.5, _planar_rotation(-s, -c)),
                  "shank": (knee * 0.5, _planar_rotation(s, -c))}
        return frames, {}

    l2 = l**2
    bodies = {"trunk": (masses["trunk"], np.diag([0.0, 0.0, 0.01])),
              "thigh": (masses["thigh"], np.diag([0.0, 0.0, masses["thigh"] * l2 / 12])),
              "shank": (masses["shank"], np.diag([0.0, 0.0, masses["shank"] * l2 / 12]))}
    return _MinimalModel(kinematics, bodies, [0.0, -G, 0.0])


# ------------------------------------------------------------------ long and large steps


def _pendulum_exact(t, psi0: float, omega0: float) -> np.ndarray:
    """Angle from the downward vertical of a pendulum released at rest from ``psi0``:
    ``psi = 2 arcsin(k sn(K - omega0 t, k))``, ``k = sin(psi0 / 2)`` (as
    :func:`hexapod.benchmarks.references.pendulum_exact`)."""
    from scipy.special import ellipj, ellipk

    k = np.sin(psi0 / 2)
    sn, _, _, _ = ellipj(ellipk(k * k) - omega0 * np.asarray(t, dtype=float), k * k)
    return 2 * np.arcsin(k * sn)


def _pendulum_period(psi0: float, omega0: float) -> float:
    from scipy.special import ellipk

    return float(4 * ellipk(np.sin(psi0 / 2) ** 2) / omega0)


def long_pendulum(periods: int = 1000) -> Case:
    """The spatial pendulum of ``data/scenes/pendulum.toml`` (a 1 m, 1 kg rod about the y axis
    through its end, inertia (0.001, 0.0833, 0.0833) kg m^2) released horizontal, over
    ``periods`` periods (1000: about 1700 s). Reference: Jacobi elliptic functions (exact)."""
    inertia = (0.001, 0.0833, 0.0833)
    arm, I_O = 0.5, inertia[1] + 0.25
    omega0, psi0 = np.sqrt(G * arm / I_O), np.pi / 2
    period = _pendulum_period(psi0, omega0)
    scene = Scene("long-pendulum", dimension=3)
    scene.add(SpatialBody("rod", 1.0, list(inertia), position=[arm, 0.0, 0.0]))
    scene.add(Revolute("pivot", "ground", "rod", origin=[0.0, 0.0, 0.0], axis=[0.0, 1.0, 0.0]))

    def reference(times):
        psi = _pendulum_exact(np.atleast_1d(times), psi0, omega0)
        return np.column_stack([arm * np.sin(psi), np.zeros_like(psi), -arm * np.cos(psi)])

    # released horizontal at rest: psi'' = -omega0^2, the centre of mass accelerates down
    return Case(scene.name, scene, periods * period,
                f"{periods} periods of a pendulum: error growth and energy drift", "long",
                ("rod",), reference, {"rod": np.array([0.0, 0.0, -arm * omega0**2])},
                length=arm, dof=1, counted_dof=1,
                source="data/scenes/pendulum.toml; exact solution as hexapod.benchmarks.references")


def large_step_pendulum(psi0: float = 3.0, periods: int = 10) -> Case:
    """A planar pendulum (a 1 m, 1 kg rod about an end) released at rest ``psi0`` rad from the
    downward vertical (3 rad: 8 degrees from the top): it lingers near the top and swings
    through the bottom fast, so a step that suits one phase is far too large for the other.
    Reference: Jacobi elliptic functions (exact)."""
    m, l = 1.0, 1.0
    I_c = m * l**2 / 12
    arm, I_O = l / 2, I_c + m * l**2 / 4
    omega0 = np.sqrt(m * G * arm / I_O)
    period = _pendulum_period(psi0, omega0)
    scene = Scene(f"large-step-pendulum-{psi0:g}", dimension=2)
    scene.add(PlanarBody("rod", m, I_c, position=[arm * np.sin(psi0), -arm * np.cos(psi0)],
                         angle=psi0 - np.pi / 2))
    scene.add(Revolute("pivot", "ground", "rod", origin=[0.0, 0.0]))

    def reference(times):
        psi = _pendulum_exact(np.atleast_1d(times), psi0, omega0)
        return np.column_stack([arm * np.sin(psi), -arm * np.cos(psi)])

    psi_dd = -omega0**2 * np.sin(psi0)
    tangent = np.array([np.cos(psi0), np.sin(psi0)])
    return Case(scene.name, scene, periods * period,
                f"released {np.degrees(np.pi - psi0):.0f} degrees from the top: slow near the "
                f"top, fast at the bottom (period {period:.2f} s)", "large-step", ("rod",),
                reference, {"rod": arm * psi_dd * tangent}, length=arm, dof=1, counted_dof=1)


# ------------------------------------------------------------------ the suite


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


__all__ = [
    "CATEGORIES", "Case", "bricard", "flyball_governor", "four_bar_dead_points",
    "large_step_pendulum", "long_pendulum", "mass_ratio", "mass_ratio_pendulum", "n_four_bar",
    "stiff_slider", "stiff_spring_pendulum", "stretched_leg", "suite",
]
