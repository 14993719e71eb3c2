"""Derivatives of an inverse-dynamics result along a change of its scene's laws (a gait's step
height: the feet's paths), by the phase path's sample Function differentiated in forward mode.

At a sample, the Function of a :class:`~hexapod.algorithms.phase_plan.PhasePlan` maps the
laws' values, rates and accelerations to the positions (Newton's steps on the kept rows), the
velocities and accelerations, the multipliers (the saddle-point solve and the redundancy
policy) and the joint wrenches. Started from the sample's own solution with no time step, one
Newton step leaves the positions where they are, and its forward derivative along the laws'
change ``(dw, dwd, dwdd)`` is the implicit function theorem's: ``dq = -Phi_q^-1 phi_w dw`` on
the kept rows, then the velocities', accelerations' and multipliers' derivatives through the
same solves, and the policy's through its small least-squares problem, whose Jacobian, wrench
map and weights move with the positions. Exact to round-off, no difference quotient, and no
second copy of any of it: the derivative of the one step.

A guided model (the walking robot: the trunk's pose and the feet's paths are guides, and its
joints follow them) goes in two stages, as its inverse dynamics does
(:mod:`hexapod.algorithms.guided`): the guides' kinematics (a motion plan) gives the motion's
derivative; the guided joints' coordinates' derivatives follow from it; the twin (its guided
joints driven by those coordinates) takes the motion and the laws with their derivatives and
gives the forces'.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from hexapod._support.execution import executing
from hexapod.algorithms.friction_motion import friction_motion_tangents
from hexapod.algorithms.phase_inverse import POSITION_TOL, RESIDUAL_TOL, SIGMA_TOL, sample_plans
from hexapod.errors import HexapodError
from hexapod.model.model import Model

if TYPE_CHECKING:
    from hexapod.algorithms.inverse import InverseResult
    from hexapod.model.model import Law

__all__ = ["LawTangents", "law_tangents"]


@dataclass(frozen=True)
class LawTangents:
    """The derivatives of an inverse-dynamics result along ``P`` changes of its laws.

    Attributes
    ----------
    q : ndarray (N, n_q, P)
        The positions'.
    wrench : ndarray (N, P, J, 6)
        The joint wrenches', joint frames (force then moment).
    frames, dframes : ndarray (N, J, 9) and (N, P, J, 9)
        The joint frames' rotations (column-major) and their derivatives.
    ground : ndarray (N, C, 3, P)
        The ground's forces on the feet's, world axes.
    rates : ndarray (N, n_w, P)
        The laws' rates' (the guided joints' coordinates' rates for a guided model).
    changes : ndarray
        With the friction policy, the sample times where its active set changes (there the
        derivatives are one-sided); empty otherwise.
    """

    q: np.ndarray
    wrench: np.ndarray
    frames: np.ndarray
    dframes: np.ndarray
    ground: np.ndarray
    rates: np.ndarray
    changes: np.ndarray


def law_tangents(model: Model, result: InverseResult,
                 changes: Sequence[Mapping[Law, Law]], *, keys: Sequence[str] | None = None,
                 progress: Callable[[int, int], None] | None = None) -> LawTangents:
    """The derivatives of ``result`` (an inverse dynamics of ``model``) along each change of
    ``changes``: a mapping from each law the parameter changes to the law of its derivative
    (value, rate and acceleration per unit of the parameter). ``keys``, one per change (""
    for none): the parameter's scene key, which the laws the model makes of its contacts (the
    footholds) and the feet's load-sharing weights answer too (``gait.duty``).
    ``progress`` is called with ``(samples done, samples)`` (a guided model's two stages:
    twice the samples).

    Raises
    ------
    HexapodError
        At a sample the phase path's plans do not cover (a motion the drivers leave free), or
        where a plan's checks fail at the result's own state; a contact's law that depends on
        the key in a way not derived.
    """
    times, n = result.times, result.times.size
    motion = (result.q, result.v, result.v_dot)
    keys = list(keys) if keys is not None else [""] * len(changes)
    with executing(compiled=False):  # compiled Functions carry no derivatives
        if model.guidance is None:
            seeds = _seeds(model, times, changes, keys)
            dx, lam, dwrench, frames, dframes, switches = _tangents(
                model, times, motion, seeds, progress=_stage(progress, 0, n))
        else:
            from hexapod.algorithms.guided import guided_coordinate_tangents
            from hexapod.algorithms.inverse import motion_model

            kinematics = model.guidance.kinematics
            dx = _tangents(kinematics, times, motion, _seeds(kinematics, times, changes, keys),
                           kinematics_only=True, progress=_stage(progress, 0, 2 * n))[0]
            twin = motion_model(model, result)
            seeds = _seeds(twin, times, changes, keys)
            n_q, n_v = model.n_q, model.n_v
            joints = guided_coordinate_tangents(model, *motion, dx[:, :n_q],
                                                dx[:, n_q:n_q + n_v], dx[:, n_q + n_v:])
            for m in range(3):
                seeds[m][model.guidance.laws] = joints[m]
            dx, lam, dwrench, frames, dframes, switches = _tangents(
                twin, times, motion, seeds, known=dx, progress=_stage(progress, n, 2 * n))
    rows = np.array([c.rows for c in model.contacts], dtype=int).reshape(-1, 3)
    return LawTangents(dx[:, :model.n_q], dwrench, frames, dframes, -lam[:, rows],
                       seeds[1].transpose(1, 0, 2).reshape(n, model.n_w, -1), switches)


def _seeds(model: Model, times: np.ndarray, changes, keys) -> list[np.ndarray]:
    """The laws' derivatives: values, rates, accelerations, each (n_w, N, P); then the feet's
    policy values' and load-sharing weights' (C, N, P each)."""
    out = [np.zeros((model.n_w, times.size, len(changes))) for _ in range(3)]
    for p, (change, key) in enumerate(zip(changes, keys, strict=True)):
        for index, law in enumerate(model.laws):
            base, factor = law.unscaled()  # a scene law in the scene's units, converted
            derivative = change.get(base)
            if derivative is None and key and law.kind == "foothold":
                derivative = _held(model, law, key)
            if derivative is not None:
                derivative = derivative.scaled(factor)
                for m, x in enumerate(derivative.evaluate(times)):
                    out[m][index, :, p] = x
    return [*out, *_feet_seeds(model, times, keys)]


def _held(model: Model, law: Law, key: str) -> Law | None:
    """The derivative of a law the model made of a contact, along the parameter ``key``."""
    try:
        held = law.design_parameter(key)
    except ValueError as error:
        raise HexapodError(f"model '{model.name}': {key}: {error}") from None
    return None if held is None else held[1]


def _feet_seeds(model: Model, times: np.ndarray, keys) -> tuple[np.ndarray, np.ndarray]:
    """The derivatives of the feet's policy values (:func:`~hexapod.algorithms.ground.
    foot_values`) and of their load-sharing weights along each key (C, N, P each)."""
    from hexapod.algorithms.ground import NO_LOAD, foot_value_rates, sharing_weights

    contacts, n = model.contacts, times.size
    out = np.zeros((len(contacts), n, len(keys)))
    along = np.zeros_like(out)
    if not contacts:
        return out, along
    raw = np.array([c.weight(times) for c in contacts], dtype=float).reshape(-1, n)
    stance = np.array([c.in_stance(times) for c in contacts], dtype=bool).reshape(-1, n)
    weights = sharing_weights(raw, stance)
    shared = ~np.any(raw > NO_LOAD, axis=0)  # the feet down share the load equally there
    for p, key in enumerate(keys):
        if key:
            rates = np.array([c.weight_rate(times, key) for c in contacts]).reshape(-1, n)
            rates[:, shared] = 0.0
            along[..., p] = rates
            out[..., p] = foot_value_rates(model.ground.policy, weights, rates)
    return out, along


def _stage(progress, start: int, total: int):
    """``progress`` of one stage: its samples counted from ``start`` of ``total``."""
    return None if progress is None else (lambda done: progress(start + done, total))


def _tangents(model: Model, times, motion, seeds, *, kinematics_only: bool = False,
              known: np.ndarray | None = None, progress=None):
    """The forward derivatives at each sample of the state ``[q; v; v_dot]`` (N, n_x, P), and
    with forces of the multipliers (N, n_c, P), the joint wrenches (N, P, J, 6), the frames
    (N, J, 9) and their derivatives (N, P, J, 9). ``known``: the motion's derivative (the
    twin of a guided model takes its motion as known)."""
    n, count = times.size, seeds[0].shape[-1]
    data = model.create_data()
    w, wd, wdd = (np.asarray(x, dtype=float).reshape(model.n_w, n)
                  for x in model.law_values(times, data))
    plans = sample_plans(model, data, times, w, motion, motion=kinematics_only)
    state = np.hstack(motion)
    joints, n_c = len(model.joints), model.n_c
    dx = np.zeros((n, state.shape[1], count))
    lam, dwrench = np.zeros((n, n_c, count)), np.zeros((n, count, joints, 6))
    frames, dframes = np.zeros((n, joints, 9)), np.zeros((n, count, joints, 9))
    friction = bool(model.contacts) and model.ground.policy == "friction" and \
        not kinematics_only
    active: list[frozenset] = [frozenset()] * n
    for k, (plan, mask, feet) in enumerate(plans):
        function = _tangent_function(plan, count, known is not None)
        inputs = [state[k], 0.0, w[:, k], wd[:, k], wdd[:, k], feet, mask]
        directions = [np.zeros((state.shape[1], count)), np.zeros((1, count)),
                      seeds[0][:, k], seeds[1][:, k], seeds[2][:, k],
                      seeds[3][:, k].reshape(feet.size, count), np.zeros((mask.size, count))]
        if known is not None:
            inputs.append(state[k])
            directions.append(known[k])
        outputs = [np.asarray(x) for x in function(*inputs, *directions)]
        if progress is not None and (k % 50 == 49 or k == len(plans) - 1):
            progress(k + 1)
        _check(model, times[k], outputs[1 if kinematics_only else 4].ravel())
        if kinematics_only:
            dx[k] = outputs[2]
            continue
        if known is not None:
            dx[k] = known[k]
        else:
            dx[k] = outputs[5]
        # CasADi's column-major matrices (6 x J, and 6 x J P for P directions)
        frames[k] = outputs[3].ravel(order="F").reshape(joints, 9)
        lam[k] = outputs[6]
        dwrench[k] = outputs[7].ravel(order="F").reshape(count, joints, 6)
        dframes[k] = outputs[8].ravel(order="F").reshape(count, joints, 9)
        if friction:  # the step's multipliers are the least-squares policy's: the QP's own
            _, lam[k], dwrench[k], frames[k], dframes[k], active[k] = \
                friction_motion_tangents(model, data, float(times[k]), state[k],
                                         (w[:, k], wd[:, k], wdd[:, k]), dx[k],
                                         tuple(seeds[m][:, k] for m in range(3)),
                                         seeds[4][:, k])
    _check_consistent(model, times, state, dx, w, seeds[0], plans)
    changes = times[[k for k in range(1, n) if active[k] != active[k - 1]]]
    return dx, lam, dwrench, frames, dframes, changes


#: The most a row left out of a rank decision may move per unit of the parameter (scaled as
#: the position checks scale rows, relative to the motion's change) for the derivative to be
#: the scene's: a change the drivers' laws cannot follow moves it by order one.
CONSISTENT_TOL = 1e-8


def _check_consistent(model: Model, times, state, dx, w, dw, plans) -> None:
    """Where the drivers fix the motion with rows to spare (closed loops, feet on the
    ground), the rows left out must follow the change too: a joint moved in a robot standing
    on pinned feet with its joints' laws fixed has no motion (the scene moved cannot be
    assembled), though the kept rows give one. Checked on the positions' change, which
    solved the kept rows; raised naming the row and the time."""
    from hexapod.algorithms.step_terms import terms_of

    residual, n_q = terms_of(model).residual, model.n_q
    tangent = residual.forward(dw.shape[-1])
    scale = np.asarray(model.row_scale, dtype=float)[:, None]
    for k, (plan, _, _) in enumerate(plans):
        q = state[k, :n_q]
        moved = np.asarray(tangent(q, w[:, k], residual(q, w[:, k]), dx[k, :n_q],
                                   dw[:, k])) / scale
        size = 1.0 + np.abs(dx[k]).max()
        rows = plan.left_out
        if rows.size and np.abs(moved[rows]).max() > CONSISTENT_TOL * size:
            row = int(rows[np.argmax(np.abs(moved[rows]).max(axis=1))])
            raise HexapodError(
                f"model '{model.name}' at t = {times[k]:.6g} s: the parameter moves its row "
                f"'{model.rows[row].name}' (left out as redundant) where its drivers cannot "
                "follow: with the parameter moved the scene has no motion (closed loops whose "
                "drivers' laws were written for the scene's values): no derivative")


def _tangent_function(plan, count: int, known: bool) -> ca.Function:
    """The plan's step (one Newton step, or none from known positions) with its forward
    derivative in ``count`` directions: ``(inputs, directions) -> (outputs, derivatives)``,
    built once per plan."""
    cache = plan.__dict__.setdefault("_tangent_functions", {})
    key = (count, known)
    if key not in cache:
        step = plan.step(0 if known else 1, False, known)
        inputs = [ca.MX.sym(step.name_in(i), step.sparsity_in(i)) for i in range(step.n_in())]
        directions = [ca.MX.sym("d_" + step.name_in(i), step.size1_in(i), count)
                      for i in range(step.n_in())]
        outputs = step.call(inputs)
        derivatives = step.forward(count).call([*inputs, *outputs, *directions])
        kept = 1 if plan.motion else 3  # of the state, or of the state, lam and wrench
        frames = [derivatives[3]] if not plan.motion else []
        cache[key] = ca.Function("phase_tangent", [*inputs, *directions],
                                 [*outputs, *derivatives[:kept], *frames])
    return cache[key]


def _check(model: Model, t: float, checks: np.ndarray) -> None:
    """The plan's checks at the result's own state (:data:`~hexapod.algorithms.phase_plan.
    CHECKS`): the derivative is its rows' only where they hold."""
    position, residuals, outside, sigma = checks[0], checks[1:5], checks[5], checks[6]
    if not (position <= 10 * POSITION_TOL and np.all(residuals <= RESIDUAL_TOL)
            and outside == 0 and sigma >= SIGMA_TOL):
        raise HexapodError(f"model '{model.name}' at t = {t:.6g} s: the phase path's rank "
                           "decision does not hold at the result's state (a singular pose, or "
                           "a foot that touches down unweighed): no derivative there")
