"""Design sensitivities of an inverse-dynamics result: the derivatives of every joint effort,
joint wrench and ground reaction with respect to the bodies' masses and inertias, the friction
coefficient and the joints' positions.

Along a prescribed motion the positions, velocities and accelerations do not depend on the
masses and inertias; only the multipliers do, through the right-hand side of

    Phi_v^T lambda = Q - M v_dot,

which is linear in them: a body's mass ``m`` and inertia ``J`` (centre-of-mass axes) enter it as
``m (g - a)`` on its translation rows and ``-(J alpha + omega' x J omega')`` on its rotation rows.
The scene's redundancy policies (least wrench, least effort, with the feet's load sharing)
choose multipliers linear in that right-hand side, and the wrenches and efforts are linear in
the multipliers. So the derivative with respect to a parameter ``p`` that changes the inertia
of one body by ``(dm/dp, dJ/dp)`` is the solution of the same saddle-point system and policy
(:func:`hexapod.algorithms.dynamics.policy_solution`) for the forces
``dm/dp (g - a) - (dJ/dp alpha + omega' x dJ/dp omega')``, with a zero ``gamma`` and without the
force elements across joints: exact, not a difference quotient, and computed by the one solve
the inverse dynamics uses. The friction policy (a QP over a pyramid) is piecewise linear: its
derivative is taken on the active set of each sample's solution (the constraints held at
equality stay so), and the samples where that set changes are named; the friction coefficient
moves the active faces, and the forces follow on the same set.

A joint's position (a segment's length) moves the motion itself. For an open tree with every
joint driven, the tree path builds the whole sample as one CasADi graph
(:meth:`hexapod.algorithms.inverse.TreePlan.graph`): with the joints' frame origins as
expressions of the parameters, its forward-mode derivative gives the positions', velocities',
accelerations' and wrenches' derivatives exactly.

A parameter that changes the laws alone (the gait's step height: the feet's paths, which the
walking robot's legs follow) moves the motion through them: :class:`LawChange`, derived by the
phase path's sample Function differentiated in forward mode
(:mod:`hexapod.algorithms.law_tangents`: the implicit function theorem on the positions, then
the same solves and policy). Where loops close, feet stand or joints follow guides (the
walking robot), a joint's position becomes such a parameter: the scene is assembled again
with the joint's frame origins shifted by a symbol held as a law (zero:
:class:`~hexapod.scene.laws.base.DesignShift`), whose derivative is one. On the child, the
shift also moves the point the joint's wrench is reported (and weighed by the least-wrench
policy) about, and the characteristic length the policy weighs moments by, which the scene
measures on the joints' points: both follow it. Where the rows a rank decision leaves out
cannot follow the change (a robot on pinned feet whose joints' laws were written for the
scene's lengths), there is no moved motion, and that is said.

The gait's period ``T`` is the exception among them: a scene whose time laws are all functions
of the gait's phase ``t / T`` (as the gait builders make them: each foot's path, the coupled
joints, the stance schedule, the trunk's advance of one stride per period) passes, with
another period, through the same poses at the same fractions of the stride, its velocities
scaled by ``1 / T`` and its accelerations by ``1 / T^2``. At a fixed phase the positions do not
move, and the right-hand side ``Q(q, v) - M v_dot`` changes by
``(-dQ/dv v + 2 M v_dot) / T``: the derivative with respect to the period is the same
policy solve for these forces (:class:`PeriodChange`; derivatives at fixed phase, as the
figures of merit over a stride compare them).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from hexapod.algorithms.dynamics import policy_tangents
from hexapod.algorithms.kinematics import state_split
from hexapod.algorithms.liaison import efforts_and_axes
from hexapod.algorithms.saddle import constraint_jacobian, dynamics_terms
from hexapod.algorithms.step_terms import terms_of
from hexapod.errors import HexapodError
from hexapod.model.model import Model

if TYPE_CHECKING:
    from hexapod.algorithms.inverse import InverseResult

__all__ = ["FrameChange", "FrictionChange", "InertiaChange", "InverseSensitivity", "LawChange",
           "PeriodChange", "ScaleChange", "check_parameters", "inverse_sensitivities", "moved_laws",
           "tree_solved"]


@dataclass(frozen=True)
class InertiaChange:
    """How one design parameter changes one body's inertia.

    Attributes
    ----------
    name : str
        The parameter's name (a scene key, e.g. ``body.femur.mass``).
    body : str
        The body it belongs to.
    mass : float
        ``dm/dp``, kg per unit of the parameter.
    inertia : ndarray, shape (3, 3) or (1, 1)
        ``dJ/dp``, kg m^2 per unit of the parameter, in the body's centre-of-mass axes (a
        planar body's is 1 x 1; zero for a particle).
    unit : str
        The parameter's SI unit (``kg``, ``kg m^2``).
    value : float
        The parameter's value, in ``unit`` (for elasticities; NaN if unknown).
    scene_scale : float
        ``unit`` per unit of the value the scene writes (1, or the square of the scene's
        length unit in metres for an inertia in kg L^2).
    """

    name: str
    body: str
    mass: float
    inertia: np.ndarray
    unit: str
    value: float = float("nan")
    scene_scale: float = 1.0


@dataclass(frozen=True)
class FrameChange:
    """How one design parameter moves one joint's origin (a segment's length, a joint's
    position): the joint frame's origin on its parent and on its child, each in that body's
    centre-of-mass frame, per unit of the parameter.

    Attributes
    ----------
    name : str
        The parameter's name (a scene key, e.g. ``joint.fti.origin.0``).
    joint : str
        The joint it moves.
    parent, child : ndarray, shape (3,)
        ``d origin / dp`` on the parent and on the child, m per m.
    unit : str
        ``m``.
    value : float
        The parameter's value, m.
    scene_scale : float
        Metres per unit of the value the scene writes.
    """

    name: str
    joint: str
    parent: np.ndarray
    child: np.ndarray
    unit: str = "m"
    value: float = float("nan")
    scene_scale: float = 1.0
    mass: float = 0.0  # it changes no mass


@dataclass(frozen=True)
class FrictionChange:
    """The friction coefficient ``mu`` of the scene's ground (``ground.mu``) as a parameter:
    it bounds the friction policy's forces (the other policies do not see it).

    Attributes
    ----------
    name : str
        ``ground.mu``.
    value : float
        Its value.
    unit : str
        ``1``.
    """

    name: str = "ground.mu"
    value: float = float("nan")
    unit: str = "1"
    scene_scale: float = 1.0
    mass: float = 0.0  # it changes no mass


@dataclass(frozen=True)
class PeriodChange:
    """The gait's period ``T`` (``gait.period``) as a parameter, the motion kept at the same
    fractions of the stride (see the module's text): derivatives at fixed phase. For a scene
    whose time laws are all functions of the phase ``t / T`` (the gait builders' scenes);
    :func:`inverse_sensitivities` checks that the model's periodic laws repeat with ``value``
    and that it has no force element (a load's, a spring's or a controller's change with the
    period is not known: only gravity and the inertial forces are derived).

    Attributes
    ----------
    name : str
        ``gait.period``.
    value : float
        The period, s.
    unit : str
        ``s``.
    """

    name: str = "gait.period"
    value: float = float("nan")
    unit: str = "s"
    scene_scale: float = 1.0
    mass: float = 0.0  # it changes no mass


@dataclass(frozen=True, eq=False)
class LawChange:
    """A parameter that changes the scene's laws (``gait.step_height``: the feet's paths),
    the rest of the scene kept: each law it changes and the law of its derivative (value,
    rate and acceleration per unit of the parameter, SI). The motion moves with it: its
    derivatives are the phase path's, differentiated (:mod:`hexapod.algorithms.law_tangents`).

    Attributes
    ----------
    name : str
        The parameter's name (a scene key, or a builder's argument).
    laws : dict
        Scene law -> its derivative's law.
    unit : str
        The parameter's SI unit.
    value : float
        Its value, in ``unit``.
    scene_scale : float
        ``unit`` per unit of the value the scene writes.
    key : str
        The scene key the laws answer to (:meth:`hexapod.scene.Law.design_parameter`), which
        the model's contacts answer too (their footholds and load-sharing weights: the duty
        factor); "" for none.
    """

    name: str
    laws: dict
    unit: str = "m"
    value: float = float("nan")
    scene_scale: float = 1.0
    mass: float = 0.0  # it changes no mass
    key: str = ""


@dataclass(frozen=True)
class ScaleChange:
    """The geometric scale ``s`` (``geometric_scale``), relative to the scene as given
    (``value`` 1):
    every length times ``s``, masses times ``s^3``, inertias times ``s^5`` (as the robot
    builders' ``scale`` argument), the motion's times kept. Its lengths move the motion
    (the scene assembled again with them scaled by a symbol: ``moved``); its masses and
    inertias are the inertial forces' change along the motion.

    Attributes
    ----------
    mass : float
        ``dm/ds``, the model's total mass times 3 (kg).
    """

    name: str = "geometric_scale"
    value: float = 1.0
    unit: str = "1"
    scene_scale: float = 1.0
    mass: float = 0.0


@dataclass
class InverseSensitivity:
    """Derivatives of an :class:`~hexapod.algorithms.inverse.InverseResult`'s forces, the
    parameters along the last axis.

    Attributes
    ----------
    parameters : tuple of InertiaChange
        The parameters, in the order of the last axis.
    effort : ndarray (N, J, P)
        ``d tau / dp`` (NaN for the joints without a coordinate).
    force, torque : ndarray (N, J, 3, P)
        Derivatives of the joint wrenches, in the result's axes (``frame``).
    ground_force : ndarray (N, C, 3, P)
        Derivatives of the ground's force on each foot, world axes.
    q : ndarray (N, n_q, P)
        Derivatives of the positions (zero but for parameters that move joints or change
        laws).
    active_set_changes : ndarray
        With the friction policy, the sample times where the constraints its QP holds at
        equality differ from the sample before: there the forces are piecewise linear in the
        parameters and the derivatives one-sided (empty for the other policies).
    """

    parameters: tuple[InertiaChange | FrameChange | FrictionChange | PeriodChange | LawChange
                      | ScaleChange, ...]
    effort: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    ground_force: np.ndarray
    q: np.ndarray
    active_set_changes: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: (N, n_w, P): the derivatives of the laws' rates (those of a guided model's guided
    #: joints: their coordinates'), nonzero for the parameters that change laws only
    rates: np.ndarray | None = None


def inertial_force_changes(model: Model, change: InertiaChange, v: np.ndarray,
                           v_dot: np.ndarray) -> np.ndarray:
    """``d(Q - M v_dot)/dp`` (N, n_v) at the states ``(v, v_dot)`` (N, n_v) for one
    parameter."""
    info = model.bodies[model.body_index[change.body]]
    out = np.zeros(v.shape)
    start, dim = info.v.start, model.gravity.size
    linear = slice(start, info.v.stop if info.kind == "particle" else start + dim)
    out[:, linear] = change.mass * (model.gravity[:linear.stop - start] - v_dot[:, linear])
    if info.kind == "spatial":
        omega, alpha = v[:, start + 3:start + 6], v_dot[:, start + 3:start + 6]
        dJ = change.inertia
        out[:, start + 3:start + 6] = -(alpha @ dJ.T) - np.cross(omega, omega @ dJ.T)
    elif info.kind == "planar":
        out[:, start + 2] = -float(change.inertia[0, 0]) * v_dot[:, start + 2]
    return out


def scale_force_changes(model: Model, v: np.ndarray, v_dot: np.ndarray) -> np.ndarray:
    """``d(Q - M v_dot)/ds`` of the masses (``3 m``) and inertias (``5 J``) under the
    geometric scale, every body's, along the states ``(v, v_dot)`` (N, n_v)."""
    return sum((inertial_force_changes(model, InertiaChange(
        "scale", body.name, 3.0 * body.mass, 5.0 * body.inertia, "1"), v, v_dot)
        for body in model.bodies), np.zeros(v.shape))


def period_force_changes(model: Model, change: PeriodChange, q: np.ndarray, v: np.ndarray,
                         v_dot: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``d(Q - M v_dot)/dT`` (N, n_v) at fixed phase, at the states ``(q, v, v_dot)`` (N, n_v)
    with the laws' values ``w`` (n_w, N): ``(C v + 2 M v_dot) / T``, ``C = -dQ/dv`` (the
    tangent damping of :attr:`~hexapod.model.model.Model.force_tangents`)."""
    tangents = model.force_tangents
    damping = np.empty_like(v)
    for k in range(v.shape[0]):
        values = {"q": q[k], "v": v[k], "w": w[:, k]}
        C = np.asarray(tangents(*[values[n] for n in tangents.name_in()])[1])
        damping[k] = C @ v[k]
    return (damping + 2.0 * (model.mass @ v_dot.T).T) / change.value


def _check_period(model: Model, change: PeriodChange) -> None:
    """Refuse a period the model's laws do not repeat with, or a model with force elements
    (gravity and the inertial forces alone are derived at fixed phase)."""
    periods = {c for law in model.laws if (c := law.cycle_time()) is not None}
    if not (np.isfinite(change.value) and change.value > 0
            and all(abs(p - change.value) <= 1e-12 * change.value for p in periods)
            and periods):
        shown = ", ".join(f"{p:g} s" for p in sorted(periods)) or "none"
        raise HexapodError(f"parameter '{change.name}': model '{model.name}' has no gait of "
                           f"period {change.value:g} s (its laws repeat with: {shown})")
    if model.forces:  # loads, springs, dampers, controllers: gravity and inertia alone
        raise HexapodError(
            f"parameter '{change.name}': model '{model.name}' has forces of its own (the "
            f"{model.forces[0].kind} '{model.forces[0].name}'), whose change with the period "
            "is not derived (a load may follow the period otherwise than by its phase: the "
            "front leg's ground reaction is the walking robot's at that period)")


def check_parameters(model: Model, parameters, moved: Model | None = None) -> None:
    """Raise what :func:`inverse_sensitivities` refuses before it computes anything (a run's
    caller checks first: see its ``Raises``)."""
    for change in parameters:
        if isinstance(change, PeriodChange):
            _check_period(model, change)
        through_motion = isinstance(change, LawChange | ScaleChange) or (
            isinstance(change, FrameChange) and not tree_solved(model))
        if through_motion and model.contacts and model.ground.policy == "friction" and (
                model.Q_across is not None):
            raise HexapodError(
                f"parameter '{change.name}': model '{model.name}' shares its ground forces by "
                "the friction policy and has forces across joints, whose wrenches the policy "
                "weighs: its derivative along a moving motion is not derived with them")
        if isinstance(change, ScaleChange):
            _check_scaled(model, change, moved)
        if isinstance(change, FrictionChange | PeriodChange | LawChange | ScaleChange):
            continue
        known = (model.joint_index if isinstance(change, FrameChange) else model.body_index)
        element = change.joint if isinstance(change, FrameChange) else change.body
        if element not in known:
            kind = "joint" if isinstance(change, FrameChange) else "body"
            raise HexapodError(f"parameter '{change.name}': model '{model.name}' has no {kind} "
                               f"'{element}'")
        if through_motion:
            _check_shifted(model, change, moved)


def tree_solved(model: Model) -> bool:
    """Whether a joint's position is derived by the tree path's graph: an open tree with
    every joint driven by its own laws (else through the phase path's step)."""
    from hexapod.algorithms.inverse import tree_plan

    return model.guidance is None and tree_plan(model) is not None


def _check_shifted(model: Model, change: FrameChange, moved: Model | None) -> None:
    """A joint moved in a model the tree path does not solve: not a foot, and the model
    assembled again with the shift as a symbol at hand."""
    joint = model.joints[model.joint_index[change.joint]]
    if joint.kind == "contact":
        raise HexapodError(f"parameter '{change.name}': joint '{change.joint}' is a foot's "
                           "contact: moving it is not derived")
    _require_moved(model, change, moved,
                   f"model '{model.name}' is not an open tree with every joint driven: the "
                   "derivative needs its scene assembled again with the joint's frame shifted "
                   "by a symbol")


def _check_scaled(model: Model, change: ScaleChange, moved: Model | None) -> None:
    """The scale: its model at hand; only gravity and the inertial forces scale as derived
    (a load's or a spring's change with the scale is not known), on flat ground."""
    if model.forces:
        raise HexapodError(
            f"parameter '{change.name}': model '{model.name}' has forces of its own (the "
            f"{model.forces[0].kind} '{model.forces[0].name}'), whose change with the scale is "
            "not derived")
    if model.contacts and model.ground.terrain is not None and not model.ground.terrain.flat:
        raise HexapodError(f"parameter '{change.name}': model '{model.name}' stands on "
                           "terrain that is not flat, whose heights' scaling is not derived")
    _require_moved(model, change, moved, "the derivative needs the scene assembled again with "
                   "its lengths scaled by a symbol")


def _require_moved(model: Model, change, moved: Model | None, why: str) -> None:
    """Raise ``why`` unless ``moved`` holds the symbol of ``change``."""
    if moved is None or change.name not in {law.name for law in moved_laws(model, moved)}:
        raise HexapodError(f"parameter '{change.name}': {why} (moved, from "
                           "hexapod.sweeps.moved_model)")


def moved_laws(model: Model, moved: Model) -> tuple:
    """The symbols of ``moved`` (``model`` assembled again with joints' frames shifted, or its
    lengths scaled, by symbols): its laws after ``model``'s."""
    return tuple(moved.laws[model.n_w:])


def inverse_sensitivities(model: Model, result: InverseResult,
                          parameters: Sequence[InertiaChange | FrameChange | FrictionChange
                                               | PeriodChange | LawChange],
                          *,
                          progress: Callable[[int, int], None] | None = None,
                          moved: Model | None = None) -> InverseSensitivity:
    """The derivatives of ``result``'s efforts, joint wrenches and ground forces with respect
    to each parameter, sample by sample (see the module's text for the method).

    Parameters
    ----------
    model : Model
        The model ``result`` was computed with.
    result : InverseResult
        An inverse-dynamics result of ``model``.
    parameters : sequence of InertiaChange, FrameChange, FrictionChange or PeriodChange
        What each parameter changes.
    progress : callable, optional
        Called with ``(samples done, samples)``.
    moved : Model, optional
        ``model``'s scene assembled again with the joints moved outside the tree path shifted
        by symbols (:func:`hexapod.sweeps.moved_model`): needed for them.

    Returns
    -------
    InverseSensitivity

    Raises
    ------
    HexapodError
        A parameter names a body or joint the model does not have; a joint moved in a model
        the tree path does not solve: a foot's, without ``moved``, or where the
        rows left out cannot follow; with the friction policy, the exact cone
        (``faces = 0``), a sample where no forces are inside the cones, or a parameter that
        moves the motion (changes the laws, or a joint outside the tree path); such a
        parameter at a sample the phase path's plans do not cover (a trunk on two feet).
    """
    parameters = tuple(parameters)
    check_parameters(model, parameters, moved)
    n, count, joints = result.times.size, len(parameters), len(model.joints)
    wrench = np.zeros((n, count, joints, 6))
    rotations = np.zeros((n, joints, 9))
    ground = np.zeros((n, len(model.contacts), 3, count))
    q = np.zeros((n, model.n_q, count))
    laws = [np.asarray(x, dtype=float).reshape(model.n_w, n)
            for x in model.law_values(result.times)]  # the laws' values at each sample
    inertial = [k for k, c in enumerate(parameters)
                if not isinstance(c, FrameChange | LawChange)]
    moving = [k for k, c in enumerate(parameters) if isinstance(c, FrameChange)]
    shifted: list[int] = []  # moved joints derived through the phase path's step
    if moving and not tree_solved(model):
        moving, shifted = [], moving
    changing = [k for k, c in enumerate(parameters) if isinstance(c, LawChange)]
    # the scale: its masses' and inertias' part along the motion, and its lengths' moving it
    shifted += [k for k, c in enumerate(parameters) if isinstance(c, ScaleChange)]
    changes = np.zeros(0)
    rates = np.zeros((n, model.n_w, count))
    turning = np.zeros((n, count, joints, 9))  # the joint frames' rotations' derivatives
    if inertial or not (moving or changing or shifted):
        part = _inertial_part(model, result, [parameters[k] for k in inertial], laws, progress)
        wrench[:, inertial], rotations, ground[..., inertial], changes = part
    if moving:
        wrench[:, moving], rotations, q[..., moving] = _moving_part(
            model, result, [parameters[k] for k in moving], laws)
    if changing or shifted:
        from hexapod.algorithms.law_tangents import law_tangents

        design, shifts = model, []
        if shifted:  # each shift (or the scale) a law of the moved model, named as it
            design = moved
            symbols = {law.name: law for law in moved_laws(model, moved)}
            shifts = [{symbols[parameters[k].name]: symbols[parameters[k].name].design_parameter(
                parameters[k].name)[1]} for k in shifted]
        tangents = law_tangents(design, result,
                                [parameters[k].laws for k in changing] + shifts,
                                keys=[parameters[k].key for k in changing] + [""] * len(shifts),
                                progress=progress)
        through = changing + shifted
        rotations, q[..., through] = tangents.frames, tangents.q
        wrench[:, through] += tangents.wrench  # to the scale's inertial part
        ground[..., through] += tangents.ground
        rates[..., through] = tangents.rates[:, :model.n_w]  # the shifts come last
        turning[:, through] = tangents.dframes
        changes = np.union1d(changes, tangents.changes)
    force, torque, effort = efforts_and_axes(model, wrench[..., :3], wrench[..., 3:],
                                             rotations[:, None], result.frame)
    if result.frame == "world" and (changing or shifted):  # the frames turn: R dF + dR F
        dR = turning.reshape(n, count, joints, 3, 3).swapaxes(-1, -2)
        force = force + np.einsum("npjab,njb->npja", dR, _in_joint_frames(
            result.force, rotations))
        torque = torque + np.einsum("npjab,njb->npja", dR, _in_joint_frames(
            result.torque, rotations))
    # (N, P, J, 3) -> (N, J, 3, P)
    return InverseSensitivity(parameters, effort.transpose(0, 2, 1),
                              force.transpose(0, 2, 3, 1), torque.transpose(0, 2, 3, 1),
                              ground, q, changes, rates)


def _in_joint_frames(world: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """Vectors ``world`` (N, J, 3) in world axes in the joint frames ``rotations`` (N, J, 9,
    column-major)."""
    R = rotations.reshape(rotations.shape[:-1] + (3, 3)).swapaxes(-1, -2)
    return np.einsum("njba,njb->nja", R, world)


def _inertial_part(model: Model, result, parameters, laws, progress):
    """The masses', inertias' and friction coefficient's: joint-frame wrenches (N, P, J, 6),
    the joint frames' rotations (N, J, 9), the ground forces (N, C, 3, P) and the friction
    QP's active-set changes (times)."""
    n, count, joints = result.times.size, len(parameters), len(model.joints)
    wrench = np.zeros((n, count, joints, 6))
    rotations = np.zeros((n, joints, 9))
    lams = np.zeros((n, model.n_c, count))
    data = model.create_data()
    terms = terms_of(model)
    friction = bool(model.contacts) and model.ground.policy == "friction"
    active: list[frozenset] = [frozenset()] * n
    forces = np.zeros((n, model.n_v, count))  # the friction coefficient changes no force
    for p, change in enumerate(parameters):
        if isinstance(change, InertiaChange):
            forces[..., p] = inertial_force_changes(model, change, result.v, result.v_dot)
        elif isinstance(change, PeriodChange):
            forces[..., p] = period_force_changes(model, change, result.q, result.v,
                                                  result.v_dot, laws[0])
        elif isinstance(change, ScaleChange):
            forces[..., p] = scale_force_changes(model, result.v, result.v_dot)
    along_mu = np.array([isinstance(c, FrictionChange) for c in parameters], dtype=float)
    for k, t in enumerate(result.times):
        q, v, w = result.q[k], result.v[k], laws[0][:, k]
        state = None
        if friction:  # the QP's active set at this state: its forces and Q_across
            values = {"q": q, "v": v, "w": w, "wd": laws[1][:, k], "wdd": laws[2][:, k]}
            Phi_v, gamma, Q = dynamics_terms(model, values, data)
            across = (model.call("Q_across", data, q=q, v=v, w=w)
                      if model.Q_across is not None else None)
            state = (Q, gamma, across)
        else:
            Phi_v = constraint_jacobian(model, q, w, data)
        split = state_split(model, data, q, w, Phi_v)
        lams[k], active[k] = policy_tangents(model, data, float(t), q, w, Phi_v, split,
                                             forces[k], state, tol=model.rank_tolerance,
                                             along_mu=along_mu)
        # the report's wrenches, without the forces across joints: linear in the multipliers
        B, frames = terms.evaluate(data, "report_map", q, w, terms.nonzeros(Phi_v))
        B = np.reshape(B, (6 * joints, model.n_c))
        wrench[k] = (B @ lams[k]).reshape(joints, 6, count).transpose(2, 0, 1)
        rotations[k] = np.reshape(frames, (9, joints)).T
        if progress is not None:
            progress(k + 1, n)
    rows = np.array([c.rows for c in model.contacts], dtype=int).reshape(-1, 3)
    changes = [k for k in range(1, n) if active[k] != active[k - 1]]
    return wrench, rotations, -lams[:, rows], result.times[np.array(changes, dtype=int)]


def _moving_part(model: Model, result, parameters, laws):
    """The moved joints': joint-frame wrenches (N, P, J, 6), rotations (N, J, 9) and
    positions (N, n_q, P), by the tree path's one graph with the joints' frame origins as
    expressions of the parameters, differentiated (forward mode, exact): for a model the
    tree path solves (:func:`tree_solved`)."""
    from hexapod.algorithms.inverse import tree_plan

    plan = tree_plan(model)
    key = ("moving-joints", tuple((c.joint, tuple(c.parent), tuple(c.child))
                                  for c in parameters))
    function = model.built_once(key, lambda m: _moving_function(m, plan, parameters))
    n, joints = result.times.size, len(model.joints)
    mapped = function.map(n, "serial") if n > 1 else function
    outputs = mapped(*laws)
    dq, dwrench, frames = (np.asarray(x) for x in outputs)
    count = len(parameters)
    dq = dq.reshape(model.n_q, count, n, order="F").transpose(2, 0, 1)
    dwrench = dwrench.reshape(6, joints, count, n, order="F").transpose(3, 2, 1, 0)
    rotations = frames.reshape(9, joints, n, order="F").transpose(2, 1, 0)
    return dwrench, rotations, dq


def _moving_function(model: Model, plan, parameters):
    """``(w, wd, wdd) -> (dq/dp, d wrench/dp, rotations)`` at the scene's values."""
    import casadi as ca

    w, wd, wdd = (ca.SX.sym(name, model.n_w) for name in ("w", "wd", "wdd"))
    p = ca.SX.sym("p", len(parameters))
    frames = [[ca.DM(j.parent_frame.position), ca.DM(j.child_frame.position)]
              for j in model.joints]
    for k, change in enumerate(parameters):
        j = model.joint_index[change.joint]
        frames[j][0] = frames[j][0] + p[k] * ca.DM(change.parent)
        frames[j][1] = frames[j][1] + p[k] * ca.DM(change.child)
    q, _, _, wrench, rotation = plan.graph(w, wd, wdd, frames)
    at_scene = ca.DM.zeros(len(parameters))  # the derivatives at the scene's values
    dq = ca.substitute(ca.jacobian(q, p), p, at_scene)
    dwrench = ca.substitute(ca.jacobian(ca.vec(wrench), p), p, at_scene)
    return ca.Function("moving_joints", [w, wd, wdd], [dq, dwrench, rotation],
                       ["w", "wd", "wdd"], ["dq", "dwrench", "rotation"])
