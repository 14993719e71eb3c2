"""The rows of a posture rule (:class:`~hexapod.scene.drivers.PostureDriver`): of the joint
angles that put a foot where its three guides say, the one nearest the rest posture, weighted.

With ``G`` the foot point's velocity per joint rate (3 x n: column ``a_i x (r - p_i)`` for
joint ``i`` of world axis ``a_i`` through ``p_i``, ``r`` the foot point) and ``d`` the weighted
offsets ``w_i (theta_i - rest_i)``, the least ``sum w_i (theta_i - rest_i)^2`` on the guides'
constraint has ``d`` orthogonal to the null space of ``G`` (the joint motions that leave the
foot still). Three joints whose columns are best conditioned at the initial pose (the largest
``|det|`` of the 3 x 3 minors) span the foot's motion; each other joint ``j`` gives a null
vector by Cramer's rule, ``n_j = det(G_B) e_j - sum_k det(G_B with column k replaced by g_j)
e_{B_k}``, and the row ``n_j . d``, divided by ``|det(G_B)|`` at the initial pose (so that it
is an angle). No inverse and no square root: the rows are polynomials of the columns, smooth
wherever the three basic columns stay independent.
"""

from __future__ import annotations

from itertools import combinations

import casadi as ca
import numpy as np


def posture_rows(columns: list, offsets: list, q: ca.SX, q0: np.ndarray
                 ) -> list[tuple[int, ca.SX]]:
    """The rows of a posture rule: per joint beyond the three basic ones, its index in the
    rule's joints and its row (an expression of ``q``).

    Parameters
    ----------
    columns : list of SX (3,)
        ``a_i x (r - p_i)`` of each of the rule's joints, world axes.
    offsets : list of SX
        ``w_i (theta_i - rest_i)`` of each joint (the angle wrapped).
    q : SX
        The positions the expressions depend on.
    q0 : ndarray
        The initial positions, where the basic joints are chosen.
    """
    G = ca.horzcat(*columns)
    G0 = np.asarray(ca.Function("posture_columns", [q], [G])(q0).full())
    basis = max(combinations(range(len(columns)), 3),
                key=lambda b: abs(np.linalg.det(G0[:, list(b)])))
    c = [columns[k] for k in basis]
    det = ca.dot(c[0], ca.cross(c[1], c[2]))
    scale = abs(float(np.linalg.det(G0[:, list(basis)]))) or 1.0
    rows = []
    for j in (k for k in range(len(columns)) if k not in basis):
        g = columns[j]
        cramer = [ca.dot(g, ca.cross(c[(k + 1) % 3], c[(k + 2) % 3])) for k in range(3)]
        row = det * offsets[j] - sum(x * offsets[k] for x, k in zip(cramer, basis, strict=True))
        rows.append((j, row / scale))
    return rows
