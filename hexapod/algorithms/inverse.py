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
  It is kept in the cache on disk under the model's content hash
  (:mod:`hexapod._support.compiled`): serialized, so that another run of the same model does not
  build its graph again, as an array program that evaluates long runs with one NumPy operation
  per instruction over many samples (:mod:`hexapod._support.array_program`), and compiled to C
  once compiling has paid (:func:`compile_pays`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np

from hexapod._support import signals
from hexapod._support.array_program import BlockEvaluator, Program, block_size, cached_program
from hexapod._support.compiled import (
    COMPILER_FLAGS,
    QUICK_FLAGS,
    compiled,
    find_compiled,
    interpreted_samples,
    serialized,
)
from hexapod.errors import HexapodError
from hexapod.model.model import GROUND_INDEX, Model
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
    joints : tuple of str
        Joint names, in model order.
    force, torque : ndarray (N, J, 3)
        N and N m: by the parent on the child, about the joint origin, in the child's joint
        frame (``frame="joint"``) or in world axes (``frame="world"``).
    effort : ndarray (N, J)
        ``tau`` of the joints with a coordinate (revolute and prismatic: torque about the axis,
        force along it), NaN for the others.
    q, v, v_dot : ndarray (N, n_q), (N, n_v), (N, n_v)
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
        ``swing``, ``ok``, or where the friction policy found no admissible force, ``slip`` or
        ``pull`` (see :mod:`hexapod.algorithms.ground`).
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


#: From this many samples, the tree path evaluates its Function uncompiled as an array program
#: (:mod:`hexapod._support.array_program`: one NumPy operation per instruction over a block of
#: samples) rather than in CasADi's virtual machine, sample by sample. Over 1000 samples, the
#: laws' evaluation included, a sample costs 3.8 against 21 us for the front leg and 10.0
#: against 22.6 us for 18 joints, and 2.8 and 6.6 us with optimized C code
#: (scripts/bench_inverse.py --vm); reading the program from the Function (once, then kept in
#: the cache) costs 8 and 18 ms. Below some hundreds of samples, NumPy's half microsecond per
#: call makes the virtual machine the faster.
ARRAY_FROM_SAMPLES = 500
#: Quick code (gcc -O0) of the tree path costs 0.13 s of CPU to compile for the front leg and
#: 0.23 s for 18 joints, and evaluates a sample in 3.3 and 7.3 us against the virtual machine's
#: 12.8 and 24.7 us: for runs too short for the array program, it pays from some 14 000
#: samples on, counted over every run of the model (:func:`compile_pays`).
COMPILE_FROM_SAMPLES = 15_000
#: Optimized code (gcc -O2) costs 0.39 and 0.91 s to compile and saves 1 to 3 us a sample over
#: the array program (more over quick code): a run of this many samples compiles it.
OPTIMIZE_FROM_SAMPLES = 200_000
#: CasADi's map of a Function over ``b`` samples costs about 4 microseconds per sample to build
#: (once per size), and each call of it about 50 microseconds of Python: the tree path calls
#: maps over blocks of about sqrt(12 N) of the N samples (at least 64), which keeps both small.
#: One map over all the samples costs more to build than the compiled code takes to evaluate
#: them: for the front leg, 4.9 ms against 1.5 ms in blocks at 1000 samples, 194 ms against
#: 25 ms at 20 000.
BLOCK_FACTOR, SMALLEST_BLOCK = 12, 64
#: ``method="auto"`` takes the phase path for closed loops and contacts from this many samples
#: (below, building its Functions costs about as much as the saddle path's samples: some two
#: seconds for the walking hexapod, whose samples cost 70 ms each on the saddle path).
PHASE_FROM_SAMPLES = 32
#: The phase path compiles its Functions to C from this many samples (compiling the walking
#: hexapod's takes some tens of seconds and saves about a millisecond per sample).
PHASE_COMPILE_FROM_SAMPLES = 50_000


def inverse_dynamics(model: Model, times, *, method: str = "auto", frame: str = "joint",
                     compile: bool | None = None, arrays: bool | None = None,
                     progress: Callable[[int, int], None] | None = None) -> InverseResult:
    """Joint wrenches and driver efforts of the prescribed motion at ``times``.

    The drivers' laws give the motion (a motion file becomes laws exact at its samples, see
    :mod:`hexapod.motion`).

    Parameters
    ----------
    method :
        ``"auto"`` (the tree path when the model allows it, else the phase path from
        :data:`PHASE_FROM_SAMPLES` samples, else the saddle path), ``"tree"``, ``"phase"``
        (closed loops and contacts, compiled: :mod:`hexapod.algorithms.phase_inverse`) or
        ``"saddle"`` (any mechanism, every sample solved exactly in Python: the reference).
    frame :
        ``"joint"`` (the report convention) or ``"world"``.
    compile :
        Tree and phase paths: evaluate compiled C code (True) or interpret (False: on the tree
        path, as ``arrays`` says). Tree path, by default: optimized code when it is at hand
        (compiled before, in this process or in the cache on disk) or the run is very long,
        else the array program when the run is long enough, else quick code when it is at
        hand or compiling pays, else CasADi's virtual machine (:func:`compile_pays`). Phase
        path, by default: compiled from :data:`PHASE_COMPILE_FROM_SAMPLES` samples, or when
        this process compiled the model's phase path before, and otherwise the libraries the
        cache on disk holds (an earlier run compiled them) where it holds them. ``False``: the
        interpreter only.
    arrays :
        Tree path, when not compiled: evaluate the array program (True, whatever the number of
        samples; :mod:`hexapod._support.array_program`), CasADi's virtual machine (False: the
        reference interpreter, sample by sample), or the array program from
        :data:`ARRAY_FROM_SAMPLES` samples and the virtual machine below (None).
    progress :
        Called as ``progress(done, total)`` as samples are done (after each block of samples
        on the tree path, see :data:`BLOCK_FACTOR`; after each run of samples sharing one
        rank decision on the phase path).

    Raises
    ------
    SingularSystemError
        When the drivers leave degrees of freedom free (the motion is not prescribed).
    HexapodError
        When ``method="tree"`` and the model is not an open tree with every joint driven.
    """
    times = np.atleast_1d(np.asarray(times, dtype=float))
    if frame not in ("joint", "world"):
        raise ValueError(f"frame must be 'joint' or 'world', got {frame!r}")
    w, wd, wdd = (x.reshape(model.n_w, times.size) for x in model.law_values(times))
    plan = tree_plan(model)
    if method == "tree" and plan is None:
        raise HexapodError(f"model '{model.name}' is not an open tree with every joint driven, "
                         "which the tree method needs: use the saddle method")
    if method not in ("auto", "tree", "phase", "saddle"):
        raise ValueError(f"method must be 'auto', 'tree', 'phase' or 'saddle', got {method!r}")
    if plan is not None and method in ("auto", "tree"):
        if compile is None:
            compile = False if arrays else compile_pays(plan, times.size, arrays)
        as_arrays = not compile and plan.evaluates_arrays(times.size, arrays)
        result = plan.solve(times, w, wd, wdd, frame, compiled=compile, as_arrays=as_arrays,
                            progress=progress)
        if not compile and not as_arrays:
            interpreted_samples(plan.key, times.size)  # counted over runs, until compiling pays
    elif method == "phase" or (method == "auto" and times.size >= PHASE_FROM_SAMPLES):
        use_cached = compile is None  # compile=False: the interpreter only
        if compile is None:
            compile = (model.was_built(("phase-terms", True, True))
                       or times.size >= PHASE_COMPILE_FROM_SAMPLES)
        result = _phase(model, times, w, wd, wdd, frame, compile, use_cached, progress)
    else:
        result = _saddle(model, times, frame, progress)
    _check_finite(model, result)
    return result


def compile_pays(plan: TreePlan, samples: int, arrays: bool | None = None) -> bool:
    """Whether to evaluate ``samples`` samples of the tree path compiled, compiling when it
    pays. Optimized code compiled before (in this process, or in the cache on disk) is used; a
    run of :data:`OPTIMIZE_FROM_SAMPLES` samples or more compiles it if there is none. A run
    long enough for the array program (:data:`ARRAY_FROM_SAMPLES`; ``arrays`` as
    :func:`inverse_dynamics` takes it) is evaluated so, faster than quick code and without a
    compiler. Shorter runs use quick code compiled before, else are interpreted by CasADi's
    virtual machine until the samples it evaluated, over every run of the model the cache
    remembers, and this run's reach :data:`COMPILE_FROM_SAMPLES`; then quick code is
    compiled: the rule of renting skis until their price is spent. The interpreter's time
    spent first never passes what compiling costs, so the total is at most twice what the
    best choice in hindsight would cost; short runs never wait for a compiler, and a model
    used often is compiled once for all its later runs."""
    if not plan.is_compiled:
        plan.find_library()
    if plan.is_compiled and plan.optimized:
        return True
    if samples >= OPTIMIZE_FROM_SAMPLES:
        plan.compile(optimized=True)
        return True
    if plan.evaluates_arrays(samples, arrays):
        return False
    if plan.is_compiled:
        return True
    if interpreted_samples(plan.key) + samples >= COMPILE_FROM_SAMPLES:
        plan.compile(optimized=False)
        return True
    return False


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

def _phase(model, times, w, wd, wdd, frame, compile, use_cached, progress) -> InverseResult:
    from hexapod.algorithms.phase_inverse import phase_inverse  # loaded when it runs, as below

    fields = phase_inverse(model, times, w, wd, wdd, frame, to_c=compile, use_cached=use_cached,
                           progress=progress)
    return InverseResult(times, tuple(j.name for j in model.joints), fields["force"],
                         fields["torque"], fields["effort"], fields["q"], fields["v"],
                         fields["v_dot"], frame, "phase", fields["max_violation"],
                         fields["redundant_rows"], tuple(c.name for c in model.contacts),
                         fields["ground"], fields["status"],
                         model.ground.policy if model.contacts else "")


def _saddle(model, times, frame, progress) -> InverseResult:
    # the saddle path's algorithms, loaded when it runs: the tree path (and 'hexapod inverse'
    # on a leg or a URDF robot) starts without them
    from hexapod.algorithms.sample_inverse import exact_sample

    n, J = times.size, len(model.joints)
    force, torque, effort = np.zeros((n, J, 3)), np.zeros((n, J, 3)), np.zeros((n, J))
    Q, V, A = np.zeros((n, model.n_q)), np.zeros((n, model.n_v)), np.zeros((n, model.n_v))
    redundant: list[str] = []
    ground = np.zeros((n, len(model.contacts), 3))
    status = np.full((n, len(model.contacts)), "swing", dtype=object)
    worst = 0.0
    data = model.create_data()
    model.law_values(times)  # all samples at once: the per-sample calls below reuse them
    for k, t in enumerate(times):
        sample = exact_sample(model, data, times[k - 1] if k else t,
                              Q[k - 1] if k else model.q0, t,
                              (V[k - 1], A[k - 1]) if k else None, frame=frame, first=k == 0)
        Q[k], V[k], A[k] = sample.q, sample.v, sample.v_dot
        force[k], torque[k], effort[k] = sample.force, sample.torque, sample.effort
        if model.contacts:
            ground[k], status[k] = sample.ground, sample.status
        worst = max(worst, sample.violation)
        redundant += [name for name in sample.redundant if name not in redundant]
        if signals.received() is not None:  # an interruption a library call swallowed
            raise KeyboardInterrupt
        if progress is not None:
            progress(k + 1, n)
    contacts = tuple(c.name for c in model.contacts)
    return InverseResult(times, tuple(j.name for j in model.joints), force, torque, effort,
                         Q, V, A, frame, "saddle", worst, tuple(redundant), contacts,
                         ground, status.astype(str),
                         model.ground.policy if model.contacts else "")


# ------------------------------------------------------------------ the tree path

class TreePlan:
    """The tree-ordered inverse dynamics of one model (built once, evaluated on many samples)."""

    def __init__(self, model: Model, order: list[int], driver_of: dict[int, int]):
        self.model = model
        self.order = order  # joints, parents first
        self.driver_of = driver_of  # joint index -> driver index
        #: the compiled Function in use (None before any), and whether it is optimized code
        self.library: ca.Function | None = None
        self.optimized = False
        #: the array program: None before it is sought, False when there is none
        self._program: Program | bool | None = None

    @property
    def key(self) -> str | None:
        """The key of the plan's Functions in the cache: the model's content hash and the
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
        rotations (9 x J, column-major). Interpreted by CasADi's virtual machine; read from the
        cache when it holds it (no graph to build), else built and stored there."""
        return serialized(self.key, lambda: ca.Function("tree_inverse", *self._expressions),
                          what=self._what)

    @property
    def compiled(self) -> ca.Function:
        """The same Function compiled to C: the library in use, else optimized code from the
        cache, or compiled now and stored there; the interpreted one when no compiler is present
        or ``HEXAPOD_NO_JIT`` is set."""
        if self.library is None:
            self.compile(optimized=True)
        return self.library

    def compile(self, optimized: bool) -> ca.Function:
        """Use code compiled with :data:`~hexapod._support.compiled.COMPILER_FLAGS` (optimized)
        or :data:`~hexapod._support.compiled.QUICK_FLAGS`: from the cache, else compiled now
        and stored there."""
        flags = COMPILER_FLAGS if optimized else QUICK_FLAGS
        self.library = compiled(self.key, lambda: self.function, what=self._what, flags=flags)
        self.optimized = optimized
        return self.library

    def find_library(self) -> bool:
        """Use the library the cache holds, optimized code first; False when it holds none."""
        for optimized, flags in ((True, COMPILER_FLAGS), (False, QUICK_FLAGS)):
            found = find_compiled(self.key, flags)
            if found is not None:
                self.library, self.optimized = found, optimized
                return True
        return False

    @cached_property
    def _expressions(self) -> tuple:
        model = self.model
        w, wd, wdd = (ca.SX.sym(n, model.n_w) for n in ("w", "wd", "wdd"))
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
            point = r_p + ca.mtimes(A_p, ca.DM(joint.parent_frame.position))
            # the joint's step: the child frame's rotation and translation on the parent's
            turn, shift = joint.type.tree_step(self._driver_value(j, w))
            frame_c = frame_p if turn is None else quaternion_product(frame_p, turn)
            origin = point if shift is None else point + ca.mtimes(
                rotation_from_euler_parameters(frame_p), shift)
            inverse_child = _quaternion(joint.child_frame.rotation) * np.array([1, -1, -1, -1])
            p_c = quaternion_product(frame_c, ca.DM(inverse_child))
            R_c = rotation_from_euler_parameters(p_c)
            p[joint.child] = p_c
            r[joint.child] = origin - ca.mtimes(R_c, ca.DM(joint.child_frame.position))
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
        wrench, frames = [], []
        for j in range(len(model.joints)):
            force, moment = world[j]
            about_origin = moment - ca.cross(origins[j], force)
            R = rotations[j]
            wrench.append(ca.vertcat(ca.mtimes(R.T, force), ca.mtimes(R.T, about_origin)))
            frames.append(ca.reshape(R, 9, 1))
        # common subexpressions shared: about a third fewer instructions for a leg
        outputs = ca.cse([q, v, v_dot, ca.horzcat(*wrench), ca.horzcat(*frames)])
        return ([w, wd, wdd], outputs, ["w", "wd", "wdd"],
                ["q", "v", "v_dot", "wrench", "rotation"])

    def build(self, compiled: bool = False) -> ca.Function:
        """Build (and compile, when ``compiled``) the Function now rather than at a solve."""
        return self.compiled if compiled else self.function

    @property
    def is_compiled(self) -> bool:
        """Whether compiled code is in use (not the interpreter)."""
        return self.library is not None and self.library is not self.__dict__.get("function")

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

    def _evaluator(self, n: int, compiled: bool):
        """The Function mapped over ``n`` samples and its buffer, built once per ``n``."""
        cache = self.__dict__.setdefault("_evaluators", {})
        key = (n, compiled, compiled and self.optimized)  # quick code may give way to optimized
        if key not in cache:
            function = self.compiled if compiled else self.function
            mapped = function.map(n, "serial") if n > 1 else function
            cache[key] = (mapped, *mapped.buffer())
        return cache[key]

    def evaluates_arrays(self, samples: int, arrays: bool | None = None) -> bool:
        """Whether ``samples`` samples are evaluated, uncompiled, as an array program rather
        than by CasADi's virtual machine: never with ``arrays=False``; with ``arrays=True``
        whenever the Function has a program; by default from :data:`ARRAY_FROM_SAMPLES`
        samples, when the Function has a program and blocks that long fit in its memory
        bound. The program is read from the cache, or from the Function (and kept there)
        once."""
        least = 1 if arrays else ARRAY_FROM_SAMPLES
        if arrays is False or samples < least:
            return False
        if self._program is None:
            program = cached_program(  # not read from a Function whose blocks are too short
                self.key, lambda: self.function
                if _long_blocks(self.function.sz_w(), least) else None, what=self._what)
            if program is None:
                return False  # not read for blocks this long: sought again for shorter ones
            self._program = program  # False: the Function has none
        return bool(self._program) and _long_blocks(self._program.work_size, least)

    def _array_evaluator(self, block: int) -> BlockEvaluator:
        """An evaluator of at least ``block`` samples: the one kept when it is at most twice as
        wide (its extra columns computed for nothing), else a new one, which is kept instead
        (one evaluator at a time: runs of many sizes do not pile up buffers)."""
        kept = self.__dict__.get("_array_evaluator_kept")
        if kept is None or not block <= kept.block <= 2 * block:
            kept = self.__dict__["_array_evaluator_kept"] = BlockEvaluator(self._program, block)
        return kept

    def solve(self, times, w, wd, wdd, frame, compiled: bool, as_arrays: bool = False,
              progress: Callable[[int, int], None] | None = None) -> InverseResult:
        """The result at ``times`` (laws' values ``w``, ``wd``, ``wdd``: one column per
        sample): the Function compiled (``compiled``), as an array program (``as_arrays``,
        after :meth:`evaluates_arrays` said yes) or in CasADi's virtual machine."""
        model, n, J = self.model, times.size, len(self.model.joints)
        q, v, v_dot = np.empty((n, model.n_q)), np.empty((n, model.n_v)), np.empty((n, model.n_v))
        wrench, rotation = np.empty((n, J, 6)), np.empty((n, J, 9))
        results = (q, v, v_dot, wrench, rotation)
        if as_arrays and not compiled:
            self._solve_arrays((w, wd, wdd), results, progress)
        else:
            self._solve_mapped((w, wd, wdd), results, compiled, progress)
        force, torque = wrench[..., :3], wrench[..., 3:]
        effort = np.full((n, J), np.nan)
        for j, joint in enumerate(model.joints):
            effort[:, j] = joint.type.effort(force[:, j], torque[:, j], model.dimension)
        if frame == "world":
            R = rotation.reshape(n, J, 3, 3).transpose(0, 1, 3, 2)  # column-major blocks
            force = np.einsum("njab,njb->nja", R, force)
            torque = np.einsum("njab,njb->nja", R, torque)
        phi_max = 0.0
        if model.n_c and n:
            rows = model.call("phi", q=q[0], w=w[:, 0]) / model.row_scale
            phi_max = float(np.max(np.abs(rows)))
        return InverseResult(times, tuple(j.name for j in model.joints), force, torque, effort,
                             q, v, v_dot, frame, "tree", phi_max)

    def _solve_mapped(self, inputs, results, compiled: bool, progress) -> None:
        """Evaluate the Function, compiled or in CasADi's virtual machine, mapped over blocks of
        samples (:data:`BLOCK_FACTOR`)."""
        n = inputs[0].shape[1]
        # CasADi's column-major (rows x n) is NumPy's C-order (n x rows): no conversion
        inputs = [np.ascontiguousarray(x.T) for x in inputs]
        block = min(n, max(SMALLEST_BLOCK, round(math.sqrt(BLOCK_FACTOR * n))))
        for start in range(0, n, block):
            stop = min(n, start + block)
            _, buffer, evaluate = self._evaluator(stop - start, compiled)
            for i, x in enumerate(inputs):
                buffer.set_arg(i, memoryview(x[start:stop]))
            for i, y in enumerate(results):
                buffer.set_res(i, memoryview(y[start:stop]))
            evaluate()
            if progress is not None:
                progress(stop, n)

    def _solve_arrays(self, inputs, results, progress) -> None:
        """Evaluate the array program over blocks of samples as equal as the memory bound
        allows (:data:`~hexapod._support.array_program.WORK_BYTES`)."""
        n = inputs[0].shape[1]
        largest = block_size(self._program.work_size, n)
        blocks = -(-n // largest)
        block = -(-n // blocks)
        evaluate = self._array_evaluator(block)
        flat = [y.reshape(n, -1) for y in results]  # views: (n, entries), entries column-major
        with np.errstate(all="ignore"):  # an overflow is reported by _check_finite, by name
            for start in range(0, n, block):
                stop = min(n, start + block)
                for buffer, x in zip(evaluate.inputs, inputs, strict=True):
                    buffer[:, :stop - start] = x[:, start:stop]
                evaluate()
                for y, buffer in zip(flat, evaluate.outputs, strict=True):
                    y[start:stop] = buffer[:, :stop - start].T
                if progress is not None:
                    progress(stop, n)


def _long_blocks(work_size: int, least: int) -> bool:
    """Whether blocks of ``least`` samples fit in an array program's memory bound, for work
    rows of ``work_size``."""
    return block_size(work_size, least) >= least


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
