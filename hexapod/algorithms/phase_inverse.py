"""Compiled inverse dynamics of closed loops and feet on the ground: the phase path.

The saddle path solves every sample in Python (Newton's method, a rank decision, the saddle-point
solve, the policy, the wrenches: some 70 ms a sample for the walking hexapod). The phase path
does the same work in CasADi Functions evaluated over many samples in one call:

* **phases**: runs of samples with one contact set (the gates of ``model.contacts``; one run for
  a mechanism without contacts). Each contact set gets one rank decision (kept rows ``I``, as
  many as velocities, left-out rows ``R``) with the pivots of the factorisation of
  ``Phi_v[I]``, and a :class:`~hexapod.algorithms.phase_plan.PhasePlan` for it (built once per
  model and decision), mapped over the phase with ``mapaccum``: each sample starts from the
  positions predicted by the one before. The decision is the exact solve's at the first sample
  (and wherever the exact solve redid a sample because the decision had stopped holding); for a
  new contact set the joints' and drivers' rows are kept as decided and the feet's chosen as
  the exact decision chooses them (the farthest from the span of those kept first), the feet
  that carry nothing at that sample last, so that their multipliers can be held at zero.
* **checks**: each sample comes with its position residual, the residuals of its kept and
  left-out rows, the size of the rows its decision did not weigh (the feet in swing: zero) and
  an estimate of its smallest singular value. A sample whose positions did not converge is
  evaluated again with more Newton steps, as are the samples after it (:data:`NEWTON_STEPS`).
  A sample that fails the checks otherwise (or with the most Newton steps: the rows left out no
  longer follow from those kept; a foot touched down unweighed; a singular pose), or one whose
  kept rows belong to a foot that carries nothing, is redone by the exact path
  (:func:`~hexapod.algorithms.sample_inverse.exact_sample`), and the phase goes on from it
  with the exact solve's decision when the failure was the decision's.
* **the first sample**: its positions by Newton's method from the scene's guess (or known),
  its rank decision there (which checks that the drivers fix every degree of freedom), then the
  plan's step from those positions, checked as any other sample; the exact path where the
  decision keeps fewer rows than velocities (it names what is free).
* **friction** (a QP): the plan gives the least-effort forces without the cones; a sample where
  they leave a pyramid (or fall below the least normal force), and every sample of the exact
  cone (``faces = 0``, IPOPT), gets its forces from the exact per-sample solve, QP included, at
  the compiled positions and velocities. (The walking hexapod's least-effort forces push its
  feet inwards: with ``mu = 0.8`` they leave the pyramids almost everywhere, so that its
  friction policy gains only the compiled kinematics.)

Same numbers as the saddle path to round-off (tests: the walking hexapod across a touch-down,
the standing one, the four-bars, friction). What differs: ``redundant_rows`` names the rows
left out by the decisions taken (one per contact set) and at the exact samples, where the
saddle path names those of every sample's own decision (which, among equivalent rows, pivots
by conditioning).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from hexapod._support import signals
from hexapod._support.execution import current
from hexapod.algorithms.ground import NO_LOAD, foot_values, in_contact_axes, sharing_weights
from hexapod.algorithms.kinematics import assemble_positions, state_split
from hexapod.algorithms.liaison import efforts_and_axes
from hexapod.algorithms.linalg import as_dense, equilibrate, split_rows
from hexapod.algorithms.phase_plan import NEWTON_STEPS, PhasePlan, plan_for
from hexapod.algorithms.sample_inverse import (
    SampleResult,
    exact_forces,
    exact_motion,
    exact_sample,
    known_sample,
)
from hexapod.algorithms.static_lu import StaticLU
from hexapod.algorithms.step_terms import StepTerms, relative_residuals, terms_of
from hexapod.errors import HexapodError
from hexapod.model.model import Data, Model

#: A sample is redone exactly when its scaled position residual is above this (a tenth of the
#: exact path's Newton tolerance, which then takes one more step) ...
POSITION_TOL = 1e-13
#: ... or the relative residual of its kept or left-out rows above this ...
RESIDUAL_TOL = 1e-9
#: ... or the estimated smallest singular value of its equilibrated kept rows below this
#: (an estimate from above: at most about sqrt(n_v) times the true value, so that the exact
#: rank decision, with its tolerance of 1e-9, keeps every row whenever this one passes).
SIGMA_TOL = 1e-6
#: The first sample's positions are found from the scene's guess to this scaled residual (the
#: exact path's Newton goes to 1e-12, then a step more): the plan's Newton steps take them to
#: round-off, as they do from the sample before's prediction (1e-6 off at samples 2 ms apart).
FIRST_TOL = 1e-8
#: Samples per call when progress is reported, and the most per call.
CHUNK = 2_000


class _Feet:
    """The per-sample inputs of the contacts: stance, weights, idle feet and the policy's
    per-foot values (see :meth:`PhasePlan._objective`)."""

    def __init__(self, model: Model, times: np.ndarray, motion: bool = False):
        contacts = model.contacts
        n = times.size
        self.stance = np.array([c.in_stance(times) for c in contacts], dtype=bool).reshape(-1, n)
        weights = np.array([c.weight(times) for c in contacts], dtype=float).reshape(-1, n)
        self.weights = weights = sharing_weights(weights, self.stance)
        # a foot that carries nothing has its multipliers held at zero (none in a motion run)
        self.idle = self.stance & (weights <= NO_LOAD) & (not motion)
        self.values = foot_values(model.ground.policy if contacts else "min-wrench", weights)
        self.owner = np.full(model.n_c, -1)  # the contact of each row
        for k, c in enumerate(contacts):
            self.owner[c.rows] = k
        # runs of samples with one contact set, numbered: a phase ends where the number changes
        changes = np.any(self.stance[:, 1:] != self.stance[:, :-1], axis=0)
        self.run = np.concatenate([[0], np.cumsum(changes)])

    def contact_set(self, k: int) -> tuple[bool, ...]:
        return tuple(bool(x) for x in self.stance[:, k])

    def run_end(self, k: int) -> int:
        """The first sample after ``k`` whose contact set is not that of ``k`` (or the end)."""
        return int(np.searchsorted(self.run, self.run[k], side="right"))

    def rows_idle(self, rows: np.ndarray, k: int) -> np.ndarray:
        """Which of ``rows`` belong to a foot that carries nothing at sample ``k``."""
        return self.rows_idle_over(rows, k, k + 1)[0]

    def rows_idle_over(self, rows: np.ndarray, start: int, stop: int) -> np.ndarray:
        """Which of ``rows`` belong to a foot that carries nothing, at each sample from
        ``start`` to ``stop - 1`` (samples x rows)."""
        owner = self.owner[rows]
        if not self.idle.size:
            return np.zeros((stop - start, owner.size), dtype=bool)
        return ((owner >= 0)[:, None] & self.idle[np.maximum(owner, 0), start:stop]).T


class _Results:
    """The arrays of an :class:`~hexapod.algorithms.inverse.InverseResult`, filled sample by
    sample or by runs of samples."""

    def __init__(self, model: Model, n: int, world: bool, motion: bool = False):
        self.model = model
        J, C = (0, 0) if motion else (len(model.joints), len(model.contacts))
        self.q, self.v = np.zeros((n, model.n_q)), np.zeros((n, model.n_v))
        self.v_dot = np.zeros((n, model.n_v))
        self.force, self.torque = np.zeros((n, J, 3)), np.zeros((n, J, 3))
        self.effort, self.ground = np.zeros((n, J)), np.zeros((n, C, 3))
        self.violation = np.zeros(n)
        self.known: tuple | None = None  # the motion known at the samples (q, v, v_dot)
        # the joint frames of the compiled samples, kept for world axes only
        self.frames = np.zeros((n, J, 9)) if world else None
        self.redundant: list[str] = []
        self.exact = np.zeros(n, dtype=bool)

    def store(self, k: int, sample: SampleResult) -> None:
        self.q[k], self.v[k], self.v_dot[k] = sample.q, sample.v, sample.v_dot
        self.force[k], self.torque[k], self.effort[k] = (sample.force, sample.torque,
                                                         sample.effort)
        if sample.ground.size:
            self.ground[k] = sample.ground
        self.violation[k] = sample.violation
        self.name(sample.redundant)
        self.exact[k] = True

    def name(self, rows) -> None:
        self.redundant += [r for r in rows if r not in self.redundant]

    def state(self, k: int) -> np.ndarray:
        return np.concatenate([self.q[k], self.v[k], self.v_dot[k]])

    def predicted(self, k: int, times) -> np.ndarray:
        """The positions at sample ``k``: known (a guided model's, from its guides'
        kinematics), or predicted from ``k - 1``."""
        if self.known is not None:
            return self.known[0][k]
        h = times[k] - times[k - 1]
        return self.model.integrate(self.q[k - 1],
                                    h * self.v[k - 1] + h * h / 2 * self.v_dot[k - 1])


def phase_inverse(model: Model, data: Data, times: np.ndarray, w, wd, wdd, frame: str, *,
                  progress: Callable[[int, int], None] | None = None,
                  known: tuple | None = None, motion: bool = False) -> dict:
    """The phase path over ``times`` (laws ``w, wd, wdd`` given, n_w x N): the fields of an
    :class:`~hexapod.algorithms.inverse.InverseResult` as a dict, with ``exact_samples``, the
    number of samples solved by the exact path, and ``newton_steps``, the Newton steps a
    sample took at the end (:data:`~hexapod.algorithms.phase_plan.NEWTON_STEPS`). Compiled or
    interpreted as the execution setting says (:mod:`hexapod._support.execution`). ``known``:
    the motion ``(q, v, v_dot)`` at the samples when it is known already (a guided model's):
    Newton's starting points, and where the constraints leave a motion free, its velocities
    (by the exact path). ``motion``: the motion alone (a kinematics run: the fields of forces
    are empty, and the drivers must prescribe every degree of freedom), as
    :func:`phase_motion` gives it."""
    to_c = current().compiled
    n = times.size
    out = _Results(model, n, frame == "world", motion)
    out.known = known
    feet = _Feet(model, times, motion)
    first = _first_positions(model, data, times, w, wd, wdd, known)
    if first is None:  # the drivers leave a motion free there: the exact path says which
        out.store(0, _exact(model, data, out, times, 0, frame, known, motion))
    decisions = _Decisions(model, data, terms_of(model), feet, to_c, motion)
    decisions.adopt(0, data, w[:, 0])
    # Newton steps per sample (none from known positions): more once samples prove far apart
    newton = NEWTON_STEPS[0] if known is None else 0
    k, chunk = (1 if first is None else 0), CHUNK
    while k < n:
        plan = decisions.plan(k, out.predicted(k, times) if k else first, w[:, k])
        stop = min(n, k + chunk, feet.run_end(k))
        failed = None
        if plan is not None:
            failed = _run(plan, data, newton, out, feet, times, w, wd, wdd, k, stop, first)
        more = [] if failed is None or failed[1] != "newton" else [
            steps for steps in NEWTON_STEPS if steps > newton]
        if more:  # samples too far apart for the Newton steps taken: from there on, more
            newton, k = more[0], failed[0]
        elif plan is None or failed is not None:
            bad, blame = (k, "rank") if plan is None else failed
            out.store(bad, _exact(model, data, out, times, bad, frame, known, motion))
            if blame == "rank":  # the decision no longer holds: take the exact solve's
                decisions.adopt(bad, data, w[:, bad], plan)
            k, chunk = bad + 1, 1  # short runs after a failure, growing again
        else:
            k, chunk = stop, min(2 * chunk, CHUNK)
        if signals.received() is not None:  # an interruption a library call swallowed
            raise KeyboardInterrupt
        if progress is not None:
            progress(k, n)
    if motion:
        return {"q": out.q, "v": out.v, "v_dot": out.v_dot,
                "max_violation": float(out.violation.max()),
                "redundant_rows": tuple(out.redundant), "exact_samples": int(out.exact.sum()),
                "newton_steps": newton}
    _frames(model, out, frame)
    if model.contacts and model.ground.policy == "friction":
        _friction(model, data, out, feet, times, frame)
    return {"q": out.q, "v": out.v, "v_dot": out.v_dot, "force": out.force,
            "torque": out.torque, "effort": out.effort, "ground": out.ground,
            "max_violation": float(out.violation.max()),
            "redundant_rows": tuple(out.redundant), "exact_samples": int(out.exact.sum()),
            "newton_steps": newton}


def phase_motion(model: Model, data: Data, times: np.ndarray, w, wd, wdd, *,
                 progress: Callable[[int, int], None] | None = None) -> tuple:
    """The motion ``(q, v, v_dot)`` (each (N, size)) the drivers of ``model`` prescribe at
    ``times`` (laws ``w, wd, wdd`` given, n_w x N), continuous along them: the phase path's
    positions, velocities and accelerations without the multipliers, the policy or the
    wrenches (a guided model's guides' kinematics, :mod:`hexapod.algorithms.guided`).

    Raises
    ------
    SingularSystemError
        When the drivers leave degrees of freedom free.
    """
    fields = phase_inverse(model, data, times, w, wd, wdd, "joint", progress=progress,
                           motion=True)
    return fields["q"], fields["v"], fields["v_dot"]


def sample_plans(model: Model, data: Data, times: np.ndarray, w, known: tuple, *,
                 motion: bool = False) -> list[tuple[PhasePlan, np.ndarray, np.ndarray]]:
    """The phase path's plan at each sample of a motion ``known`` there (``q, v, v_dot``,
    each (N, size); laws ``w``, n_w x N), with the mask of its left-out rows (1: free, 0: a
    foot that carries nothing) and the feet's policy values: one rank decision per run of
    samples with one contact set, the exact solve's at the run's first sample, the feet
    chosen again where one stops carrying (as :func:`phase_inverse` decides). For
    evaluating the plans' Functions at known samples (their derivatives:
    :mod:`hexapod.algorithms.law_tangents`).

    Raises
    ------
    HexapodError
        At a sample where the drivers and contacts do not fix every degree of freedom (a
        trunk on two feet): no plan covers it.
    """
    feet = _Feet(model, times, motion)
    decisions = _Decisions(model, data, terms_of(model), feet, current().compiled, motion)
    out, run = [], -1
    for k in range(times.size):
        if feet.run[k] != run:  # a new contact set: the exact solve's decision
            run = feet.run[k]
            if motion:
                exact_motion(model, data, times[k], known[0][k], times[k])
            else:
                known_sample(model, data, times, known, k)
            decisions.adopt(k, data, w[:, k])
        plan = decisions.plan(k, known[0][k], w[:, k])
        if plan is None:
            raise HexapodError(f"model '{model.name}' at t = {times[k]:.6g} s: its drivers and "
                               "contacts leave a motion free (its dynamics decides it), which "
                               "the phase path's plans do not cover")
        mask = (~feet.rows_idle(plan.left_out, k)).astype(float)
        out.append((plan, mask, feet.values[:, k]))
    return out


def _first_positions(model: Model, data: Data, times: np.ndarray, w, wd, wdd,
                     known: tuple | None) -> np.ndarray | None:
    """The first sample's positions, Newton's from the scene's guess (or known there), with
    the rank decision at them left in ``data`` as the exact path leaves its own, when that
    decision keeps as many rows as velocities (the drivers fix every degree of freedom): the
    plan's step then evaluates the sample from them, as if from the sample before at rest and
    no time before, and checks it like any other. None where rows are missing, or where a
    known motion's accelerations do not meet the constraints (:func:`_accelerations_met`):
    the exact path evaluates the sample and says what the drivers leave free, or where the
    dynamics leaves the known motion."""
    t = float(times[0])
    if known is None:  # to FIRST_TOL: the plan's Newton steps take them to round-off
        q = assemble_positions(model, data, t, model.q0, tol=FIRST_TOL, polish=False)
    else:
        q = np.array(known[0][0], dtype=float)
        data.at(t, q)
    Phi = model.call("Phi_v", data, q=q, w=w[:, 0])
    split = state_split(model, data, q, w[:, 0], Phi)
    if split.independent.size != model.n_v or (known is not None and not _accelerations_met(
            model, data, q, known[1][0], known[2][0], Phi, split.scale, w[:, 0], wd[:, 0],
            wdd[:, 0])):
        return None
    data.independent_rows, data.redundant_rows = split.independent, split.redundant
    return q


def _accelerations_met(model: Model, data: Data, q, v, v_dot, Phi, d, w, wd, wdd) -> bool:
    """Whether a known motion's accelerations ``v_dot`` meet the acceleration constraints at
    ``(q, v)`` (``d``: the rows' norms, the rank decision's scales), each row's residual
    weighed as the plans' checks weigh it (:func:`~hexapod.algorithms.step_terms.
    relative_residuals`, at most :data:`RESIDUAL_TOL`). A plan takes a known motion's
    accelerations as they are; at the first sample the exact path checked that the dynamics
    follows them, and this is that check."""
    gamma = model.call("gamma", data, q=q, v=v, w=w, wd=wd, wdd=wdd)
    residuals = relative_residuals(Phi, v_dot, gamma, d, model.mass.power(0.5))
    return bool(np.max(residuals, initial=0.0) <= RESIDUAL_TOL)


def _exact(model: Model, data: Data, out: _Results, times: np.ndarray, k: int, frame: str,
           known: tuple | None, motion: bool) -> SampleResult:
    """Sample ``k`` by the exact path: Newton from the positions known there, or predicted
    from the sample before (the first from the scene's guess, checking that the drivers leave
    no degree of freedom free)."""
    if known is not None:
        return known_sample(model, data, times, known, k, frame)
    t0, q0, rates = ((times[0], model.q0, None) if k == 0 else
                     (times[k - 1], out.q[k - 1], (out.v[k - 1], out.v_dot[k - 1])))
    if motion:
        return exact_motion(model, data, t0, q0, times[k], rates)
    return exact_sample(model, data, t0, q0, times[k], rates, frame=frame)


class _Decisions:
    """The rank decisions of a run, one per contact set, and their plans.

    A decision is the exact solve's where it has one (the first sample, and where it redid a
    sample because the decision had stopped holding); for a new contact set, the rows of the
    joints and drivers are kept as decided, and the feet's rows the run before kept are held
    while their feet are on the ground and carry load (as the exact path holds its last
    decision while its rows stay independent: each sample's checks watch their rank, and the
    policy's forces do not depend on which independent rows are kept); else those of the feet
    are chosen among the feet on the ground as the exact decision chooses them (the farthest
    from the span of those kept first), the feet that carry nothing last, so that their
    multipliers can be held at zero."""

    def __init__(self, model: Model, data: Data, terms: StepTerms, feet: _Feet, to_c: bool,
                 motion: bool = False):
        self.model, self.data, self.terms, self.feet, self.to_c = model, data, terms, feet, to_c
        self.motion = motion
        self.plans: dict = {}
        self.base = None  # the kept and left-out rows that are no foot's
        self.last: PhasePlan | None = None  # the plan of the run before
        self.generation: dict = {}  # per kept and left-out rows: plans whose pivots failed

    def adopt(self, k: int, data, w_k, failed: PhasePlan | None = None) -> None:
        """The exact solve's decision at sample ``k`` (held in ``data``); when it keeps the
        rows of the plan that ``failed`` there, new pivots for them."""
        kept, left = np.sort(data.independent_rows), np.sort(data.redundant_rows)
        if failed is not None and np.array_equal(failed.kept, kept) and np.array_equal(
                failed.left_out, left):
            key = (tuple(kept.tolist()), tuple(left.tolist()))
            self.generation[key] = self.generation.get(key, 0) + 1
        foot = self.feet.owner >= 0
        self.base = (kept[~foot[kept]], left[~foot[left]])
        key = self.feet.contact_set(k)
        idle = self.feet.rows_idle(kept, k)
        if kept.size != self.model.n_v:
            self.plans.pop(key, None)
        elif idle.any():
            self.plans[key] = self._select(k, data.q, w_k)
        else:
            self.plans[key] = self._plan(data.q, w_k, kept, left)

    def plan(self, k: int, q, w_k) -> PhasePlan | None:
        """The plan of sample ``k``'s contact set (decided at ``q`` when it has none yet, or
        when its kept rows hold a foot that carries nothing at ``k``)."""
        key = self.feet.contact_set(k)
        plan = self.plans.get(key)
        if plan is None or self.feet.rows_idle(plan.kept, k).any():
            plan = self.plans[key] = self._held(k, q, w_k) or self._select(k, q, w_k)
        self.last = plan
        return plan

    def _held(self, k: int, q, w_k) -> PhasePlan | None:
        """The plan keeping the rows the plan of the run before kept, at sample ``k``'s new
        contact set, when their feet are on the ground and carry load there (the other feet's
        rows left out); None otherwise."""
        last, feet = self.last, self.feet
        if last is None or self.base is None:
            return None
        owner = feet.owner[last.kept]
        base, left = self.base
        if (not np.array_equal(last.kept[owner < 0], base)
                or not feet.stance[owner[owner >= 0], k].all()
                or feet.rows_idle(last.kept, k).any()):
            return None
        on_ground = self._feet_rows(w_k)
        return self._plan(q, w_k, last.kept,
                          np.concatenate([left, np.setdiff1d(on_ground, last.kept)]).astype(int))

    def _feet_rows(self, w_k) -> np.ndarray:
        """The rows of the feet on the ground at law values ``w_k``, in the model's priority
        order."""
        priority, _ = self.model.rank_order(w_k)
        return priority[self.feet.owner[priority] >= 0]

    def _select(self, k: int, q, w_k) -> PhasePlan | None:
        """The feet's rows to keep at sample ``k`` with the joints' and drivers' as decided:
        the rank decision (:func:`~hexapod.algorithms.linalg.split_rows`) on those rows, then
        the feet that carry load, then the others."""
        model = self.model
        if self.base is None or not model.contacts:
            return None
        base, left = self.base
        Phi = model.call("Phi_v", self.data, q=q, w=w_k)
        W, d = equilibrate(Phi, model.mass_inv_sqrt)
        feet = self._feet_rows(w_k)
        idle = self.feet.rows_idle(feet, k)
        order = np.concatenate([base, feet[~idle], feet[idle]]).astype(int)
        groups = np.concatenate([np.arange(base.size), np.full((~idle).sum(), base.size),
                                 np.full(idle.sum(), base.size + 1)])
        split = split_rows(as_dense(W), d, order, model.rank_tolerance, groups=groups)
        if split.rank != model.n_v:
            return None
        return self._plan(q, w_k, split.independent,
                          np.concatenate([left, split.redundant]).astype(int))

    def _plan(self, q, w_k, kept, left) -> PhasePlan | None:
        """The plan of a decision (for a new one, the pivots of ``Phi_v[kept]`` at the model's
        reference positions ``q0`` where they serve the matrix at ``q``, else at ``q``). The
        rows are sorted: a decision that keeps the same rows in another order (the exact one
        orders drivers and feet by their conditioning) is the same plan."""
        model, terms = self.model, self.terms
        kept, left = np.sort(kept), np.sort(left)
        key = (tuple(kept.tolist()), tuple(left.tolist()))
        generation = self.generation.get(key, 0)

        def make() -> StaticLU:
            where = np.full(model.n_c, -1)
            where[kept] = np.arange(kept.size)
            entries = np.flatnonzero(where[terms.pattern_rows] >= 0)
            rows, columns = where[terms.pattern_rows[entries]], terms.pattern_columns[entries]

            def values(at) -> np.ndarray:
                return model.call("Phi_v", self.data, q=at, w=w_k)[kept[rows], columns]

            def at_reference() -> StaticLU | None:
                try:
                    return StaticLU.pivoted(rows, columns, model.n_v, values(model.q0))
                except RuntimeError:  # singular at q0
                    return None

            here = values(q)
            if generation == 0:
                # the same pivots whatever the samples and the process (the decisions' own
                # differed with the positions they were taken at: a run on other samples
                # compiled its plans' code again); on the walking robot they factor every
                # sample of a stride with a growth of at most 2.9 (1.3 to 2.0 at q0). One
                # object per kept rows: plans that leave out other rows share its Functions.
                reference = model.built_once(("phase reference pivots", kept.tobytes()),
                                             lambda m: at_reference())
                if reference is not None and reference.serves(here):
                    return reference
            return StaticLU.pivoted(rows, columns, model.n_v, here)

        try:
            return plan_for(terms, kept, left, make, generation, self.to_c, self.motion)
        except RuntimeError:  # exactly singular there
            return None


def _run(plan: PhasePlan, data: Data, newton: int, out: _Results, feet: _Feet, times, w, wd,
         wdd, k: int, stop: int, first: np.ndarray | None = None):
    """Samples ``k`` to ``stop - 1`` by the plan; results kept up to the first that fails
    (from the first sample on, ``k = 0``: from its positions ``first``, at rest).
    Returns None, or that sample and what failed: ``"newton"`` (its positions did not
    converge), ``"rank"`` (its rows left out no longer follow from those kept, or rows the
    decision did not weigh constrain it, or it is near a singular pose, or its kept rows hold a
    foot that carries nothing)."""
    model = plan.model
    span = slice(k, stop)
    mask = (~feet.rows_idle_over(plan.left_out, k, stop)).astype(float).T
    if k:
        before, steps = out.state(k - 1), np.diff(times[k - 1:stop])
    else:  # the first sample: its own positions predicted over no time
        before = np.concatenate([first, np.zeros(2 * model.n_v)])
        steps = np.diff(times[:stop], prepend=times[0])
    state, lam, wrench, frames, checks = plan.evaluate(
        data, before, steps, w[:, span], wd[:, span], wdd[:, span],
        feet.values[:, span], mask, newton,
        None if out.known is None else np.hstack([x[span] for x in out.known]))
    checks = np.nan_to_num(checks, nan=np.inf)
    finite = np.all(np.isfinite(state), axis=1) & np.all(np.isfinite(wrench), axis=(1, 2))
    idle_kept = feet.rows_idle_over(plan.kept, k, stop).any(axis=1)
    rank_ok = (finite & (checks[:, 1:5].max(axis=1) <= RESIDUAL_TOL) & (checks[:, 5] == 0)
               & (checks[:, 6] < np.inf) & (checks[:, 6] >= SIGMA_TOL) & ~idle_kept)
    good = rank_ok & (checks[:, 0] <= POSITION_TOL)
    count = stop - k if good.all() else int(np.argmin(good))
    n_q, n_v = model.n_q, model.n_v
    done = slice(k, k + count)
    out.q[done], out.v[done] = state[:count, :n_q], state[:count, n_q:n_q + n_v]
    out.v_dot[done] = state[:count, n_q + n_v:]
    out.force[done], out.torque[done] = wrench[:count, :, :3], wrench[:count, :, 3:]
    if out.frames is not None:
        out.frames[done] = frames[:count]
    out.violation[done] = checks[:count, 0]
    for c, contact in enumerate(model.contacts if not plan.motion else ()):
        out.ground[done, c] = -lam[:count][:, contact.rows]
    if count:
        out.name([model.rows[i].name for i in plan.left_out])
    if count == stop - k:
        return None
    return k + count, ("newton" if rank_ok[count] else "rank")


def _frames(model: Model, out: _Results, frame: str) -> None:
    """Efforts from the joint-frame wrenches of the compiled samples, and world axes when
    asked (the exact samples are already in the frame asked)."""
    compiled = np.flatnonzero(~out.exact)
    if compiled.size == 0:
        return
    rotations = out.frames[compiled] if frame == "world" else None
    out.force[compiled], out.torque[compiled], out.effort[compiled] = efforts_and_axes(
        model, out.force[compiled], out.torque[compiled], rotations, frame)


def _friction(model: Model, data: Data, out: _Results, feet: _Feet, times, frame: str) -> None:
    """Samples where the least-effort forces leave a friction cone (or the exact cone is
    asked): forces by the exact per-sample solve, QP included."""
    ground = model.ground
    for k in np.flatnonzero(~out.exact):
        if ground.faces and _inside_cones(ground, feet, in_contact_axes(model, out.ground[k]),
                                          k):
            continue
        sample = exact_forces(model, data, times[k], out.q[k], out.v[k], frame=frame)
        out.store(k, sample)


def _inside_cones(ground, feet: _Feet, forces: np.ndarray, k: int) -> bool:
    """Whether every loaded foot's force (``forces``, each in its contact's axes) is inside its
    pyramid and above its least normal force (then the least-effort forces are the QP's
    solution)."""
    angles = 2 * np.pi * (np.arange(ground.faces) + 0.5) / ground.faces
    for c in np.flatnonzero(feet.weights[:, k] > NO_LOAD):
        fx, fy, fz = forces[c]
        if fz < feet.weights[c, k] * ground.min_normal:
            return False
        limit = ground.mu * np.cos(np.pi / ground.faces) * fz
        if np.max(np.cos(angles) * fx + np.sin(angles) * fy) > limit:
            return False
    return True
