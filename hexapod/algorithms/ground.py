"""Ground forces of feet in contact: the reactions, and the policy that shares them.

With three or more feet down, the contact rows are redundant and the ground forces statically
indeterminate: every multiplier vector ``lam + N z`` (``N`` spanning the null space of
``Phi_v^T``) balances every body. The scene's :class:`~hexapod.scene.contacts.GroundForces`
chooses ``z``:

* ``min-wrench``: the least ``sum_k |F_k|^2 + |T_k / l|^2`` over every joint's wrench (the
  engine's unit-free default), a contact's term divided by the foot's weight;
* ``min-effort``: the least ``sum_j (tau_j / tau_ref_j)^2`` over the actuator efforts;
* ``friction``: the same least effort subject to ``F_n >= w F_min`` and ``|F_t| <= mu F_n`` for
  every foot in stance (a pyramid of ``faces`` faces inscribed in the cone, by DAQP, or the
  exact cone, by IPOPT, both through CasADi). Where no force satisfies them all, the least
  violation is returned and the feet that would slip or pull are named (``data.ground_status``),
  never a silent clamp.

Load sharing: a foot of weight ``w`` (:meth:`hexapod.model.model.ContactInfo.weight`) adds
``(1 / w - 1) |F / (m g)|^2`` to the effort objectives (``m g`` the robot's weight), and its
wrench term is divided by ``w`` in ``min-wrench``; a foot of weight zero (swing, touch-down,
lift-off) carries nothing. Forces are then continuous in time.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod.algorithms.linalg import RowSplit, multiplier_null_space
from hexapod.algorithms.step_terms import terms_of
from hexapod.model.model import Model

#: Below this weight a foot carries nothing.
NO_LOAD = 1e-12
#: Relative violation above which the friction policy reports a foot as slipping or pulling.
VIOLATION_TOL = 1e-7


def contact_weights(model: Model, t: float) -> np.ndarray:
    """Each contact's weight in the ground-force policy at ``t`` (0 in swing)."""
    return np.array([float(c.weight(t)) for c in model.contacts])


def ground_reactions(model: Model, lam: np.ndarray) -> np.ndarray:
    """The ground's force on each foot (n_contacts, 3), N, world axes: ``-lam`` of the
    contact's rows (their Jacobian on the foot point is the identity in stance).

    Parameters
    ----------
    model : Model
    lam : ndarray, shape (n_c,)
        Multipliers (e.g. ``data.lam`` after forward or inverse dynamics).

    Returns
    -------
    ndarray, shape (n_contacts, 3)
        N, world axes, in the order of ``model.contacts``; zero in swing.
    """
    return np.array([-lam[c.rows] for c in model.contacts]).reshape(-1, 3)


def robot_weight(model: Model) -> float:
    """``m |g|`` (N): the total mass times the magnitude of gravity (0 without gravity)."""
    return model.total_mass * float(np.linalg.norm(model.gravity))


def sharing_weights(weights: np.ndarray, stance: np.ndarray) -> np.ndarray:
    """The feet's weights in the policy (contacts first; samples along a second axis, if
    any): their load-sharing weights, except where every foot down is at touch-down or
    lift-off (a tripod of duty 1/2 at its switch): the load then passes in an instant, and the
    feet down share it equally."""
    weights = np.array(weights, dtype=float)
    unloaded = ~np.any(weights > NO_LOAD, axis=0)
    weights[..., unloaded] = np.asarray(stance, dtype=float)[..., unloaded]
    return weights


def foot_values(policy: str, weights: np.ndarray) -> np.ndarray:
    """The ``feet`` input of the policy's objective for the feet's weights ``w``: for
    ``min-wrench`` the factor of each foot's wrench block, ``1 / sqrt(w)`` (1 where the foot
    carries nothing: its force is held at zero); for the effort policies the factor of its
    load-sharing term, ``sqrt(1 / w - 1)`` (0 where ``w`` is 1 or the foot carries nothing)."""
    safe = np.where(weights > NO_LOAD, weights, 1.0)
    if policy == "min-wrench":
        return np.where(weights > NO_LOAD, 1.0 / np.sqrt(safe), 1.0)
    return np.where((weights > NO_LOAD) & (weights < 1.0),
                    np.sqrt(np.maximum(1.0 / safe - 1.0, 0.0)), 0.0)


def policy_objective(model: Model, data, q: np.ndarray, Phi_v, Q_across,
                     feet: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``A, b`` of the policy's objective ``|A lam + b|^2`` at a state, from its one
    definition (:meth:`hexapod.algorithms.step_terms.StepTerms.objective`); ``feet`` as
    :func:`foot_values` gives them."""
    terms = terms_of(model)
    return tuple(terms.evaluate(data, "objective", q, terms.nonzeros(Phi_v),
                                terms.offset(data, q, Q_across), feet))


def share_ground_forces(model: Model, data, t: float, q: np.ndarray, Phi_v: np.ndarray,
                        Q_across: np.ndarray | None, split: RowSplit,
                        lam: np.ndarray) -> tuple[np.ndarray, tuple[str, ...]]:
    """The multipliers chosen by the scene's ground-force policy among ``lam + N z``, and each
    contact's status (``swing``, ``ok``, ``slip``, ``pull``)."""
    stance = np.array([bool(c.in_stance(t)) for c in model.contacts])
    status = ["ok" if down else "swing" for down in stance]
    weights = sharing_weights(contact_weights(model, t), stance)
    N = multiplier_null_space(split, model.n_c)
    if N.shape[1] == 0:
        return lam, tuple(status)
    # feet of weight zero carry nothing: lam + N z = 0 on their rows
    idle = [c.rows for c, w in zip(model.contacts, weights, strict=True) if w <= NO_LOAD]
    if idle:
        rows = np.concatenate(idle)
        z0, K = _affine_solutions(N[rows], -lam[rows])
    else:
        z0, K = np.zeros(N.shape[1]), np.eye(N.shape[1])
    base = lam + N @ z0  # lam + N (z0 + K y)
    NK = _orthonormal(N @ K)  # the same multipliers, in directions the QP solvers handle well
    A, b = policy_objective(model, data, q, Phi_v, Q_across,
                            foot_values(model.ground.policy, weights))
    AK, r = A @ NK, A @ base + b
    policy = model.ground.policy
    if NK.shape[1] == 0:  # the feet that carry nothing take up all the freedom
        return base, tuple(status)
    if policy != "friction":
        y = np.linalg.lstsq(AK, -r, rcond=None)[0]
        return base + NK @ y, tuple(status)
    y, flags = _friction(model, weights, base, NK, AK, r)
    for k, flag in enumerate(flags):
        if flag:
            status[k] = flag
    return base + NK @ y, tuple(status)


def _orthonormal(B: np.ndarray) -> np.ndarray:
    """An orthonormal basis of the columns of ``B`` (the null space of ``Phi_v^T`` comes scaled
    by the rows' norms, poorly conditioned for an active-set solver)."""
    if B.shape[1] == 0:
        return B
    U, s, _ = np.linalg.svd(B, full_matrices=False)
    return U[:, :int(np.sum(s > s[0] * 1e-12))]


def _affine_solutions(E: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``z0, K`` with ``E (z0 + K y) = e`` for every ``y`` (least squares when inconsistent)."""
    U, s, Vt = np.linalg.svd(E, full_matrices=True)
    rank = int(np.sum(s > s.max(initial=0.0) * 1e-12)) if s.size else 0
    z0 = Vt[:rank].T @ ((U[:, :rank].T @ e) / s[:rank])
    return z0, Vt[rank:].T


# ------------------------------------------------------------------ the friction policy

_SOLVERS: dict = {}


def _friction(model: Model, weights, base, NK, AK, r):
    """``y`` of least ``|AK y + r|^2`` with every loaded foot's force ``F = F0 + G y`` inside
    its cone and above its least normal force; flags per contact."""
    ground = model.ground
    loaded = [k for k, w in enumerate(weights) if w > NO_LOAD]
    F0 = {k: -base[model.contacts[k].rows] for k in loaded}
    G = {k: -NK[model.contacts[k].rows] for k in loaded}
    n = NK.shape[1]
    H = AK.T @ AK
    g = AK.T @ r
    reference = robot_weight(model) or 1.0  # the forces' scale
    y, violation = _solve_cone(ground, loaded, weights, F0, G, H, g, n, reference)
    flags = [""] * len(model.contacts)
    for k in loaded:
        normal, tangential = violation[k]
        if normal > VIOLATION_TOL * reference:
            flags[k] = "pull"
        elif tangential > VIOLATION_TOL * reference:
            flags[k] = "slip"
    return y, flags


def _solve_cone(ground, loaded, weights, F0, G, H, g, n, reference):
    """The constrained least-effort ``y``; when no ``y`` is admissible, the one of least
    violation (normal and tangential slacks per foot, in N), and the violations."""
    key = (ground.faces, n, len(loaded))
    if key not in _SOLVERS:
        _SOLVERS[key] = _build_solver(ground.faces, n, len(loaded))
    solver, relaxed = _SOLVERS[key]
    mu = ground.mu
    F0s = np.concatenate([F0[k] for k in loaded]) if loaded else np.zeros(0)
    Gs = np.vstack([G[k] for k in loaded]) if loaded else np.zeros((0, n))
    minimum = np.array([weights[k] * ground.min_normal for k in loaded])
    scale = reference  # forces in units of the robot's weight keep the solvers well scaled
    params = [H, g, F0s / scale, Gs / scale, minimum / scale, mu]
    y, ok = solver(*params)
    if not ok:
        y, _ = relaxed(*params)
    F = {k: F0[k] + G[k] @ y for k in loaded}
    violation = {}
    for i, k in enumerate(loaded):
        normal = max(0.0, minimum[i] - F[k][2])
        limit = mu * (np.cos(np.pi / ground.faces) if ground.faces else 1.0) * F[k][2]
        tangential = max(0.0, _tangential(F[k], ground.faces) - max(limit, 0.0))
        violation[k] = (normal, tangential)
    return y, violation


def _tangential(F, faces) -> float:
    """The tangential force as the cone measures it: the largest face projection of the
    pyramid, or the norm for the exact cone."""
    if not faces:
        return float(np.hypot(F[0], F[1]))
    angles = 2 * np.pi * (np.arange(faces) + 0.5) / faces
    return float(np.max(np.cos(angles) * F[0] + np.sin(angles) * F[1]))


def _build_solver(faces: int, n: int, feet: int):
    """Solvers for one problem shape: ``(H, g, F0, G, minimum, mu) -> (y, ok)``, the strict
    problem and the relaxed one (slacks on every foot's normal and tangential conditions,
    their squares weighted above everything else)."""
    H, g = ca.SX.sym("H", n, n), ca.SX.sym("g", n)
    F0, G = ca.SX.sym("F0", 3 * feet), ca.SX.sym("G", 3 * feet, n)
    minimum, mu = ca.SX.sym("minimum", feet), ca.SX.sym("mu")
    y = ca.SX.sym("y", n)
    slack = ca.SX.sym("s", 2 * feet)
    parameters = ca.vertcat(ca.vec(H), g, F0, ca.vec(G), minimum, mu)
    F = F0 + ca.mtimes(G, y)
    constraints = []
    for i in range(feet):
        fx, fy, fz = F[3 * i], F[3 * i + 1], F[3 * i + 2]
        sn, st = slack[2 * i], slack[2 * i + 1]
        constraints.append((fz - minimum[i], sn))
        if faces:
            limit = mu * np.cos(np.pi / faces) * fz
            for k in range(faces):
                angle = 2 * np.pi * (k + 0.5) / faces
                constraints.append((limit - (np.cos(angle) * fx + np.sin(angle) * fy), st))
        else:
            constraints.append((mu**2 * fz**2 - fx**2 - fy**2, st))
            constraints.append((fz, sn))
    objective = 0.5 * ca.mtimes([y.T, H, y]) + ca.dot(g, y)
    strict_g = ca.vertcat(*[c for c, _ in constraints]) if constraints else ca.SX(0, 1)
    relaxed_g = (ca.vertcat(*[c + s for c, s in constraints]) if constraints
                 else ca.SX(0, 1))
    penalty = 1e6 * ca.sumsqr(slack) + ca.sum1(slack) * 1e3
    quiet = {"print_time": False}
    if faces:
        options = {**quiet, "error_on_fail": False}
        strict = ca.qpsol("ground_strict", "daqp",
                          {"x": y, "p": parameters, "f": objective, "g": strict_g}, options)
        loose = ca.qpsol("ground_relaxed", "daqp",
                         {"x": ca.vertcat(y, slack), "p": parameters,
                          "f": objective + penalty, "g": relaxed_g}, options)
    else:
        options = {**quiet, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": 1e-12,
                   "error_on_fail": False}
        strict = ca.nlpsol("ground_strict", "ipopt",
                           {"x": y, "p": parameters, "f": objective, "g": strict_g}, options)
        loose = ca.nlpsol("ground_relaxed", "ipopt",
                          {"x": ca.vertcat(y, slack), "p": parameters,
                           "f": objective + penalty, "g": relaxed_g}, options)

    def pack(H_, g_, F0_, G_, minimum_, mu_):
        return np.concatenate([H_.ravel(order="F"), g_, F0_, G_.ravel(order="F"), minimum_,
                               [mu_]])

    def run_strict(*args):
        out = strict(x0=np.zeros(n), p=pack(*args), lbg=0.0, ubg=np.inf)
        return np.asarray(out["x"]).ravel(), bool(strict.stats()["success"])

    def run_relaxed(*args):
        x0 = np.zeros(n + 2 * feet)
        out = loose(x0=x0, p=pack(*args), lbg=0.0, ubg=np.inf,
                    lbx=np.concatenate([np.full(n, -np.inf), np.zeros(2 * feet)]),
                    ubx=np.inf)
        return np.asarray(out["x"]).ravel()[:n], bool(loose.stats()["success"])

    return run_strict, run_relaxed
