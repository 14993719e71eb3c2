"""Liaison forces: the wrench each joint transmits, from the multipliers.

**Report convention**: the wrench exerted **by the parent on the child**, **about the joint
origin**, **in the child's joint frame**. For joint ``k`` it gathers the joint's own rows, the
driver rows on it and the force elements acting across it. From a generalized force ``g`` on
the child (``g = -Phi_v^T lambda`` over those rows, plus the elements' forces): the force ``f``
and the moment about the centre of mass ``n'`` (body axes) are moved to the joint origin ``P``,
``T_P = A n' + (r - P) x f``, then expressed in the joint frame. When the child is the ground,
the parent's generalized force is used with the opposite sign (action and reaction).

Planar wrenches are embedded in 3-D: ``(Fx, Fy, 0)`` and ``(0, 0, Tz)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from hexapod.algorithms.step_terms import terms_of
from hexapod.errors import HexapodError
from hexapod.model.model import Data, JointInfo, Model

if TYPE_CHECKING:
    from scipy.sparse import sparray


@dataclass(frozen=True)
class JointWrenches:
    """Wrenches of every joint at one state. Arrays have one row per joint, in model order.

    Attributes
    ----------
    names : tuple of str
        The joints' names.
    force, torque : ndarray (n_joints, 3)
        N and N m, about the joint origin, in the child's joint frame (or world axes when
        computed with ``frame="world"``).
    effort : ndarray (n_joints,)
        The effort ``tau`` along the coordinate of the joints that have one (a revolute joint's
        torque about its axis, a prismatic joint's force along it: the wrench dotted with the
        joint type's twist), NaN for the other joints. Equals ``-lambda`` of a driver on the
        joint plus the efforts and torsion springs acting across it.
    frame : {"joint", "world"}
        The axes of ``force`` and ``torque``.
    """

    names: tuple[str, ...]
    force: np.ndarray
    torque: np.ndarray
    effort: np.ndarray
    frame: str

    def as_dict(self) -> dict[str, dict[str, float]]:
        out = {}
        for k, name in enumerate(self.names):
            row = dict(zip(("Fx", "Fy", "Fz"), self.force[k].tolist(), strict=True))
            row.update(zip(("Tx", "Ty", "Tz"), self.torque[k].tolist(), strict=True))
            if np.isfinite(self.effort[k]):
                row["tau"] = float(self.effort[k])
            out[name] = row
        return out


def _embed_rotation(R: np.ndarray) -> np.ndarray:
    if R.shape == (3, 3):
        return R
    out = np.eye(3)
    out[:2, :2] = R
    return out


def _embed_vector(x: np.ndarray) -> np.ndarray:
    """2-D columns (2, m) -> 3-D (3, m) with zero z."""
    return x if x.shape[0] == 3 else np.vstack([x, np.zeros((1,) + x.shape[1:])])


def joint_origin(model: Model, q: np.ndarray, joint: JointInfo):
    """World position (3-D) and rotation (3 x 3) of the joint frame, which is fixed to the child."""
    pose = model.body_pose(q, joint.child) @ joint.child_frame
    return _embed_vector(pose.position[:, None])[:, 0], _embed_rotation(pose.rotation)


def parent_point(model: Model, q: np.ndarray, joint: JointInfo):
    """World position (3-D) and rotation (3 x 3) of the joint's frame on the parent."""
    pose = model.body_pose(q, joint.parent) @ joint.parent_frame
    return _embed_vector(pose.position[:, None])[:, 0], _embed_rotation(pose.rotation)


def joint_wrenches(model: Model, data: Data, *, frame: str = "joint",
                   on: str = "child") -> JointWrenches:
    """Wrench of every joint at the state of ``data`` (report convention: by the parent on the
    child, about the joint origin, in the child's joint frame).

    Parameters
    ----------
    model, data : Model, Data
        ``data`` filled at one state by :func:`~hexapod.algorithms.dynamics.forward_dynamics`
        (or by the inverse dynamics): it supplies ``q``, the multipliers ``lam``, ``Phi_v`` and
        the forces of the elements acting across joints ``Q_across``.
    frame : {"joint", "world"}
        Axes of the components.
    on : {"child", "parent"}
        ``"parent"`` gives the reaction on the parent: the opposite wrench, its moment about the
        parent's joint point (which differs from the child's for prismatic and distance joints),
        in the parent's joint frame (or world axes); ``effort`` stays that of the child.

    Returns
    -------
    JointWrenches
        N and N m.

    Raises
    ------
    HexapodError
        ``data`` holds no solved state of this model.
    """
    _require_solved(model, data, "joint_wrenches")
    return wrenches_from_multipliers(model, data.q, data.lam, data.Phi_v, data.Q_across,
                                     frame=frame, on=on, w=data.w)


def driver_efforts(model: Model, data: Data) -> dict[str, float]:
    """The effort each driver exerts along its coordinate at the state of ``data``:
    ``-lambda_d`` (N m about a revolute axis, N along a prismatic one), by driver name.

    Parameters
    ----------
    model, data : Model, Data
        ``data`` filled at one state by :func:`~hexapod.algorithms.dynamics.forward_dynamics`
        (or by the inverse dynamics).

    Returns
    -------
    dict of str to float
        N m or N, by driver name (a coordinate driver's: N, or N m for an angle).

    Raises
    ------
    HexapodError
        ``data`` holds no multipliers of this model.
    """
    _require_solved(model, data, "driver_efforts")
    return {d.name: float(-data.lam[d.row]) for d in model.drivers}


def _require_solved(model: Model, data: Data, caller: str) -> None:
    missing = [name for name in ("q", "lam", "Phi_v") if getattr(data, name) is None]
    if model.Q_across is not None and data.Q_across is None:
        missing.append("Q_across")
    if missing:
        raise HexapodError(f"{caller}: data holds no solved state ({', '.join(missing)} not "
                           "computed): call forward_dynamics(model, data, t, q, v) first")
    if data.lam.shape != (model.n_c,) or data.q.shape != (model.n_q,):
        raise HexapodError(f"{caller}: data was filled by another model ({data.lam.size} "
                           f"multipliers, model '{model.name}' has {model.n_c} rows)")


def wrenches_from_multipliers(model: Model, q: np.ndarray, lam: np.ndarray,
                              Phi_v: np.ndarray | sparray,
                              Q_across: np.ndarray | None = None, *, frame: str = "joint",
                              on: str = "child", data: Data | None = None,
                              w: np.ndarray | None = None) -> JointWrenches:
    """:func:`joint_wrenches` from explicit multipliers (n_c) at positions ``q`` (n_q), e.g.
    those of a recorded simulation; ``Q_across`` is ``model.Q_across`` at the same state (None
    leaves out the force elements acting across joints). The wrenches come from their one
    definition (:meth:`hexapod.algorithms.step_terms.StepTerms.report`), evaluated through
    the call buffers of ``data`` when it is given.

    Parameters
    ----------
    model : Model
    q : ndarray, shape (n_q,)
        Positions.
    lam : ndarray, shape (n_c,)
        Multipliers at ``q``.
    Phi_v : ndarray or scipy.sparse array, shape (n_c, n_v)
        The constraint Jacobian at ``q``.
    Q_across : ndarray, shape (n_v, k), optional
        ``model.Q_across`` at the same state.
    frame, on : str
        As for :func:`joint_wrenches`.
    data : Data, optional
        A workspace of ``model`` whose call buffers to use.
    w : ndarray, shape (n_w,), optional
        The laws' values at the state; they matter only where a design parameter moves a
        joint's frame (a model of ``assemble(moved_frames=...)``), zero at the scene's
        values, which None takes.

    Returns
    -------
    JointWrenches

    Raises
    ------
    ValueError
        ``frame`` or ``on`` is not one of the choices.
    """
    if on not in ("child", "parent"):
        raise ValueError(f"on must be 'child' or 'parent', got {on!r}")
    if frame not in ("joint", "world"):
        raise ValueError(f"frame must be 'joint' or 'world', got {frame!r}")
    terms = terms_of(model)
    n = len(model.joints)
    w = np.zeros(model.n_w) if w is None else w
    wrench, frames = terms.evaluate(data, "report", q, w, terms.nonzeros(Phi_v), lam,
                                    terms.offset(data, q, w, Q_across))
    wrench, frames = wrench.reshape(6, n), frames.reshape(9, n)
    force, torque, effort = np.zeros((n, 3)), np.zeros((n, 3)), np.full(n, np.nan)
    for k, joint in enumerate(model.joints):
        f, t = wrench[:3, k], wrench[3:, k]  # joint frame, about the joint origin
        effort[k] = joint.type.effort(f, t, model.dimension)
        if frame == "joint" and on == "child":
            force[k], torque[k] = f, t
            continue
        R = frames[:, k].reshape(3, 3, order="F")
        f, t = R @ f, R @ t
        if on == "parent":
            origin = joint_origin(model, q, joint)[0]
            point, R = parent_point(model, q, joint)
            f, t = -f, -t + np.cross(origin - point, -f)
        if frame == "joint":
            f, t = R.T @ f, R.T @ t
        force[k], torque[k] = f, t
    return JointWrenches(tuple(j.name for j in model.joints), force, torque, effort, frame)


def policy_map(model: Model, q: np.ndarray, w: np.ndarray, Phi_v,
               Q_across: np.ndarray | None = None,
               data: Data | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The linear map from multipliers to the wrenches of the least-wrench redundancy policy,
    and its offset: one block of 6 rows per joint (force, moment about the joint origin divided
    by the characteristic length ``l``; world axes, since norms do not depend on axes) and per
    coordinate driver (force and moment about the body's centre of mass). The policy minimises
    ``|map @ lam + offset|^2``. Written once, as CasADi expressions
    (:meth:`hexapod.algorithms.step_terms.StepTerms.wrench_map`), evaluated here on numbers
    (through the call buffers of ``data``, when given)."""
    terms = terms_of(model)
    (A,) = terms.evaluate(data, "wrench_map", q, w, terms.nonzeros(Phi_v))
    return A, terms.offset(data, q, w, Q_across)


def efforts_and_axes(model: Model, force: np.ndarray, torque: np.ndarray,
                     rotations: np.ndarray | None, frame: str
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The efforts of joint-frame wrenches, and the wrenches in the axes ``frame`` asks.

    Parameters
    ----------
    model : Model
    force, torque : ndarray, shape (..., J, 3)
        Joint wrenches in the report convention, joint frames.
    rotations : ndarray, shape (..., J, 9), or None
        The joint frames' rotations, column-major (the ``frames`` of the wrench Function);
        needed for ``frame="world"`` only.
    frame : {"joint", "world"}

    Returns
    -------
    force, torque : ndarray, shape (..., J, 3)
        In the axes asked.
    effort : ndarray, shape (..., J)
        Along each joint's coordinate (NaN without one).
    """
    effort = np.full(force.shape[:-1], np.nan)
    for j, joint in enumerate(model.joints):
        effort[..., j] = joint.type.effort(force[..., j, :], torque[..., j, :], model.dimension)
    if frame == "world":
        R = rotations.reshape(rotations.shape[:-1] + (3, 3)).swapaxes(-1, -2)
        force = np.einsum("...ab,...b->...a", R, force)
        torque = np.einsum("...ab,...b->...a", R, torque)
    return force, torque, effort
