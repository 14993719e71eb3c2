"""The friction policy's multipliers differentiated along a change that moves the motion (a
segment's length, the gait's step height or duty factor): the twin's stage of
:mod:`hexapod.algorithms.law_tangents` when the scene shares its ground forces by friction.

On the active set of its solution (the cone's faces and least normal forces it holds at
equality) the friction policy's multipliers solve a least-squares problem with equality
constraints, in the multipliers themselves::

    min |A lam + b|^2   s.t.   Phi_v^T lam = Q - M v_dot,   E lam = 0,   D_J lam = c_J

(``E``: the rows of the feet that carry nothing; ``D_J``: the active constraints, linear in
the feet's forces; ``c_J``: the least normal forces, which follow the feet's weights). Every
matrix there is smooth in the state and the laws, so along a change ``(dq, dv, dv_dot, dw,
dfeet)`` its KKT system differentiated gives ``dlam``: the implicit function theorem on the
QP's active set, where :func:`hexapod.algorithms.ground.friction_tangents` takes the
matrices as fixed (masses and inertias move the right-hand side only). The matrices'
derivatives are their CasADi Functions' forward derivatives (the policy's objective, the
constraints' Jacobian, the applied forces): nothing written twice. Where the active set
changes between samples these are one-sided derivatives, and the samples are named.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod.algorithms.ground import (
    NO_LOAD,
    foot_value_rates,
    foot_values,
    friction_active_set,
)
from hexapod.algorithms.kinematics import state_split
from hexapod.algorithms.linalg import multiplier_null_space, solve_saddle
from hexapod.algorithms.saddle import dynamics_terms
from hexapod.algorithms.step_terms import terms_of
from hexapod.errors import HexapodError

__all__ = ["friction_motion_tangents"]


def friction_motion_tangents(model, data, t: float, x: np.ndarray, laws: tuple,
                             dx: np.ndarray, dlaws: tuple, dweights: np.ndarray) -> tuple:
    """The friction policy's multipliers at the sample ``t`` (state ``x = [q; v; v_dot]``,
    the laws' values, rates and accelerations ``laws``) and their derivatives along the
    columns of ``dx`` (n_x x P), ``dlaws`` (three n_w x P) and ``dweights`` (the feet's
    load-sharing weights', C x P); also the joint wrenches' (report frames) and the frames'
    derivatives, and the active set.

    Returns
    -------
    lam : ndarray (n_c,)
    dlam : ndarray (n_c, P)
    dwrench : ndarray (P, J, 6)
    frames, dframes : ndarray (J, 9) and (P, J, 9)
    active : frozenset

    Raises
    ------
    HexapodError
        Forces across joints (springs between bodies), whose wrenches the policy weighs: not
        derived along a moving motion; the exact cone, or no admissible forces at ``t``.
    """
    if model.Q_across is not None:
        raise HexapodError(f"model '{model.name}': the friction policy's derivative along a "
                           "moving motion with forces across joints is not derived")
    n_q, n_v = model.n_q, model.n_v
    q, v = x[:n_q], x[n_q:n_q + n_v]
    w, wd, wdd = laws
    terms = terms_of(model)
    Phi_v, gamma, Q = dynamics_terms(model, {"q": q, "v": v, "w": w, "wd": wd, "wdd": wdd},
                                     data)
    Phi_v = _dense(Phi_v)
    split = state_split(model, data, q, w, Phi_v)
    priority, _ = model.rank_order(w)
    primal = solve_saddle(model.mass_inv_sqrt, Phi_v, Q, gamma, priority,
                          model.rank_tolerance, split=split).lam
    Phi_nz = terms.nonzeros(Phi_v)
    lam, D, minimum_rows, scale, weights, active = friction_active_set(
        model, data, t, q, Phi_nz, None, primal, multiplier_null_space(split, model.n_c))
    A, b = terms.objective(q, w, Phi_nz, np.zeros(6 * terms.owners),
                           foot_values(model.ground.policy, weights))
    A, b = A.full(), b.full().reshape(-1)
    idle = np.concatenate([c.rows for c, wk in zip(model.contacts, weights, strict=True)
                           if wk <= NO_LOAD] or [np.zeros(0, dtype=int)])
    E = np.eye(model.n_c)[idle]
    Psi = np.hstack([Phi_v, E.T, D.T])
    residual = A @ lam + b
    multipliers = np.linalg.lstsq(Psi, -(A.T @ residual), rcond=None)[0]
    nu = multipliers[:n_v]
    H = A.T @ A
    size = Psi.shape[1]
    kkt = np.block([[H, Psi], [Psi.T, np.zeros((size, size))]])
    count = dx.shape[1]
    dPhi = _forward(model, "Phi_v", [q, w], dx[:n_q], dlaws[0])
    dQ = _forward(model, "Q", [q, v, w], dx[:n_q], dx[n_q:n_q + n_v], dlaws[0])[:, :, 0].T
    dfeet = foot_value_rates(model.ground.policy, weights[:, None], dweights)
    objective = _forwards(model, "objective", count)
    dPhi_nz = np.array([terms.nonzeros(dPhi[p]) for p in range(count)]).T
    dA, db = objective(q, w, Phi_nz, np.zeros(6 * terms.owners), foot_values(
        model.ground.policy, weights), A, b, dx[:n_q], dlaws[0], dPhi_nz,
        np.zeros((6 * terms.owners, count)), dfeet)
    dA = _columns(dA, A.shape, count)
    db = ca.DM(db).full().reshape(-1, count, order="F")
    rhs = np.zeros((kkt.shape[0], count))
    for p in range(count):
        top = -(dA[p].T @ residual + A.T @ (dA[p] @ lam + db[:, p])) - dPhi[p] @ nu
        force = dQ[:, p] - model.mass.dense() @ dx[n_q + n_v:, p] - dPhi[p].T @ lam
        moved = np.zeros(D.shape[0])  # the least normal forces follow the feet's weights
        for row, foot in minimum_rows:
            moved[row] = dweights[foot, p] * model.ground.min_normal / scale
        rhs[:, p] = np.concatenate([top, force, np.zeros(idle.size), moved])
    dlam = np.linalg.lstsq(kkt, rhs, rcond=None)[0][:model.n_c]
    B, frames = (np.asarray(x) for x in terms.report_map(q, w, Phi_nz))
    dB, dF = _forwards(model, "report_map", count)(q, w, Phi_nz, B, frames, dx[:n_q],
                                                     dlaws[0], dPhi_nz)
    dB = _columns(dB, B.shape, count)
    dF = np.asarray(dF).reshape(9, len(model.joints), count, order="F")
    joints = len(model.joints)
    dwrench = np.array([(dB[p] @ lam + B @ dlam[:, p]).reshape(joints, 6)
                        for p in range(count)])
    return (lam, dlam, dwrench, frames.reshape(9, joints, order="F").T,
            dF.transpose(2, 1, 0), active)


def _dense(matrix) -> np.ndarray:
    return np.asarray(matrix.toarray() if hasattr(matrix, "toarray") else matrix, dtype=float)


def _columns(derivative, shape, count) -> list[np.ndarray]:
    """The ``count`` matrices of ``shape`` a forward Function returns side by side."""
    full = ca.DM(derivative).full()
    return [full[:, p * shape[1]:(p + 1) * shape[1]] for p in range(count)]


def _forwards(model, name: str, count: int) -> ca.Function:
    """The forward derivative in ``count`` directions of the model's Function ``name`` (the
    step terms' ``objective`` and ``report_map``, else the model's own), built once."""
    def build(m):
        terms = terms_of(m)
        function = getattr(terms, name) if name in ("objective", "report_map") else \
            getattr(m, name)
        return function, function.forward(count)

    return model.built_once(("friction motion", name, count), build)[1]


def _forward(model, name: str, inputs: list, *seeds) -> np.ndarray:
    """The model's Function ``name``'s one output's forward derivatives along the columns of
    ``seeds`` (one per input): (P, rows, columns)."""
    count = seeds[0].shape[1]
    nominal = getattr(model, name)(*inputs)
    derivative = _forwards(model, name, count)(*inputs, nominal, *seeds)
    return np.array(_columns(derivative, nominal.shape, count))
