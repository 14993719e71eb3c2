"""How far a mechanism's drivers are from being met when they ask for a pose out of its reach (a
robot's foot path beyond its leg's length), to name them.

The drivers are grouped by their names' namespace (``LH/x``, ``LH/y``, ``LH/z``: ``LH``; a name
without ``/`` is its own group), ranked as the scene's rows are (in file order). From where
Newton's method stalled, the pose is sought that keeps every other row (the joints'; the feet's
contacts are lifted) and meets each group as nearly as it can without disturbing the groups
before it: the task-priority least squares of redundant robots' inverse kinematics (Nakamura,
Hanafusa and Yoshikawa 1987; Siciliano and Slotine 1991), each group's step taken in the motions
the groups before it leave free, by damped Gauss-Newton steps (Levenberg-Marquardt: a straight
leg, where the nearest pose lies, is singular) and Newton back onto the joints' rows, each step
kept only when it brings the groups, in their order, nearer. What each group then misses by
names the drivers that cannot be followed, and how far.
"""

from __future__ import annotations

import numpy as np

from hexapod.algorithms.kinematics import null_space
from hexapod.algorithms.linalg import as_dense
from hexapod.algorithms.saddle import constraint_jacobian
from hexapod.model.model import Data, Model

#: Scaled residual (rows of lengths divided by the characteristic length) below which a driver
#: is met.
MET = 1e-6
#: The most damped Gauss-Newton steps, and the step (m or rad, the largest component of the
#: velocity-space step) below which they stop.
STEPS, SMALLEST_STEP = 100, 1e-10


class _Reach:
    """The scaled residuals and Jacobian at a time, the feet lifted, and the rows to keep."""

    def __init__(self, model: Model, data: Data, t: float):
        self.model, self.data = model, data
        self.w = model.law_values(t, data)[0].copy()
        self.w[[c.gate for c in model.contacts]] = 0.0
        driven = {d.row for d in model.drivers if d.kind != "posture"}  # a rule is kept
        self.kept = np.array([i for i in range(model.n_c) if i not in driven], dtype=int)

    def residual(self, q: np.ndarray) -> np.ndarray:
        return self.model.call("phi", self.data, q=q, w=self.w) / self.model.row_scale

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        Phi_v = np.asarray(as_dense(constraint_jacobian(self.model, q, self.w, self.data)))
        return Phi_v / self.model.row_scale[:, None]

    def onto_kept(self, q: np.ndarray) -> np.ndarray | None:
        """Newton's method (least-norm steps) on the kept rows alone; None when it fails."""
        for _ in range(20):
            r = self.residual(q)[self.kept]
            if np.max(np.abs(r), initial=0.0) <= 1e-13:
                return q
            q = self.model.integrate(q, np.linalg.lstsq(self.jacobian(q)[self.kept], -r,
                                                        rcond=None)[0])
        return None

    def directions(self, q: np.ndarray, groups: list[np.ndarray]) -> list[tuple]:
        """Per group, in order: its rows' scaled residuals and Jacobian, and the motions the
        kept rows and the groups before it leave free (a basis, n_v x k)."""
        r, Phi = self.residual(q), self.jacobian(q)
        out, free = [], null_space(self.model, Phi[self.kept])
        for rows in groups:
            if free.shape[1] == 0:
                break
            out.append((r[rows], Phi[rows], free))
            free = free @ null_space(self.model, Phi[rows] @ free)
        return out


def _step(directions: list[tuple], n_v: int, damping: float) -> np.ndarray:
    """The task-priority step: each group's damped least squares in its free motions, after
    the steps of the groups before it."""
    step = np.zeros(n_v)
    for r, Phi, free in directions:
        J = Phi @ free
        step += free @ (J.T @ np.linalg.solve(J @ J.T + damping**2 * np.eye(r.size),
                                              -r - Phi @ step))
    return step


def _nearer(trial: list[float], before: list[float]) -> bool:
    """Whether the groups' squared misses ``trial`` are nearer than ``before``, the first
    group first (a group's change within round-off counts as none)."""
    for a, b in zip(trial, before, strict=True):
        if abs(a - b) > 1e-15 * (1.0 + b):
            return a < b
    return False


def driver_misses(model: Model, data: Data, t: float, q: np.ndarray
                  ) -> list[tuple[str, list[tuple[str, float, str]]]] | None:
    """The groups of drivers that the joints cannot follow at ``t``, and by how much.

    Parameters
    ----------
    model, data : Model, Data
    t : float
        The time, s.
    q : ndarray (n_q,)
        Where to start: where Newton's method stalled (``AssemblyError.positions``).

    Returns
    -------
    list of (str, list of (str, float, str)), or None
        Each group that misses (its name, then each of its rows: name, residual in m or rad,
        and ``"length"`` or ``"angle"``), the farthest first (scaled residuals); None when the
        joints' own rows cannot be met.
    """
    reach = _Reach(model, data, t)
    order: dict[str, list[int]] = {}
    for driver in (d for d in model.drivers if d.kind != "posture"):
        order.setdefault(driver.name.rsplit("/", 1)[0], []).append(driver.row)
    groups = [np.array(rows, dtype=int) for rows in order.values()]

    def misses(q: np.ndarray) -> list[float]:
        r = reach.residual(q)
        return [float(r[rows] @ r[rows]) for rows in groups]

    q = reach.onto_kept(q)
    if q is None:
        return None
    damping = 0.5
    for _ in range(STEPS):
        before, directions = misses(q), reach.directions(q, groups)
        while damping < 1e3:  # more damping, shorter steps, until one brings them nearer
            step = _step(directions, model.n_v, damping)
            trial = reach.onto_kept(model.integrate(q, step))
            if trial is not None and _nearer(misses(trial), before):
                damping = max(damping / 3, 1e-3)
                break
            damping *= 4
        else:
            break
        q = trial
        if np.max(np.abs(step)) <= SMALLEST_STEP:
            break
    r = reach.residual(q)
    found = [(name, rows) for name, rows in zip(order, groups, strict=True)
             if np.max(np.abs(r[rows])) > MET]
    found.sort(key=lambda item: -float(np.linalg.norm(r[item[1]])))
    return [(name, [(model.rows[i].name, float(r[i] * model.row_scale[i]), model.rows[i].kind)
                    for i in rows]) for name, rows in found]
