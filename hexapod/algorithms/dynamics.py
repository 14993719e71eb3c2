"""Forward dynamics at a state: accelerations and multipliers from the saddle-point system

    [[M, Phi_v^T], [Phi_v, 0]] [v_dot; lambda] = [Q; gamma]

solved on the equilibrated constraint matrix (:mod:`hexapod.algorithms.linalg`). Accelerations are
always unique. When rows are redundant their multipliers follow the unit-free default policy: among
all multipliers that satisfy the equations, those minimising ``sum_k |F_k|^2 + |T_k / l|^2`` over
the joint wrenches, with ``l = model.characteristic_length``; the redundant rows are named.
"""

from __future__ import annotations

import numpy as np

from hexapod.algorithms.contact_frames import refuse_contacts
from hexapod.algorithms.ground import friction_tangents, share_ground_forces
from hexapod.algorithms.kinematics import state_split
from hexapod.algorithms.liaison import policy_map
from hexapod.algorithms.linalg import (
    RowSplit,
    SaddleSolution,
    multiplier_null_space,
    solve_saddle,
)
from hexapod.algorithms.saddle import dynamics_terms
from hexapod.algorithms.step_terms import terms_of
from hexapod.model.model import Data, Model


def forward_dynamics(model: Model, data: Data, t: float, q: np.ndarray, v: np.ndarray, *,
                     condition: bool = False,
                     baumgarte: tuple[float, float] | None = None,
                     rank_tolerance: float | None = None,
                     consistency_tol: float = 1e-6,
                     open_contacts: bool = False) -> np.ndarray:
    """Accelerations ``v_dot`` at ``(t, q, v)``; fills ``data``.

    A scene's unilateral contacts (``ground-contact`` force elements) carry forces that only a
    contact scheme decides, over a step (:mod:`hexapod.simulation.integrators.moreau_jean`):
    at an instant they are refused, unless ``open_contacts`` asks for the accelerations with
    every contact open (no contact force), as such a scheme's free motion.

    With ``baumgarte = (alpha, beta)`` (1/s) the acceleration constraints are stabilised,
    ``Phi_v v_dot = gamma - 2 alpha (Phi_v v - nu) - beta^2 phi``, so that drifted positions
    and velocities are pulled back to the constraints (Baumgarte 1972).

    ``rank_tolerance`` overrides ``model.rank_tolerance`` (rows whose equilibrated distance
    from the span of those kept falls below it are left out as redundant);
    ``consistency_tol`` is the largest relative violation of the rows left out (above it they
    contradict the others: an error).

    ``data`` receives ``Phi_v, gamma, Q, Q_across, v_dot, lam`` (n_c), ``independent_rows``,
    ``redundant_rows`` (row indices; names in ``model.rows``), ``inconsistency``, and, when
    ``condition`` is true, ``condition_number`` (2-norm, of the equilibrated saddle-point matrix
    of the independent rows), ``singular_values`` (of the equilibrated kept rows of ``Phi_v``,
    ascending) and ``sigma_min``, the smallest (the distance to a singular configuration).
    ``Phi_v`` is a NumPy array, or for a large model a SciPy CSR array: the whole solve is
    then sparse, its cost linear in the number of bodies (:mod:`hexapod.algorithms.saddle`).

    Parameters
    ----------
    model, data : Model, Data
        The model and its workspace (``model.create_data()``).
    t : float
        s.
    q, v : ndarray, shape (n_q,) and (n_v,)
        The state (consistent, e.g. from :func:`~hexapod.algorithms.kinematics.consistent_state`,
        unless ``baumgarte`` pulls it back).
    condition : bool
        Also the condition number and the singular values.
    baumgarte : (float, float), optional
        ``(alpha, beta)``, 1/s.
    rank_tolerance : float, optional
        Default ``model.rank_tolerance``.
    consistency_tol : float
        The largest relative violation of the redundant rows.
    open_contacts : bool
        With unilateral contacts: the accelerations with all of them open, asked for.

    Returns
    -------
    ndarray, shape (n_v,)
        ``v_dot`` (m/s^2, rad/s^2).

    Raises
    ------
    SingularSystemError
        When redundant constraints contradict each other.
    HexapodError
        The scene has unilateral contacts and ``open_contacts`` is false.
    """
    model.check(data)
    if not open_contacts:
        refuse_contacts(model)
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    w, wd, wdd = model.law_values(t, data)
    Phi_v, gamma, Q = dynamics_terms(model, {"q": q, "v": v, "w": w, "wd": wd, "wdd": wdd},
                                     data)
    if baumgarte is not None and model.n_c:
        alpha, beta = baumgarte
        velocity_error = Phi_v @ v - model.call("nu", data, q=q, w=w, wd=wd)
        gamma = gamma - 2 * alpha * velocity_error - beta**2 * model.call("phi", data, q=q, w=w)
    Q_across = (model.call("Q_across", data, q=q, v=v, w=w) if model.Q_across is not None
                else None)
    tol = model.rank_tolerance if rank_tolerance is None else rank_tolerance
    split = state_split(model, data, q, w, Phi_v, tol)  # shared with the velocity analysis
    solution, lam, status = policy_solution(model, data, t, q, w, Phi_v, split, Q, gamma,
                                            Q_across, tol=tol,
                                            consistency_tol=consistency_tol)
    data.at(t, q, v)
    data.ground_status = status
    data.w, data.wd, data.wdd = w, wd, wdd
    data.Phi_v, data.gamma, data.Q = Phi_v, gamma, Q
    data.v_dot, data.lam = solution.v_dot, lam
    data.independent_rows, data.redundant_rows = split.independent, split.redundant
    data.Q_across = Q_across
    data.inconsistency = solution.inconsistency
    data.condition_number = data.sigma_min = data.singular_values = None
    if condition:
        data.condition_number = split.condition_number(model.n_v)
        data.singular_values = np.sort(split.singular_values())
        sigma = data.singular_values
        data.sigma_min = float(sigma[0]) if sigma.size else float("inf")
    return solution.v_dot


def policy_solution(model: Model, data: Data, t: float, q: np.ndarray, w: np.ndarray, Phi_v,
                    split: RowSplit, Q: np.ndarray, gamma: np.ndarray,
                    Q_across: np.ndarray | None, *, tol: float, consistency_tol: float = 1e-6,
                    status: bool = True) -> tuple[SaddleSolution, np.ndarray, tuple | None]:
    """The saddle-point solution for the forces ``Q`` and the right-hand side ``gamma`` at
    ``(t, q)``, and the multipliers the scene's redundancy policy chooses (the ground-force
    policy with contacts: then also each foot's status when ``status`` asks, else None). The
    policies but friction are linear in ``(Q, gamma, Q_across)``, and solve the columns of
    matrices ``Q`` and ``gamma`` together: the design sensitivities
    (:mod:`hexapod.algorithms.sensitivity`) solve their derivatives here."""
    priority, _ = model.rank_order(w)  # feet in swing have no rows to decide on
    wrench_map = offset = None
    if split.redundant.size and not model.contacts:
        wrench_map, offset = policy_map(model, q, w, Phi_v, Q_across, data)
    solution = solve_saddle(model.mass_inv_sqrt, Phi_v, Q, gamma, priority,
                            tol, row_names=[r.name for r in model.rows],
                            consistency_tol=consistency_tol,
                            wrench_map=wrench_map, wrench_offset=offset, split=split)
    lam = solution.lam
    if model.contacts:  # the scene's ground-force policy
        lam, feet = share_ground_forces(model, data, t, q, Phi_v, Q_across, split, lam,
                                        status=status)
        return solution, lam, feet
    return solution, lam, None


def policy_tangents(model: Model, data: Data, t: float, q: np.ndarray, w: np.ndarray, Phi_v,
                    split: RowSplit, forces: np.ndarray, state=None, *, tol: float,
                    along_mu: np.ndarray | None = None) -> tuple[np.ndarray, frozenset]:
    """The derivatives of the multipliers the scene's policy chooses, for the derivatives of
    the forces ``forces`` (columns; ``gamma`` and the forces across joints unchanged) and of
    the friction coefficient (``along_mu``, per column): for the linear policies
    :func:`policy_solution` of the forces (the coefficient changes nothing); for friction (a
    QP, piecewise linear) on the active set of the solution at the state, whose ``(Q, gamma,
    Q_across)`` ``state`` gives (:func:`hexapod.algorithms.ground.friction_tangents`), with
    that active set."""
    zero = np.zeros((model.n_c,) + forces.shape[1:])
    if not (model.contacts and model.ground.policy == "friction"):
        _, lam, _ = policy_solution(model, data, t, q, w, Phi_v, split, forces, zero, None,
                                    tol=tol, status=False)
        return lam, frozenset()
    Q, gamma, Q_across = state
    priority, _ = model.rank_order(w)
    primal, along = (solve_saddle(model.mass_inv_sqrt, Phi_v, f, g, priority, tol,
                                  split=split).lam for f, g in ((Q, gamma), (forces, zero)))
    _, tangents, active = friction_tangents(model, data, t, q, terms_of(model).nonzeros(Phi_v),
                                            Q_across, primal,
                                            multiplier_null_space(split, model.n_c), along,
                                            along_mu)
    return tangents, active
