"""The motion of the joints that follow a scene's guides, as laws of the model that carries their
efforts.

A guided model (:mod:`hexapod.scene.laws.guided`) holds the kinematics of its scene with the
guides as drivers (``model.guidance.kinematics``). Its positions, velocities and accelerations
at the samples, found by the engine's own solves, give each guided joint's coordinate, rate and
acceleration there (the joint coordinate of the joint's own driver row, differentiated along the
motion); a twin of the model takes them as laws exact at the samples (the quintic Hermite
interpolant of a motion file), and its inverse dynamics gives the joints' efforts with the guides
left out. Both models have the same bodies and coordinates, so the kinematics' positions are the
twin's to round-off. When the guides ask for a pose the joints cannot reach (a foot's path
beyond its leg's length), the error names the guides and how far out they are
(:mod:`hexapod.algorithms.reach`).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod._support.across_samples import across_samples, in_groups
from hexapod._support.compiled import compiled_graph
from hexapod._support.execution import current
from hexapod._support.fastcall import FastFunction, InPlaceFunction, dense_outputs
from hexapod.algorithms import phase_plan
from hexapod.algorithms.phase_plan import blocks
from hexapod.algorithms.prescribed import prescribed_motion
from hexapod.errors import AssemblyError, HexapodError
from hexapod.model.model import Model
from hexapod.model.tabulation import sampled_laws

#: A guided joint whose coordinate changes between two samples by more than its rates and
#: accelerations at both account for (the quintic Hermite's integral), by this share of the
#: change and at least :data:`JUMP_FLOOR`, has jumped to another solution of the guides (a knee
#: flipped between samples too far apart for the Newton solves to follow the motion).
JUMP_SHARE = 0.5
JUMP_FLOOR = 1e-3
#: How many times the samples are halved where the motion jumped before giving up.
REFINEMENTS = 6


def _coordinates(model: Model) -> ca.Function:
    """``(q, v, v_dot) -> (theta, theta_dot, theta_ddot)`` of the guided joints."""
    s = model._sym  # the model's expressions: the guided joints' own coordinates
    v_dot = ca.SX.sym("v_dot", model.n_v)
    rate = ca.jtimes(s.guided, s.q, s.qdot)
    state, state_rate = ca.vertcat(s.q, s.v), ca.vertcat(s.qdot, v_dot)
    # common subexpressions merged: 8,393 operations a sample for the walking robot, 11,829
    # without
    return ca.Function("guided_coordinates", [s.q, s.v, v_dot],
                       ca.cse([s.guided, rate, ca.jtimes(rate, state, state_rate)]))


def guided_coordinates(model: Model, q: np.ndarray, v: np.ndarray, v_dot: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The guided joints' coordinates, rates and accelerations (each (G, N)) along the motion
    ``q, v, v_dot`` (each (N, size)), the coordinates unwrapped along the samples. The
    samples go in the phase path's blocks (:func:`~hexapod.algorithms.phase_plan.blocks`):
    mapping the Function over N samples costs its building in proportion to N (0.12 s for
    5,001 samples of the walking robot), over a block once per model; compiled to C when the
    execution setting says so, and called through buffers (CasADi's own call converting the
    arrays cost ten times the compiled evaluation). Interpreted, once the model has evaluated
    :data:`~hexapod.algorithms.phase_plan.EXPAND_AFTER` samples, :data:`~hexapod.algorithms.
    phase_plan.ACROSS` samples at a time by CasADi's MX virtual machine
    (:func:`~hexapod._support.across_samples.across_samples`, the same numbers: the walking
    robot's 8,393 operations a sample cost some 43 us a sample one at a time, 9 us 32 at a
    time, in a one-off timing at 501 samples)."""
    to_c = current().compiled
    n = q.shape[0]
    evaluated = model.built_once(("guided coordinates evaluated",), lambda m: _Samples())
    evaluated.count += n
    if not to_c and evaluated.count >= phase_plan.EXPAND_AFTER:
        across = InPlaceFunction(model.built_once(("guided coordinates across",), lambda m: (
            across_samples(dense_outputs(m.built_once(("guided coordinates",), _coordinates)),
                           phase_plan.ACROSS))))
        out = [np.empty((n, len(model.guidance.laws))) for _ in range(3)]
        in_groups(across, [np.ascontiguousarray(x, dtype=float) for x in (q, v, v_dot)], out,
                  phase_plan.ACROSS)
        theta, rate, acceleration = (x.T for x in out)
        return np.unwrap(theta, axis=1), rate, acceleration
    out = np.empty((3, len(model.guidance.laws), n))
    start, calls = 0, {}  # the blocks' Functions through buffers (this call's: threads)
    for size in blocks(n):
        if size not in calls:
            calls[size] = FastFunction(model.built_once(
                ("guided coordinates", to_c, size),
                lambda m, size=size: _mapped_coordinates(m, to_c, size)))
        span = slice(start, start + size)
        for k, x in enumerate(calls[size](q[span].T, v[span].T, v_dot[span].T)):
            out[k, :, span] = x.reshape(-1, size)
        start += size
    theta, rate, acceleration = out
    return np.unwrap(theta, axis=1), rate, acceleration


class _Samples:
    """How many samples a model's guided coordinates have been evaluated at (all its runs')."""

    count = 0


def _mapped_coordinates(model: Model, to_c: bool, size: int) -> ca.Function:
    """:func:`_coordinates` (compiled when ``to_c``, once per model) mapped over ``size``
    samples."""
    function = model.built_once(("guided coordinates", to_c), lambda m: (
        compiled_graph(_coordinates(m), "phase", "guided coordinates") if to_c
        else m.built_once(("guided coordinates",), _coordinates)))
    return function.map(size, "serial") if size > 1 else function


def guided_coordinate_tangents(model: Model, q: np.ndarray, v: np.ndarray,
                               v_dot: np.ndarray, dq: np.ndarray, dv: np.ndarray,
                               dv_dot: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The derivatives of the guided joints' coordinates, rates and accelerations (each
    (G, N, P)) along a change ``dq, dv, dv_dot`` (each (N, size, P)) of the motion ``q, v,
    v_dot`` (each (N, size)): the forward derivative of :func:`guided_coordinates`'s
    Function, exact."""
    function = model.built_once(("guided coordinates",), _coordinates)
    n, count = q.shape[0], dq.shape[-1]
    tangent = function.forward(count)
    out = np.zeros((3, function.size1_out(0), n, count))
    for k in range(n):
        nominal = function(q[k], v[k], v_dot[k])
        for m, x in enumerate(tangent(q[k], v[k], v_dot[k], *nominal, dq[k], dv[k],
                                      dv_dot[k])):
            out[m, :, k] = np.asarray(x)
    return out[0], out[1], out[2]


def guided_twin(model: Model, times: np.ndarray, q: np.ndarray, v: np.ndarray,
                v_dot: np.ndarray, joints: tuple | None = None) -> Model:
    """``model`` with its guided joints' laws the motion ``q, v, v_dot`` (at ``times``) gives
    them, exact at the samples; what it has built is shared (only the laws' values differ).
    ``joints``: the guided joints' coordinates, rates and accelerations along that motion when
    they are known already (:func:`followed_guides`)."""
    if joints is None:
        joints = guided_coordinates(model, q, v, v_dot)
    laws = list(model.laws)
    for index, law in zip(model.guidance.laws, sampled_laws(times, *joints), strict=True):
        laws[index] = law
    return model.with_laws(tuple(laws), model.digest, share_built=True)


def guides_motion(model: Model, times: np.ndarray, progress=None, *,
                  solve=prescribed_motion) -> tuple:
    """The guides' kinematics ``(q, v, v_dot)`` of a guided ``model`` at ``times``: those of
    :func:`followed_guides`."""
    return followed_guides(model, times, progress, solve=solve)[:3]


def followed_guides(model: Model, times: np.ndarray, progress=None, *,
                    solve=prescribed_motion) -> tuple:
    """The guides' kinematics ``(q, v, v_dot)`` of a guided ``model`` at ``times``, continuous
    along them (``solve(kinematics, grid, progress=progress)``, by default
    :func:`hexapod.algorithms.prescribed.prescribed_motion`), and the guided joints'
    coordinates, rates and accelerations there (:func:`guided_coordinates`, the fourth item,
    found on the way); where a guided joint jumps to another solution between two samples
    (see :data:`JUMP_SHARE`) the motion is solved again through their midpoint, until it
    follows one solution.

    Raises
    ------
    HexapodError
        The motion still jumps after :data:`REFINEMENTS` halvings (naming the joint and time).
    AssemblyError
        The guides ask for a pose out of the joints' reach (naming the guides, how far off).
    """
    grid = np.asarray(times, dtype=float)
    for _ in range(REFINEMENTS + 1):
        try:
            q, v, v_dot = solve(model.guidance.kinematics, grid, progress=progress)
        except AssemblyError as error:  # a pose out of reach: which guides, how far
            raise unreachable_guides(model, error) from None
        theta, rate, acceleration = guided_coordinates(model, q, v, v_dot)
        h = np.diff(grid)
        accounted = (h / 2 * (rate[:, :-1] + rate[:, 1:])
                     + h**2 / 12 * (acceleration[:, :-1] - acceleration[:, 1:]))
        change = np.diff(theta, axis=1)
        jumps = np.abs(change - accounted) > np.maximum(JUMP_SHARE * np.abs(change), JUMP_FLOOR)
        if not jumps.any():
            kept = np.searchsorted(grid, times)
            return (q[kept], v[kept], v_dot[kept],
                    (theta[:, kept], rate[:, kept], acceleration[:, kept]))
        bad = jumps.any(axis=0)
        grid = np.sort(np.concatenate([grid, (grid[:-1][bad] + grid[1:][bad]) / 2]))
    guided, k = np.unravel_index(np.argmax(jumps), jumps.shape)
    law = int(model.guidance.laws[guided])
    joint = next(model.joints[d.joint].name for d in model.drivers if d.law == law)
    raise HexapodError(f"model '{model.name}': joint '{joint}' jumps between solutions of the "
                       f"guides near t = {grid[k]:.6g} s even with samples {h[k]:.3g} s "
                       "apart: the guides ask for a motion it cannot follow continuously")


#: How many of the guides out of reach a message names.
NAMED = 3


def unreachable_guides(model: Model, error: AssemblyError) -> AssemblyError:
    """The error of a guided ``model`` whose guides' kinematics ``error`` could not assemble
    (Newton's method stalled at ``error.time``): the guides the joints cannot follow there,
    the farthest first, with how far off they are as near as the joints come; ``error``
    itself when that cannot be told (the joints' own rows do not assemble)."""
    from hexapod.algorithms.reach import driver_misses

    if error.time is None or error.positions is None:
        return error
    kinematics = model.guidance.kinematics
    found = driver_misses(kinematics, kinematics.create_data(), error.time, error.positions)
    if not found:
        return error
    named = "; ".join(_miss(name, rows) for name, rows in found[:NAMED])
    more = f"; and {len(found) - NAMED} more" if len(found) > NAMED else ""
    where = f" ({model.source})" if model.source else ""
    return AssemblyError(
        f"model '{model.name}'{where}: at t = {error.time:g} s the guides ask for a pose out of "
        f"the joints' reach; as near as they come, {named}{more} (check the gait: a stride or "
        "a step too long for the legs, or the rest posture)", error.time, error.positions)


def _miss(name: str, rows: list[tuple[str, float, str]]) -> str:
    """``guide 'LH' is 40.3 mm off (LH/x +26.6 mm, LH/y -0.724 mm, LH/z +30.2 mm)``: the
    distance when every row is a length."""
    shown = ", ".join(f"{row} {value * 1e3:+.3g} mm" if kind == "length" else
                      f"{row} {value:+.3g} rad" for row, value, kind in rows)
    lengths = [value for _, value, kind in rows if kind == "length"]
    off = f" {np.linalg.norm(lengths) * 1e3:.3g} mm" if len(lengths) == len(rows) else ""
    return f"guide '{name}' is{off} off ({shown})"
