"""Position, velocity and acceleration analysis.

Position: Newton iterations on ``phi(q, t) = 0`` in the tangent space. Each step is the
least-``M``-norm velocity-space correction ``dv`` with ``Phi_v dv = -phi`` (so the step is
unit-free and redundant rows are handled by the rank decision of :mod:`hexapod.algorithms.linalg`),
applied with the Lie-group update of :meth:`Model.integrate` and a backtracking line search.
Velocity: the least-``M``-norm correction of a guess onto ``Phi_v v = nu``. Acceleration: the
same for ``Phi_v v_dot = gamma``; both are unique when drivers fix every degree of freedom.
"""

from __future__ import annotations

import numpy as np

from hexapod.algorithms.linalg import (
    RowSplit,
    as_dense,
    check_consistency,
    equilibrate,
    hold_rows,
    split_rows,
)
from hexapod.algorithms.saddle import constraint_jacobian
from hexapod.errors import AssemblyError, SingularSystemError
from hexapod.model.model import Data, Model
from hexapod.spatial import rotation_from_euler_parameters

#: The largest scaled residual of a guess from which Newton's method starts with the rank
#: decision of the last state it solved (a guess predicted from the sample before: about
#: 3e-6 for the walking robot's samples a millisecond apart) instead of deciding again; a
#: held decision whose rows have come near dependence is decided again anyway.
HOLD_BELOW = 1e-3
#: A scaled residual this small is round-off already: Newton's method returns without the
#: polishing step (and its rank decision), as from positions solved before (a guided model's
#: twin starts from its guides' positions, 3e-16 off on the walking robot).
ROUND_OFF = 1e-14
#: A Newton step keeps the factorisation of the one before when it reduced the largest scaled
#: residual by at least this factor (as Newton's method proper does near the solution);
#: a slower step factorises again.
CHORD_RATE = 0.1


def _subject(model: Model) -> str:
    """How messages name a model: with the file it was read from, when there is one."""
    return f"model '{model.name}'" + (f" ({model.source})" if model.source else "")


def rank_split(model: Model, Phi_v: np.ndarray, w: np.ndarray, *,
               held: RowSplit | None = None, tol: float | None = None) -> RowSplit:
    """The rank decision on the equilibrated ``Phi_v`` at law values ``w`` by the model's
    policy (its kept rows and their singular values), with the model's rank tolerance or
    ``tol``; the decision ``held`` (taken at a nearby state) when its kept rows are still
    independent there. Errors name the model."""
    tol = model.rank_tolerance if tol is None else tol
    try:
        W, d = equilibrate(Phi_v, model.mass_inv_sqrt)
        priority, groups = model.rank_order(w)
        split = None
        if held is not None and held.independent.size + held.redundant.size == priority.size \
                and np.array_equal(np.sort(np.concatenate([held.independent, held.redundant])),
                                   np.sort(priority)):  # the same rows to decide on
            split = hold_rows(W, d, held, tol)
        if split is None:
            split = split_rows(W, d, priority, tol, groups=groups)
        return split
    except SingularSystemError as error:  # the linear algebra does not know the model
        raise SingularSystemError(f"{_subject(model)}: {error}") from None


def state_split(model: Model, data: Data, q: np.ndarray, w: np.ndarray, Phi_v,
                tol: float | None = None) -> RowSplit:
    """The rank decision at the state ``(q, w)``, taken once per state and workspace: the
    velocity analysis and the dynamics at the same state share it. The workspace's last
    decision (a simulation's previous state) is held while its kept rows stay independent
    and its redundant ones dependent (:func:`~hexapod.algorithms.linalg.hold_rows`: one
    factorisation instead of a decision row by row). Among dependent rows it may keep others
    than a fresh decision would: the accelerations and the policy's multipliers do not
    depend on which."""
    tol = model.rank_tolerance if tol is None else tol
    kept = data.built.get("state decision")
    if kept is not None and kept[2] == tol and np.array_equal(kept[0], q) \
            and np.array_equal(kept[1], w):
        return kept[3]
    split = rank_split(model, Phi_v, w, tol=tol,
                       held=kept[3] if kept is not None and kept[2] == tol else None)
    data.built["state decision"] = (np.array(q), np.array(w), tol, split)
    return split


def _check(model: Model, split: RowSplit, y: np.ndarray, rhs: np.ndarray, what: str,
           size: float = 0.0) -> None:
    """The redundant rows are met too (see :func:`hexapod.algorithms.linalg.check_consistency`),
    relative to ``size`` or the correction's own, whichever is larger."""
    try:
        check_consistency(split, y, rhs, size, row_names=_names(model), what=what)
    except SingularSystemError as error:
        raise SingularSystemError(f"{_subject(model)}: {error}") from None


def _names(model: Model) -> list[str]:
    return [r.name for r in model.rows]


def scaled_residual(model: Model, t: float, q: np.ndarray) -> np.ndarray:
    """``phi`` with length rows divided by the characteristic length (dimensionless)."""
    w, _, _ = model.law_values(t)
    return model.call("phi", q=q, w=w) / model.row_scale


def _violations(model: Model, scaled: np.ndarray, count: int = 5) -> str:
    worst = np.argsort(-np.abs(scaled))[:count]
    return ", ".join(f"{model.rows[i].name} = {scaled[i] * model.row_scale[i]:.3g}"
                     + (" m" if model.rows[i].kind == "length" else " rad")
                     for i in worst if abs(scaled[i]) > 0)


def assemble_positions(model: Model, data: Data, t: float = 0.0, q: np.ndarray | None = None,
                       *, tol: float = 1e-12, max_iterations: int = 60,
                       counts: dict | None = None, diagnose: bool = True,
                       polish: bool = True) -> np.ndarray:
    """A configuration satisfying every constraint at time ``t``, near the guess ``q``; left in
    ``data.t`` and ``data.q``.

    Parameters
    ----------
    model, data : Model, Data
        The model and its workspace (``model.create_data()``).
    t : float
        Time in s (the drivers' laws are evaluated there).
    q : ndarray (n_q,), optional
        Rough guess (default: the scene's initial poses).
    tol : float
        On ``max |phi_i| / s_i`` with ``s_i`` the characteristic length for length rows and 1
        for angle rows.
    max_iterations : int
        The most Newton iterations.
    counts : dict, optional
        Receives the work done: ``newton`` (iterations, each a Jacobian evaluation and a
        factorisation) added to what it holds.
    diagnose : bool
        When Newton's method stalls on a model with feet, find which footholds keep the rest
        from assembling, for the error's message (a Newton solve per foot and more: seconds
        for the walking robot). False for a caller that catches the error and tries another
        way.
    polish : bool
        Once within ``tol``, one more Newton step (to round-off, kept only if it helps); False
        for a caller whose own Newton steps follow (the phase path's first sample).

    Returns
    -------
    ndarray, shape (n_q,)
        The positions (m, Euler parameters, rad).

    Raises
    ------
    AssemblyError
        Naming the constraints still violated when Newton's method stalls.
    """
    model.check(data)
    q = _assemble(model, data, t, model.normalize(model.q0 if q is None else q), tol,
                  max_iterations, counts, diagnose, polish)
    data.at(t, q)
    return q


def _assemble(model: Model, data: Data, t: float, q: np.ndarray, tol: float,
              max_iterations: int, counts: dict | None, diagnose: bool,
              polish: bool = True) -> np.ndarray:
    w, _, _ = model.law_values(t, data)
    try:
        return _newton(model, data, t, w, q, tol, max_iterations, counts, polish)
    except AssemblyError as error:
        if not diagnose:
            raise
        feet = _feet_off(model, data, t, w, q, tol, max_iterations)
        if not feet:
            raise
        raise AssemblyError(f"{_subject(model)}: at t = {t:g} the footholds do not agree with "
                            f"the legs' motion: {feet}; check the contacts' footholds and the "
                            f"gait, or the joint frames ({error})") from None


def _feet_off(model: Model, data: Data, t: float, w: np.ndarray, q: np.ndarray, tol: float,
              max_iterations: int) -> str:
    """The feet in stance whose footholds alone keep the constraints from assembling at ``t``:
    each foot that, lifted, lets the rest assemble, with how far it then is from its foothold
    (``FL 25 mm off (x +25, y +0, z +0)``); when every foot down does (two feet of a trot: the
    rest cannot tell), all of them, said so. Empty when no single foot explains the
    failure."""
    down = [c for c in model.contacts if w[c.gate] >= 0.5]
    if len(down) < 2:
        return ""
    found = []
    for contact in down:
        lifted = w.copy()
        lifted[contact.gate] = 0.0
        try:
            trial = _closest(model, data, t, w, lifted, contact,
                             _newton(model, data, t, lifted, q, tol, max_iterations, None), tol)
        except AssemblyError:
            continue
        offset = model.call("phi", data, q=trial, w=w)[contact.rows] * 1e3  # r - a, mm
        found.append(f"{contact.name.removesuffix('/ground')} {np.linalg.norm(offset):.3g} mm "
                     f"off (x {offset[0]:+.3g}, y {offset[1]:+.3g}, z {offset[2]:+.3g})")
    if not found:
        return ""
    if len(found) == len(down):
        return ("lifting any one foot lets the rest assemble, so which foothold is wrong cannot "
                "be told; the feet's offsets, each lifted: " + "; ".join(found))
    return "; ".join(found) + " (lifted, the other feet agree)"


def _closest(model: Model, data: Data, t: float, w: np.ndarray, lifted: np.ndarray, contact,
             q: np.ndarray, tol: float, steps: int = 8) -> np.ndarray:
    """From ``q`` (the other constraints met, ``contact``'s foot lifted), the configuration
    that brings the foot nearest its foothold while the others stay met: Gauss-Newton on the
    foot's offset within the motions the other constraints leave free (two feet of a tripod
    leave the trunk a roll), each step followed by Newton back onto the others."""
    for _ in range(steps):
        Phi_v = np.asarray(as_dense(constraint_jacobian(model, q, w, data)))
        free = null_space(model, np.delete(Phi_v, contact.rows, axis=0))
        offset = model.call("phi", data, q=q, w=w)[contact.rows]
        if free.shape[1] == 0 or np.linalg.norm(offset) <= tol * model.characteristic_length:
            return q
        dv = free @ np.linalg.lstsq(Phi_v[contact.rows] @ free, -offset, rcond=None)[0]
        trial = _newton(model, data, t, lifted, model.integrate(q, dv), tol, 20, None)
        if np.linalg.norm(model.call("phi", data, q=trial, w=w)[contact.rows]) >= \
                np.linalg.norm(offset):
            return q
        q = trial
    return q


def null_space(model: Model, matrix: np.ndarray) -> np.ndarray:
    """An orthonormal basis (n_v, k) of the motions ``matrix`` (rows of ``Phi_v``) leaves
    free: singular values below the model's rank tolerance (relative, at least 1) count as
    zero."""
    _, s, Vt = np.linalg.svd(matrix)
    rank = int(np.sum(s > model.rank_tolerance * max(float(s.max(initial=0.0)), 1.0)))
    return Vt[rank:].T


def _newton(model: Model, data: Data, t: float, w: np.ndarray, q: np.ndarray, tol: float,
            max_iterations: int, counts: dict | None, polish: bool = True) -> np.ndarray:
    """Newton's method on the constraints at law values ``w`` from ``q`` (see
    :func:`assemble_positions`)."""
    if model.n_c == 0:
        return q
    residual = model.call("phi", data, q=q, w=w) / model.row_scale
    if not np.all(np.isfinite(residual)) or not np.all(np.isfinite(q)):
        raise AssemblyError(f"{_subject(model)}: the constraint residuals are not finite at "
                            "the initial guess (check the scene's magnitudes and length unit)")
    merit = float(np.max(np.abs(residual)))
    # near the solution (a guess predicted from the sample before), the decision of the last
    # state this workspace saw, held while its rows stay independent; else decided here. Its
    # factorisation is kept over the iterations (a chord method) until a step fails to
    # reduce the residual, then decided again where that step started
    held = data.built.get("state decision", (None,) * 4)[3] if merit <= HOLD_BELOW else None
    polished, split, factorised_at = False, None, None
    for _ in range(max_iterations):
        if merit <= tol:
            if polished or merit <= ROUND_OFF or not polish:
                return q
            # Newton converges quadratically: one more step takes the residual to round-off
            # (joint points coincide to ~1e-16 m instead of ~tol), kept only if it helps
            polished = True
        if factorised_at is None:
            split = rank_split(model, constraint_jacobian(model, q, w, data), w, held=held)
            factorised_at, held = q, None
        if counts is not None:
            counts["newton"] = counts.get("newton", 0) + 1
        dv = model.mass_inv_sqrt @ split.min_norm_correction(-residual * model.row_scale)
        trial, trial_residual, trial_merit = _line_search(model, data, w, q, dv, merit, tol,
                                                          polished)
        if trial_merit >= merit and (polished or trial_merit > tol):
            if factorised_at is not q:  # a chord step that failed: the Jacobian here, again
                factorised_at = None
                continue
            if polished:
                return q
            break
        if trial_merit > CHORD_RATE * merit:  # too slow for a chord: the Jacobian again
            factorised_at = None
        q, residual, merit = trial, trial_residual, trial_merit
    if merit <= tol:
        return q
    raise AssemblyError(
        f"{_subject(model)}: cannot assemble the constraints at t = {t:g} from the given "
        f"guess (largest violations: {_violations(model, residual)}); check the joint "
        "frames and initial poses, or the driver laws at that time", t, q)


def _line_search(model: Model, data: Data, w, q, dv, merit: float, tol: float,
                 polished: bool):
    """Backtracking on the largest scaled residual: the first of ``q (+) s dv``, ``s`` = 1,
    1/2, ..., that lowers ``merit`` (or meets ``tol`` unless ``polished``): the trial
    position, its scaled residual and its merit."""
    step = 1.0
    while True:
        trial = model.integrate(q, step * dv)
        trial_residual = model.call("phi", data, q=trial, w=w) / model.row_scale
        trial_merit = float(np.max(np.abs(trial_residual)))
        if trial_merit < merit or (trial_merit <= tol and not polished):
            return trial, trial_residual, trial_merit
        step *= 0.5
        if polished or step < 1e-4:
            return trial, trial_residual, trial_merit


def solve_velocities(model: Model, data: Data, t: float, q: np.ndarray,
                     v: np.ndarray | None = None) -> np.ndarray:
    """Velocities (n_v) satisfying ``Phi_v v = nu`` at ``(t, q)`` closest to the guess ``v``
    (default: the scene's initial velocities) in the kinetic-energy norm; left in ``data.v``
    (with ``data.t``, ``data.q``).

    Parameters
    ----------
    model, data : Model, Data
        The model and its workspace (``model.create_data()``).
    t : float
        s.
    q : ndarray, shape (n_q,)
        Positions satisfying the constraints (e.g. from :func:`assemble_positions`).
    v : ndarray, shape (n_v,), optional
        The guess (default: the scene's initial velocities).

    Returns
    -------
    ndarray, shape (n_v,)

    Raises
    ------
    SingularSystemError
        The velocity constraints of redundant rows contradict the others.
    """
    model.check(data)
    v = _project_velocities(model, data, t, q,
                            model.v0 if v is None else np.asarray(v, dtype=float))
    data.at(t, q, v)
    return v


def _project_velocities(model: Model, data: Data, t: float, q: np.ndarray,
                        v: np.ndarray) -> np.ndarray:
    if model.n_c == 0:
        return v.copy()
    w, wd, _ = model.law_values(t, data)
    Phi_v = constraint_jacobian(model, q, w, data)
    nu = model.call("nu", data, q=q, w=w, wd=wd)
    split = state_split(model, data, q, w, Phi_v)
    residual = nu - Phi_v @ v
    dy = split.min_norm_correction(residual)
    # relative to the velocities themselves: re-projecting a consistent state makes a
    # correction of round-off, against which Bricard's redundant row looked inconsistent
    size = float(np.linalg.norm(model.mass @ (model.mass_inv_sqrt @ v)))  # |M^1/2 v|
    _check(model, split, dy, residual, "velocity constraints", size)
    return v + model.mass_inv_sqrt @ dy


def solve_accelerations(model: Model, data: Data, t: float, q: np.ndarray,
                        v: np.ndarray) -> np.ndarray:
    """Accelerations (n_v) satisfying ``Phi_v v_dot = gamma`` of least kinetic-energy norm
    (unique for a fully driven mechanism): the acceleration analysis of prescribed motion; left
    in ``data.v_dot`` (with ``data.t, q, v, Phi_v, gamma``).

    Parameters
    ----------
    model, data : Model, Data
        The model and its workspace (``model.create_data()``).
    t : float
        s.
    q, v : ndarray, shape (n_q,) and (n_v,)
        A consistent state (e.g. from :func:`consistent_state`).

    Returns
    -------
    ndarray, shape (n_v,)

    Raises
    ------
    SingularSystemError
        The acceleration constraints of redundant rows contradict the others.
    """
    w, wd, wdd = model.law_values(t, data)
    Phi_v = constraint_jacobian(model, q, w, data)
    gamma = model.call("gamma", data, q=q, v=v, w=w, wd=wd, wdd=wdd)
    split = state_split(model, data, q, w, Phi_v)  # the velocities' decision, when at q
    y = split.min_norm_correction(gamma)
    _check(model, split, y, gamma, "acceleration constraints")
    data.at(t, q, v)
    data.Phi_v, data.gamma = Phi_v, gamma
    data.v_dot = model.mass_inv_sqrt @ y
    return data.v_dot


def consistent_state(model: Model, data: Data, t: float = 0.0, q: np.ndarray | None = None,
                     v: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Positions assembled and velocities projected at time ``t`` from guesses (default: the
    scene's initial state): ``(q (n_q), v (n_v))``, also left in ``data``.

    Parameters
    ----------
    model, data : Model, Data
        The model and its workspace (``model.create_data()``).
    t : float
        s.
    q : ndarray, shape (n_q,), optional
        Guess of the positions (default: the scene's initial poses).
    v : ndarray, shape (n_v,), optional
        Guess of the velocities (default: the scene's initial velocities).

    Returns
    -------
    q, v : ndarray, shape (n_q,) and (n_v,)

    Raises
    ------
    AssemblyError, SingularSystemError
        As :func:`assemble_positions` and :func:`solve_velocities`.
    """
    q = assemble_positions(model, data, t, q)
    return q, solve_velocities(model, data, t, q, v)


def degrees_of_freedom(model: Model, data: Data, t: float, q: np.ndarray) -> dict:
    """Numerical mobility at ``(t, q)``: ``n_v - rank(Phi_v)`` of the joints alone (``dof``)
    and with the drivers (``dof_with_drivers``), and the redundant rows by name
    (``redundant_rows``); ``data`` receives ``Phi_v``.

    Parameters
    ----------
    model, data : Model, Data
        The model and its workspace (``model.create_data()``).
    t : float
        s.
    q : ndarray, shape (n_q,)
        Positions.

    Returns
    -------
    dict
        ``dof`` and ``dof_with_drivers`` (int), ``redundant_rows`` (list of row names).
    """
    w, _, _ = model.law_values(t, data)
    Phi_v = constraint_jacobian(model, q, w, data)
    data.at(t, q)
    data.Phi_v = Phi_v
    split = rank_split(model, Phi_v, w)
    driver_rows = {d.row for d in model.drivers}
    joint_rows = np.array([i for i in range(model.n_c) if i not in driver_rows], dtype=int)
    W, d = split.W[joint_rows], split.scale[joint_rows]
    priority = [i for i in model.rank_order(w)[0] if i not in driver_rows]
    position = {row: k for k, row in enumerate(joint_rows)}
    joint_split = split_rows(W, d, np.array([position[i] for i in priority], dtype=int),
                             model.rank_tolerance)
    return {
        "dof": model.n_v - joint_split.rank,
        "dof_with_drivers": model.n_v - split.rank,
        "redundant_rows": [model.rows[i].name for i in split.redundant],
    }


#: How a free motion's leading velocity component reads (:func:`free_motions`).
_MOTION_WORDS = {**{f"v{c}": f"translating along world {c}" for c in "xyz"},
                 **{f"w{c}_body": f"turning about its own {c} axis" for c in "xyz"},
                 "w": "turning in the plane"}


def free_motions(model: Model, Phi_v: np.ndarray) -> list[str]:
    """The motions the constraints ``Phi_v`` (n_c, n_v) leave free, in words: a basis of the
    null space of ``Phi_v``, each vector led by one velocity component (the basis reduced on
    the components a pivoted QR picks, weighted by their bodies' masses so that a robot's
    trunk leads: each vector is 1 on its own component and 0 on the others') and naming every
    body it moves, e.g. ``trunk translating along world x (moves trunk, leg0)``."""
    N = null_space(model, np.asarray(as_dense(Phi_v), dtype=float).reshape(-1, model.n_v))
    if N.shape[1] == 0:
        return []
    from scipy.linalg import qr

    mass = np.zeros(model.n_v)
    for body in model.bodies:
        mass[body.v] = body.mass
    picked = np.sort(qr(N.T * np.sqrt(mass), pivoting=True, mode="r")[1][:N.shape[1]])
    reduced = N @ np.linalg.solve(N[picked], np.eye(N.shape[1]))
    names = model.velocity_names
    out = []
    for k, i in enumerate(picked):
        body, _, part = names[i].rpartition(".")
        moved = [b.name for b in model.bodies
                 if np.abs(reduced[b.v, k]).max(initial=0.0) > 1e-9]
        out.append(f"{body} {_MOTION_WORDS.get(part, part)} (moves {', '.join(moved)})")
    return out


def body_poses(model: Model, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World poses of every body's centre-of-mass frame over samples ``q`` (N, n_q): positions
    (N, n_bodies, 3) and rotations (N, n_bodies, 3, 3), planar poses embedded in 3-D (z = 0,
    rotation about z) and particles with the identity.

    Parameters
    ----------
    model : Model
    q : ndarray, shape (N, n_q) or (n_q,)
        Positions at N samples (one sample: N = 1).

    Returns
    -------
    position : ndarray, shape (N, n_bodies, 3)
        The centres of mass, m.
    rotation : ndarray, shape (N, n_bodies, 3, 3)
        Body -> world.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n, n_b = q.shape[0], len(model.bodies)
    position, rotation = np.zeros((n, n_b, 3)), np.tile(np.eye(3), (n, n_b, 1, 1))
    for b, body in enumerate(model.bodies):
        qb = q[:, body.q]
        if body.kind == "spatial":
            position[:, b] = qb[:, :3]
            rotation[:, b] = np.moveaxis(rotation_from_euler_parameters(qb[:, 3:].T), -1, 0)
        elif body.kind == "planar":
            position[:, b, :2] = qb[:, :2]
            c, s = np.cos(qb[:, 2]), np.sin(qb[:, 2])
            rotation[:, b, :2, :2] = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], 1)
        else:
            position[:, b, :qb.shape[1]] = qb
    return position, rotation


def marker_trajectories(model: Model, q: np.ndarray, marker: str) -> dict[str, np.ndarray]:
    """World positions (N, 3) over samples ``q`` of the markers named ``marker``, by body (every
    body that has one).

    Parameters
    ----------
    model : Model
    q : ndarray, shape (N, n_q) or (n_q,)
        Positions at N samples.
    marker : str
        The marker's name (e.g. ``"foot"``).

    Returns
    -------
    dict of str to ndarray, shape (N, 3)
        By body name, m; empty when no body has such a marker.
    """
    owners = [b for b, body in enumerate(model.bodies) if marker in body.markers]
    if not owners:
        return {}
    position, rotation = body_poses(model, q)
    out = {}
    for b in owners:
        offset = model.bodies[b].markers[marker].position
        offset = np.concatenate([offset, np.zeros(3 - offset.size)])
        out[model.bodies[b].name] = position[:, b] + rotation[:, b] @ offset
    return out
