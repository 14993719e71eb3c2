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
  violation is returned, never a silent clamp.

Whatever the policy, each foot's status says whether the ground can give the force it gets
(:func:`feet_status`): ``pull`` where its normal force falls below its least normal force
(zero unless the scene sets ``min_normal``), ``slip`` where its tangential force exceeds ``mu``
times the normal force (the exact cone, the scene's ``mu``, 0.8 by default), each beyond
:data:`VIOLATION_TOL` of the robot's weight; else ``ok`` (``swing`` off the ground). The
least-wrench and least-effort policies ignore friction and can ask the ground to pull: their
statuses are how a user learns it.

Load sharing: a foot of weight ``w`` (:meth:`hexapod.model.model.ContactInfo.weight`) adds
``(1 / w - 1) |F l / tau_ref|^2`` to the effort objectives (``l`` the model's characteristic
length, ``tau_ref`` the default reference effort: the effort the load would cause, in the
efforts' units, so the term outweighs them as soon as ``w`` falls), and its wrench term is
divided by ``w`` in ``min-wrench``; a foot of weight zero (swing, touch-down, lift-off) carries
nothing. Forces are then Lipschitz in time, the loads shed over the whole ramp.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
from scipy.linalg import block_diag

from hexapod.algorithms.linalg import RowSplit, multiplier_null_space
from hexapod.algorithms.step_terms import terms_of
from hexapod.errors import HexapodError
from hexapod.model.infos import ContactSchedules
from hexapod.model.model import Model

#: Below this weight a foot carries nothing.
NO_LOAD = 1e-12
#: The statuses of a foot whose force the ground cannot give (:func:`feet_status`).
INFEASIBLE_STATUSES = ("slip", "pull")
#: Violation, relative to the robot's weight, above which a foot is reported as slipping or
#: pulling (round-off in the forces stays some five orders below it).
VIOLATION_TOL = 1e-7
#: A friction constraint at most this far from equality (in the robot's weight) is active.
ACTIVE_TOL = 1e-9
#: How far the friction QP's solution may leave its constraints (in the robot's weight).
PRIMAL_TOL = 1e-10


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


def foot_value_rates(policy: str, weights: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """The derivative of :func:`foot_values` along a change ``rates`` of the ``weights``
    (zero where a foot carries nothing, or, for the effort policies, where its weight is 1)."""
    carrying = weights > NO_LOAD
    safe = np.where(carrying, weights, 1.0)
    if policy == "min-wrench":
        return np.where(carrying, -0.5 * rates / safe**1.5, 0.0)
    ramping = carrying & (weights < 1.0)
    root = np.sqrt(np.where(ramping, 1.0 / safe - 1.0, 1.0))
    return np.where(ramping, -0.5 * rates / (safe**2 * root), 0.0)


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


def policy_objective(model: Model, data, q: np.ndarray, w: np.ndarray, Phi: np.ndarray,
                     Q_across, feet: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``A`` (a SciPy CSR array) and ``b`` of the policy's objective ``|A lam + b|^2`` at a
    state, from its one definition (:meth:`hexapod.algorithms.step_terms.StepTerms.objective`);
    ``Phi`` the nonzeros of ``Phi_v`` (:meth:`~hexapod.algorithms.step_terms.StepTerms.
    nonzeros`), ``feet`` as :func:`foot_values` gives them."""
    terms = terms_of(model)
    return tuple(terms.evaluate_sparse(data, "objective", q, w, Phi,
                                       terms.offset(data, q, w, Q_across), feet))


def contact_axes(model: Model) -> np.ndarray | None:
    """Each contact's axes as rows ``(t_1, t_2, n)`` (world), from the ground under it; None
    when the ground is flat (the axes are the world's). Built once per model: its ground's
    shape is built into its contacts and never changes."""
    return model.built_once(("contact axes",), _contact_axes)


def _contact_axes(model: Model) -> np.ndarray | None:
    terrains = [c.schedule.terrain for c in model.contacts]
    if all(terrain is None or terrain.flat for terrain in terrains):
        return None
    return np.array([np.eye(3) if terrain is None else terrain.axes() for terrain in terrains])


def in_contact_axes(model: Model, forces: np.ndarray) -> np.ndarray:
    """Forces on the feet ``(..., C, 3)``, world, in each contact's axes: tangential, then
    normal last (the world's own axes on flat ground).

    Parameters
    ----------
    model : Model
        A model with foot contacts.
    forces : ndarray, shape (..., C, 3)
        N, world axes.

    Returns
    -------
    ndarray, shape (..., C, 3)
        ``(F . t_1, F . t_2, F . n)`` per contact.
    """
    axes = contact_axes(model)
    forces = np.asarray(forces, dtype=float)
    return forces if axes is None else np.einsum("cij,...cj->...ci", axes, forces)


def feet_status(model: Model, times: np.ndarray, forces: np.ndarray) -> np.ndarray:
    """Each foot's status at each sample, from the ground's forces on the feet.

    Parameters
    ----------
    model : Model
        A model with foot contacts (its ``ground`` gives ``mu`` and ``min_normal``).
    times : ndarray, shape (N,)
        s.
    forces : ndarray, shape (N, C, 3)
        The ground's force on each foot, N, world axes (the normal and tangential parts are
        taken in each contact's axes, :func:`in_contact_axes`).

    Returns
    -------
    ndarray, shape (N, C), of str
        ``swing`` (not in stance), ``pull`` (normal force below the foot's least normal force,
        ``min_normal`` times its load-sharing weight), ``slip`` (tangential force above ``mu``
        times the normal force), else ``ok``; each beyond :data:`VIOLATION_TOL` of the
        robot's weight.
    """
    times = np.atleast_1d(np.asarray(times, dtype=float))
    forces = in_contact_axes(model, np.asarray(forces, dtype=float).reshape(
        times.size, len(model.contacts), 3))
    stance = np.array([np.asarray(c.in_stance(times), dtype=bool) for c in model.contacts])
    weights = np.array([np.asarray(c.weight(times), dtype=float) for c in model.contacts])
    stance, weights = stance.reshape(-1, times.size).T, sharing_weights(weights, stance).T
    ground = model.ground
    tolerance = VIOLATION_TOL * (robot_weight(model) or 1.0)
    normal, tangential = forces[..., 2], np.hypot(forces[..., 0], forces[..., 1])
    status = np.where(stance, "ok", "swing").astype("<U5")
    status[stance & (tangential > ground.mu * np.maximum(normal, 0.0) + tolerance)] = "slip"
    status[stance & (normal < weights * ground.min_normal - tolerance)] = "pull"
    return status


def share_ground_forces(model: Model, data, t: float, q: np.ndarray, Phi_v: np.ndarray,
                        Q_across: np.ndarray | None, split: RowSplit, lam: np.ndarray, *,
                        status: bool = True) -> tuple[np.ndarray, tuple[str, ...] | None]:
    """The multipliers chosen by the scene's ground-force policy among ``lam + N z`` (columns
    of ``lam`` together, but for friction), and each contact's status (:func:`feet_status`;
    None when ``status`` is false)."""
    chosen = ground_policy(model, data, t, q, terms_of(model).nonzeros(Phi_v), Q_across, lam,
                           multiplier_null_space(split, model.n_c))
    if not status:
        return chosen, None
    feet = feet_status(model, np.array([t]), ground_reactions(model, chosen)[None])[0]
    return chosen, tuple(feet.tolist())


def ground_policy(model: Model, data, t: float, q: np.ndarray, Phi: np.ndarray,
                  Q_across: np.ndarray | None, lam: np.ndarray, N: np.ndarray) -> np.ndarray:
    """The multipliers among ``lam + N z`` of least policy objective at ``(t, q)``: ``N``
    (n_c x m) spans the multipliers that change no constraint force, ``Phi`` holds the
    nonzeros of ``Phi_v``. Columns of ``lam`` are chosen together (linear policies: not
    friction)."""
    if N.shape[1] == 0:
        return lam
    problem = _PolicyProblem(model, data, t, q, Phi, Q_across, lam, N)
    if problem.NK.shape[1] == 0:  # the feet that carry nothing take up all the freedom
        return problem.base
    if model.ground.policy != "friction":
        return problem.base + problem.NK @ np.linalg.lstsq(problem.AK, -problem.r,
                                                           rcond=None)[0]
    return problem.base + problem.NK @ problem.friction()[0]


def friction_tangents(model: Model, data, t: float, q: np.ndarray, Phi: np.ndarray,
                      Q_across: np.ndarray | None, lam: np.ndarray, N: np.ndarray,
                      along: np.ndarray, along_mu: np.ndarray | None = None
                      ) -> tuple[np.ndarray, np.ndarray, frozenset]:
    """The friction policy's multipliers (as :func:`ground_policy` chooses them among ``lam +
    N z``) and their derivatives along the columns of ``along`` (particular multipliers of
    the derivatives of the right-hand side, without forces across joints) and of the friction
    coefficient (``along_mu``: its derivative per column, none by default), on the active set
    of that solution: the constraints held at equality stay so, the others stay slack. The
    QP's solution is piecewise linear in its data: where the active set changes, these are
    one-sided derivatives. Also the active set, as (contact, constraint) pairs.

    Raises
    ------
    HexapodError
        The exact cone (``faces = 0``), or no admissible forces at ``t`` (the relaxed
        problem's solution has no derivative here).
    """
    problem, solution = _friction_solution(model, data, t, q, Phi, Q_across, lam, N)
    if problem is None:
        return lam, along, frozenset()
    base_along = problem.shift(along)
    if solution is None:
        return problem.base, base_along, frozenset()
    y, active, C, slopes = solution
    loaded = problem.loaded
    rows = np.concatenate([model.contacts[k].rows for k in loaded]) if loaded \
        else np.zeros(0, dtype=int)
    H, n = problem.AK.T @ problem.AK, problem.NK.shape[1]
    C_J = C[active]
    kkt = np.block([[H, C_J.T], [C_J, np.zeros((active.size, active.size))]])
    dc_dF0, dc_dmu = slopes
    moved = dc_dF0[active] @ base_along[rows]  # F0 = -base on the loaded rows
    if along_mu is not None:
        moved = moved - np.outer(dc_dmu[active], along_mu)
    rhs = np.vstack([-problem.AK.T @ (problem.A @ base_along), moved])
    y_along = np.linalg.lstsq(kkt, rhs, rcond=None)[0][:n]
    per_foot = 1 + model.ground.faces  # the least normal force, then the pyramid's faces
    labels = frozenset((loaded[j // per_foot], j % per_foot) for j in active)
    return problem.base + problem.NK @ y, base_along + problem.NK @ y_along, labels


def friction_active_set(model: Model, data, t: float, q: np.ndarray, Phi: np.ndarray,
                        Q_across: np.ndarray | None, lam: np.ndarray, N: np.ndarray) -> tuple:
    """The friction policy's multipliers (among ``lam + N z``, as :func:`friction_tangents`)
    and its active set as constraints on the multipliers: ``D`` (active x n_c, the
    constraints' Jacobian over ``scale``, linear in the feet's forces ``F = -lam``), the rows
    of ``D`` that hold a least normal force with their contact (``(row, contact)``: there
    ``D lam`` is the contact's weight times ``min_normal`` over ``scale``), ``scale``, the
    feet's weights and the labels ((contact, constraint) pairs).

    Raises
    ------
    HexapodError
        As :func:`friction_tangents`.
    """
    scale = robot_weight(model) or 1.0  # the constraints' forces are in the robot's weight
    problem, solution = _friction_solution(model, data, t, q, Phi, Q_across, lam, N)
    if problem is None or solution is None:
        weights = _policy_weights(model, t) if problem is None else problem.weights
        return (lam if problem is None else problem.base), np.zeros((0, model.n_c)), [], \
            scale, weights, frozenset()
    y, active, _, (dc_dF0, _) = solution
    per_foot = 1 + model.ground.faces  # the least normal force, then the pyramid's faces
    loaded = problem.loaded
    D = np.zeros((active.size, model.n_c))
    minimum_rows = []
    for i, j in enumerate(active):
        k = loaded[j // per_foot]
        D[i, model.contacts[k].rows] = -dc_dF0[j, 3 * (j // per_foot):3 * (j // per_foot) + 3]
        if j % per_foot == 0:
            minimum_rows.append((i, k))
    labels = frozenset((loaded[j // per_foot], j % per_foot) for j in active)
    return problem.base + problem.NK @ y, D, minimum_rows, scale, problem.weights, labels


def _friction_solution(model: Model, data, t: float, q, Phi, Q_across, lam, N) -> tuple:
    """The friction policy's problem at a state (None where the multipliers have no freedom)
    and its solution: ``y``, the active constraints, their Jacobians in ``y`` and in ``(F0,
    mu)`` (None where no multipliers are free once the idle feet are unloaded).

    Raises
    ------
    HexapodError
        The exact cone (``faces = 0``), or no admissible forces at ``t``.
    """
    if model.ground.faces == 0:
        raise HexapodError(f"model '{model.name}': derivatives of the friction policy on the "
                           "exact cone are not available; use a pyramid (faces = 4 or more)")
    if N.shape[1] == 0:
        return None, None
    problem = _PolicyProblem(model, data, t, q, Phi, Q_across, lam, N)
    if problem.NK.shape[1] == 0:
        return problem, None
    y, active, C, slopes = problem.friction()
    if active is None:
        raise HexapodError(f"model '{model.name}': at t = {t:.6g} s no ground forces are "
                           "inside the friction cones (a foot slips): the friction policy's "
                           "derivative is not defined there")
    return problem, (y, active, C, slopes)


def _policy_weights(model: Model, t: float) -> np.ndarray:
    """The feet's weights in the policy at ``t`` (:func:`sharing_weights` of their
    load-sharing weights), all feet in one pass (a simulation asks at every saved state)."""
    schedules = model.built_once(("contact schedules",), lambda m: ContactSchedules(m.contacts))
    stance, weights = schedules(float(t))
    return sharing_weights(weights, stance)


class _PolicyProblem:
    """The policy's problem at a state: the multipliers ``base + NK y`` that keep the feet
    of weight zero unloaded, and the objective ``|A (base + NK y) + b|^2 = |AK y + r|^2``."""

    def __init__(self, model: Model, data, t: float, q, Phi, Q_across, lam, N):
        self.model, self.N = model, N
        self.weights = weights = _policy_weights(model, t)
        self.loaded = [k for k, w in enumerate(weights) if w > NO_LOAD]
        # feet of weight zero carry nothing: lam + N z = 0 on their rows
        idle = [c.rows for c, w in zip(model.contacts, weights, strict=True) if w <= NO_LOAD]
        self.idle_rows = np.concatenate(idle) if idle else np.zeros(0, dtype=int)
        self.unload, K = (_affine_solutions(N[self.idle_rows]) if idle
                          else (None, np.eye(N.shape[1])))
        self.base = self.shift(lam)
        self.NK = _orthonormal(N @ K)  # the same multipliers, in directions a QP handles well
        # the laws matter only where a design parameter moves a joint's frame (zero there)
        w = data.w if data is not None and data.w is not None else np.zeros(model.n_w)
        self.A, b = policy_objective(model, data, q, w, Phi, Q_across,
                                     foot_values(model.ground.policy, weights))
        base = self.base
        self.AK, self.r = self.A @ self.NK, self.A @ base + b.reshape((-1,) + (1,) *
                                                                      (base.ndim - 1))

    def shift(self, lam: np.ndarray) -> np.ndarray:
        """``lam + N z0``: the multipliers ``lam`` moved to unload the feet of weight zero
        (linear in ``lam``; its columns together)."""
        if self.unload is None:
            return lam
        return lam - self.N @ (self.unload @ lam[self.idle_rows])

    def friction(self):
        """:func:`_friction` on this problem."""
        return _friction(self.model, self.weights, self.base, self.NK, self.AK, self.r)


def _orthonormal(B: np.ndarray) -> np.ndarray:
    """An orthonormal basis of the columns of ``B`` (the null space of ``Phi_v^T`` comes scaled
    by the rows' norms, poorly conditioned for an active-set solver)."""
    if B.shape[1] == 0:
        return B
    U, s, _ = np.linalg.svd(B, full_matrices=False)
    return U[:, :int(np.sum(s > s[0] * 1e-12))]


def _affine_solutions(E: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``P, K`` with ``E (P e + K y) = e`` for every ``y`` and every ``e`` (least squares when
    inconsistent): ``P`` the pseudo-inverse of ``E``, ``K`` spanning its null space."""
    U, s, Vt = np.linalg.svd(E, full_matrices=True)
    rank = int(np.sum(s > s.max(initial=0.0) * 1e-12)) if s.size else 0
    return Vt[:rank].T @ (U[:, :rank].T / s[:rank, None]), Vt[rank:].T


# ------------------------------------------------------------------ the friction policy

_SOLVERS: dict = {}


def _friction(model: Model, weights, base, NK, AK, r):
    """``y`` of least ``|AK y + r|^2`` with every loaded foot's force ``F = F0 + G y`` inside
    its cone and above its least normal force (of least violation where none is), and at that
    ``y`` the constraints held at equality (indices), the constraints' Jacobians with respect
    to ``y`` and to ``(F0, mu)``; None for these when no ``y`` is admissible."""
    ground = model.ground
    loaded = [k for k, w in enumerate(weights) if w > NO_LOAD]
    axes = contact_axes(model)  # the cones are about each ground's normal
    turn = (lambda k, F: F) if axes is None else (lambda k, F: axes[k] @ F)
    F0 = {k: turn(k, -base[model.contacts[k].rows]) for k in loaded}
    G = {k: turn(k, -NK[model.contacts[k].rows]) for k in loaded}
    n = NK.shape[1]
    H = AK.T @ AK
    g = AK.T @ r
    reference = robot_weight(model) or 1.0  # the forces' scale
    y, active, dc_dy, slopes = _solve_cone(ground, loaded, weights, F0, G, H, g, n, reference)
    if slopes is not None and axes is not None and loaded:  # back to world axes
        slopes = (slopes[0] @ block_diag(*[axes[k] for k in loaded]), slopes[1])
    return y, active, dc_dy, slopes


def _solve_cone(ground, loaded, weights, F0, G, H, g, n, reference):
    """The constrained least-effort ``y``; when no ``y`` is admissible, the one of least
    violation (slacks on the normal and tangential conditions). Returns ``y``, and for the
    strict problem the active constraints and the constraints' Jacobians (see
    :func:`_friction`)."""
    key = (ground.faces, n, len(loaded))
    if key not in _SOLVERS:
        _SOLVERS[key] = _build_solver(ground.faces, n, len(loaded))
    solver, relaxed, constraints = _SOLVERS[key]
    mu = ground.mu
    F0s = np.concatenate([F0[k] for k in loaded]) if loaded else np.zeros(0)
    Gs = np.vstack([G[k] for k in loaded]) if loaded else np.zeros((0, n))
    minimum = np.array([weights[k] * ground.min_normal for k in loaded])
    scale = reference  # forces in units of the robot's weight keep the solvers well scaled
    params = [H, g, F0s / scale, Gs / scale, minimum / scale, mu]
    y, ok = solver(*params)
    if not ok:
        y, _ = relaxed(*params)
        return y, None, None, None
    c, dc_dy, dc_dF0, dc_dmu = constraints(y, *params)
    active = np.flatnonzero(c <= ACTIVE_TOL)
    return y, active, dc_dy, (dc_dF0 / scale, dc_dmu)


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
    values = ca.Function("ground_constraints", [y, parameters],
                         [strict_g, ca.jacobian(strict_g, y), ca.jacobian(strict_g, F0),
                          ca.jacobian(strict_g, mu)])
    relaxed_g = (ca.vertcat(*[c + s for c, s in constraints]) if constraints
                 else ca.SX(0, 1))
    penalty = 1e6 * ca.sumsqr(slack) + ca.sum1(slack) * 1e3
    quiet = {"print_time": False}
    if faces:  # DAQP's primal tolerance (1e-6 by default) in forces over the robot's weight:
        # below the statuses' VIOLATION_TOL, so that a solved foot is never called slipping
        options = {**quiet, "error_on_fail": False, "daqp": {"primal_tol": PRIMAL_TOL}}
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

    def constraint_values(y_, *args):
        c, dc_dy, dc_dF0, dc_dmu = values(y_, pack(*args))
        return (np.asarray(c).ravel(), np.asarray(dc_dy), np.asarray(dc_dF0),
                np.asarray(dc_dmu).ravel())

    def run_relaxed(*args):
        x0 = np.zeros(n + 2 * feet)
        out = loose(x0=x0, p=pack(*args), lbg=0.0, ubg=np.inf,
                    lbx=np.concatenate([np.full(n, -np.inf), np.zeros(2 * feet)]),
                    ubx=np.inf)
        return np.asarray(out["x"]).ravel()[:n], bool(loose.stats()["success"])

    return run_strict, run_relaxed, constraint_values
