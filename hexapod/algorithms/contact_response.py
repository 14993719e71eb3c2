"""The engine's constrained step with contact forces on its right-hand side, linear in them.

With ``M^1/2``-scaled unknowns ``y = M^1/2 x``, the saddle-point system of the step on the
bilateral rows kept by the rank decision,

    M x + Phi_v^T lam = M^1/2 top + J^T F,     Phi_v x = rows,

has the solution ``y + Y F``, ``lam + Lam F``: ``(y, lam)`` that of the forces in ``top``
alone and ``(Y, Lam)`` the response to unit contact forces (``G = M^-1/2 J^T`` on the
right-hand side), from one factorisation. The contacts then see ``J x = G^T y + W F`` with the
Delassus operator ``W = G^T Y = Y^T Y`` (``Y`` is ``G`` projected on the rows' null space).
At velocity level (an impact) ``x`` is the new velocity; at acceleration level (a smooth
phase) the acceleration: the event-driven scheme solves its contact problems on it. The
time-stepping scheme solves the same system, its metric stiffened by the forces it takes
implicitly, in one CasADi call (:class:`hexapod.simulation.kernels.CompiledContactStep`).
"""

from __future__ import annotations

import numpy as np

from hexapod.algorithms.kinematics import state_split
from hexapod.model.model import Data, Model


def contact_response(model: Model, data: Data, q: np.ndarray, w: np.ndarray, Phi_v,
                     top: np.ndarray, rows: np.ndarray, G: np.ndarray) -> tuple:
    """The solution of the forces in ``top`` and the response to the contact forces.

    Parameters
    ----------
    model, data : Model, Data
    q, w : ndarray
        Positions and law values (where the rank decision is taken).
    Phi_v : matrix
        The bilateral rows' Jacobian at ``q``.
    top : ndarray, shape (n_v,)
        ``M^-1/2`` times the forces (and, at velocity level, ``M^1/2`` times the velocities
        before the step).
    rows : ndarray, shape (n_c,)
        The rows' right-hand side (``gamma`` or ``nu``).
    G : ndarray, shape (n_v, k)
        ``M^-1/2 J^T``.

    Returns
    -------
    y : ndarray, shape (n_v,)
    lam : ndarray, shape (n_c,)
    Y : ndarray, shape (n_v, k)
    Lam : ndarray, shape (n_c, k)
    """
    n = model.n_c
    lam, Lam = np.zeros(n), np.zeros((n, G.shape[1]))
    split = state_split(model, data, q, w, Phi_v) if n else None
    if split is None or not split.rank:
        return top, lam, G, Lam
    kept, scale = split.independent, split.scale
    y, scaled = split.kept_solve(top, rows[kept] / scale[kept])
    Y, scaled_unit = split.kept_solve(G, np.zeros((kept.size, G.shape[1])))
    lam[kept] = scaled / scale[kept]
    Lam[kept] = scaled_unit / scale[kept][:, None]
    return y, lam, Y, Lam
