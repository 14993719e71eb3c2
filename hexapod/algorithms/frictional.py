"""The frictional contact problem of a time step, at velocity level (Moreau's sweeping process,
Jean's contact dynamics): the impulses of the closed contacts given their Delassus operator.

Each contact ``a`` has an impulse ``P_a`` (normal ``P_N`` first, then the tangential ``P_T``,
in its own axes) and a velocity at the end of the step ``u = W P + b`` (``W``: the Delassus
operator, the contacts' velocity response to their impulses through the constrained
mechanism; ``b``: their velocity without contact impulses). With Newton's restitution ``e``
and the normal velocity ``u_N-`` at the start of the step, the conditions on ``u_N + e u_N-``
are, per contact, one of

* **open**: ``P = 0`` and ``u_N + e u_N- >= 0``;
* **stick**: ``u_N + e u_N- = 0``, ``u_T = 0`` and ``|P_T| <= mu P_N``;
* **slip**: ``u_N + e u_N- = 0``, ``P_T = -mu P_N u_T / |u_T|`` with ``P_N > 0``,

the complementarity ``K_mu ∋ P ⟂ u_hat ∈ K_mu*`` of de Saxcé's bipotential with the exact
(quadratic) cone, not a pyramid. It is solved by block Gauss-Seidel (Jean and Moreau 1992):
each sweep solves every contact's own problem exactly, the others' impulses held, until the
impulses change by less than :data:`SWEEP_TOLERANCE` of their scale. A contact's own problem is
solved by trying the three cases: open, then stick (a ``d x d`` solve), then slip, whose
direction is the root of one scalar function of its angle (two candidates in the plane).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from hexapod.algorithms.linalg import least_norm_psd
from hexapod.errors import HexapodError

#: sweeps stop when no contact velocity changed by more than this, relative to their scale
SWEEP_TOLERANCE = 1e-13
#: at most this many Gauss-Seidel sweeps (one per contact suffices without coupling)
MAX_SWEEPS = 5000
#: the slip direction's angle is bracketed on this many points of the circle, then refined
ANGLE_SAMPLES = 72


class ContactProblemError(HexapodError):
    """A frictional contact problem without a solution the method can find."""


@dataclass(frozen=True)
class ContactSolution:
    """Impulses and states of the contacts of one step.

    Attributes
    ----------
    impulses : ndarray, shape (m, d)
        Each contact's impulse in its own axes (normal first), N s.
    velocities : ndarray, shape (m, d)
        Each contact's velocity at the end of the step, its own axes (m/s).
    states : tuple of str
        ``"open"``, ``"stick"`` or ``"slip"`` per contact.
    sweeps : int
        Gauss-Seidel sweeps taken.
    """

    impulses: np.ndarray
    velocities: np.ndarray
    states: tuple[str, ...]
    sweeps: int


def solve_contacts(W: np.ndarray, b: np.ndarray, mu: np.ndarray, target: np.ndarray,
                   names: tuple[str, ...] = (),
                   initial: np.ndarray | None = None) -> ContactSolution:
    """The impulses of ``m`` contacts (see the module's description).

    Parameters
    ----------
    W : ndarray, shape (m d, m d)
        The Delassus operator (symmetric, positive semi-definite), contact by contact.
    b : ndarray, shape (m d,)
        The contacts' velocities without contact impulses.
    mu : ndarray, shape (m,)
        Friction coefficients.
    target : ndarray, shape (m,)
        ``-e u_N-`` per contact: the least normal velocity at the end of the step.
    names : tuple of str
        The contacts' names, for messages.
    initial : ndarray, shape (m, d), optional
        Where the sweeps start (the impulses of the step before: a steady contact then
        settles in a sweep or two); default zero.

    Returns
    -------
    ContactSolution

    Raises
    ------
    ContactProblemError
        A contact's own problem has no solution (a contact that cannot move along its
        normal), or the sweeps do not converge.
    """
    m = mu.size
    d = b.size // m if m else 1
    rest = b.reshape(m, d).copy()
    rest[:, 0] -= target  # the normal condition becomes u_N >= 0 on this velocity
    sticking = _all_stick(W, rest, mu)
    if sticking is not None:
        return ContactSolution(sticking, (W @ sticking.reshape(-1) + b).reshape(m, d),
                               ("stick",) * m, 0)
    P = np.zeros((m, d)) if initial is None else np.array(initial, dtype=float).reshape(m, d)
    states = ["open"] * m
    blocks = [W[a * d:(a + 1) * d, a * d:(a + 1) * d] for a in range(m)]
    scale = float(np.max(np.abs(rest))) if m else 0.0
    sweeps = 0
    for sweeps in range(1, MAX_SWEEPS + 1):  # noqa: B007 (counted)
        before = P.copy()
        for a in range(m):
            c = rest[a] + W[a * d:(a + 1) * d] @ P.reshape(-1) - blocks[a] @ P[a]
            P[a], states[a] = _local(blocks[a], c, float(mu[a]), _name(names, a))
        # the velocities the sweep changed: impulses shared among redundant contacts may drift
        # along what changes no velocity, and need not settle
        change = float(np.max(np.abs(W @ (P - before).reshape(-1)))) if m else 0.0
        scale = max(scale, float(np.max(np.abs(W @ P.reshape(-1)))) if m else 0.0)
        if m <= 1 or change <= SWEEP_TOLERANCE * scale:
            break
    else:
        raise ContactProblemError(f"the contacts' impulses did not settle in {MAX_SWEEPS} "
                                  f"Gauss-Seidel sweeps (their velocities still changed by "
                                  f"{change:.3g} m/s of {scale:.3g})")
    velocities = (W @ P.reshape(-1) + b).reshape(m, d)
    return ContactSolution(P, velocities, tuple(states), sweeps)


def _all_stick(W: np.ndarray, rest: np.ndarray, mu: np.ndarray) -> np.ndarray | None:
    """The impulses of every contact sticking (``u = 0``), of least norm where contacts are
    redundant (a block on four corners), when they all push and lie inside their cones: the
    common case of feet at rest, found by one solve instead of sweeps. None otherwise."""
    m, d = rest.shape
    if m == 0 or d == 1:
        return None
    r = rest.reshape(-1)
    P = least_norm_psd(W, -r)
    if np.abs(W @ P + r).max() > SWEEP_TOLERANCE * max(float(np.abs(r).max()), 1e-300):
        return None
    P = P.reshape(m, d)
    if np.all(P[:, 0] >= 0.0) and np.all(np.linalg.norm(P[:, 1:], axis=1)
                                         <= mu * P[:, 0] * (1 + 1e-12)):
        return P
    return None


def _name(names: tuple[str, ...], a: int) -> str:
    return f"contact '{names[a]}'" if a < len(names) else f"contact {a}"


def _local(D: np.ndarray, c: np.ndarray, mu: float, name: str) -> tuple[np.ndarray, str]:
    """One contact's impulse with ``u = D P + c``: open, stick or slip (see the module)."""
    if c[0] >= 0.0:
        return np.zeros_like(c), "open"
    if not D[0, 0] > 0.0:
        raise ContactProblemError(f"{name} cannot move along its normal: nothing it can push "
                                  "is free to move (a contact on a body held by its joints)")
    if c.size > 1 and mu > 0.0:
        try:
            P = -np.linalg.solve(D, c)
        except np.linalg.LinAlgError:
            P = None
        if P is not None and P[0] >= 0.0 and np.linalg.norm(P[1:]) <= mu * P[0] * (1 + 1e-12):
            return P, "stick"
    P = _slip(D, c, mu, name)
    if mu == 0.0:  # frictionless: it slips only where it moves along the ground
        u_T = (D @ P + c)[1:]
        return P, "slip" if np.linalg.norm(u_T) > 1e-12 * np.linalg.norm(c) else "stick"
    return P, "slip"


def _slip(D: np.ndarray, c: np.ndarray, mu: float, name: str) -> np.ndarray:
    """The sliding impulse ``(P_N, -mu P_N s)``: ``u_N = 0`` and the tangential velocity
    ``sigma s`` along the slip direction ``s`` (unit, in the tangent plane), ``sigma >= 0``:

        D_NN P_N - mu P_N D_NT s + c_N = 0,
        D_TN P_N - mu P_N D_TT s + c_T = sigma s,     |s| = 1,

    solved by Newton's method in ``(P_N, s, sigma)`` from the frictionless slip; where it does
    not converge to a slip that pushes and moves forwards, the direction's angle is bracketed
    around the circle (:func:`_slip_by_angle`)."""
    if c.size == 1 or mu == 0.0:  # no friction: the normal impulse alone
        return np.concatenate([[-c[0] / D[0, 0]], np.zeros(c.size - 1)])
    if c.size == 2:
        return _slip_by_angle(D, c, mu, name)
    P_N = -c[0] / D[0, 0]
    r = c[1:] + D[1:, 0] * P_N
    s = r / np.linalg.norm(r) if np.linalg.norm(r) > 0 else np.array([1.0, 0.0])
    x = np.array([P_N, s[0], s[1], max(float(np.linalg.norm(r)), 1e-300)])
    scale = float(np.max(np.abs(c)))
    J = np.zeros((4, 4))
    for _ in range(40):
        P_N, s, sigma = x[0], x[1:3], x[3]
        F = np.concatenate([[D[0, 0] * P_N - mu * P_N * (D[0, 1:] @ s) + c[0]],
                            D[1:, 0] * P_N - mu * P_N * (D[1:, 1:] @ s) + c[1:] - sigma * s,
                            [(s @ s - 1.0) / 2]])
        if np.max(np.abs(F[:3])) <= 1e-15 * scale and abs(F[3]) <= 1e-15:
            if P_N >= 0.0 and sigma >= 0.0:
                return np.concatenate([[P_N], -mu * P_N * s])
            break
        J[0, 0], J[0, 1:3] = D[0, 0] - mu * (D[0, 1:] @ s), -mu * P_N * D[0, 1:]
        J[1:3, 0] = D[1:, 0] - mu * (D[1:, 1:] @ s)
        J[1:3, 1:3] = -mu * P_N * D[1:, 1:] - sigma * np.eye(2)
        J[1:3, 3], J[3, 1:3] = -s, s
        try:
            x = x - np.linalg.solve(J, F)
        except np.linalg.LinAlgError:
            break
    return _slip_by_angle(D, c, mu, name)


def _slip_by_angle(D: np.ndarray, c: np.ndarray, mu: float, name: str) -> np.ndarray:
    """The sliding impulse by bracketing the slip direction's angle (any coupling)."""
    def impulse(s):
        denominator = D[0, 0] - mu * D[0, 1:] @ s
        P_N = -c[0] / denominator if denominator > 0 else -1.0
        return P_N, np.concatenate([[P_N], -mu * P_N * s])

    def slip_velocity(s):
        P_N, P = impulse(s)
        return P_N, (D @ P + c)[1:]

    if c.size == 2:
        candidates = [np.array([1.0]), np.array([-1.0])]
    else:
        def misalignment(angle):  # s x u_T(s), for one angle or an array of them
            s = np.array([np.cos(np.atleast_1d(angle)), np.sin(np.atleast_1d(angle))])
            P_N = -c[0] / (D[0, 0] - mu * (D[0, 1:] @ s))
            u_T = c[1:, None] + np.outer(D[1:, 0], P_N) - mu * D[1:, 1:] @ (s * P_N)
            value = s[0] * u_T[1] - s[1] * u_T[0]
            return value if np.ndim(angle) else float(value[0])

        grid = np.linspace(0.0, 2 * np.pi, ANGLE_SAMPLES + 1)
        values = misalignment(grid)
        candidates = []
        for k in range(ANGLE_SAMPLES):
            if values[k] == 0.0:
                root = grid[k]
            elif values[k] * values[k + 1] < 0.0:
                root = brentq(misalignment, grid[k], grid[k + 1], xtol=1e-15, rtol=1e-15)
            else:
                continue
            candidates.append(np.array([np.cos(root), np.sin(root)]))
    best = None
    for s in candidates:
        P_N, u_T = slip_velocity(s)
        if P_N >= 0.0 and u_T @ s >= 0.0:
            if best is None or P_N < best[0]:  # the least normal impulse: the slip's
                best = (P_N, impulse(s)[1])
    if best is None:
        raise ContactProblemError(f"{name}: no sliding impulse satisfies Coulomb's law with "
                                  f"mu = {mu:g} (a Painleve configuration: the friction "
                                  "pulls the contact into the ground faster than it pushes)")
    return best[1]
