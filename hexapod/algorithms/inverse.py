"""Inverse dynamics of prescribed motion (Dumitru, Marin and Margine, eqs. (12)-(16)) over a
whole gait.

When drivers fix every degree of freedom, each sample needs position, velocity and acceleration
analysis, then the multipliers of ``[[M, Phi_v^T], [Phi_v, 0]] [v_dot; lambda] = [Q; gamma]``,
and from them the joint wrenches (:mod:`hexapod.algorithms.liaison`). Three ways, with the
same results:

* **saddle** (any mechanism, closed loops included; the reference): per sample in Python,
  Newton's method warm-started from the previous sample, velocity projection, and the
  saddle-point solve of :mod:`hexapod.algorithms.dynamics` (rank decision and redundancy policy
  included), one sample at a time by :mod:`hexapod.algorithms.sample_inverse`;
* **phase** (closed loops and feet on the ground): the same work in CasADi Functions mapped
  over the samples of each contact phase, the rank decision taken once per contact set and
  every sample checked, any sample that fails its checks redone by the saddle path's exact
  solve (:mod:`hexapod.algorithms.phase_inverse`);
* **tree** (an open tree of spatial bodies whose joints the tree path follows, revolute,
  prismatic and fixed ones, every drivable one driven: the legs of this project): the same
  system solved in tree order. A forward pass composes each body's pose from its parent's and
  its joint's step for its driver's value (exactly: no Newton iterations), CasADi
  differentiates it for velocities and accelerations, and a backward pass from the leaves gives
  each joint's wrench from its child's Newton-Euler equations. The whole pass is one CasADi
  Function, mapped over blocks of samples; its cost grows linearly with the number of bodies.
  When it is compiled and the execution setting has a cache
  (:mod:`hexapod._support.execution`), the library is kept there under the model's content
  hash: another run of the same model compiles nothing.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cached_property

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from hexapod._support import signals
from hexapod._support.compiled import compiled
from hexapod._support.execution import current
from hexapod._support.fastcall import InPlaceFunction
from hexapod.algorithms.contact_frames import refuse_contacts
from hexapod.algorithms.joint_limits import check_joint_limits
from hexapod.algorithms.liaison import efforts_and_axes
from hexapod.algorithms.prescribed import PHASE_FROM_SAMPLES
from hexapod.errors import HexapodError
from hexapod.model.data import kept
from hexapod.model.model import GROUND_INDEX, Data, Model
from hexapod.spatial import (
    g_matrix,
    quaternion_product,
    rotation_from_euler_parameters,
)


@dataclass
class InverseResult:
    """Joint wrenches and efforts at every sample.

    Attributes
    ----------
    times : ndarray (N,)
        Sample times, s.
    joints : tuple of str
        Joint names, in model order.
    force, torque : ndarray (N, J, 3)
        N and N m: by the parent on the child, about the joint origin, in the child's joint
        frame (``frame="joint"``) or in world axes (``frame="world"``).
    effort : ndarray (N, J)
        ``tau`` of the joints with a coordinate (revolute and prismatic: torque about the axis,
        force along it), NaN for the others.
    q, v, v_dot : ndarray (N, n_q), (N, n_v), (N, n_v)
        The prescribed motion: positions, velocities and accelerations (SI).
    frame : {"joint", "world"}
        The axes of ``force`` and ``torque``.
    method : str
        ``"tree"``, ``"phase"`` or ``"saddle"``.
    max_violation : float
        Largest scaled constraint residual over the samples (round-off for the tree path).
    redundant_rows : tuple of str
        Rows named redundant at some sample (saddle path), or by the rank decisions of the
        phase path (one per phase, and at the samples it solved exactly).
    contacts : tuple of str
        The model's foot contacts (joint names), in model order.
    ground_force : ndarray (N, C, 3)
        The ground's force on each foot, N, world axes (zero in swing).
    ground_status : ndarray (N, C) of str
        Whatever the policy, whether the ground can give each foot its force:
        ``swing``, ``ok``, ``slip`` (outside the friction cone of the scene's ``mu``) or
        ``pull`` (the ground pulling the foot) (:func:`hexapod.algorithms.ground.feet_status`).
    policy : str
        The ground-force policy of the model (empty without contacts).
    """

    times: np.ndarray
    joints: tuple[str, ...]
    force: np.ndarray
    torque: np.ndarray
    effort: np.ndarray
    q: np.ndarray
    v: np.ndarray
    v_dot: np.ndarray
    frame: str
    method: str
    max_violation: float
    redundant_rows: tuple[str, ...] = ()
    contacts: tuple[str, ...] = ()
    ground_force: np.ndarray | None = None
    ground_status: np.ndarray | None = None
    policy: str = ""

    @property
    def infeasible(self) -> np.ndarray:
        """``(N,)`` bool: the samples where some foot slips or pulls (``ground_status``), so
        that the ground cannot give the forces; all False without contacts."""
        if self.ground_status is None or self.ground_status.size == 0:
            return np.zeros(self.times.size, dtype=bool)
        from hexapod.algorithms.ground import INFEASIBLE_STATUSES

        return np.isin(self.ground_status, INFEASIBLE_STATUSES).any(axis=1)

    @property
    def feasible(self) -> bool:
        """Whether the ground can give every foot its force at every sample (always True
        without contacts): an infeasible result's efforts are not ones to size motors by."""
        return not self.infeasible.any()


#: CasADi's map of a Function over ``b`` samples costs about 4 microseconds per sample to build
#: (once per size), and each call of it about 50 microseconds of Python: the tree path calls
#: maps over blocks of about sqrt(12 N) of the N samples (at least 64), which keeps both small.
#: One map over all the samples costs more to build than the compiled code takes to evaluate
#: them: for the front leg, 4.9 ms against 1.5 ms in blocks at 1000 samples, 194 ms against
#: 25 ms at 20 000.
BLOCK_FACTOR, SMALLEST_BLOCK = 12, 64


def inverse_dynamics(model: Model, times: ArrayLike, *, method: str = "auto", frame: str = "joint",
                     data: Data | None = None,
                     progress: Callable[[int, int], None] | None = None,
                     check_limits: bool = True) -> InverseResult:
    """Joint wrenches and driver efforts of the prescribed motion at ``times``.

    The drivers' laws give the motion (a motion file becomes laws exact at its samples, see
    :mod:`hexapod.scene.motion`). How the Functions are evaluated (CasADi's virtual machine, or
    compiled C) is the execution setting's (:func:`hexapod.executing`), never this call's.

    Parameters
    ----------
    model : Model
        Assembled from a scene whose drivers prescribe the motion.
    times : array_like (N,)
        Sample times, s.
    method : str
        ``"auto"`` (the tree path when the model allows it, else the phase path from
        :data:`~hexapod.algorithms.prescribed.PHASE_FROM_SAMPLES` samples, else the saddle
        path), ``"tree"``, ``"phase"`` (closed loops and contacts, batched:
        :mod:`hexapod.algorithms.phase_inverse`) or ``"saddle"`` (any mechanism, every sample
        solved exactly: the reference).
    frame : str
        ``"joint"`` (the report convention) or ``"world"``.
    data : Data, optional
        A workspace of ``model`` to run in (default: a new one). A run leaves there what it
        built for its samples (call buffers, rank decisions and their plans), which a later
        run with the same workspace reuses.
    progress : callable, optional
        Called as ``progress(done, total)`` as samples are done (after each block of samples
        on the tree path, see :data:`BLOCK_FACTOR`; after each run of samples sharing one
        rank decision on the phase path).
    check_limits : bool
        Whether a joint leaving its range (``limits``) is an error (the default; a guided
        model's positions are checked before its dynamics runs).

    Returns
    -------
    InverseResult
        Wrenches and efforts in N and N m, with the motion.

    Raises
    ------
    SingularSystemError
        When the drivers leave degrees of freedom free (the motion is not prescribed).
    JointLimitError
        A joint leaves its range (``check_limits``): the first, when and how far.
    HexapodError
        When ``method="tree"`` and the model is not an open tree with every joint driven, or
        when it has unilateral contacts (whose forces only a contact scheme decides).
    """
    times = np.atleast_1d(np.asarray(times, dtype=float))
    if data is None:
        data = model.create_data()
    model.check(data)
    refuse_contacts(model)
    if frame not in ("joint", "world"):
        raise ValueError(f"frame must be 'joint' or 'world', got {frame!r}")
    known = None  # the motion known at the samples (q, v, v_dot): a guided model's
    if guided := model.guidance is not None:  # the guides' kinematics first, then the efforts
        model, progress, known = _guided(model, times, progress, check_limits)
    w, wd, wdd = (x.reshape(model.n_w, times.size) for x in model.law_values(times, data))
    plan = tree_plan(model)
    if method == "tree" and plan is None:
        raise HexapodError(f"model '{model.name}' is not an open tree with every joint driven, "
                         "which the tree method needs: use the saddle method")
    if method not in ("auto", "tree", "phase", "saddle"):
        raise ValueError(f"method must be 'auto', 'tree', 'phase' or 'saddle', got {method!r}")
    if plan is not None and method in ("auto", "tree"):
        result = plan.solve(data, times, w, wd, wdd, frame, progress=progress)
    elif method == "phase" or (method == "auto" and times.size >= PHASE_FROM_SAMPLES):
        result = _phase(model, data, times, w, wd, wdd, frame, progress, known)
    else:
        result = _saddle(model, data, times, frame, progress, known)
    _check_finite(model, result)
    if check_limits and not guided:
        check_joint_limits(model, times, result.q)
    if model.contacts:  # whatever the path and the policy: can the ground give these forces?
        from hexapod.algorithms.ground import feet_status

        result = replace(result, ground_status=feet_status(model, times, result.ground_force))
    return result


def _guided(model: Model, times: np.ndarray, progress, check_limits: bool):
    """The twin of a guided model whose joints follow the motion the guides give them, the
    progress of its run as the second half of the whole, and the motion ``(q, v, v_dot)`` at
    the samples (the twin's laws are exact there, not between: its Newton solves start from
    its positions, and a motion its constraints leave free takes its velocities); the
    motion's joints checked against their ranges (``check_limits``), in the name of
    ``model``, and guides out of the joints' reach named."""
    from hexapod.algorithms.guided import followed_guides, guided_twin

    n = times.size
    q, v, v_dot, joints = followed_guides(model, times, None if progress is None else (
        lambda done, total: progress(done * n // total, 2 * n)))
    if check_limits:  # the same bodies and joints: the kinematics' positions are the model's
        check_joint_limits(model, times, q)
    twin = guided_twin(model, times, q, v, v_dot, joints)
    return (twin, None if progress is None else lambda done, total: progress(n + done, 2 * n),
            (q, v, v_dot))


def motion_model(model: Model, result: InverseResult) -> Model:
    """The model whose laws are the motion of the inverse-dynamics ``result`` it gave: a guided
    model's twin with its guided joints' laws exact at the result's samples (what reports,
    balances and metrics of the result evaluate the laws on); any other model itself.

    Parameters
    ----------
    model : Model
        The model of the run.
    result : InverseResult
        Its inverse dynamics (``hexapod.inverse_dynamics(model, times)``).

    Returns
    -------
    Model
        The guided joints driven by the motion found (quintic Hermite laws through the samples'
        angles, rates and accelerations), or ``model`` itself when nothing follows guides.
    """
    if model.guidance is None:
        return model
    from hexapod.algorithms.guided import guided_twin

    return guided_twin(model, result.times, result.q, result.v, result.v_dot)


def _check_finite(model: Model, result: InverseResult) -> None:
    """A non-finite wrench or acceleration (an overflow: laws or loads too large) is an error
    naming the first sample's time and the quantity, not numbers written as NaN."""
    for what, values in (("acceleration", result.v_dot), ("joint force", result.force),
                         ("joint moment", result.torque)):
        finite = np.isfinite(values).all(axis=tuple(range(1, values.ndim)))
        if not finite.all():
            k = int(np.argmin(finite))
            raise HexapodError(f"model '{model.name}': non-finite {what} at the sample t = "
                               f"{result.times[k]:.6g} s (an overflow: the scene's laws or "
                               "loads are too large there)")


# ------------------------------------------------------------------ the saddle path

def _phase(model, data, times, w, wd, wdd, frame, progress, known) -> InverseResult:
    from hexapod.algorithms.phase_inverse import phase_inverse  # loaded when it runs, as below

    fields = phase_inverse(model, data, times, w, wd, wdd, frame, progress=progress,
                           known=known)
    return InverseResult(times, tuple(j.name for j in model.joints), fields["force"],
                         fields["torque"], fields["effort"], fields["q"], fields["v"],
                         fields["v_dot"], frame, "phase", fields["max_violation"],
                         fields["redundant_rows"], tuple(c.name for c in model.contacts),
                         fields["ground"], None, model.ground.policy if model.contacts else "")


def _saddle(model, data, times, frame, progress, known=None) -> InverseResult:
    # the saddle path's algorithms, loaded when it runs: the tree path (and 'hexapod inverse'
    # on a leg or a URDF robot) starts without them
    from hexapod.algorithms.sample_inverse import exact_sample, known_sample

    n, J = times.size, len(model.joints)
    force, torque, effort = np.zeros((n, J, 3)), np.zeros((n, J, 3)), np.zeros((n, J))
    Q, V, A = np.zeros((n, model.n_q)), np.zeros((n, model.n_v)), np.zeros((n, model.n_v))
    redundant: list[str] = []
    ground = np.zeros((n, len(model.contacts), 3))
    worst = 0.0
    for k, t in enumerate(times):
        if known is not None:  # Newton from the positions known there
            sample = known_sample(model, data, times, known, k, frame)
        else:
            sample = exact_sample(model, data, times[k - 1] if k else t,
                                  Q[k - 1] if k else model.q0, t,
                                  (V[k - 1], A[k - 1]) if k else None, frame=frame)
        Q[k], V[k], A[k] = sample.q, sample.v, sample.v_dot
        force[k], torque[k], effort[k] = sample.force, sample.torque, sample.effort
        if model.contacts:
            ground[k] = sample.ground
        worst = max(worst, sample.violation)
        redundant += [name for name in sample.redundant if name not in redundant]
        if signals.received() is not None:  # an interruption a library call swallowed
            raise KeyboardInterrupt
        if progress is not None:
            progress(k + 1, n)
    contacts = tuple(c.name for c in model.contacts)
    return InverseResult(times, tuple(j.name for j in model.joints), force, torque, effort,
                         Q, V, A, frame, "saddle", worst, tuple(redundant), contacts,
                         ground, None, model.ground.policy if model.contacts else "")


# ------------------------------------------------------------------ the tree path

class TreePlan:
    """The tree-ordered inverse dynamics of one model (built once, evaluated on many samples)."""

    def __init__(self, model: Model, order: list[int], driver_of: dict[int, int]):
        self.model = model
        self.order = order  # joints, parents first
        self.driver_of = driver_of  # joint index -> driver index

    @property
    def key(self) -> str | None:
        """The key of the plan's library in the cache: the model's content hash and the
        plan's name (None for a model without a content hash: nothing is cached)."""
        return f"{self.model.digest}/tree-inverse" if self.model.digest else None

    @property
    def _what(self) -> str:
        return (f"tree-ordered inverse dynamics of '{self.model.name}' "
                f"({len(self.model.joints)} joints)")

    @cached_property
    def function(self) -> ca.Function:
        """``(w, wd, wdd) -> (q, v, v_dot, wrench, rotation)`` for one sample: the joint wrenches
        (6 x J: force then moment about the joint origin, joint frame) and the joint frames'
        rotations (9 x J, column-major)."""
        return ca.Function("tree_inverse", *self._expressions)

    @cached_property
    def compiled(self) -> ca.Function:
        """The same Function compiled to C (from the cache when it holds the library); the
        interpreted one when no compiler is present."""
        return compiled(self.key, lambda: self.function, what=self._what)

    @cached_property
    def _expressions(self) -> tuple:
        w, wd, wdd = (ca.SX.sym(n, self.model.n_w) for n in ("w", "wd", "wdd"))
        frames = [(ca.DM(j.parent_frame.position), ca.DM(j.child_frame.position))
                  for j in self.model.joints]
        return ([w, wd, wdd], self.graph(w, wd, wdd, frames), ["w", "wd", "wdd"],
                ["q", "v", "v_dot", "wrench", "rotation"])

    def graph(self, w, wd, wdd, frames: list) -> list:
        """``[q, v, v_dot, wrench, rotation]`` as expressions of the laws' values ``w, wd,
        wdd`` and of each joint's frame origins on its parent and its child (``frames``, in
        their centre-of-mass frames: numbers, or expressions of design parameters)."""
        model = self.model
        law = ca.vertcat(w, wd)
        law_rate = ca.vertcat(wd, wdd)
        n_b = len(model.bodies)
        p = [None] * n_b
        r = [None] * n_b
        origins, rotations = [None] * len(model.joints), [None] * len(model.joints)
        for j in self.order:
            joint = model.joints[j]
            if joint.parent == GROUND_INDEX:
                p_p, r_p = ca.DM([1.0, 0.0, 0.0, 0.0]), ca.DM.zeros(3)
            else:
                p_p, r_p = p[joint.parent], r[joint.parent]
            A_p = rotation_from_euler_parameters(p_p)
            frame_p = quaternion_product(p_p, ca.DM(_quaternion(joint.parent_frame.rotation)))
            point = r_p + ca.mtimes(A_p, frames[j][0])
            # the joint's step: the child frame's rotation and translation on the parent's
            turn, shift = joint.type.tree_step(self._driver_value(j, w))
            frame_c = frame_p if turn is None else quaternion_product(frame_p, turn)
            origin = point if shift is None else point + ca.mtimes(
                rotation_from_euler_parameters(frame_p), shift)
            inverse_child = _quaternion(joint.child_frame.rotation) * np.array([1, -1, -1, -1])
            p_c = quaternion_product(frame_c, ca.DM(inverse_child))
            R_c = rotation_from_euler_parameters(p_c)
            p[joint.child] = p_c
            r[joint.child] = origin - ca.mtimes(R_c, frames[j][1])
            origins[j] = origin
            rotations[j] = rotation_from_euler_parameters(frame_c)
        q = ca.vertcat(*[ca.vertcat(r[b], p[b]) for b in range(n_b)])
        # one forward-mode derivative of all coordinates: the shared kinematic graph is walked
        # once (derivatives body by body would walk it per body, quadratically in bodies)
        q_dot = ca.jtimes(q, law, law_rate)
        v_parts = []
        for b in range(n_b):
            r_dot, p_dot = q_dot[7 * b:7 * b + 3], q_dot[7 * b + 3:7 * b + 7]
            v_parts += [r_dot, 2 * ca.mtimes(g_matrix(p[b]), p_dot)]
        v = ca.vertcat(*v_parts)
        v_dot = ca.jtimes(v, law, law_rate)
        Q = model.Q(*[{"q": q, "v": v, "w": w}[n] for n in model.Q.name_in()])
        if model.Q_across is not None:
            across = model.Q_across(*[{"q": q, "v": v, "w": w}[n]
                                      for n in model.Q_across.name_in()])
            Q = Q - ca.sum2(across)  # forces across joints belong to the joint wrenches
        needed = self._mass_times(v_dot) - Q  # what the constraints must apply to each body
        world = [None] * len(model.joints)  # wrenches about the world origin
        children: dict[int, list[int]] = {}
        for k in self.order:
            children.setdefault(model.joints[k].parent, []).append(k)
        for j in reversed(self.order):
            joint = model.joints[j]
            b = model.bodies[joint.child]
            force = needed[b.v.start:b.v.start + 3]
            moment = (ca.mtimes(rotation_from_euler_parameters(p[joint.child]),
                                needed[b.v.start + 3:b.v.stop])
                      + ca.cross(r[joint.child], force))
            for k in children.get(joint.child, ()):  # what this body passes on to its children
                force = force + world[k][0]
                moment = moment + world[k][1]
            world[j] = (force, moment)
        wrench, rotation_columns = [], []
        for j in range(len(model.joints)):
            force, moment = world[j]
            about_origin = moment - ca.cross(origins[j], force)
            R = rotations[j]
            wrench.append(ca.vertcat(ca.mtimes(R.T, force), ca.mtimes(R.T, about_origin)))
            rotation_columns.append(ca.reshape(R, 9, 1))
        # common subexpressions shared: about a third fewer instructions for a leg
        return ca.cse([q, v, v_dot, ca.horzcat(*wrench), ca.horzcat(*rotation_columns)])

    def _driver_value(self, joint: int, w: ca.SX):
        if joint not in self.driver_of:
            return 0.0
        driver = self.model.drivers[self.driver_of[joint]]
        if driver.law >= 0:
            return w[driver.law]
        return float(driver.spec.value)

    def _mass_times(self, a: ca.SX) -> ca.SX:
        """``M a`` for the constant block-diagonal mass matrix."""
        mass = self.model.mass
        out = ca.DM(mass.diagonal) * a
        for block, index in zip(mass.blocks, mass.block_index, strict=True):
            out[index.tolist()] = ca.mtimes(ca.DM(block), a[index.tolist()])
        return out

    def _evaluator(self, data: Data, n: int, compiled: bool):
        """The Function mapped over ``n`` samples (built once per plan and ``n``: a pure
        function of the model) and its buffer (made once per workspace)."""
        def mapped(model: Model) -> ca.Function:
            function = self.compiled if compiled else self.function
            return function.map(n, "serial") if n > 1 else function

        function = self.model.built_once(("tree-map", n, compiled), mapped)
        return kept(data, ("tree-buffer", n, compiled), lambda: InPlaceFunction(function))

    def solve(self, data: Data, times, w, wd, wdd, frame,
              progress: Callable[[int, int], None] | None = None) -> InverseResult:
        """The result at ``times`` (laws' values ``w``, ``wd``, ``wdd``: one column per
        sample), the Function compiled or interpreted as the execution setting says."""
        model, n, J = self.model, times.size, len(self.model.joints)
        q, v, v_dot = np.empty((n, model.n_q)), np.empty((n, model.n_v)), np.empty((n, model.n_v))
        wrench, rotation = np.empty((n, J, 6)), np.empty((n, J, 9))
        results = (q, v, v_dot, wrench, rotation)
        self._solve_mapped(data, (w, wd, wdd), results, current().compiled, progress)
        force, torque, effort = efforts_and_axes(model, wrench[..., :3], wrench[..., 3:],
                                                 rotation, frame)
        phi_max = 0.0
        if model.n_c and n:
            rows = model.call("phi", q=q[0], w=w[:, 0]) / model.row_scale
            phi_max = float(np.max(np.abs(rows)))
        return InverseResult(times, tuple(j.name for j in model.joints), force, torque, effort,
                             q, v, v_dot, frame, "tree", phi_max)

    def _solve_mapped(self, data: Data, inputs, results, compiled: bool, progress) -> None:
        """Evaluate the Function, compiled or in CasADi's virtual machine, mapped over blocks of
        samples (:data:`BLOCK_FACTOR`)."""
        n = inputs[0].shape[1]
        # CasADi's column-major (rows x n) is NumPy's C-order (n x rows): no conversion
        inputs = [np.ascontiguousarray(x.T) for x in inputs]
        block = min(n, max(SMALLEST_BLOCK, round(math.sqrt(BLOCK_FACTOR * n))))
        for start in range(0, n, block):
            stop = min(n, start + block)
            self._evaluator(data, stop - start, compiled)([x[start:stop] for x in inputs],
                                                         [y[start:stop] for y in results])
            if progress is not None:
                progress(stop, n)


def _quaternion(R: np.ndarray) -> np.ndarray:
    from hexapod.spatial import euler_parameters_from_rotation

    return euler_parameters_from_rotation(R)


def tree_plan(model: Model) -> TreePlan | None:
    """The tree path for ``model``, or None when it does not apply: an open tree of spatial
    bodies hanging from the ground, joints whose type has a ``tree_step`` (revolute, prismatic
    and fixed joints), every drivable joint driven by exactly one joint driver, no other
    driver.

    The plan (and its compiled Function) is built once per model and kept with it."""
    return model.built_once(("tree-plan",), _make_tree_plan)


def _make_tree_plan(model: Model) -> TreePlan | None:
    if model.dimension != 3 or any(b.kind != "spatial" for b in model.bodies):
        return None
    if any(d.kind != "joint" for d in model.drivers):
        return None
    driver_of: dict[int, int] = {}
    for k, driver in enumerate(model.drivers):
        if driver.joint in driver_of:
            return None
        driver_of[driver.joint] = k
    children = set()
    for joint in model.joints:
        if joint.type.tree_step is None or joint.loop_closing:
            return None
        if joint.child == GROUND_INDEX or joint.child in children:
            return None
        children.add(joint.child)
        if joint.type.drivable and joint.index not in driver_of:
            return None
    if len(children) != len(model.bodies):
        return None
    order, placed = [], {GROUND_INDEX}
    while len(order) < len(model.joints):
        ready = [j.index for j in model.joints if j.index not in order and j.parent in placed]
        if not ready:
            return None
        order += ready
        placed.update(model.joints[j].child for j in ready)
    return TreePlan(model, order, driver_of)


def joint_frames_world(model: Model, q: np.ndarray) -> list:
    """World origin and rotation of every joint frame at ``q`` (for reports)."""
    from hexapod.algorithms.liaison import joint_origin

    return [joint_origin(model, q, joint) for joint in model.joints]
