"""The exact inverse dynamics of one sample: the reference the other paths are measured against.

Positions by Newton's method warm-started from the sample before (:func:`next_positions`),
velocities by projection, then the saddle-point solve with its rank decision and the scene's
redundancy policy (:func:`hexapod.algorithms.dynamics.forward_dynamics`) and the joint wrenches
(:func:`hexapod.algorithms.liaison.joint_wrenches`). The saddle path of
:func:`hexapod.algorithms.inverse.inverse_dynamics` runs it at every sample; the compiled phase
path (:mod:`hexapod.algorithms.phase_inverse`) at the first sample and wherever its own result
cannot be trusted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.algorithms.dynamics import forward_dynamics
from hexapod.algorithms.ground import ground_reactions
from hexapod.algorithms.kinematics import (
    assemble_positions,
    degrees_of_freedom,
    free_motions,
    solve_accelerations,
    solve_velocities,
    state_split,
)
from hexapod.algorithms.liaison import joint_wrenches
from hexapod.errors import AssemblyError, HexapodError, SingularSystemError
from hexapod.model.model import Data, Model


@dataclass
class SampleResult:
    """The exact inverse dynamics at one sample (arrays of one sample, as in
    :class:`hexapod.algorithms.inverse.InverseResult`)."""

    q: np.ndarray
    v: np.ndarray
    v_dot: np.ndarray
    lam: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    effort: np.ndarray
    ground: np.ndarray
    violation: float
    redundant: tuple[str, ...]


def exact_sample(model: Model, data: Data, t0: float, q0: np.ndarray, t: float,
                 rates=None, *, frame: str = "joint",
                 known: tuple | None = None) -> SampleResult:
    """The sample at ``t`` from the solved positions ``q0`` at ``t0`` (and their velocities
    and accelerations ``rates``, for a second-order prediction), checking that the drivers
    leave no degree of freedom free (wherever the dynamics' rank decision keeps fewer rows
    than velocities: that decision is the check). ``known``: the velocities and accelerations at
    ``t`` when the motion is known already (a guided model's, from its guides' kinematics,
    ``q0`` its positions there): a motion the constraints leave free (a trunk on two feet
    turning about the line through them) then takes the known velocities, and the dynamics'
    accelerations must be the known ones (:func:`require_followed`).

    Raises
    ------
    SingularSystemError
        When the drivers leave degrees of freedom free (without ``known``).
    HexapodError
        When the dynamics does not follow the ``known`` motion.
    AssemblyError
        When the positions cannot be found.
    """
    q = next_positions(model, data, t0, q0, t, rates)
    v = solve_velocities(model, data, t, q, None if known is None else known[0])
    out = exact_forces(model, data, t, q, v, frame=frame)
    if known is not None:
        require_followed(model, data, t, q, out.v_dot, known[1])
    elif data.independent_rows is not None and data.independent_rows.size < model.n_v:
        # the constraints left a motion free here (a foot lifted off): its accelerations
        # would be the dynamics', not the prescribed motion's
        require_prescribed(model, data, t, q)
    return out


def exact_motion(model: Model, data: Data, t0: float, q0: np.ndarray, t: float,
                 rates=None) -> SampleResult:
    """The motion alone at ``t`` (positions as :func:`exact_sample` finds them, velocities and
    accelerations by the constraints), for a kinematics run: no multipliers, wrenches or
    ground forces (empty arrays). The rank decision taken is left in ``data``
    (``independent_rows``, ``redundant_rows``) as the dynamics leaves its own.

    Raises
    ------
    SingularSystemError
        When the drivers leave degrees of freedom free (wherever the velocities' rank
        decision keeps fewer rows than velocities: that decision is the check, none is taken
        for it alone).
    AssemblyError
        When the positions cannot be found.
    """
    q = next_positions(model, data, t0, q0, t, rates)
    v = solve_velocities(model, data, t, q)
    v_dot = solve_accelerations(model, data, t, q, v)  # leaves Phi_v in data
    w = model.law_values(t, data)[0]
    split = state_split(model, data, q, w, data.Phi_v)  # the velocities' own decision
    if split.independent.size < model.n_v:
        require_prescribed(model, data, t, q)
    data.independent_rows, data.redundant_rows = split.independent, split.redundant
    empty = np.zeros((0, 3))
    return SampleResult(q, v, v_dot, np.zeros(0), empty, empty, np.zeros(0), empty,
                        _violation(model, data, q, w),
                        tuple(model.rows[i].name for i in split.redundant))


def known_sample(model: Model, data: Data, times: np.ndarray, known: tuple, k: int,
                 frame: str = "joint") -> SampleResult:
    """The exact sample ``k`` of a motion known at the samples ``times`` (``known``: its
    ``q, v, v_dot``, each (N, size)): Newton from its positions there (:func:`exact_sample`)."""
    return exact_sample(model, data, times[k], known[0][k], times[k], frame=frame,
                        known=(known[1][k], known[2][k]))


def exact_forces(model: Model, data: Data, t: float, q: np.ndarray, v: np.ndarray, *,
                 frame: str = "joint") -> SampleResult:
    """Accelerations, multipliers by the scene's policy, joint wrenches and ground forces at a
    consistent state ``(t, q, v)``."""
    v_dot = forward_dynamics(model, data, t, q, v)
    wrenches = joint_wrenches(model, data, frame=frame)
    ground = (ground_reactions(model, data.lam) if model.contacts
              else np.zeros((0, 3)))
    redundant = tuple(model.rows[i].name for i in data.redundant_rows)
    return SampleResult(q, v, v_dot, data.lam, wrenches.force, wrenches.torque,
                        wrenches.effort, ground, _violation(model, data, q, data.w), redundant)


def _violation(model: Model, data: Data, q: np.ndarray, w: np.ndarray) -> float:
    """The largest scaled constraint residual at ``(q, w)`` (0 without constraints)."""
    if not model.n_c:
        return 0.0
    return float(np.max(np.abs(model.call("phi", data, q=q, w=w) / model.row_scale)))


#: m/s^2 and rad/s^2: the most the dynamics' accelerations may differ from a known motion's
#: (a guided model's). Where every degree of freedom is driven they agree to round-off; where
#: the constraints leave a motion free (a trunk on two feet), the dynamics decides it, and a
#: motion planned so that the feet can carry it (:mod:`legs.carried`) agrees to about 1e-9.
FOLLOWED_TOL = 1e-6


def require_followed(model: Model, data: Data, t: float, q: np.ndarray, v_dot: np.ndarray,
                     known: np.ndarray) -> None:
    """Raise when the dynamics' accelerations ``v_dot`` at ``(t, q)`` leave the known motion's
    ``known`` by more than :data:`FOLLOWED_TOL`: where the constraints leave a motion free,
    as :func:`require_prescribed` does, else naming the body and by how much."""
    gap = np.abs(np.asarray(v_dot) - np.asarray(known))
    if not gap.max(initial=0.0) > FOLLOWED_TOL:
        return
    i = int(np.argmax(gap))
    body = next(b.name for b in model.bodies if b.v.start <= i < b.v.stop)
    departure = (f"body '{body}' accelerates {gap[i]:.3g} (m/s^2 or rad/s^2) away from the "
                 "motion the guides give")
    require_prescribed(model, data, t, q, departure)
    raise HexapodError(f"model '{model.name}': at t = {t:g} s the dynamics does not follow "
                       f"the known motion: {departure}")


def require_prescribed(model: Model, data: Data, t: float, q: np.ndarray,
                       departure: str = "") -> None:
    """Raise when the drivers leave degrees of freedom free at ``(t, q)`` (``departure``: how
    the dynamics leaves the motion asked of them, when it is known)."""
    free = degrees_of_freedom(model, data, t, q)["dof_with_drivers"]
    if not free:
        return
    motions = "; ".join(free_motions(model, data.Phi_v))
    gates = model.law_values(t)[0]
    down = [c.name.removesuffix("/ground") for c in model.contacts if gates[c.gate] >= 0.5]
    if 0 < len(down) < 3:  # a walking robot's trunk on one or two point feet
        raise SingularSystemError(
            f"model '{model.name}': at t = {t:g} s only "
            f"{'the foot' if len(down) == 1 else 'the feet'} {' and '.join(down)} "
            f"{'is' if len(down) == 1 else 'are'} on the ground, leaving {free} degree(s) of "
            f"freedom free: {motions}; point feet on a line cannot hold the trunk's moment "
            "about it, so the trunk cannot follow an arbitrary path there"
            f"{': ' + departure if departure else ''} (plan the trunk's motion so that the "
            "feet can carry it, as a robot description's gait does: docs/robots.md)")
    driven = {d.joint for d in model.drivers if d.kind == "joint"}
    idle = [j.name for j in model.joints
            if j.type.drivable and j.index not in driven]
    hint = f" (joints without a driver: {', '.join(idle)})" if idle else ""
    raise SingularSystemError(
        f"model '{model.name}': the drivers leave {free} degree(s) of freedom "
        f"free{hint}: {motions}; inverse dynamics needs the motion of every degree of "
        "freedom (drive them, or hold the bodies that move: a free base of a URDF model "
        "is held by reading it with a fixed base, --base fixed)")


def next_positions(model: Model, data, t0: float, q0: np.ndarray, t: float, rates):
    """Positions at ``t`` from the solved ones at ``t0``: from a second-order prediction with
    the velocities and accelerations ``rates`` at ``t0`` (Newton's method then needs one or two
    steps, not five), else by :func:`follow`."""
    if rates is not None:
        h = t - t0
        guess = model.integrate(q0, h * rates[0] + h * h / 2 * rates[1])
        if np.all(np.isfinite(guess)):
            try:  # a failure here is not reported (follow tries): no diagnosis
                return assemble_positions(model, data, t, guess, diagnose=False)
            except AssemblyError:
                pass
    return follow(model, data, t0, q0, t)


def follow(model: Model, data, t0: float, q0: np.ndarray, t: float, depth: int = 6):
    """Positions at ``t`` from those at ``t0``: Newton's method from ``q0``, and when the
    samples are too far apart for it (a robot's legs swing a long way between coarse samples),
    through the time halfway first."""
    last = depth == 0 or t == t0  # only its failure is reported: diagnosed
    try:
        return assemble_positions(model, data, t, q0, diagnose=last)
    except AssemblyError:
        if last:
            raise
    middle = follow(model, data, t0, q0, (t0 + t) / 2, depth - 1)
    return follow(model, data, (t0 + t) / 2, middle, t, depth - 1)
