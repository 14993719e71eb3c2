"""Pendulums with exact or independent references.

* :func:`pendulum_exact` and :func:`pendulum_period`: the physical pendulum released from
  rest, in Jacobi elliptic functions (exact to round-off at any time);
* :func:`long_pendulum` (category "long") and :func:`large_step_pendulum` ("large-step"): the
  extreme-case suite's pendulums, judged against that solution;
* :class:`ClosedLoopPendulum`: the closed-loop pendulum of Richard, Anderson and Andrews
  (1989/90; two particles on two rods joined by a rigid coupler: a four-bar with one degree of
  freedom) by its one-degree-of-freedom Lagrange equation in the first rod's angle, integrated by
  SciPy's DOP853 to 1e-12, as the paper checks RESTRI (its Figs. 7-10).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.benchmarks.reference import Case, G
from hexapod.scene import PlanarBody, Revolute, Scene, SpatialBody

# ------------------------------------------------------------------ the exact pendulum


def pendulum_exact(t, psi0: float, omega0: float) -> tuple[np.ndarray, np.ndarray]:
    """Angle from the downward vertical and its rate of a pendulum released at rest from
    ``psi0`` (rad, ``|psi0| < pi``), with small-oscillation frequency ``omega0``
    (``sqrt(m g l / I_O)``, rad/s):

        psi = 2 arcsin(k sn(K - omega0 t, k)),   psi_dot = -2 k omega0 cn(K - omega0 t, k),

    ``k = sin(psi0 / 2)`` and ``K`` the complete elliptic integral of the first kind. The
    period is ``4 K / omega0``."""
    from scipy.special import ellipj, ellipk

    t = np.asarray(t, dtype=float)
    k = np.sin(psi0 / 2)
    m = k * k
    u = ellipk(m) - omega0 * t
    sn, cn, _, _ = ellipj(u, m)
    return 2 * np.arcsin(k * sn), -2 * k * omega0 * cn


def pendulum_period(psi0: float, omega0: float) -> float:
    """Period (s) of the pendulum of :func:`pendulum_exact`: ``4 K(sin^2(psi0 / 2)) / omega0``."""
    from scipy.special import ellipk

    return float(4 * ellipk(np.sin(psi0 / 2) ** 2) / omega0)


# ------------------------------------------------------------------ the suite's pendulums


def long_pendulum(periods: int = 1000, *, duration: float | None = None) -> Case:
    """The spatial pendulum of ``data/scenes/pendulum.toml`` (a 1 m, 1 kg rod about the y axis
    through its end, inertia (0.001, 0.0833, 0.0833) kg m^2) released horizontal, over
    ``periods`` periods (1000: about 1700 s), or over ``duration`` seconds when given (the
    IFToMM pendulum's 2000 s). Reference: Jacobi elliptic functions (exact)."""
    inertia = (0.001, 0.0833, 0.0833)
    arm, I_O = 0.5, inertia[1] + 0.25
    omega0, psi0 = np.sqrt(G * arm / I_O), np.pi / 2
    period = pendulum_period(psi0, omega0)
    scene = Scene("long-pendulum", dimension=3)
    scene.add(SpatialBody("rod", 1.0, list(inertia), position=[arm, 0.0, 0.0]))
    scene.add(Revolute("pivot", "ground", "rod", origin=[0.0, 0.0, 0.0], axis=[0.0, 1.0, 0.0]))

    def reference(times):
        psi, _ = pendulum_exact(np.atleast_1d(times), psi0, omega0)
        return np.column_stack([arm * np.sin(psi), np.zeros_like(psi), -arm * np.cos(psi)])

    # released horizontal at rest: psi'' = -omega0^2, the centre of mass accelerates down
    span = periods * period if duration is None else float(duration)
    return Case(scene.name, scene, span,
                f"{span / period:.0f} periods ({span:.0f} s) of a pendulum: error growth and "
                "energy drift", "long",
                ("rod",), reference, {"rod": np.array([0.0, 0.0, -arm * omega0**2])},
                length=arm, dof=1, counted_dof=1,
                source="data/scenes/pendulum.toml; exact solution: "
                       "hexapod.benchmarks.pendulum_exact")


def large_step_pendulum(psi0: float = 3.0, periods: int = 10) -> Case:
    """A planar pendulum (a 1 m, 1 kg rod about an end) released at rest ``psi0`` rad from the
    downward vertical (3 rad: 8 degrees from the top): it lingers near the top and swings
    through the bottom fast, so a step that suits one phase is far too large for the other.
    Reference: Jacobi elliptic functions (exact)."""
    m, l = 1.0, 1.0
    I_c = m * l**2 / 12
    arm, I_O = l / 2, I_c + m * l**2 / 4
    omega0 = np.sqrt(m * G * arm / I_O)
    period = pendulum_period(psi0, omega0)
    scene = Scene(f"large-step-pendulum-{psi0:g}", dimension=2)
    scene.add(PlanarBody("rod", m, I_c, position=[arm * np.sin(psi0), -arm * np.cos(psi0)],
                         angle=psi0 - np.pi / 2))
    scene.add(Revolute("pivot", "ground", "rod", origin=[0.0, 0.0]))

    def reference(times):
        psi, _ = pendulum_exact(np.atleast_1d(times), psi0, omega0)
        return np.column_stack([arm * np.sin(psi), -arm * np.cos(psi)])

    psi_dd = -omega0**2 * np.sin(psi0)
    tangent = np.array([np.cos(psi0), np.sin(psi0)])
    return Case(scene.name, scene, periods * period,
                f"released {np.degrees(np.pi - psi0):.0f} degrees from the top: slow near the "
                f"top, fast at the bottom (period {period:.2f} s)", "large-step", ("rod",),
                reference, {"rod": arm * psi_dd * tangent}, length=arm, dof=1, counted_dof=1)


# ---------------------------------------- the closed loop of Richard, Anderson and Andrews


@dataclass(frozen=True)
class ClosedLoopPendulum:
    """The pendulum of Section 5 of Richard, Anderson and Andrews in minimal coordinates (SI
    units).

    Particle 1 (``m1``) hangs from ``anchor1`` by a rod of length ``|p1 - anchor1|``, particle 2
    from ``anchor2``; a coupler keeps ``|p2 - p1|``. Gravity ``g`` along +y (the paper's y
    points down). The coordinate is the first rod's angle ``theta``, ``p1 = anchor1 + L1 (cos
    theta, sin theta)``; ``p2`` is where the circles about ``anchor2`` and ``p1`` meet, on the
    side of the initial pose. Lagrange's equation,

        a(theta) theta_dd + a'(theta) theta_d^2 / 2 = g (m1 y1' + m2 y2'),
        a = m1 |p1'|^2 + m2 |p2'|^2,

    with ``p2'`` and ``p2''`` from the derivatives of the two distance conditions.
    """

    m1: float = 2.0
    m2: float = 1.0
    anchor1: tuple[float, float] = (0.0, 0.0)
    anchor2: tuple[float, float] = (0.7, 0.0)
    p1: tuple[float, float] = (0.4, 0.4)
    p2: tuple[float, float] = (1.2, 0.5)
    g: float = 9.81

    @property
    def lengths(self) -> tuple[float, float, float]:
        a1, a2, p1, p2 = (np.array(x) for x in (self.anchor1, self.anchor2, self.p1, self.p2))
        return (float(np.linalg.norm(p1 - a1)), float(np.linalg.norm(p2 - a2)),
                float(np.linalg.norm(p2 - p1)))

    def positions(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """``p1``, ``p2`` (arrays (..., 2)) at angles ``theta``."""
        theta = np.asarray(theta, dtype=float)
        L1, L2, L3 = self.lengths
        a1, a2 = np.array(self.anchor1), np.array(self.anchor2)
        p1 = a1 + L1 * np.stack([np.cos(theta), np.sin(theta)], axis=-1)
        # intersection of the circles (a2, L2) and (p1, L3), on the initial pose's side
        d_vec = p1 - a2
        d = np.linalg.norm(d_vec, axis=-1, keepdims=True)
        along = (L2**2 - L3**2 + d**2) / (2 * d)
        across = np.sqrt(np.maximum(L2**2 - along**2, 0.0))
        unit = d_vec / d
        normal = np.stack([-unit[..., 1], unit[..., 0]], axis=-1)
        side = self._side()
        return p1, a2 + along * unit + side * across * normal

    def _side(self) -> float:
        a2, p1, p2 = np.array(self.anchor2), np.array(self.p1), np.array(self.p2)
        unit = (p1 - a2) / np.linalg.norm(p1 - a2)
        normal = np.array([-unit[1], unit[0]])
        return float(np.sign(np.dot(p2 - a2, normal)))

    def _derivatives(self, theta: float):
        """``p1', p1'', p2', p2''`` at ``theta``."""
        L1 = self.lengths[0]
        a2 = np.array(self.anchor2)
        p1, p2 = (x for x in self.positions(theta))
        d1 = L1 * np.array([-np.sin(theta), np.cos(theta)])
        dd1 = L1 * np.array([-np.cos(theta), -np.sin(theta)])
        # (p2 - a2) . p2' = 0 and (p2 - p1) . (p2' - p1') = 0
        A = np.array([p2 - a2, p2 - p1])
        d2 = np.linalg.solve(A, np.array([0.0, np.dot(p2 - p1, d1)]))
        rhs = np.array([-np.dot(d2, d2),
                        np.dot(p2 - p1, dd1) - np.dot(d2 - d1, d2 - d1)])
        dd2 = np.linalg.solve(A, rhs)
        return d1, dd1, d2, dd2

    def _rates(self, _t, state):
        theta, rate = state
        d1, dd1, d2, dd2 = self._derivatives(theta)
        a = self.m1 * d1 @ d1 + self.m2 * d2 @ d2
        a_prime = 2 * (self.m1 * d1 @ dd1 + self.m2 * d2 @ dd2)
        force = self.g * (self.m1 * d1[1] + self.m2 * d2[1])
        return [rate, (force - a_prime * rate**2 / 2) / a]

    def solve(self, t_end: float, rtol: float = 1e-12, atol: float = 1e-12):
        """The motion from rest at the initial pose over ``[0, t_end]``: a function of time
        giving ``p1, p2`` (arrays (N, 2), m) and ``theta``."""
        from scipy.integrate import solve_ivp

        a1, p1 = np.array(self.anchor1), np.array(self.p1)
        theta0 = float(np.arctan2(*(p1 - a1)[::-1]))
        solution = solve_ivp(self._rates, (0.0, t_end), [theta0, 0.0], method="DOP853",
                             rtol=rtol, atol=atol, dense_output=True)
        if not solution.success:
            raise RuntimeError(solution.message)

        def motion(t):
            theta = solution.sol(np.asarray(t, dtype=float))[0]
            q1, q2 = self.positions(theta)
            return q1, q2, theta

        return motion
