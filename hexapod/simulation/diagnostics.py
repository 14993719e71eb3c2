"""Numerical diagnostics of a mechanism at a state: how well posed, how stiff, how close to a
singular configuration, and the largest step each explicit method can take there.

* **Conditioning.** The 2-norm condition number of the saddle-point matrix
  ``[[M, Phi_v^T], [Phi_v, 0]]`` as written (kept rows only: a redundant row makes it singular
  by construction) and as solved, equilibrated to ``[[I, W^T], [W, 0]]`` with
  ``W = D^-1 Phi_v M^-1/2`` (:mod:`hexapod.algorithms.linalg`). A mass ratio of 1e-6 shows in the
  first and not in the second.
* **Rank.** The singular values of the kept rows of ``W``, the numerical degrees of freedom
  ``n_v - rank`` against Grubler-Kutzbach's count, and the redundant rows by name.
* **Distance to the nearest singular configuration.** Where the joints' rows lose rank the
  smallest singular value ``sigma`` of their equilibrated Jacobian ``W_J`` vanishes; to first order
  it does so after a motion of ``sigma / |grad sigma|`` along the motions the joints allow, the
  gradient taken by central differences in coordinates where a length counts in units of the
  model's characteristic length ``l`` and an angle in radians. The distance is in those units
  (about radians of joint motion), with the rows that become dependent there (the largest entries
  of the left singular vector).
* **Stiffness.** The equations linearised on the constraint manifold: with ``N`` an
  ``M``-orthonormal basis of the motions the constraints allow (``Phi_v N = 0``,
  ``N^T M N = I``) and ``K, C`` the derivatives of ``Phi_v^T lambda - Q`` in the positions and
  the velocities (:attr:`Model.tangent_matrices`),

      xi'' + N^T C N xi' + N^T K N xi = 0,

  exact at rest; in motion it leaves out the turning of the tangent space. Its eigenvalues are the
  modes ``exp(lambda t)``; the stiffness ratio is the largest ``|lambda|`` over the smallest
  non-zero one (zero modes are free motions, such as a free yaw).
* **Largest stable steps.** Each method's stability region along each mode
  (:meth:`Integrator.largest_stable_step`); implicit methods have none.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict, dataclass, field

import numpy as np
import scipy.linalg

from hexapod.algorithms.dynamics import forward_dynamics
from hexapod.algorithms.linalg import as_dense, equilibrate, split_rows
from hexapod.algorithms.topology import mobility
from hexapod.model.model import Data, Model
from hexapod.simulation.registry import INTEGRATORS

#: above this many velocities the finite-difference distance to a singular configuration is not
#: computed (2 n_v evaluations and singular value decompositions): say so rather than stall
DISTANCE_LIMIT = 600
#: relative step of the central differences of the smallest singular value
DIFFERENCE_STEP = 1e-6


@dataclass
class Diagnosis:
    """The diagnostics of :func:`diagnose` (see the module's description).

    Attributes
    ----------
    t : float
        The state's time, s.
    n_v, n_c : int
        Velocities and constraint rows.
    rank : int
        Rows kept by the rank decision.
    dof, dof_counted, dof_with_drivers : int
        Numerical degrees of freedom of the joints, Grubler-Kutzbach's count, and the
        numerical ones with the drivers.
    redundant_rows : list of str
        The rows left out as redundant.
    condition_number, condition_number_unscaled : float, float or None
        Of the saddle-point matrix as solved (equilibrated) and as written.
    singular_values : ndarray
        Of the equilibrated kept rows of ``Phi_v``, ascending.
    sigma_min : float
        The smallest singular value (``inf`` without rows).
    singular_distance : float or None
        The distance to the nearest singular configuration (rad, lengths in units of
        ``characteristic_length``); None when not computed.
    singular_rows : list of str
        The rows that become dependent there.
    eigenvalues : ndarray of complex
        The linearised modes ``exp(lambda t)``, 1/s.
    stiffness_ratio, fastest_rate, slowest_rate : float
        The largest over the smallest nonzero ``|lambda|``, and those two (1/s).
    growing_modes : int
        Modes with a positive real part (an unstable equilibrium).
    stable_steps : dict of str to (float or None)
        The largest stable step of each method, s (None for an implicit one).
    characteristic_length : float
        The model's, m.
    """

    t: float
    n_v: int
    n_c: int
    rank: int
    dof: int
    dof_counted: int
    dof_with_drivers: int
    redundant_rows: list[str]
    condition_number: float
    condition_number_unscaled: float | None
    singular_values: np.ndarray
    sigma_min: float
    singular_distance: float | None
    singular_rows: list[str]
    eigenvalues: np.ndarray
    stiffness_ratio: float
    fastest_rate: float
    slowest_rate: float
    growing_modes: int
    stable_steps: dict[str, float | None] = field(default_factory=dict)
    characteristic_length: float = 1.0

    def as_dict(self) -> dict:
        out = asdict(self)
        out["singular_values"] = self.singular_values.tolist()
        out["eigenvalues"] = [[float(z.real), float(z.imag)] for z in self.eigenvalues]
        return out

    def text(self) -> str:
        """A short report, one quantity per line."""
        def number(x):
            return "n/a" if x is None else f"{x:.3g}"

        lines = [
            f"degrees of freedom: {self.dof} numerical, {self.dof_counted} counted "
            f"(Grubler-Kutzbach); {self.dof_with_drivers} with the drivers",
            f"rank {self.rank} of {self.n_c} rows; redundant: "
            + (", ".join(self.redundant_rows) if self.redundant_rows else "none"),
            f"condition number of the saddle-point matrix: {number(self.condition_number)} "
            f"equilibrated (as solved), {number(self.condition_number_unscaled)} as written",
            f"smallest singular value of the equilibrated Phi_v: {number(self.sigma_min)}",
            "distance to the nearest singular configuration: "
            + (f"{number(self.singular_distance)} (rad, lengths in units of "
               f"l = {self.characteristic_length:.3g} m)" if self.singular_distance is not None
               else "not computed (too many velocities)")
            + (f"; rows that become dependent there: {', '.join(self.singular_rows)}"
               if self.singular_rows else ""),
            f"linearised modes: {self.eigenvalues.size}, fastest |lambda| = "
            f"{number(self.fastest_rate)} 1/s, slowest {number(self.slowest_rate)} 1/s, "
            f"stiffness ratio {number(self.stiffness_ratio)}"
            + (f", {self.growing_modes} growing (unstable equilibrium)" if self.growing_modes
               else ""),
            "largest stable step of the explicit methods: "
            + ", ".join(f"{m} {number(h)} s" for m, h in self.stable_steps.items()
                        if h is not None),
        ]
        return "\n".join(lines)


def _tangent_scale(model: Model) -> np.ndarray:
    """Per velocity coordinate, the length that makes it dimensionless: ``l`` for translations,
    1 for rotations."""
    scale = np.full(model.n_v, model.characteristic_length)
    for body in model.bodies:
        start = body.v.start
        if body.kind == "spatial":
            scale[start + 3:start + 6] = 1.0
        elif body.kind == "planar":
            scale[start + 2] = 1.0
    return scale


def _null_space(W: np.ndarray, rank: int) -> np.ndarray:
    """Orthonormal basis of the null space of ``W`` whose rank is known."""
    if W.shape[0] == 0:
        return np.eye(W.shape[1])
    _, _, vt = np.linalg.svd(W, full_matrices=True)
    return vt[rank:].T


def _saddle_condition(model: Model, Phi_kept: np.ndarray) -> float | None:
    """2-norm condition number of ``[[M, Phi^T], [Phi, 0]]`` as written (dense)."""
    n = model.n_v + Phi_kept.shape[0]
    if n > 3000:
        return None
    K = np.zeros((n, n))
    K[:model.n_v, :model.n_v] = model.mass.dense()
    K[model.n_v:, :model.n_v] = Phi_kept
    K[:model.n_v, model.n_v:] = Phi_kept.T
    s = np.linalg.svd(K, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


def _joint_rows(model: Model) -> np.ndarray:
    driven = {d.row for d in model.drivers}
    return np.array([i for i in range(model.n_c) if i not in driven], dtype=int)


def _sigma_min(model: Model, q: np.ndarray, w: np.ndarray, rows: np.ndarray,
               Phi_v: np.ndarray | None = None):
    """Smallest singular value of the equilibrated ``rows`` of ``Phi_v`` (evaluated at ``q``
    unless given), and its left singular vector."""
    if Phi_v is None:
        Phi_v = model.call("Phi_v", q=q, w=w)
    W, _ = equilibrate(Phi_v[rows], model.mass_inv_sqrt)
    u, s, _ = np.linalg.svd(W, full_matrices=False)
    return float(s[-1]), u[:, -1]


def singular_distance(model: Model, t: float, q: np.ndarray) -> tuple[float, float, list[str]]:
    """``(distance, sigma, rows)``: the first-order distance to the nearest configuration where
    the joints' independent rows lose rank (see the module's description), the smallest singular
    value there now, and the rows that become dependent (largest entries of its left vector)."""
    w = model.law_values(t)[0]
    rows = _joint_rows(model)
    if rows.size == 0:
        return float("inf"), float("inf"), []
    Phi_v = model.call("Phi_v", q=q, w=w)
    W, d = equilibrate(Phi_v[rows], model.mass_inv_sqrt)
    split = split_rows(W, d, np.arange(rows.size), model.rank_tolerance)
    rows = rows[np.sort(split.independent)]
    sigma, u = _sigma_min(model, q, w, rows, Phi_v)
    scale = _tangent_scale(model)
    Phi_scaled = Phi_v[rows] * scale
    directions = _null_space(Phi_scaled / np.linalg.norm(Phi_scaled, axis=1, keepdims=True),
                             rows.size)
    gradient = np.zeros(directions.shape[1])
    for k in range(directions.shape[1]):
        dv = DIFFERENCE_STEP * scale * directions[:, k]
        plus = _sigma_min(model, model.integrate(q, dv), w, rows)[0]
        minus = _sigma_min(model, model.integrate(q, -dv), w, rows)[0]
        gradient[k] = (plus - minus) / (2 * DIFFERENCE_STEP)
    slope = float(np.linalg.norm(gradient))
    distance = sigma / slope if slope > 1e-9 * max(sigma, 1e-300) else float("inf")
    if not np.isfinite(distance):
        return distance, sigma, []
    order = np.argsort(-np.abs(u))
    weights = np.abs(u[order])
    names = [model.rows[rows[i]].name for i, weight in zip(order, weights, strict=True)
             if weight > 0.25 * weights[0]][:6]
    return distance, sigma, names


def linearised_modes(model: Model, data: Data, t: float, q: np.ndarray, v: np.ndarray,
                     kept: np.ndarray) -> np.ndarray:
    """Eigenvalues of the equations linearised on the constraint manifold (module
    description), from the multipliers and kept rows of a forward-dynamics solve in ``data``."""
    w = data.w
    names = model.tangent_matrices.name_in()
    values = {"q": q, "v": v, "lam": data.lam, "w": w}
    K, C = model.tangent_matrices(*[values[n] for n in names])
    K, C = np.array(K), np.array(C)
    half = model.mass_inv_sqrt
    if kept.size:
        W, _ = equilibrate(as_dense(data.Phi_v[kept]), half)
        basis = _null_space(W, kept.size)
    else:
        basis = np.eye(model.n_v)
    N = half @ basis  # M-orthonormal: N^T M N = I
    f = N.shape[1]
    if f == 0:
        return np.zeros(0, dtype=complex)
    stiffness = N.T @ K @ N
    damping = N.T @ C @ N
    A = np.block([[np.zeros((f, f)), np.eye(f)], [-stiffness, -damping]])
    return scipy.linalg.eigvals(A)


def diagnose(model: Model, data: Data, t: float, q: np.ndarray, v: np.ndarray, *,
             methods: Iterable[str] | None = None, distance: bool | None = None) -> Diagnosis:
    """The diagnostics at ``(t, q, v)`` (a consistent state), for the explicit ``methods``
    (default: every registered one; implicit ones report None); ``data`` is left with the
    forward dynamics at that state (with its condition number).

    ``distance`` computes the distance to the nearest singular configuration (default: when
    ``n_v <= DISTANCE_LIMIT``).

    Parameters
    ----------
    model, data : Model, Data
        The model and its workspace.
    t : float
        s.
    q, v : ndarray, shape (n_q,) and (n_v,)
        A consistent state (:func:`~hexapod.algorithms.kinematics.consistent_state`).
    methods : iterable of str, optional
        Registered integrator names whose largest stable steps to compute.
    distance : bool, optional
        Compute the distance to the nearest singular configuration.

    Returns
    -------
    Diagnosis

    Raises
    ------
    SingularSystemError
        Redundant constraints contradict each other at the state.
    """
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    forward_dynamics(model, data, t, q, v, condition=True)
    kept = np.sort(data.independent_rows)
    sigma = data.singular_values
    m = mobility(model, data, t, q)
    if distance is None:
        distance = model.n_v <= DISTANCE_LIMIT
    nearest, rows = None, []
    if distance:
        nearest, _, rows = singular_distance(model, t, q)
    modes = linearised_modes(model, data, t, q, v, kept)
    size = np.abs(modes)
    nonzero = size[size > 1e-9 * size.max()] if size.size else size
    fastest = float(nonzero.max()) if nonzero.size else 0.0
    slowest = float(nonzero.min()) if nonzero.size else 0.0
    growing = int(np.sum(modes.real > 1e-6 * np.maximum(size, 1e-300)))
    methods = INTEGRATORS if methods is None else {name: INTEGRATORS[name] for name in methods}
    steps = {name: cls.largest_stable_step(modes, constrained=model.n_c > 0)
             for name, cls in methods.items()}
    return Diagnosis(
        t=float(t), n_v=model.n_v, n_c=model.n_c, rank=int(kept.size), dof=m.numerical,
        dof_counted=m.counted, dof_with_drivers=m.numerical_with_drivers,
        redundant_rows=[model.rows[i].name for i in data.redundant_rows],
        condition_number=float(data.condition_number),
        condition_number_unscaled=_saddle_condition(model, as_dense(data.Phi_v[kept])),
        singular_values=sigma, sigma_min=float(sigma[0]) if sigma.size else float("inf"),
        singular_distance=nearest, singular_rows=rows, eigenvalues=modes,
        stiffness_ratio=fastest / slowest if slowest > 0 else 1.0,
        fastest_rate=fastest, slowest_rate=slowest, growing_modes=growing,
        stable_steps={k: (None if h is None else float(h)) for k, h in steps.items()},
        characteristic_length=model.characteristic_length)
