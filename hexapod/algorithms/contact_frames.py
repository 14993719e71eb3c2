"""Where the unilateral contacts of a model are, and how fast they close: gaps and the contact
Jacobian in each contact's own axes (normal first, then the tangents).

A contact (a ``ground-contact`` force element, :class:`~hexapod.model.infos.SurfaceContact`)
touches with a point ``P`` of a body, fixed in its centre-of-mass frame at ``s``. Its gap is
``g = n . (P - S)`` and its velocity in the contact's axes ``u = [n; t_1; t_2] v_P = J v``,
with ``v_P = J_P v`` the point's world velocity:

* a spatial body, ``P = r + R s``: ``J_P = [I, -R [s]x]`` on ``(r_dot, omega')`` (the angular
  velocity in body axes, as the model's velocities);
* a planar body, ``P = r + R(theta) s``: ``J_P = [I, k x R s]`` on ``(x_dot, y_dot,
  theta_dot)``;
* a particle, ``P = r + s``: ``J_P = I``.

The contacts' acceleration is ``J v_dot + b`` with the bias ``b = J_dot v`` (a plane's axes are
fixed): ``R (w' x (w' x s))`` for a spatial body, ``-theta_dot^2 R s`` for a planar one, zero
for a particle (:func:`contact_bias`, formed by CasADi from the Jacobian's expressions along
``q_dot(q, v)``: 276 -> 29 us a call for the six feet, where the NumPy formulas served).

These few numbers per contact are written once, as CasADi expressions
(:func:`contact_expressions`, which a kernel can take in), and :func:`contact_frames`
evaluates them through a run's call buffers (the walking robot's six feet: 19 us a call,
where the NumPy code they replace took 50).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from hexapod._support.fastcall import FastFunction, dense_outputs
from hexapod.errors import HexapodError
from hexapod.model.data import Data, kept
from hexapod.model.infos import ForceInfo
from hexapod.model.model import Model
from hexapod.spatial import rotation_2d, rotation_from_euler_parameters


@dataclass(frozen=True)
class ContactFrames:
    """The unilateral contacts at one state.

    Attributes
    ----------
    gaps : ndarray, shape (m,)
        ``n . (P - S)`` per contact (m): positive when apart.
    jacobian : ndarray, shape (m d, n_v)
        Rows ``[n; t_1 ...]`` of each contact in turn (``d`` the scene's dimension).
    scaled : ndarray, shape (m d, n_v)
        ``jacobian M^-1/2``: the rows on the mass-scaled velocities ``M^1/2 v`` (the transpose
        of what the contact schemes' kernels take).
    points : ndarray, shape (m, d)
        The touching points, world (m).
    axes : ndarray, shape (m, d, d)
        Each contact's axes as rows (normal, tangents), world.
    """

    gaps: np.ndarray
    jacobian: np.ndarray
    points: np.ndarray
    axes: np.ndarray
    scaled: np.ndarray


def ground_contacts(model: Model) -> tuple[ForceInfo, ...]:
    """The model's unilateral contacts (its ``ground-contact`` force elements), in order."""
    return tuple(f for f in model.forces if f.contact is not None)


def refuse_contacts(model: Model) -> None:
    """Raise a :class:`~hexapod.errors.HexapodError` when ``model`` has unilateral contacts:
    their forces only a contact scheme decides, over a step, and an analysis at an instant (or
    along a prescribed motion) would leave them out as if they were not there.

    Parameters
    ----------
    model : Model
    """
    touching = [f.name for f in ground_contacts(model)]
    if touching:
        raise HexapodError(
            f"model '{model.name}' has unilateral contacts ("
            + ", ".join(f"'{n}'" for n in touching[:5]) + "), whose forces only a contact "
            "scheme decides, over time: simulate it (method moreau-jean or event-driven); an "
            "analysis at an instant or along a prescribed motion would leave them out")


def contact_frames(model: Model, q: np.ndarray,
                   contacts: tuple[ForceInfo, ...] | None = None,
                   data: Data | None = None) -> ContactFrames:
    """Gaps, Jacobian, points and axes of ``contacts`` (default all the model's) at ``q``.

    Parameters
    ----------
    model : Model
    q : ndarray, shape (n_q,)
    contacts : tuple of ForceInfo, optional
        Default :func:`ground_contacts`.
    data : Data, optional
        A run's workspace, whose call buffers serve the evaluation (fresh ones without it).

    Returns
    -------
    ContactFrames
    """
    contacts = ground_contacts(model) if contacts is None else contacts
    d, m = model.dimension, len(contacts)
    if not m:
        return ContactFrames(np.zeros(0), np.zeros((0, model.n_v)), np.zeros((0, d)),
                             np.zeros((0, d, d)), np.zeros((0, model.n_v)))
    key = ("contact frames", tuple(id(c) for c in contacts))
    function, axes = model.built_once(key, lambda built: _frames_function(built, contacts))
    evaluate = kept(data, key, lambda: FastFunction(function))
    gaps, jacobian, points, scaled = evaluate(np.asarray(q, dtype=float))
    return ContactFrames(gaps, jacobian.reshape(m * d, model.n_v), points.reshape(m, d),
                         axes.copy(), scaled.reshape(m * d, model.n_v))


def contact_gaps(model: Model, q: np.ndarray, contacts: tuple[ForceInfo, ...],
                 data: Data | None = None) -> np.ndarray:
    """The gaps of ``contacts`` at ``q`` alone (:attr:`ContactFrames.gaps`), through the call
    buffers of ``data``: what a position correction reads, without the Jacobians."""
    key = ("contact gaps", tuple(id(c) for c in contacts))
    function = model.built_once(key, lambda built: _gaps_function(built, contacts))
    return kept(data, key, lambda: FastFunction(function))(np.asarray(q, dtype=float))[0]


def contact_expressions(model: Model, q, contacts: tuple[ForceInfo, ...]) -> tuple:
    """``(gaps, jacobian, points)`` of ``contacts`` at the positions ``q`` (CasADi SX):
    :func:`contact_frames`'s quantities as expressions (see the module's description for the
    formulas), ``points`` stacked, ``(m d,)``."""
    fixed = model.built_once(("contact statics",), _statics)
    d = model.dimension
    gaps, points = [], []
    jacobian = ca.SX(len(contacts) * d, model.n_v)
    for k, element in enumerate(contacts):
        info, columns, local, frame, skew_local, surface = fixed[id(element)]
        qb, axes = q[info.q], ca.DM(frame)
        if info.kind == "spatial":  # J_P = [I, -R [s]x]
            rotation = rotation_from_euler_parameters(qb[3:])
            point = qb[:3] + ca.mtimes(rotation, ca.DM(local))
            block = ca.horzcat(axes, -ca.mtimes(axes, ca.mtimes(rotation, ca.DM(skew_local))))
        elif info.kind == "planar":  # J_P = [I, k x R s]
            arm = ca.mtimes(rotation_2d(qb[2]), ca.DM(local))
            point = qb[:2] + arm
            block = ca.mtimes(axes, ca.vertcat(ca.horzcat(1.0, 0.0, -arm[1]),
                                               ca.horzcat(0.0, 1.0, arm[0])))
        else:  # a particle: J_P = I
            point, block = qb + ca.DM(local), axes
        jacobian[k * d:(k + 1) * d, columns.tolist()] = block
        gaps.append(ca.dot(axes[0, :].T, point - ca.DM(surface)))
        points.append(point)
    return ca.vertcat(*gaps), jacobian, ca.vertcat(*points)


def _frames_function(model: Model, contacts: tuple[ForceInfo, ...]) -> tuple:
    """The Function ``q -> (gaps, jacobian, points, scaled)`` of ``contacts`` and their axes
    (rows: normal, tangents), built once per model and contact set."""
    fixed = model.built_once(("contact statics",), _statics)
    q = ca.SX.sym("q", model.n_q)
    gaps, jacobian, points = contact_expressions(model, q, contacts)
    scaled = ca.mtimes(jacobian, ca.sparsify(ca.DM(model.mass_inv_sqrt.dense())))
    function = ca.Function("contact_frames", [q], [gaps, jacobian, points, scaled], ["q"],
                           ["gaps", "jacobian", "points", "scaled"])
    return dense_outputs(function), np.array([fixed[id(c)][3] for c in contacts])


def _gaps_function(model: Model, contacts: tuple[ForceInfo, ...]) -> ca.Function:
    """The Function ``q -> gaps`` of ``contacts``."""
    q = ca.SX.sym("q", model.n_q)
    gaps = contact_expressions(model, q, contacts)[0]
    return dense_outputs(ca.Function("contact_gaps", [q], [gaps], ["q"], ["gaps"]))


def _statics(model: Model) -> dict:
    """Per contact element (by identity): its body's info and velocity columns, the touching
    point in the body's centre-of-mass frame, its axes as rows (normal, tangents), the point's
    cross-product matrix (a spatial body's) and a point of its surface: what
    :func:`contact_frames` reads at every state, formed once per model."""
    out = {}
    for element in ground_contacts(model):
        surface = element.contact
        local = np.asarray(element.points[0], dtype=float)
        info = model.bodies[element.bodies[0]]
        out[id(element)] = (info, np.arange(model.n_v)[info.v], local,
                            np.vstack([surface.normal, surface.tangents]),
                            _skew(local) if local.size == 3 else None,
                            np.asarray(surface.surface_point, dtype=float))
    return out


def contact_bias(model: Model, q: np.ndarray, v: np.ndarray,
                 contacts: tuple[ForceInfo, ...] | None = None,
                 data: Data | None = None) -> np.ndarray:
    """``J_dot v``: the contacts' acceleration, in their axes, at zero accelerations.

    Parameters
    ----------
    model : Model
    q, v : ndarray
        Positions and velocities.
    contacts : tuple of ForceInfo, optional
        Default :func:`ground_contacts`.
    data : Data, optional
        A run's workspace, whose call buffers serve the evaluation.

    Returns
    -------
    ndarray, shape (m d,)
    """
    contacts = ground_contacts(model) if contacts is None else contacts
    if not contacts:
        return np.zeros(0)
    key = ("contact bias", tuple(id(c) for c in contacts))
    function = model.built_once(key, lambda built: _bias_function(built, contacts))
    evaluate = kept(data, key, lambda: FastFunction(function))
    return evaluate(np.asarray(q, dtype=float), np.asarray(v, dtype=float))[0]


def _bias_function(model: Model, contacts: tuple[ForceInfo, ...]) -> ca.Function:
    """The Function ``(q, v) -> J_dot v`` of ``contacts``: the derivative of ``J(q) v`` along
    the positions' rate ``q_dot(q, v)`` (CasADi's forward mode on the Jacobian's expressions,
    so that the bias is the Jacobian's own: ``R (w' x (w' x s))`` for a spatial body,
    ``-theta_dot^2 R s`` for a planar one)."""
    q, v = ca.SX.sym("q", model.n_q), ca.SX.sym("v", model.n_v)
    jacobian = contact_expressions(model, q, contacts)[1]
    q_dot = model.qdot(q, v)
    bias = ca.jtimes(ca.mtimes(jacobian, v), q, q_dot)
    return dense_outputs(ca.Function("contact_bias", [q, v], [bias], ["q", "v"],
                                     ["bias"]))


def armed(frames: ContactFrames, contacts: tuple[ForceInfo, ...]) -> np.ndarray:
    """Which ``contacts`` may touch down at the state of ``frames`` (theirs): those without an
    arming condition, and those ahead of the contact they name along their ``forward``.

    Parameters
    ----------
    frames : ContactFrames
    contacts : tuple of ForceInfo
        All the model's contacts (those named by the conditions among them).

    Returns
    -------
    ndarray of bool, shape (m,)
    """
    index = {c.name: k for k, c in enumerate(contacts)}
    out = np.ones(len(contacts), dtype=bool)
    for k, element in enumerate(contacts):
        other = element.contact.armed_ahead_of
        if other is not None:
            ahead = frames.points[k] - frames.points[index[other]]
            out[k] = ahead @ element.contact.forward > 0.0
    return out


def _skew(s: np.ndarray) -> np.ndarray:
    """``[s]x``: ``[s]x w = s x w``."""
    return np.array([[0.0, -s[2], s[1]], [s[2], 0.0, -s[0]], [-s[1], s[0], 0.0]])
