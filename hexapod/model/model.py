"""The assembled model: frozen index maps, the constant mass matrix, and named CasADi Functions.

A :class:`Model` is built once by :func:`hexapod.assemble` and serves any number of runs; the
algorithms of layer 3 are functions ``f(model, data, t, q, v, ...)`` that keep their per-state
results in a :class:`Data` workspace (the model/data split of Pinocchio and MuJoCo).

Inputs of every Function (absent ones are dropped from the signature when a scene has no laws):

===========  ======  =====================================================================
``q``        n_q     positions: per body ``r, p`` (space), ``x, y, angle`` (plane), ``r`` (particle)
``v``        n_v     velocities: per body ``r_dot, omega'`` (body frame), or coordinate rates
``w``        n_w     values of the time laws at ``t`` (driver laws and load laws)
``wd``       n_w     their first time derivatives
``wdd``      n_w     their second time derivatives
===========  ======  =====================================================================

Functions: ``phi``, ``Phi_q``, ``Phi_v`` (of q, w), ``nu`` (q, w, wd), ``gamma``, ``M``, ``Q``;
``Phi_v v = nu``, ``Phi_v v_dot = gamma``, ``M v_dot + Phi_v^T lambda = Q`` along motions.
"""

from __future__ import annotations

import copy
import threading
from collections.abc import Callable
from functools import cached_property
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from hexapod._support.compiled import compiled_graph
from hexapod._support.execution import current
from hexapod._support.fastcall import FastFunction, ScatteredFunction, dense_outputs
from hexapod.errors import HexapodError
from hexapod.model.data import Data, kept
from hexapod.model.infos import (
    GROUND_INDEX,
    BodyInfo,
    ContactInfo,
    DriverInfo,
    ForceInfo,
    Guidance,
    JointInfo,
    RowInfo,
    Symbolic,
)
from hexapod.model.law_values import RecentLaws, evaluate_laws
from hexapod.model.mass import BlockDiagonal
from hexapod.scene.laws import Law
from hexapod.spatial import (
    Placement,
    quaternion_log,
    quaternion_product,
    retract_symbolic,
    rotation_from_euler_parameters,
)

if TYPE_CHECKING:
    from hexapod.scene.contacts import GroundForces

__all__ = ["GROUND_INDEX", "BodyInfo", "ContactInfo", "Data", "DriverInfo", "ForceInfo",
           "JointInfo", "Model", "RowInfo", "Symbolic"]
_MATRIX_OUTPUTS = frozenset({"Phi_q", "Phi_v", "M", "Q_across"})
#: what :meth:`Model.built_once` builds from the laws themselves (kept per set of laws)
_FROM_LAWS = frozenset({"law batches", "driven laws", "tabulated laws"})
#: outputs with more entries than this are evaluated on their nonzeros (ScatteredFunction)
_DENSE_OUTPUT_ENTRIES = 100_000


def _large(function: ca.Function) -> bool:
    """Whether an output of ``function`` has too many entries to be densified."""
    return any(function.numel_out(i) > _DENSE_OUTPUT_ENTRIES for i in range(function.n_out()))


class Model:
    """A frozen multibody model: sizes, index maps, the constant mass matrix and named CasADi
    Functions. Build it with :func:`hexapod.assemble`; run the algorithms on it with a
    workspace from :meth:`create_data`.

    Nothing in a model changes after it is built: its attributes cannot be set, and what it
    derives on first use (its CasADi Functions, and objects built from them alone such as the
    tree path's Function) is a pure function of what it was built from, the same whenever and
    in whichever thread it is derived. Everything that belongs to a run (call buffers, law
    values, rank decisions and the plans built for them) lives in a :class:`Data`, so that
    threads with their own ``Data`` share a model safely.

    The parameters of ``__init__`` are the attributes of the same names (keyword-only), which
    :func:`hexapod.assemble` computes from a scene.

    Attributes
    ----------
    name : str
        The scene's name.
    dimension : int
        3 (space) or 2 (plane).
    bodies, joints, drivers, rows, forces, contacts : tuple
        :class:`BodyInfo`, :class:`JointInfo`, :class:`DriverInfo`, :class:`RowInfo`,
        :class:`ForceInfo`, :class:`ContactInfo`, in model order.
    laws : tuple of Law
        The time laws whose values are the Functions' inputs ``w, wd, wdd``.
    n_q, n_v, n_c, n_w : int
        Numbers of coordinates, velocities, constraint rows and time laws.
    q0, v0 : ndarray (n_q,), (n_v,)
        The scene's initial positions and velocities (guesses; not necessarily consistent).
    mass : BlockDiagonal
        The constant mass matrix ``M`` (n_v x n_v), kg and kg m^2.
    gravity : ndarray (3,) or (2,)
        m/s^2.
    characteristic_length : float
        m: divides moments in the unit-free redundancy policy and scales length rows.
    rank_tolerance : float
        Of the rank decision on the equilibrated constraint matrix.
    digest : str
        The content hash of what the model was built from (:mod:`hexapod.model.digest`): the
        key of its cached code; empty for a model not built by :func:`hexapod.assemble`.
    source : str
        The file the scene was read from (empty for a scene built in Python).
    symbolic : Symbolic
        The CasADi symbols and expressions the Functions are built from.
    working_elements : tuple of str
        The drivers with time laws and force elements that do work not drawn from a potential
        (dampers, loads, efforts): the energy is conserved when there are none.
    report_forces : bool
        Whether simulations ask for the joint wrenches at the saved states (the scene's
        setting).
    ground : GroundForces or None
        The policy that shares the ground forces among the feet (None without contacts).
    guidance : Guidance or None
        The kinematics of the scene's guides and the laws of the joints that follow them
        (:mod:`hexapod.scene.laws.guided`); None without guides.
    """

    def __init__(self, *, name: str, dimension: int, bodies: tuple[BodyInfo, ...],
                 joints: tuple[JointInfo, ...], drivers: tuple[DriverInfo, ...],
                 rows: tuple[RowInfo, ...], laws: tuple[Law, ...], gravity: np.ndarray,
                 characteristic_length: float, q0: np.ndarray, v0: np.ndarray,
                 mass: BlockDiagonal, symbolic: Symbolic, forces: tuple[ForceInfo, ...],
                 rank_tolerance: float = 1e-9, working_elements: tuple[str, ...] = (),
                 report_forces: bool = False, contacts: tuple[ContactInfo, ...] = (),
                 ground: GroundForces | None = None, digest: str = "", source: str = "",
                 guidance: Guidance | None = None):
        self.name, self.source, self.digest, self.guidance = name, source, digest, guidance
        self.contacts, self.ground, self.report_forces = contacts, ground, report_forces
        self.dimension, self.bodies, self.joints, self.drivers = dimension, bodies, joints, drivers
        self.rows, self.laws, self.gravity, self.forces = rows, laws, gravity, forces
        self.characteristic_length, self.rank_tolerance = characteristic_length, rank_tolerance
        self.q0, self.v0, self.mass = q0, v0, mass
        self.mass_inv = mass.map_blocks(np.linalg.inv)
        self.mass_inv_sqrt = mass.power(-0.5)
        self.force_names = tuple(f.name for f in forces)
        self.working_elements = working_elements
        self._sym = symbolic
        self.n_q, self.n_v = q0.size, v0.size
        self.n_c, self.n_w = len(rows), len(laws)
        self.body_index = {b.name: b.index for b in bodies}
        self.joint_index = {j.name: j.index for j in joints}
        self.driver_index = {d.name: i for i, d in enumerate(drivers)}
        self.row_index = {r.name: i for i, r in enumerate(rows)}
        self._built: dict = {}  # see built_once
        self._built_from_laws: dict = {}  # the same, for what the laws decide
        self._lock = threading.RLock()
        self._recent_laws = RecentLaws()  # see law_values
        self._lie_indices()
        self._frozen = True

    def __setattr__(self, name: str, value) -> None:
        if getattr(self, "_frozen", False):
            raise AttributeError(f"a Model is frozen: '{name}' cannot be set (assemble a new "
                                 "model from a changed scene)")
        object.__setattr__(self, name, value)

    # ---------------------------------------------------------------- descriptions

    def __repr__(self) -> str:
        return (f"Model('{self.name}', {self.dimension}-D: {len(self.bodies)} bodies, "
                f"{len(self.joints)} joints, {len(self.drivers)} drivers; n_q={self.n_q}, "
                f"n_v={self.n_v}, n_c={self.n_c})")

    @cached_property
    def total_mass(self) -> float:
        """The sum of the bodies' masses (kg)."""
        return float(sum(b.mass for b in self.bodies))

    @cached_property
    def coordinate_names(self) -> tuple[str, ...]:
        names = {"spatial": ("x", "y", "z", "e0", "e1", "e2", "e3"),
                 "planar": ("x", "y", "angle"), "particle": ("x", "y", "z")}
        return tuple(f"{b.name}.{c}" for b in self.bodies
                     for c in names[b.kind][: b.q.stop - b.q.start])

    @cached_property
    def velocity_names(self) -> tuple[str, ...]:
        # spatial: the centre of mass's velocity in world axes, the angular velocity in body
        # axes (``wx_body``; the world-axes ``wx`` is what the report's trunk.csv writes)
        names = {"spatial": ("vx", "vy", "vz", "wx_body", "wy_body", "wz_body"),
                 "planar": ("vx", "vy", "w"), "particle": ("vx", "vy", "vz")}
        return tuple(f"{b.name}.{c}" for b in self.bodies
                     for c in names[b.kind][: b.v.stop - b.v.start])

    @cached_property
    def row_priority(self) -> np.ndarray:
        """Order in which rows are kept when the constraints are redundant: tree joints first,
        then loop-closing joints, then drivers (so a redundant closure or an over-constraining
        driver is what gets named), then the feet's contacts (with three feet or more down, the
        contact rows beyond the six the trunk needs are what gets named)."""
        feet = {c.joint for c in self.contacts}
        tree = [j.rows for j in self.joints if not j.loop_closing and j.index not in feet]
        loops = [j.rows for j in self.joints if j.loop_closing and j.index not in feet]
        drivers = [np.array([d.row]) for d in self.drivers]
        contacts = [c.rows for c in self.contacts]
        parts = tree + loops + drivers + contacts
        return np.concatenate(parts).astype(int) if parts else np.zeros(0, dtype=int)

    @cached_property
    def row_groups(self) -> np.ndarray:
        """The group of each entry of :attr:`row_priority` for the rank decision: joint rows
        each on their own (taken in order), drivers together (the best-conditioned first, see
        :func:`hexapod.algorithms.linalg.split_rows`), contact rows together (likewise). Which
        of several drivers over-constrains a mechanism, and which feet's rows are beyond what
        the trunk needs, are matters of conditioning; which joint row closes a loop is the
        policy's."""
        contact_rows = sum(c.rows.size for c in self.contacts)
        joint_rows = sum(j.rows.size for j in self.joints) - contact_rows
        return np.concatenate([np.arange(joint_rows), np.full(len(self.drivers), joint_rows),
                               np.full(contact_rows, joint_rows + 1)]).astype(int)

    def rank_order(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:attr:`row_priority` and :attr:`row_groups` for the rank decision at law values
        ``w``: without the rows of the feet in swing, which are identically zero there,
        constrain nothing and are neither kept nor redundant."""
        swing = [c.rows for c in self.contacts if w[c.gate] < 0.5]
        if not swing:
            return self.row_priority, self.row_groups
        keep = ~np.isin(self.row_priority, np.concatenate(swing))
        return self.row_priority[keep], self.row_groups[keep]

    @cached_property
    def row_scale(self) -> np.ndarray:
        """Natural size of each row's residual: the characteristic length for length rows, 1 for
        angle rows; used for convergence tests and drift reports in SI."""
        return np.array([self.characteristic_length if r.kind == "length" else 1.0
                         for r in self.rows])

    # ---------------------------------------------------------------- time laws

    def law_values(self, t, data: Data | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Values and derivatives of every law at ``t``: arrays (n_w,) or (n_w, len(t)).

        With ``data``, the values at the times of the last call with several times are kept
        there: the saddle path of the inverse dynamics asks for them again sample by sample,
        and some laws cost far less per sample evaluated together. The model keeps the last
        few single times' (:class:`~hexapod.model.law_values.RecentLaws`)."""
        t = np.asarray(t, dtype=float)
        if not self.n_w:  # no law to evaluate (a ball, a mechanism without drivers)
            return tuple(np.zeros((0,) + t.shape) for _ in range(3))
        batch = data.laws if data is not None else None
        if t.ndim == 0 and batch is not None and (column := batch[0].get(float(t))) is not None:
            return tuple(x[:, column].copy() for x in batch[1:])
        if t.ndim == 0 and (recent := self._recent_laws.get(float(t))) is not None:
            return recent
        shape = (self.n_w,) + t.shape
        w, wd, wdd = np.zeros(shape), np.zeros(shape), np.zeros(shape)
        evaluate_laws(self, t, w, wd, wdd)
        if data is not None and t.ndim == 1 and t.size > 1:
            data.laws = ({float(x): k for k, x in enumerate(t)}, w, wd, wdd)
        if t.ndim == 0:
            self._recent_laws.keep(float(t), (w, wd, wdd))
        return w, wd, wdd

    def cycle_time(self) -> float | None:
        """The longest period of the model's periodic laws (a gait's stride), in s; None when
        no law repeats."""
        cycles = [c for law in self.laws if (c := law.cycle_time()) is not None]
        return max(cycles) if cycles else None

    def time_window(self, duration: float | None = None) -> tuple[float, str]:
        """The duration of a report or a simulation, in s, and why: as asked, else one cycle of
        the model's periodic laws (the longest), else one second."""
        if duration is not None:
            return duration, "as asked"
        cycle = self.cycle_time()
        if cycle is not None:
            return cycle, "one cycle of the scene's periodic laws"
        return 1.0, "the default duration: the scene's laws do not repeat"

    def with_ground(self, ground: GroundForces, digest: str) -> Model:
        """This model with other ground-force settings, in SI (``digest``: the content hash of
        the scene they come from). What the model has built is shared when the settings differ
        only in numbers the solvers read at run time (``mu``, ``faces``, ``min_normal``: a
        sweep over friction reuses the built phase plans); a change of the policy or of the
        reference efforts, which the policy's Functions are built from, starts from nothing.
        The ground's shape cannot change (the footholds are built on it): assemble again."""
        if self.ground is not None and ground.terrain != self.ground.terrain:
            raise ValueError(f"model '{self.name}': the ground's shape (slope, heading, steps) "
                             "is built into its contacts; assemble the scene again")
        return self._twin(_built_from(ground) == _built_from(self.ground), ground=ground,
                          digest=digest)

    def with_laws(self, laws: tuple[Law, ...], digest: str, *,
                  share_built: bool = False) -> Model:
        """This model with other time laws, as many (``digest``: a content hash that tells
        them apart). With ``share_built``, what this model builds from its Functions alone
        (the inverse dynamics' terms and plans) is shared with it, for laws that change only
        the values of inputs (another motion of the same drivers); otherwise nothing is
        (compiled time loops may hold the laws themselves)."""
        if len(laws) != self.n_w:
            raise ValueError(f"model '{self.name}' has {self.n_w} laws, got {len(laws)}")
        return self._twin(share_built, laws=tuple(laws), digest=digest)

    def _twin(self, share_built: bool, **changes) -> Model:
        """A shallow copy with ``changes`` made (not the laws' recent values, nor what was
        built from them: its laws may not be these), sharing what is built or not."""
        # the call buffers made before the copy, for both to share: a guided model's twin, new
        # at each run, made and compiled its own retraction's (3 ms of the walking robot's run)
        _ = self._own_calls
        twin = copy.copy(self)
        for name, value in {**changes, "_recent_laws": RecentLaws(),
                            "_built_from_laws": {}}.items():
            object.__setattr__(twin, name, value)
        if not share_built:
            object.__setattr__(twin, "_built", {})
            object.__setattr__(twin, "_lock", threading.RLock())
        return twin

    def built_once(self, key: tuple, build: Callable[[Model], object]):
        """``build(self)``, computed on the first call with ``key`` and returned again after:
        immutable objects that are pure functions of the frozen model and cost a build (the
        tree path's Function, an integrator's Functions). Nothing of a run may go here (it goes
        in a :class:`Data`): no result depends on whether or when they were built."""
        store = self._built_from_laws if key[0] in _FROM_LAWS else self._built
        with self._lock:
            if key not in store:
                store[key] = build(self)
            return store[key]

    def create_data(self) -> Data:
        """A new, empty :class:`Data` workspace for this model."""
        return Data(model_sizes=self._sizes)

    @property
    def _sizes(self) -> tuple:
        return (self.name, self.n_q, self.n_v, self.n_c, self.n_w, self.digest)

    def check(self, data: Data) -> None:
        """Raise when ``data`` was not made by this model's :meth:`create_data` (or by a model
        of the same sizes and content).

        Raises
        ------
        HexapodError
        """
        if not isinstance(data, Data) or data.model_sizes != self._sizes:
            made = getattr(data, "model_sizes", None)
            raise HexapodError(f"this Data was made for another model ({made}), not for model "
                               f"'{self.name}': use model.create_data()")

    # ---------------------------------------------------------------- CasADi Functions

    def _function(self, name: str, inputs: list[str], outputs: list[tuple[str, ca.SX]]):
        sym = self._sym
        names = [n for n in inputs if n in ("q", "v") or self.n_w > 0]
        return ca.Function(name, [getattr(sym, n) for n in names], [e for _, e in outputs],
                           names, [n for n, _ in outputs])

    def _args(self, inputs: list[str], values: dict) -> list:
        return [values[n] for n in inputs if n in ("q", "v") or self.n_w > 0]

    @cached_property
    def _Phi_q_expr(self) -> ca.SX:
        return ca.jacobian(self._sym.phi, self._sym.q)

    @cached_property
    def _B_expr(self) -> ca.SX:
        """``B(q)``: ``qdot = B v``."""
        return ca.jacobian(self._sym.qdot, self._sym.v)

    @cached_property
    def _Phi_v_v_expr(self) -> ca.SX:
        """``Phi_v v = d phi/dq . q_dot``, forward mode (linear in ``v``)."""
        s = self._sym
        return ca.jtimes(s.phi, s.q, s.qdot)

    @cached_property
    def _Phi_v_expr(self) -> ca.SX:
        # ``Phi_q B``, formed as the coefficients of ``Phi_v v`` in ``v``: a fifth fewer
        # operations than the product of the two Jacobians
        return ca.jacobian(self._Phi_v_v_expr, self._sym.v)

    @cached_property
    def phi(self) -> ca.Function:
        """``phi(q, w)``: constraint residuals (n_c)."""
        return self._function("phi", ["q", "w"], [("phi", self._sym.phi)])

    @cached_property
    def Phi_q(self) -> ca.Function:
        """``Phi_q(q, w)``: Jacobian of ``phi`` in the coordinates (n_c x n_q)."""
        return self._function("Phi_q", ["q", "w"], [("Phi_q", self._Phi_q_expr)])

    @cached_property
    def Phi_v(self) -> ca.Function:
        """``Phi_v(q, w) = Phi_q B(q)``: Jacobian in the velocities (n_c x n_v)."""
        return self._function("Phi_v", ["q", "w"], [("Phi_v", self._Phi_v_expr)])

    @cached_property
    def _time_derivative(self) -> ca.SX:
        """``Phi_t``: the explicit time derivative of ``phi`` through the laws."""
        s = self._sym
        if self.n_w == 0:
            return ca.SX.zeros(self.n_c)
        return ca.jtimes(s.phi, s.w, s.wd)

    @cached_property
    def nu(self) -> ca.Function:
        """``nu(q, w, wd) = -Phi_t``: right-hand side of ``Phi_v v = nu``."""
        return self._function("nu", ["q", "w", "wd"], [("nu", -self._time_derivative)])

    @cached_property
    def gamma(self) -> ca.Function:
        """``gamma(q, v, w, wd, wdd)``: right-hand side of ``Phi_v v_dot = gamma``.

        ``gamma = -[d(Phi_v v)/dq] B v - 2 d(Phi_v v)/dt - Phi_tt``, with ``B(q)`` inside the
        derivative (``q_dot = B(q) v``: Euler parameters make ``n_q != n_v``). ``Phi_v v`` is
        formed as the derivative of ``phi`` along ``q_dot`` (forward mode), not as the product
        of the Jacobian's expression with ``v``: half the operations.
        """
        s = self._sym
        if self.n_w == 0:
            expr = -ca.jtimes(self._Phi_v_v_expr, s.q, s.qdot)
        else:
            # one direction (q_dot, wd) in (q, w): d/dt of Phi_v v + Phi_t along it holds the
            # cross term twice (the mixed derivatives are equal), as gamma needs, in 5 % fewer
            # operations than the three derivatives taken apart
            qw, rates = ca.vertcat(s.q, s.w), ca.vertcat(s.qdot, s.wd)
            expr = (-ca.jtimes(ca.jtimes(s.phi, qw, rates), qw, rates)
                    - ca.jtimes(s.phi, s.w, s.wdd))
        return self._function("gamma", ["q", "v", "w", "wd", "wdd"], [("gamma", expr)])

    @cached_property
    def M(self) -> ca.Function:
        """``M()``: the constant block-diagonal mass matrix (n_v x n_v)."""
        return ca.Function("M", [], [ca.DM(self.mass.dense())], [], ["M"])

    @cached_property
    def Q(self) -> ca.Function:
        """``Q(q, v, w)``: applied, spring, gyroscopic and gravity forces (n_v)."""
        return self._function("Q", ["q", "v", "w"], [("Q", self._sym.Q)])

    @cached_property
    def Q_across(self) -> ca.Function | None:
        """``Q_across(q, v, w)``: generalized forces of the force elements acting across joints,
        one column per such joint (see ``JointInfo.across_column``); None when there are none."""
        if self._sym.Q_across is None:
            return None
        return self._function("Q_across", ["q", "v", "w"], [("Q_across", self._sym.Q_across)])

    @cached_property
    def dynamics_terms(self) -> ca.Function:
        """``dynamics_terms(q, v, w, wd, wdd) -> (Phi_v, gamma, Q)``: what a forward-dynamics
        solve needs, in one call (each call costs tens of microseconds of overhead)."""
        s = self._sym
        args = [n for n in ("q", "v", "w", "wd", "wdd") if n in ("q", "v") or self.n_w > 0]
        outputs = [function(*[getattr(s, n) for n in function.name_in()])
                   for function in (self.Phi_v, self.gamma, self.Q)]
        return ca.Function("dynamics_terms", [getattr(s, n) for n in args], outputs, args,
                           ["Phi_v", "gamma", "Q"])

    @property
    def energy_conserved(self) -> bool:
        """True when no driver follows a time law and every force element derives from a
        potential: then kinetic plus potential energy is constant along motions."""
        return not self.working_elements

    @cached_property
    def energy(self) -> ca.Function:
        """``energy(q, v) -> (kinetic, potential)``: ``v^T M v / 2``, and the potential energy of
        gravity and springs (J)."""
        s = self._sym
        kinetic = ca.mtimes([s.v.T, ca.DM(self.mass.dense()), s.v]) / 2
        potential = s.potential if s.potential is not None else ca.SX(0.0)
        return ca.Function("energy", [s.q, s.v], [kinetic, potential], ["q", "v"],
                           ["kinetic", "potential"])

    @cached_property
    def tangent_matrices(self) -> ca.Function:
        """``tangent_matrices(q, v, lam, w) -> (K, C)``: derivatives of the force residual
        ``g = Phi_v^T lam - Q`` along a Lie-group displacement of the positions,
        ``K = dg/dq B(q)``, and in the velocities, ``C = dg/dv`` (n_v x n_v each): the tangent
        stiffness and damping of implicit integrators."""
        s = self._sym
        lam = ca.SX.sym("lam", self.n_c)
        names = [n for n in ("q", "v", "lam", "w") if n != "w" or self.n_w > 0]
        symbols = {"q": s.q, "v": s.v, "lam": lam, "w": s.w}
        return ca.Function("tangent_matrices", [symbols[n] for n in names],
                           self._tangents(ca.mtimes(self._Phi_v_expr.T, lam) - s.Q), names,
                           ["K", "C"])

    @cached_property
    def force_tangents(self) -> ca.Function:
        """``force_tangents(q, v, w) -> (K, C, Q)``: :attr:`tangent_matrices` with no
        multiplier, the derivatives of ``-Q`` alone (what a linearly implicit step takes),
        without the constraints' second derivatives that zero multipliers would multiply (on
        the walking robot half the instructions), and ``Q`` itself: one Function, their common
        subexpressions shared (the walking robot on the ground, its 36 joints under
        controllers: 45,049 instructions against 54,405 for ``Q`` and the tangents apart)."""
        s = self._sym
        names = [n for n in ("q", "v", "w") if n != "w" or self.n_w > 0]
        symbols = {"q": s.q, "v": s.v, "w": s.w}
        return ca.Function("force_tangents", [symbols[n] for n in names],
                           ca.cse([*self._tangents(-s.Q), s.Q]), names, ["K", "C", "Q"])

    def _tangents(self, g: ca.SX) -> list[ca.SX]:
        """``[dg/dq B(q), dg/dv]``: ``g``'s derivatives along a Lie-group displacement of the
        positions and in the velocities."""
        s = self._sym
        return [ca.mtimes(ca.jacobian(g, s.q), self._B_expr), ca.jacobian(g, s.v)]

    @cached_property
    def qdot(self) -> ca.Function:
        """``qdot(q, v) = B(q) v``."""
        return self._function("qdot", ["q", "v"], [("qdot", self._sym.qdot)])

    def call(self, name: str, data: Data | None = None, /, **values) -> np.ndarray:
        """Evaluate the Function ``name`` on numbers given by input name; vectors come back 1-D,
        matrices (``Phi_q``, ``Phi_v``, ``M``, ``Q_across``) 2-D. With ``data``, through call
        buffers kept in that workspace (about a microsecond of overhead instead of tens).

        >>> model.call("phi", q=q, w=w)      # doctest: +SKIP
        """
        function = self.fast(name, data)
        (array,) = function(*[values[n] for n in function.name_in])
        if name in _MATRIX_OUTPUTS:  # the shape of what is built (a twin may not have built
            # the Function itself: forming Phi_v's expressions cost the walking robot 17 ms)
            return array.reshape(self._evaluated(name).size_out(0))
        return array.reshape(-1)

    def fast(self, name: str, data: Data | None = None) -> FastFunction | ScatteredFunction:
        """The Function ``name`` evaluated through buffers (:mod:`hexapod._support.fastcall`):
        the same numbers, without the cost of converting arguments. The buffers are those of
        ``data`` (made once per workspace), or fresh ones without it. Large matrix outputs
        are evaluated on their nonzeros only (:class:`ScatteredFunction`)."""
        def make() -> FastFunction | ScatteredFunction:
            function = self._evaluated(name)
            return (ScatteredFunction if _large(function) else FastFunction)(function)

        return kept(data, name, make)

    def _evaluated(self, name: str) -> ca.Function:
        """The Function ``name`` as its buffers evaluate it: outputs densified, unless large."""
        def build(model: Model) -> ca.Function:
            function = getattr(model, name)
            return function if _large(function) else dense_outputs(function)
        return self.built_once(("evaluated", name), build)

    def call_samples(self, name: str, **values) -> np.ndarray:
        """Evaluate the Function ``name`` at N samples in one call: inputs by name with the
        samples along the first axis, (N, size); the output likewise, (N, size) for vectors and
        (N, rows, columns) for matrices."""
        function = getattr(self, name)
        inputs = [np.atleast_2d(np.asarray(values[n], dtype=float)) for n in function.name_in()]
        n = inputs[0].shape[0] if inputs else 1
        array = function.map(n, "serial")(*[x.T for x in inputs]).full()
        if name in _MATRIX_OUTPUTS:
            rows, columns = function.size_out(0)
            return array.reshape(rows, n, columns).transpose(1, 0, 2)
        return array.T

    # ---------------------------------------------------------------- Lie-group helpers

    def _lie_indices(self):
        lin_q, lin_v, quat_q, omega_v = [], [], [], []
        for b in self.bodies:
            q = list(range(b.q.start, b.q.stop))
            v = list(range(b.v.start, b.v.stop))
            if b.kind == "spatial":
                lin_q += q[:3]
                lin_v += v[:3]
                quat_q.append(q[3:])
                omega_v.append(v[3:])
            else:
                lin_q += q
                lin_v += v
        self._lin_q = np.array(lin_q, dtype=int)
        self._lin_v = np.array(lin_v, dtype=int)
        self._quat_q = np.array(quat_q, dtype=int).reshape(-1, 4)
        self._omega_v = np.array(omega_v, dtype=int).reshape(-1, 3)

    def integrate(self, q: np.ndarray, dv: np.ndarray) -> np.ndarray:
        """``q (+) dv``: translate by the linear part, rotate each spatial body by its body-frame
        rotation vector, ``p <- p * exp(dpi'/2)`` (unit Euler parameters stay unit): the
        :attr:`retract` Function evaluated through this thread's call buffers, compiled when
        the execution setting says so (on the walking robot 12 us a call by CasADi's virtual
        machine, 5 compiled, against 29 for the NumPy formulas it replaced)."""
        return self.retraction()(q, dv)[0]

    def retraction(self) -> FastFunction:
        """:meth:`integrate`'s Function under the execution setting, through this thread's call
        buffers: made once per thread (a tenth of a millisecond), compiled (or loaded from the
        cache) when the setting says so. An integrator makes it before its time loop, so that
        no compiler runs inside the loop (whose CPU counts the compiler's)."""
        compiled = current().compiled
        own, name = self._own_calls, "compiled retract" if compiled else "retract"
        fast = own.__dict__.get(name)
        if fast is None:
            function = self._evaluated("retract")
            fast = own.__dict__[name] = FastFunction(
                compiled_graph(function, "model", "the retraction") if compiled else function)
        return fast

    @cached_property
    def retract(self) -> ca.Function:
        """``retract(q, dv) -> q_new``: ``q (+) dv`` (:meth:`integrate`) on SX symbols, the one
        writing of the retraction (:func:`~hexapod.spatial.retract_symbolic`)."""
        q, dv = ca.SX.sym("q", self.n_q), ca.SX.sym("dv", self.n_v)
        q_new = retract_symbolic(q, dv, self._lin_q, self._lin_v, self._quat_q, self._omega_v)
        return ca.Function("retract", [q, dv], [q_new], ["q", "dv"], ["q_new"])

    @cached_property
    def _own_calls(self) -> threading.local:
        """Call buffers of each thread's own, for evaluations without a workspace (a twin
        shares them: the same Functions)."""
        return threading.local()

    def normalize(self, q: np.ndarray) -> np.ndarray:
        """Euler parameters scaled to unit length."""
        out = np.array(q, dtype=float)
        if self._quat_q.size:
            p = out[self._quat_q]
            out[self._quat_q] = p / np.linalg.norm(p, axis=1, keepdims=True)
        return out

    def difference(self, q1: np.ndarray, q0: np.ndarray) -> np.ndarray:
        """``q1 (-) q0``: the velocity-space step ``dv`` with ``integrate(q0, dv) = q1``."""
        dv = np.zeros(self.n_v)
        dv[self._lin_v] = q1[self._lin_q] - q0[self._lin_q]
        if self._quat_q.size:
            conjugate = q0[self._quat_q] * np.array([1.0, -1.0, -1.0, -1.0])
            dv[self._omega_v] = quaternion_log(quaternion_product(conjugate, q1[self._quat_q]))
        return dv

    def body_pose(self, q: np.ndarray, body: int) -> Placement:
        """World pose of a body's centre-of-mass frame (identity for the ground)."""
        if body == GROUND_INDEX:
            return Placement.identity(self.dimension)
        info = self.bodies[body]
        qb = np.asarray(q, dtype=float)[info.q]
        if info.kind == "spatial":
            return Placement(qb[:3], rotation_from_euler_parameters(qb[3:]))
        if info.kind == "planar":
            return Placement(qb[:2], float(qb[2]))
        return Placement(qb)


def _built_from(ground: GroundForces | None) -> tuple:
    """The ground-force settings the policy's Functions are built from (the rest are read at
    run time)."""
    if ground is None:
        return ()
    return (ground.policy, tuple(sorted(ground.reference_efforts.items())),
            ground.default_reference)
