"""The model's part of the constrained step: CasADi SX Functions that do not depend on which rows
are kept, built (and compiled, when the execution setting says so) once per model.

The batched inverse dynamics (:mod:`hexapod.algorithms.phase_plan`) composes them, with the
linear algebra of one row set, into one Function per sample; the exact path evaluates the
policy's objective, the wrench map and the report from here on numbers, so that each is written
once (:func:`hexapod.algorithms.liaison.policy_map`, :func:`~.liaison.wrenches_from_multipliers`,
:func:`hexapod.algorithms.ground.policy_objective`). Here:

* ``predict(q, v, a, h)``: ``q (+) (h v + h^2/2 a)``, the positions a sample ahead;
* ``correct(q, dq)``: ``q (+) (-dq)`` (a Newton step; :func:`hexapod.algorithms.step.retract`);
* ``residual(q, w)``: ``phi``; ``jacobian(q, w)``: ``phi`` and the nonzeros of ``Phi_v``;
* ``rates(q, w, wd)``: ``nu``; ``gamma(q, v, w, wd, wdd)`` alone (a kinematics run's), or
  ``forces(q, v, w, wd, wdd)``: ``gamma``, ``Q`` and the wrenches
  of the force elements acting across joints;
* ``wrench_terms(q, w, Phi)``: the wrench map ``W`` (below) and the joint frames' rotations,
  formed once a sample for the two that follow;
* ``policy(m)(W, offset, feet, lam, N, mask, w)``: the redundancy policy, among ``lam + N
  z`` the least ``|A (lam + N z) + b|^2`` (``m`` the columns of ``N``, one Function per
  ``m``): for ``min-wrench`` ``A = W`` maps multipliers to the joint wrenches
  (force and moment about the joint origin over the characteristic length, world axes, one
  block of 6 rows per joint and per coordinate driver), each foot's block times ``feet``
  (one over the square root of its weight); for
  ``min-effort`` to the actuator efforts over their references and the feet's load-sharing
  terms (coefficients ``feet``), as in :mod:`hexapod.algorithms.ground`;
* ``joint_wrenches(W, frames, lam, offset, w)``: the joint wrenches in the report convention
  (joint frames); ``report(q, w, Phi, lam, offset)`` the same and the frames from the positions,
  on numbers; ``wrench_map(q, w, Phi)``, ``objective(q, w, Phi, offset, feet)``
  and ``across(q, w, Q_across)``: the policy's map, its objective and its constant term on numbers;
* ``residuals(Phi, phi, v, nu, a, gamma, d)``: what the checks need: the velocity and
  acceleration residuals per row, over the row scales ``d`` (the norms of the rows of
  ``Phi_v M^-1/2`` at the rank decision, the equilibration of :mod:`hexapod.algorithms.linalg`)
  and relative to the solution's size, and the largest scaled position residual.

``gamma`` is formed as ``-d/dq (Phi_v v) B v - 2 d/dt (Phi_v v) - Phi_tt`` through directional
derivatives of ``phi`` (``Phi_v v`` by one forward derivative along ``B(q) v``), the same
derivatives as :attr:`hexapod.model.model.Model.gamma` (equal to round-off) in about a quarter
of the operations.
"""

from __future__ import annotations

from functools import cached_property

import casadi as ca
import numpy as np

from hexapod._support.compiled import compiled_graph
from hexapod._support.fastcall import FastFunction, ScatteredFunction
from hexapod.algorithms.step import equilibrated, mass_factors, retract, sparse_dm
from hexapod.model.data import kept
from hexapod.model.model import GROUND_INDEX, Model
from hexapod.spatial import rotation_from_euler_parameters


def _call(function: ca.Function, **values):
    """Call a model Function with the inputs it has (law inputs are absent without laws)."""
    return function(*[values[name] for name in function.name_in()])


def _embed_rotation(R):
    if R.shape == (3, 3):
        return R
    out = ca.SX.eye(3)
    out[:2, :2] = R
    return out


class StepTerms:
    """The model-level SX Functions of the compiled closed-loop inverse dynamics.

    Parameters
    ----------
    model : Model
    to_c : bool
        Compile the Functions to C (kept in the execution setting's cache, when it has one);
        else CasADi's virtual machine evaluates them.
    """

    def __init__(self, model: Model, to_c: bool = False):
        self.model = model
        self.to_c = to_c
        s = model._sym
        self.q, self.v, self.w, self.wd, self.wdd = s.q, s.v, s.w, s.wd, s.wdd
        self.pattern = model._Phi_v_expr.sparsity()  # of Phi_v, fixed
        # the characteristic length, an expression of the laws where design parameters move
        # the points it is measured on
        self.length = s.length if s.length is not None else model.characteristic_length
        self.pattern_rows, self.pattern_columns = (np.asarray(x, dtype=int) for x in
                                                   self.pattern.get_triplet())

    def _function(self, name, inputs, outputs, names_in, names_out, cse=True, to_c=None):
        # common subexpressions removed only where the graph is compiled: there they shorten
        # the C compiler's work by far more than the search costs. Interpreted, the search
        # costs more than a report's samples save: on the walking robot (one-off script,
        # 2026-12-05) it removes 6 % of the Jacobian's operations (the residuals are shared
        # where they are formed, the model's phi), 18 % of gamma's and 26 % of the wrench
        # terms', for 0.04 to 0.06 s each, where a call of 501 samples would save some 14 ms;
        # it pays only after some ten calls of one model. Never in the row norms or the
        # residuals, which have almost none (under 2 %).
        to_c = self.to_c if to_c is None else to_c
        outputs = ca.cse(outputs) if cse and to_c else outputs
        return sx_function(name, inputs, outputs, to_c, names_in, names_out)

    @cached_property
    def predict(self) -> ca.Function:
        model = self.model
        q, v, a = (ca.SX.sym(n, size) for n, size in (("q", model.n_q), ("v", model.n_v),
                                                      ("a", model.n_v)))
        h = ca.SX.sym("h")
        return self._function("phase_predict", [q, v, a, h],
                              [retract(self.model, q, h * v + h * h / 2 * a)],
                              ["q", "v", "a", "h"], ["q_predicted"], cse=False)

    @cached_property
    def correct(self) -> ca.Function:
        model = self.model
        q, dq = ca.SX.sym("q", model.n_q), ca.SX.sym("dq", model.n_v)
        return self._function("phase_correct", [q, dq], [retract(self.model, q, -dq)],
                              ["q", "dq"], ["q_corrected"], cse=False)

    @cached_property
    def residual(self) -> ca.Function:
        return self._function("phase_residual", [self.q, self.w], [self.model._sym.phi],
                              ["q", "w"], ["phi"])

    @cached_property
    def jacobian(self) -> ca.Function:
        Phi = self.model._Phi_v_expr
        return self._function("phase_jacobian", [self.q, self.w],
                              [self.model._sym.phi, Phi.nz[:]], ["q", "w"], ["phi", "Phi"])

    @cached_property
    def residuals(self) -> ca.Function:
        """``(Phi, phi, v, nu, a, gamma, d) -> (velocity, acceleration, position)``: each
        row's relative residual of the velocity and acceleration constraints and the largest
        scaled position residual."""
        return self._residuals(accelerations=True)

    @cached_property
    def velocity_residuals(self) -> ca.Function:
        """:attr:`residuals` without the accelerations' (zero): ``(Phi, phi, v, nu, d)``, for
        a motion known at the sample whose accelerations another plan solved and checked (a
        guided model's twin's: its guides')."""
        return self._residuals(accelerations=False)

    def _residuals(self, accelerations: bool) -> ca.Function:
        model = self.model
        n_c, n_v = model.n_c, model.n_v
        Phi_nz = ca.SX.sym("Phi", self.pattern.nnz())
        phi, nu, gamma, d = (ca.SX.sym(n, n_c) for n in ("phi", "nu", "gamma", "d"))
        v, a = ca.SX.sym("v", n_v), ca.SX.sym("a", n_v)
        Phi = ca.SX(self.pattern, Phi_nz)
        root_mass = sparse_dm(np.linalg.inv(model.mass_inv_sqrt.dense()))

        def relative(x, rhs):
            return relative_residuals(Phi, x, rhs, d, root_mass)

        position = ca.mmax(ca.fabs(phi / ca.DM(model.row_scale))) if n_c else ca.SX(0)
        names = ["Phi", "phi", "v", "nu", "a", "gamma", "d"]
        inputs = [Phi_nz, phi, v, nu, a, gamma, d]
        if accelerations:
            acceleration = relative(a, gamma)
        else:
            names, inputs = names[:4] + names[6:], inputs[:4] + inputs[6:]
            acceleration = ca.SX.zeros(n_c)
        return self._function("phase_residuals", inputs,
                              [relative(v, nu), acceleration, position], names,
                              ["velocity", "acceleration", "position"], cse=False)

    @cached_property
    def rates(self) -> ca.Function:
        nu = _call(self.model.nu, q=self.q, w=self.w, wd=self.wd)
        return self._function("phase_rates", [self.q, self.w, self.wd], [nu],
                              ["q", "w", "wd"], ["nu"])

    @cached_property
    def gamma(self) -> ca.Function:
        """``(q, v, w, wd, wdd) -> gamma``: the acceleration constraints' right-hand side alone
        (a kinematics run's, :class:`~hexapod.algorithms.phase_plan.PhasePlan`)."""
        gamma = _call(self.model.gamma, q=self.q, v=self.v, w=self.w, wd=self.wd, wdd=self.wdd)
        return self._function("phase_gamma", [self.q, self.v, self.w, self.wd, self.wdd],
                              [gamma], ["q", "v", "w", "wd", "wdd"], ["gamma"])

    @cached_property
    def forces(self) -> ca.Function:
        """``(q, v, w, wd, wdd) -> (gamma, Q, offset)``: ``offset`` is the policy's constant
        term, the wrenches of the force elements acting across joints (6 per block)."""
        model = self.model
        q, v, w, wd, wdd = self.q, self.v, self.w, self.wd, self.wdd
        gamma = _call(model.gamma, q=q, v=v, w=w, wd=wd, wdd=wdd)
        return self._function("phase_forces", [q, v, w, wd, wdd], [gamma, *self._loads()],
                              ["q", "v", "w", "wd", "wdd"], ["gamma", "Q", "offset"])

    @cached_property
    def loads(self) -> ca.Function:
        """``(q, v, w) -> (Q, offset)``: :attr:`forces` without ``gamma``, for a motion known
        at the sample (a guided model's twin: its accelerations are its guides')."""
        return self._function("phase_loads", [self.q, self.v, self.w], self._loads(),
                              ["q", "v", "w"], ["Q", "offset"])

    def _loads(self) -> list:
        model, q, v, w = self.model, self.q, self.v, self.w
        Q = _call(model.Q, q=q, v=v, w=w)
        offset = ca.SX.zeros(6 * self.owners)
        if model.Q_across is not None:
            offset = self._across(_call(model.Q_across, q=q, v=v, w=w))
        return [Q, offset]

    def _across(self, across):
        """The wrenches (6 per block, the wrench map's blocks) of the generalized forces of the
        force elements acting across joints (``n_v x k``, the columns of ``Q_across``)."""
        offset = ca.SX.zeros(6 * self.owners)
        for k, joint in enumerate(self.model.joints):
            if joint.across_column >= 0:
                offset[6 * k:6 * k + 6] = self._on_child(joint, across[:, joint.across_column])
        return offset

    @cached_property
    def across(self) -> ca.Function:
        """``(q, w, Q_across) -> offset``: the policy's constant term from the forces of the
        elements acting across joints (the numbers of ``Model.Q_across``)."""
        across = ca.SX.sym("Q_across", self.model.Q_across.size_out(0))
        return self._function("phase_across", [self.q, self.w, across],
                              [self._across(across)], ["q", "w", "Q_across"], ["offset"])

    @cached_property
    def wrench_map(self) -> ca.Function:
        """``(q, w, Phi) -> A``: the map from multipliers to the wrenches of the least-wrench policy
        (see :meth:`_wrench_map`; world axes, moments over the characteristic length). Never
        compiled, as :attr:`objective`: the standing robot's took gcc 65 s."""
        Phi_nz = ca.SX.sym("Phi", self.pattern.nnz())
        A, _ = self._wrench_map(Phi_nz)
        return self._function("phase_wrench_map", [self.q, self.w, Phi_nz], [ca.densify(A)],
                              ["q", "w", "Phi"], ["A"], to_c=False)

    @cached_property
    def objective(self) -> ca.Function:
        """``(q, w, Phi, offset, feet) -> (A, b)``: the redundancy policy's objective
        ``|A lam + b|^2`` (see :meth:`_objective`), ``Phi`` the nonzeros of ``Phi_v``. Never
        compiled: the batched driver evaluates it once per call (its exact first sample), the
        exact one once per sample (0.2 ms interpreted for the walking robot), and its graph
        takes gcc a minute."""
        Phi_nz = ca.SX.sym("Phi", self.pattern.nnz())
        offset = ca.SX.sym("offset", 6 * self.owners)
        feet = ca.SX.sym("feet", len(self.model.contacts))
        A, b = self._objective(self._wrench_map(Phi_nz)[0], offset, feet)
        # A sparse: the walking robot's is 252 x 234 with 792 nonzeros, and densified the
        # Function took 67,086 operations against 8,910
        return self._function("phase_objective", [self.q, self.w, Phi_nz, offset, feet],
                              [A, ca.densify(b)], ["q", "w", "Phi", "offset", "feet"],
                              ["A", "b"], to_c=False)

    @cached_property
    def row_norms(self) -> ca.Function:
        """``(Phi) -> d``: the norms of the rows of ``Phi_v M^-1/2`` (1 for a zero row): the
        equilibration of :mod:`hexapod.algorithms.linalg`, at the state of ``Phi``."""
        Phi_nz = ca.SX.sym("Phi", self.pattern.nnz())
        _, d, _ = equilibrated(ca.SX(self.pattern, Phi_nz), mass_factors(self.model)[0])
        return self._function("phase_row_norms", [Phi_nz], [d], ["Phi"], ["d"], cse=False)

    def evaluate(self, data, name: str, *arguments) -> list[np.ndarray]:
        """The Function ``name`` on numbers, through call buffers kept in the workspace
        ``data`` (fresh ones without it): ``evaluate(data, "across", q, Q_across)``."""
        fast = kept(data, ("terms", self.to_c, name), lambda: FastFunction(getattr(self, name)))
        return fast(*arguments)

    def evaluate_sparse(self, data, name: str, *arguments) -> list:
        """As :meth:`evaluate`, the matrix outputs as SciPy CSR arrays of their nonzeros:
        ``evaluate_sparse(data, "objective", q, Phi, offset, feet)``."""
        scattered = kept(data, ("sparse terms", self.to_c, name),
                         lambda: ScatteredFunction(getattr(self, name)))
        return scattered.sparse(*arguments)

    def offset(self, data, q, w, Q_across) -> np.ndarray:
        """The policy's constant term at ``q`` (laws ``w``) on numbers: the wrenches of the
        force elements acting across joints (``across``), zero without them (``Q_across``
        None)."""
        if Q_across is None:
            return np.zeros(6 * self.owners)
        return self.evaluate(data, "across", q, w, Q_across)[0]

    def nonzeros(self, Phi_v) -> np.ndarray:
        """The entries of a numeric ``Phi_v`` (dense, or SciPy sparse) at the pattern's
        nonzeros, in CasADi's order: the ``Phi`` input of the Functions above."""
        if hasattr(Phi_v, "tocsr"):
            Phi_v = Phi_v.tocsr()
            return np.asarray(Phi_v[self.pattern_rows, self.pattern_columns]).reshape(-1)
        return Phi_v[self.pattern_rows, self.pattern_columns]

    @property
    def owners(self) -> int:
        """Blocks of the wrench map: one per joint, one per coordinate driver."""
        return len(self.model.joints) + sum(d.kind == "coordinate" for d in self.model.drivers)

    # ---------------------------------------------------------------- poses and wrenches

    def _pose(self, body: int):
        """World position (3) and rotation (3 x 3) of a body's centre-of-mass frame."""
        if body == GROUND_INDEX:
            return ca.SX.zeros(3), ca.SX.eye(3)
        info = self.model.bodies[body]
        qb = self.q[info.q.start:info.q.stop]
        if info.kind == "spatial":
            return qb[:3], rotation_from_euler_parameters(qb[3:7])
        if info.kind == "planar":
            c, s = ca.cos(qb[2]), ca.sin(qb[2])
            R = ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))
            return ca.vertcat(qb[:2], 0), R
        return ca.vertcat(qb, ca.SX.zeros(3 - qb.numel())), ca.SX.eye(3)

    def _frame(self, joint):
        """World origin and rotation of the joint frame (fixed to the child; its origin shifted
        by the model's design symbols where a parameter moves it: ``JointInfo.child_shift``)."""
        r, R = self._pose(joint.child)
        frame = joint.child_frame
        position = ca.DM(np.concatenate([frame.position, np.zeros(3 - frame.position.size)]))
        if joint.child_shift is not None:
            position = position + ca.vertcat(joint.child_shift,
                                             ca.SX.zeros(3 - joint.child_shift.numel()))
        if self.model._sym.scale is not None:  # a design parameter scales every length
            position = self.model._sym.scale * position
        rotation = frame.rotation if frame.rotation.shape == (3, 3) else np.pad(
            frame.rotation, ((0, 1), (0, 1)))
        if frame.rotation.shape != (3, 3):
            rotation[2, 2] = 1.0
        return r + ca.mtimes(R, position), ca.mtimes(R, ca.DM(rotation))

    def _wrench(self, body: int, g, point):
        """Force and moment about ``point`` (world) of generalized forces ``g`` (n_v x m) on a
        body, as a (6 x m) block with the moment over the characteristic length."""
        info = self.model.bodies[body]
        r, R = self._pose(body)
        gb = g[info.v.start:info.v.stop, :]
        m = g.shape[1]
        if info.kind == "spatial":
            force, moment = gb[:3, :], ca.mtimes(R, gb[3:, :])
        elif info.kind == "planar":
            force = ca.vertcat(gb[:2, :], ca.SX.zeros(1, m))
            moment = ca.vertcat(ca.SX.zeros(2, m), gb[2:3, :])
        else:
            force = ca.vertcat(gb, ca.SX.zeros(3 - gb.shape[0], m))
            moment = ca.SX.zeros(3, m)
        arm = ca.repmat(r - point, 1, m)
        moment = moment + ca.cross(arm, force)
        return ca.vertcat(force, moment / self.length)

    def _on_child(self, joint, g):
        origin, _ = self._frame(joint)
        if joint.child != GROUND_INDEX:
            return self._wrench(joint.child, g, origin)
        return -self._wrench(joint.parent, g, origin)

    def _wrench_map(self, Phi_nz):
        """The (6 owners x n_c) map from multipliers to the policy's wrenches, and the joint
        frames' rotations (9 x J, column-major), at ``q`` and the nonzeros ``Phi_nz`` of
        ``Phi_v`` (SX)."""
        A, frames = self._wrench_terms(self.q, self.w, Phi_nz)
        return A, frames

    @cached_property
    def _wrench_terms(self) -> ca.Function:
        """``(q, w, Phi) -> (A, frames)`` of :meth:`_wrench_map`, formed once per model and
        called (inlined) by the objective, the policy of each size and the report: forming it
        took 0.07 s for the walking robot."""
        Phi_nz = ca.SX.sym("Phi", self.pattern.nnz())
        Phi = ca.SX(self.pattern, Phi_nz)
        model = self.model
        A = ca.SX(6 * self.owners, model.n_c)
        frames = []
        for k, joint in enumerate(model.joints):
            rows = np.concatenate([joint.rows, joint.driver_rows]).astype(int).tolist()
            if rows:
                A[6 * k:6 * k + 6, rows] = self._on_child(joint, -Phi[rows, :].T)
            frames.append(ca.reshape(self._frame(joint)[1], 9, 1))
        block = len(model.joints)
        for driver in model.drivers:
            if driver.kind == "coordinate":
                centre, _ = self._pose(driver.body)
                A[6 * block:6 * block + 6, driver.row] = self._wrench(
                    driver.body, -Phi[driver.row, :].T, centre)
                block += 1
        frames = ca.horzcat(*frames) if frames else ca.SX(9, 0)
        return ca.Function("wrench_terms", [self.q, self.w, Phi_nz], [A, frames])

    def _objective(self, W, offset, feet):
        """``A, b`` of the policy's objective ``|A lam + b|^2`` (SX), ``W`` the wrench map
        (:meth:`_wrench_map`; the least-effort policy does not use it)."""
        model = self.model
        policy = model.ground.policy if model.contacts else "min-wrench"
        if policy == "min-wrench":
            A = W
            scale = ca.SX.ones(A.shape[0])
            for k, contact in enumerate(model.contacts):
                scale[6 * contact.joint:6 * contact.joint + 6] = feet[k]
            return ca.mtimes(ca.diag(scale), A), scale * offset
        # min-effort, and friction's objective
        efforts = [d for d in model.drivers if d.kind == "joint"]
        A = ca.SX(len(efforts) + 3 * len(model.contacts), model.n_c)
        for i, driver in enumerate(efforts):
            A[i, driver.row] = 1.0 / model.ground.reference(model.joints[driver.joint].name)
        # a foot's load F enters as the effort it would cause at the lever arm l, in reference
        # efforts: in the efforts' own units, so the load-sharing term outweighs them as soon as
        # the foot's weight falls, whatever the robot's size (F / (m g) made it count only in
        # the last percent of a ramp: 60 N gone in 2 ms)
        lever = self.length / model.ground.default_reference
        for k, contact in enumerate(model.contacts):
            for i, row in enumerate(contact.rows):
                A[len(efforts) + 3 * k + i, int(row)] = feet[k] * lever
        return A, ca.SX.zeros(A.shape[0])

    def policy(self, pattern: ca.Sparsity) -> ca.Function:
        """``(W, offset, feet, lam, N, mask, w) -> lam``: among ``lam + N z`` (``N``, n_c x m
        of this ``pattern``, spanning the multipliers that change no constraint force), the
        one of least objective (``W`` the wrench map of :attr:`wrench_terms`), the entries of
        ``z`` where ``mask`` is 0 held at zero; by the normal equations, scaled to unit
        diagonal, and with feet on the ground (whose small weights near touch-down and
        lift-off make the problem ill-conditioned) refined once (corrected semi-normal
        equations). Built once per pattern: a plan's null space holds about half its entries
        (a foot's force travels through its own leg, the trunk and the kept feet's legs), and
        written for a dense one the walking robot's policy took twice the operations (87,641
        against 45,770 with twelve rows left out)."""
        key = (pattern.size1(), pattern.size2(), tuple(pattern.colind()),
               tuple(pattern.row()))
        cache = self.__dict__.setdefault("_policies", {})
        if key in cache:
            return cache[key]
        model, m = self.model, pattern.size2()
        W = ca.SX.sym("W", self._wrench_terms.sparsity_out(0))
        offset, feet = ca.SX.sym("offset", 6 * self.owners), ca.SX.sym("feet",
                                                                        len(model.contacts))
        lam, N, mask = ca.SX.sym("lam", model.n_c), ca.SX.sym("N", pattern), ca.SX.sym("mask", m)
        A, b = self._objective(W, offset, feet)
        G = ca.mtimes(A, N)
        H = ca.SX(m, m)
        for i in range(m):
            for j in range(i, m):
                H[i, j] = H[j, i] = ca.dot(G[:, i], G[:, j])
        solve = self.__dict__.setdefault("_normal_solves", {}).get(m)
        if solve is None:  # once per size: 11 ms each for the walking robot's
            solve = self._normal_solves[m] = ca.Function("normal_solve", *_normal_solve(m))
        g = ca.mtimes(A, lam) + b
        z = solve(H, ca.mtimes(G.T, g), mask)
        if model.contacts:  # feet of small weight make G ill-conditioned: refine once
            z = z + solve(H, ca.mtimes(G.T, ca.mtimes(G, z) + g), mask)
        cache[key] = self._function(f"phase_policy_{m}", [W, offset, feet, lam, N, mask, self.w],
                                  [lam + ca.mtimes(N, z)],
                                  ["W", "offset", "feet", "lam", "N", "mask", "w"],
                                  ["lam_policy"], cse=False)  # it would save 2 %
        return cache[key]

    @cached_property
    def report(self) -> ca.Function:
        """``(q, w, Phi, lam, offset) -> (wrench, frames)``: every joint's wrench in the report
        convention (6 x J: force, then moment about the joint origin, in the joint frame) and
        the joint frames' rotations (9 x J)."""
        model = self.model
        Phi_nz = ca.SX.sym("Phi", self.pattern.nnz())
        lam, offset = ca.SX.sym("lam", model.n_c), ca.SX.sym("offset", 6 * self.owners)
        W, frames = self._wrench_map(Phi_nz)
        return self._function("phase_report", [self.q, self.w, Phi_nz, lam, offset],
                              [self._joint_wrenches(W, frames, lam, offset), frames],
                              ["q", "w", "Phi", "lam", "offset"], ["wrench", "frames"])

    @cached_property
    def wrench_terms(self) -> ca.Function:
        """``(q, w, Phi) -> (W, frames)``: the wrench map (sparse) and the joint frames'
        rotations (:meth:`_wrench_map`), for a step that forms them once and gives them to
        the policy and to :attr:`joint_wrenches` (each formed them again: 11,000 operations a
        sample for the walking robot)."""
        Phi_nz = ca.SX.sym("Phi", self.pattern.nnz())
        return self._function("phase_wrench_terms", [self.q, self.w, Phi_nz],
                              list(self._wrench_map(Phi_nz)), ["q", "w", "Phi"],
                              ["W", "frames"])

    @cached_property
    def joint_wrenches(self) -> ca.Function:
        """``(W, frames, lam, offset, w) -> wrench``: :attr:`report`'s wrenches from the wrench
        map and the joint frames of :attr:`wrench_terms`."""
        W = ca.SX.sym("W", self._wrench_terms.sparsity_out(0))
        frames = ca.SX.sym("frames", self._wrench_terms.size_out(1))
        lam, offset = ca.SX.sym("lam", self.model.n_c), ca.SX.sym("offset", 6 * self.owners)
        return self._function("phase_joint_wrenches", [W, frames, lam, offset, self.w],
                              [self._joint_wrenches(W, frames, lam, offset)],
                              ["W", "frames", "lam", "offset", "w"], ["wrench"])

    def _joint_wrenches(self, W, frames, lam, offset):
        """Every joint's wrench in the report convention (6 x J), from the policy's wrenches
        ``W lam + offset``."""
        out = self._in_joint_frames(ca.mtimes(W, lam) + offset, frames)
        return ca.horzcat(*out) if out else ca.SX(6, 0)

    @cached_property
    def report_map(self) -> ca.Function:
        """``(q, w, Phi) -> (B, frames)``: the linear map from multipliers to :attr:`report`'s
        wrenches (6 J x n_c, joint by joint: force, then moment, in the joint frame), for
        wrenches without the forces across joints; the joint frames' rotations (9 x J)."""
        Phi_nz = ca.SX.sym("Phi", self.pattern.nnz())
        A, frames = self._wrench_map(Phi_nz)
        out = self._in_joint_frames(A, frames)
        B = ca.vertcat(*out) if out else ca.SX(0, self.model.n_c)
        return self._function("phase_report_map", [self.q, self.w, Phi_nz],
                              [ca.densify(B), frames], ["q", "w", "Phi"], ["B", "frames"],
                              to_c=False)

    def _in_joint_frames(self, world, frames) -> list:
        """The joints' blocks of ``world`` (policy wrenches, world axes, moments over the
        characteristic length: a column, or a map's columns) as the report gives them: in
        each joint's frame, moments in N m."""
        length = self.length
        out = []
        for k in range(len(self.model.joints)):
            R = ca.reshape(frames[:, k], 3, 3)
            force, moment = world[6 * k:6 * k + 3, :], world[6 * k + 3:6 * k + 6, :] * length
            out.append(ca.vertcat(ca.mtimes(R.T, force), ca.mtimes(R.T, moment)))
        return out


def terms_of(model: Model) -> StepTerms:
    """The model's :class:`StepTerms`, built once per model and execution (compiled to C when
    the execution setting says so)."""
    from hexapod._support.execution import current

    to_c = current().compiled
    return model.built_once(("phase-terms", to_c), lambda m: StepTerms(m, to_c))


def relative_residuals(Phi, x, rhs, d, root_mass):
    """Each constraint row's residual ``|Phi x - rhs| / d`` relative to the size of the
    problem, ``|M^1/2 x|_inf + |rhs / d|_inf`` (``d``: the rows' norms in ``M^-1/2``-scaled
    space, ``root_mass``: ``M^1/2``): how the phase path's checks weigh the velocity and
    acceleration constraints, on CasADi expressions (the plans' checks) or NumPy arrays (a
    first sample's known motion, ``root_mass`` anything with ``@``) alike."""
    symbolic = isinstance(x, (ca.SX, ca.MX))
    if symbolic:
        size = ca.norm_inf(ca.mtimes(root_mass, x)) + ca.norm_inf(rhs / d) + 1e-300
        return ca.fabs(ca.mtimes(Phi, x) - rhs) / d / size
    size = (np.max(np.abs(root_mass @ x), initial=0.0) + np.max(np.abs(rhs / d), initial=0.0)
            + 1e-300)
    return np.abs(Phi @ x - rhs) / d / size


def sx_function(name: str, inputs, outputs, to_c: bool, *names) -> ca.Function:
    """``ca.Function(name, inputs, outputs, *names)``, compiled to C when ``to_c``: the library
    is kept in the cache (when the execution setting has one) under the hash of the Function's
    serialized graph (a plan's Functions depend on its rows and pivots as well as on the
    model)."""
    function = ca.Function(name, inputs, outputs, *names)
    return compiled_graph(function, "phase", f"phase path {name}") if to_c else function


def _normal_solve(m: int):
    """``(H, r, mask) -> z``: ``z = -H^-1 r`` on the entries where ``mask`` is 1, zero on the
    others, with ``H`` symmetric positive definite there: scaled to unit diagonal, then
    Cholesky."""
    H, r, mask = ca.SX.sym("H", m, m), ca.SX.sym("r", m), ca.SX.sym("mask", m)
    Hm = ca.diag(mask) @ H @ ca.diag(mask) + ca.diag(1 - mask)
    s = 1 / ca.sqrt(ca.diag(Hm))
    Hs = ca.diag(s) @ Hm @ ca.diag(s)
    L = [[None] * m for _ in range(m)]
    for j in range(m):
        diagonal = Hs[j, j] - sum((L[j][k] ** 2 for k in range(j)), ca.SX(0))
        L[j][j] = ca.sqrt(diagonal)
        for i in range(j + 1, m):
            L[i][j] = (Hs[i, j] - sum((L[i][k] * L[j][k] for k in range(j)), ca.SX(0))) \
                / L[j][j]
    y = [None] * m
    rhs = -s * mask * r
    for i in range(m):
        y[i] = (rhs[i] - sum((L[i][k] * y[k] for k in range(i)), ca.SX(0))) / L[i][i]
    z = [None] * m
    for i in reversed(range(m)):
        z[i] = (y[i] - sum((L[k][i] * z[k] for k in range(i + 1, m)), ca.SX(0))) / L[i][i]
    return [H, r, mask], [s * ca.vertcat(*z)]
