"""The machinery of the extreme-case references, shared by every category.

:class:`Case` is what a case builder returns: a :class:`~hexapod.scene.Scene`, how long to run
it, what is extreme about it, and an independent solution of its motion. The observable of a
case is the centre-of-mass position of some of its bodies (:meth:`Case.observable` reads it from
an engine state); :attr:`Case.reference` gives the same numbers at any times, and
:attr:`Case.accelerations` the centres of mass' accelerations at the start (a cheap, strong
check that the scene and the reference describe the same system).

The references never call the engine: they are written in minimal (joint) coordinates, in
closed form or as ordinary differential equations integrated by SciPy at ``rtol = 1e-12``.
Lagrange's equations of a mechanism given by its joint-coordinate kinematics are formed by
Kane's method (:class:`MinimalModel`), with the kinematics differentiated exactly (to
round-off) by truncated Taylor series (:mod:`hexapod.benchmarks.jets`): no finite differences,
no symbolic algebra, no shared code with the absolute-coordinate model. Where an ODE is
integrated in a faster form (written out by hand, or, for one degree of freedom, with its
coefficients tabulated in Chebyshev series to round-off: :class:`OneDof`), Kane's equations of
the same model remain the check (``reference.model``). ODE references are solved once, when
first asked for, and kept (:class:`Trajectory`); their precision is about 1e-11 of the
motion's size.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from hexapod.benchmarks.jets import Jet, vee
from hexapod.scene import Scene

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


# ------------------------------------------------------------------ minimal coordinates


@dataclass
class Spring:
    """A spring-damper between two points of the kinematics (names), or a fixed point (array)
    and a named one: tension ``k (L - free_length) + c dL/dt``."""

    a: str | np.ndarray
    b: str
    stiffness: float
    damping: float
    free_length: float


class MinimalModel:
    """A mechanism in its own minimal coordinates ``x``: Kane's equations
    ``sum_i J_i^T (m_i a_i - f_i) + Jw_i^T (I_i alpha_i + w_i x I_i w_i - t_i) = 0``.

    ``kinematics(x)`` maps jets of the coordinates to ``(frames, points)``: each body's centre
    of mass and rotation (body -> world) as jets, and named points (for springs). ``bodies``
    gives each body's mass and inertia about its centre of mass in its own axes.
    """

    def __init__(self, kinematics, bodies: dict[str, tuple[float, np.ndarray]], gravity,
                 springs: tuple[Spring, ...] = ()):
        self.kinematics = kinematics
        self.bodies = bodies
        self.gravity = np.asarray(gravity, dtype=float)
        self.springs = springs

    def equations(self, x, xd) -> tuple[np.ndarray, np.ndarray]:
        """Mass matrix and right-hand side ``f`` of ``M xdd = f``."""
        x = np.asarray(x, dtype=float)
        n = x.size
        frames, points = self.kinematics(Jet.variables(x, xd))
        M, f = np.zeros((n, n)), np.zeros(n)
        for name, (mass, inertia) in self.bodies.items():
            p, R = frames[name]
            R0, R1 = R.c0, np.broadcast_to(R.c1, (n + 1, 3, 3))
            Jp = np.broadcast_to(p.c1, (n + 1, 3))[:n].T
            rates = vee(R1 @ R0.T)  # (n + 1, 3): Jacobian's columns, then omega
            Jw, w = rates[:n].T, rates[n]
            Iw = R0 @ inertia @ R0.T
            bias = 2 * p.c2  # the acceleration at xdd = 0
            alpha = vee(2 * R.c2 @ R0.T + R1[n] @ R1[n].T)
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
        frames, _ = self.kinematics(Jet.variables(x, np.zeros_like(x)))
        return {name: frames[name][0].c0 for name in self.bodies}

    def com_accelerations(self, x, xd) -> dict[str, np.ndarray]:
        xdd = self.accelerations(x, xd)
        frames, _ = self.kinematics(Jet.variables(x, xd, xdd))
        return {name: 2 * frames[name][0].c2 for name in self.bodies}

    def energy(self, x, xd) -> float:
        x = np.asarray(x, dtype=float)
        frames, points = self.kinematics(Jet.variables(x, xd))
        total = 0.0
        for name, (mass, inertia) in self.bodies.items():
            p, R = frames[name]
            w = vee(R.c1[-1] @ R.c0.T)  # a constant's single direction is zero as well
            total += 0.5 * mass * p.c1[-1] @ p.c1[-1] + 0.5 * w @ (R.c0 @ inertia @ R.c0.T) @ w
            total -= mass * self.gravity @ p.c0
        for spring in self.springs:
            ra = points[spring.a].c0 if isinstance(spring.a, str) else np.asarray(spring.a)
            length = np.linalg.norm(points[spring.b].c0 - ra)
            total += 0.5 * spring.stiffness * (length - spring.free_length) ** 2
        return float(total)


class Trajectory:
    """The solution of ``rates`` from ``y0``, solved when first asked for (and again, further,
    when asked beyond the end), mapped to the observable by ``observe(y) -> (k,)``."""

    def __init__(self, rates, y0, t_end: float, observe, method: str = "DOP853",
                 rtol: float = 1e-12, atol: float = 1e-12, jacobian=None):
        self.rates, self.y0, self.t_end = rates, np.asarray(y0, dtype=float), t_end
        self.observe, self.method, self.rtol, self.atol = observe, method, rtol, atol
        self.jacobian = jacobian
        self.solution = None
        self.model: MinimalModel | None = None

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


def minimal_reference(model: MinimalModel, x0, xd0, t_end: float, observed, width: int,
                       rates=None, **options) -> tuple[Trajectory, dict[str, np.ndarray]]:
    """The trajectory of a minimal model (observable: the observed centres of mass, ``width``
    coordinates each) and its initial centre-of-mass accelerations. ``rates``: the same
    equations in a faster form (written by hand, or :class:`OneDof`), default the model's."""
    n = len(x0)

    def observe(y):
        positions = model.com_positions(y[:n])
        return np.concatenate([positions[b][:width] for b in observed])

    trajectory = Trajectory(rates or model.rates, np.concatenate([x0, xd0]), t_end, observe,
                             **options)
    trajectory.model = model  # Kane's equations, to check faster forms of ``rates`` against
    accelerations = {name: a[:width] for name, a in model.com_accelerations(x0, xd0).items()}
    return trajectory, accelerations


class OneDof:
    """A one-degree-of-freedom minimal model without springs, ``m(x) x'' = f0(x) + f2(x) x'^2``
    (``f2 = -m'/2``, ``f0 = -V'``), with ``m``, ``f0`` and ``f2`` interpolated at ``degree``
    Chebyshev points of ``[lo, hi]`` from the exact model: the same equation, evaluated a
    hundred times faster. The interpolation is checked against the model between the nodes
    (to 1e-13 relative) when built; outside ``[lo, hi]`` the model itself is used."""

    def __init__(self, model: MinimalModel, lo: float, hi: float, degree: int = 128):
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


def rod_inertia(mass: float, length: float, axis: int, section: float = 0.0) -> np.ndarray:
    """Principal inertia (3 x 3) of a rod along body axis ``axis`` with a square section of
    side ``section`` (0: a slender rod)."""
    transverse = mass * (length**2 + section**2) / 12
    axial = mass * section**2 / 6
    moments = np.full(3, transverse)
    moments[axis] = axial
    return np.diag(moments)

