"""Singular configurations: how the integrators see them, cross them, and name them.

Near a pose where the constraint Jacobian loses rank (a four-bar lying flat, a leg stretched)
the smallest singular value ``sigma`` of the equilibrated ``Phi_v`` falls towards zero. The
adaptive explicit methods cross such a pose (:meth:`SingularPoses._cross_singular`): the rows
nearly dependent on the others are left out of the stages for a few short steps, the
projection after each step keeping every constraint; the others name the pose in the message
of their failure (:meth:`SingularPoses._singular_pose`). :class:`SingularPoses` is a part of
:class:`~hexapod.simulation.integrators.base.Integrator` (a base class of it), whose
``__init__`` sets the crossing's state (``_crossing``, ``_crossing_from``, ...).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
from scipy.linalg import qr

from hexapod.algorithms.kinematics import rank_split
from hexapod.algorithms.linalg import as_dense
from hexapod.algorithms.rows import gram_exceeds
from hexapod.algorithms.saddle import constraint_jacobian, is_large
from hexapod.errors import HexapodError
from hexapod.simulation.kernels import compiled_rates, row_gram
from hexapod.simulation.scales import characteristic_time

#: smallest singular value of the equilibrated ``Phi_v`` (rows of unit length, so 1 is
#: well-conditioned) below which a state counts as near a singular configuration. Approaching
#: such a pose, the motion's derivatives off the constraints grow as ``1 / sigma`` and the error
#: test lets steps shrink with the distance to it, never reaching it (the N-four-bar at rtol
#: 1e-10 stalled 3e-7 from its flat pose, the step at 7e-15 s); so the crossing leaves the
#: nearly dependent rows out there
SINGULAR_BAND = 1e-4
#: the crossing's tolerance over the smallest singular value where it begins (or widens)
CROSSING_FACTOR = 10.0
#: the largest singular value a crossing leaves out with a cluster of smaller ones (rows of
#: unit length: a well-posed row's are of order 0.1 to 1); the N-four-bar's 40 windows spread
#: theirs over a factor 26, 8e-5 to 2e-3 where DOPRI5 at rtol 1e-9 begins to cross
CLUSTER_CEILING = 1e-2
#: a crossing's step may not end nearer the pose than where the smallest singular value is
#: this fraction of the one where the crossing began (see :meth:`Integrator._lands_on_pose`)
POSE_CLEARANCE = 0.1
#: a crossing begins only where the pose is foreseen (its distance over the smallest singular
#: value's rate) within this many of the last accepted steps (none before the first) and within
#: this fraction of the model's characteristic time. At the N-four-bars (10 and 40 windows, 2-D
#: and 3-D) and the anti-parallelograms from rtol 1e-6 to 1e-10, the rejections that begin
#: crossings foresee their poses within 4.5 steps and 5.5e-4 characteristic times; the walking
#: hexapod, whose smallest singular value is 5e-5 where nothing is singular and drifts at 3e-5
#: per second, foresaw one 330 steps and 10 characteristic times ahead, and crept on the
#: crossing's capped steps to the end of its run (647 steps instead of 31)
FORESIGHT_STEPS = 50
FORESIGHT_TIME = 1e-2
#: a crossing begins only where the smallest singular value has also fallen below this
#: fraction of its value at the start: a mechanism's own value, away from any pose, may lie in
#: the band (the walking hexapod's stays between 5.2e-5 and 6.5e-5 all stride long, 0.81 to
#: 1.02 of its start), and each rejected step then paid two rank decisions and SVDs to find
#: no pose ahead (a fifth of its run). Where a mechanism starts above ``SINGULAR_BAND /
#: FALLEN`` the band alone decides, as it does for the crossings' test mechanisms (the lowest,
#: the spatial N-four-bar of ten windows, starts at 1.39e-4)
FALLEN = 0.75


class SingularPoses:
    """The singular-configuration services of an integrator (see the module's description)."""

    #: a failure is reported as one at a singular configuration (:meth:`_singular_pose`) where
    #: a singular value of the equilibrated ``Phi_v`` has fallen below this fraction of its
    #: value at the start (:attr:`_spectrum_start`, the singular values compared in sorted
    #: order): their values away from such poses depend on the mechanism and its masses (5e-5
    #: on a hexapod, 0.08 on the N-four-bar standing up), so only their fall tells one
    near_singular = 0.05
    #: the methods that cross singular configurations (the crossing of :meth:`_cross_singular`)
    crossing_methods = ("dopri5-projection", "dop853-projection")

    @property
    def crossing(self) -> bool:
        """Whether a crossing of a singular configuration is under way (its steps are short for
        a while: :meth:`_cross_singular`)."""
        return self._crossing is not None

    def _cross_singular(self) -> bool:
        """Begin crossing a singular configuration if the state is near one (see
        :data:`SINGULAR_BAND`) and moving towards it, or widen the crossing under way; returns
        whether it did. Moving away from a singular pose, the rows are all kept: the steps then
        grow back as the distance to the pose does, and a crossing begun there would leave rows
        out over a band ten times as wide as the state's, for nothing.

        While crossing, the rows nearly dependent on the others (as many as there are singular
        values of the equilibrated ``Phi_v`` below the crossing's tolerance, ``CROSSING_FACTOR``
        times the smallest where it began) are left out: the stages then solve one smooth
        system of fewer rows, compiled for them, and the projection after each step puts the
        state back on every constraint. Widening (the error test still failing) multiplies the
        tolerance by ``CROSSING_FACTOR`` again, up to ``CROSSING_FACTOR * SINGULAR_BAND``."""
        if not self.model.n_c or (self._crossing is None and self._every_row_clear()):
            return False
        split = self._rank_split()
        # most rejections are far from any pose, and a Cholesky factorisation says so at a
        # fifth of an SVD's cost (the decisions are the same: near the bounds the singular
        # value itself decides)
        if split.smallest_exceeds(SINGULAR_BAND) or (
                self._crossing is None
                and split.smallest_exceeds(FALLEN * self._spectrum_start[0])):
            return False
        # the smallest singular value alone (ARPACK on a large model's sparse factor) decides
        # whether to go on: all of them (a dense SVD, cubic in the bodies) only near a pose
        smallest = split.smallest_singular_value()
        if not smallest < SINGULAR_BAND:
            return False
        if self._crossing is None and not smallest < FALLEN * self._spectrum_start[0]:
            return False  # where it started: the mechanism's own value, no pose
        base = smallest if self._crossing is None else self._crossing
        if base >= SINGULAR_BAND:
            return False  # as wide as it goes
        if self._crossing is None:
            rate = self._singular_rate(smallest)
            if not rate < 0:
                return False  # moving away
            horizon = min(FORESIGHT_STEPS * self._accepted_step,
                          FORESIGHT_TIME * characteristic_time(self.model))
            if smallest > -rate * horizon:
                return False  # the pose far ahead, or sigma small for another reason
            self.counters.crossings += 1
            self._crossing_from, self._crossing_rate = smallest, rate
            self._crossing_start = self.t
        starting = self._crossing is None
        self._crossing = CROSSING_FACTOR * base
        # the rows left out: those a rank-revealing (column-pivoted) QR factorisation takes last
        rows = split.independent
        dependent = _collapsing(split.singular_values(), self._crossing)
        pivots = qr(as_dense(split.W[rows]).T, mode="r", pivoting=True)[1]
        kept = np.sort(rows[pivots[:rows.size - dependent]])
        self._crossing_rates = compiled_rates(self.model, kept, self._here())
        if starting:
            # no step longer than the way to the pose and as far again (one much longer lands
            # far out of the band on the rows left out), nor than their forces' absence allows
            self._crossing_cap = min(2 * smallest / -self._crossing_rate,
                                     self._crossing_step_limit())
            self.h = min(self.h, self._crossing_cap)
        return True

    def _every_row_clear(self) -> bool:
        """Whether the rows of the equilibrated ``Phi_v`` at the current state have, all of them,
        a smallest singular value above one of the bounds that begin a crossing (see
        :meth:`_cross_singular`), certified by a Cholesky factor of ``W W^T``
        (:func:`~hexapod.algorithms.rows.gram_exceeds`) without a rank decision. A fresh
        decision would then keep every row (each is farther than that from the others' span)
        and certify the same: where the run keeps every row (chains, trees, most mechanisms),
        a rejected step pays ``W W^T`` in one call (:func:`~hexapod.simulation.kernels.
        row_gram`) and a Cholesky factor instead of the decision's QR (the 18-joint robot's run
        to 1e-7: a fifth of its CPU went to these checks). False where a row is left out, the
        model is large (its ``Phi_v`` sparse), or the certificate cannot tell."""
        model, redundant = self.model, self.data.redundant_rows
        if (redundant is None or redundant.size or model.n_c > model.n_v
                or is_large(model)):
            return False
        self.counters.jacobians += 1
        self.counters.factorisations += 1
        gram = row_gram(model, self.data, self.q, model.law_values(self.t, self.data)[0])
        # above either bound is above the lower one. The band's first: a mechanism clear of
        # it never needs the start's spectrum, a rank decision and an SVD (a third of the
        # checks' cost over the 18-joint robot's run to 1e-6)
        if gram_exceeds(gram, SINGULAR_BAND, model.n_v):
            return True
        bound = FALLEN * self._spectrum_start[0]
        return bool(bound < SINGULAR_BAND) and gram_exceeds(gram, bound, model.n_v)

    def _crossing_step_limit(self) -> float:
        """The longest step a crossing may take: the one over which the rows it leaves out,
        their forces missing, move the positions by the step's tolerance, ``h^2 / 2`` times the
        gap between the accelerations of the reduced and the full system at the current state
        (in the error test's weighted RMS norm). Without this cap a crossing took the
        steps of the motion around it, and the energy its projections cost (about 5e-8 J of 620
        per pose of the N-four-bar) did not fall with the tolerance."""
        rates = self._crossing_rates(self.t, self.q, self.v, 0.0, left_out=np.inf)
        if rates is None:  # the reduced solve refused: no estimate, no cap
            return np.inf
        n_q = self.model.n_q
        gap = self.model.call("qdot", self.data, q=self.q, v=rates[1] - self.v_dot)
        weight = self.atol_vector[:n_q] + self.rtol * np.abs(self.q)
        size = float(np.sqrt(np.mean((gap / weight) ** 2)))
        return np.sqrt(2.0 / size) if size > 0 else np.inf

    def _over_pose(self, h: float) -> float:
        """The step to take instead of ``h``, a crossing's step that would end near the pose
        (:meth:`_lands_on_pose`): one long enough to pass it by as much as the current state
        is before it (from the rate of the smallest singular value where the crossing began),
        at least half as long again as ``h``."""
        rate = self._crossing_rate
        if not rate < 0:
            return 1.5 * h
        return max(1.5 * h, 2 * self._smallest_singular_value() / -rate)

    def _end_crossing(self) -> None:
        """End the crossing once the state has left the band it began in, or has passed the
        pose and is as far from it as where the crossing began (the steps that follow keep
        every row and grow back with the distance to the pose; steps leaving rows out further
        on, long ones especially, let the state leave the constraints they hold by more than
        the projection puts right without a loss of energy)."""
        if self._crossing is None:
            return
        if -self._crossing_rate * (self.t - self._crossing_start) < 1.9 * self._crossing_from:
            return  # foreseen before the pose or not yet nine tenths of its way back: no rank split
        smallest = self._smallest_singular_value()
        if not smallest <= self._crossing or (smallest >= self._crossing_from
                                              and self._singular_rate(smallest) > 0):
            self._crossing = None

    def _lands_on_pose(self, t: float, q: np.ndarray) -> bool:
        """Whether a crossing's step ending at ``(t, q)`` ends near the pose: the smallest
        singular value there below :data:`POSE_CLEARANCE` times the one where it began."""
        if (self._crossing is None
                or self._foreseen_singular_value(t) > 2 * POSE_CLEARANCE * self._crossing_from):
            return False  # far from it: no rank split
        return bool(self._smallest_singular_value(self.model.normalize(q))
                    < POSE_CLEARANCE * self._crossing_from)

    def _foreseen_singular_value(self, t: float) -> float:
        """The smallest singular value at ``t`` as the crossing under way foresees it, falling
        at its starting rate to the pose and rising as fast beyond: a crossing's steps are short
        (see :meth:`_crossing_step_limit`), and a rank split at each to see where they are cost
        four fifths of the run."""
        return abs(self._crossing_from + self._crossing_rate * (t - self._crossing_start))

    def _singular_rate(self, smallest: float) -> float:
        """The rate of change along the motion of the smallest singular value of the
        equilibrated ``Phi_v`` (``smallest`` at the current state), negative approaching a
        singular pose: a difference over a thousandth of the step, close enough never to jump
        over the pose."""
        delta = 1e-3 * self.h
        return (self._smallest_singular_value(self._positions_ahead(delta)) - smallest) / delta

    def _positions_ahead(self, delta: float) -> np.ndarray:
        """The positions ``delta`` seconds along the current motion, to first order (for the
        rates of singular values, as differences)."""
        q_dot = self.model.call("qdot", self.data, q=self.q, v=self.v)
        return self.model.normalize(self.q + delta * q_dot)

    def _rank_split(self, q: np.ndarray | None = None, t: float | None = None):
        """The rank decision on the equilibrated ``Phi_v`` at positions ``q`` (default the
        current ones), with the laws at ``t`` (default the current time)."""
        w, _, _ = self.model.law_values(self.t if t is None else t, self.data)
        self.counters.jacobians += 1
        self.counters.factorisations += 1
        return rank_split(self.model,
                          constraint_jacobian(self.model, self.q if q is None else q, w,
                                              self.data), w)

    def _smallest_singular_value(self, q: np.ndarray | None = None,
                                 t: float | None = None) -> float:
        """Of the kept rows of the equilibrated ``Phi_v`` at ``(t, q)`` (default the current
        state; ``inf`` without rows)."""
        if not self.model.n_c:
            return np.inf
        return self._rank_split(q, t).smallest_singular_value()

    @cached_property
    def _spectrum_start(self) -> np.ndarray:
        """The singular values of the kept rows of the equilibrated ``Phi_v`` at the start, in
        increasing order (a large model's smallest alone: a dense SVD is cubic in the bodies),
        computed when a failure first needs them. Measured against the start, not against 1:
        the flyball governor's smallest is 9e-4 where nothing is singular, and measured
        against 1 its failures were blamed on a singular pose."""
        return self._spectrum(self._q_start, self.t0)

    def _spectrum(self, q: np.ndarray | None = None, t: float | None = None) -> np.ndarray:
        if not self.model.n_c:
            return np.zeros(0)
        split = self._rank_split(q, t)
        if is_large(self.model):
            return np.array([split.smallest_singular_value()])
        return np.sort(split.singular_values())

    def _singular_pose(self) -> str:
        """When the current positions are near a singular configuration (see
        :attr:`near_singular`), or on the way to one foreseen close ahead, a sentence that
        names it (time, the singular value that fell) and the methods that cross it; else the
        empty string. For the messages of failures.

        The smallest singular value is compared first; where it has not fallen, the others in
        sorted order (the k-th smallest falls only where k values do): the spatial
        N-four-bar's smallest stands near 1.4e-4 all along, and the ten that collapse at its
        flat pose are the next ten (to 0.06 to 0.08 of their values at the start, which is
        near the pose already, where Radau5 fails). A method may fail before they have fallen
        that far (Radau5 at rtol 1e-8, 1.7e-3 s before that pose, the ten at 0.55 to 0.96 of
        their values at the start, 4e-3 to 8e-3): the pose is then foreseen from the rate at
        which the values fall (:meth:`_foreseen_pose`)."""
        try:
            now = self._spectrum()
            start = self._spectrum_start
        except (HexapodError, np.linalg.LinAlgError, ValueError):
            return ""
        n = min(now.size, start.size)
        if n == 0:
            return ""
        reference = np.where(np.isfinite(start[:n]) & (start[:n] > 0), start[:n], 1.0)
        ratios = now[:n] / reference
        k = 0 if ratios[0] < self.near_singular else int(np.argmin(ratios))
        which = "smallest singular value" if k == 0 else "a singular value"
        where = (f"at a singular configuration at t = {self.t:.6g} s ({which} of the "
                 f"equilibrated constraint Jacobian {now[k]:.2g}, {ratios[k]:.2g} of its value "
                 "at the start)")
        # the smallest fallen, or within the band where crossings begin with others fallen
        # tenfold (the spatial N-four-bar: its smallest 1.1e-4, ten more fallen 12 to 16 times)
        if not (ratios[0] < self.near_singular
                or (now[0] < CROSSING_FACTOR * SINGULAR_BAND
                    and ratios[k] < 1.0 / CROSSING_FACTOR)):
            foreseen = self._foreseen_pose(now[:n])
            if foreseen is None:
                return ""
            k, ahead = foreseen
            where = (f"near a singular configuration at t = {self.t:.6g} s (a singular value "
                     f"of the equilibrated constraint Jacobian, {now[k]:.2g}, falls to zero "
                     f"{ahead:.2g} s ahead at its present rate)")
        return (f"the mechanism is {where}, which {self.name} cannot pass; "
                f"{' and '.join(self.crossing_methods)} cross such poses")

    def _foreseen_pose(self, now: np.ndarray) -> tuple[int, float] | None:
        """``(k, seconds)``: the singular value (in sorted order) that, falling along the
        motion at its present rate, reaches zero soonest, and in how long, when it is one a
        crossing could leave out (below :data:`CLUSTER_CEILING`) and reaches zero within the
        crossings' horizon (:data:`FORESIGHT_STEPS` accepted steps and :data:`FORESIGHT_TIME`
        characteristic times); else None. The rates are differences over a thousandth of the
        last accepted step. The horizon counts the longest of the last accepted steps: a method
        failing near a pose shrinks its steps on the way there (Radau5 at rtol 1e-8 on the
        spatial N-four-bar, down to 3e-6 s from steps of 0.035 s), and the pose it could not
        reach is as far ahead in the steps it was taking as before."""
        delta = 1e-3 * self._accepted_step
        if not delta > 0 or not now[0] < CLUSTER_CEILING:
            return None
        ahead = self._spectrum(self._positions_ahead(delta))[:now.size]
        rates = (ahead - now) / delta
        falling = (rates < 0) & (now < CLUSTER_CEILING)
        seconds = np.where(falling, now / -np.minimum(rates, -1e-300), np.inf)
        k = int(np.argmin(seconds))
        horizon = min(FORESIGHT_STEPS * max(self._recent_steps, default=self._accepted_step),
                      FORESIGHT_TIME * characteristic_time(self.model))
        return (k, float(seconds[k])) if seconds[k] <= horizon else None


def _collapsing(sigma: np.ndarray, tolerance: float) -> int:
    """How many rows a crossing leaves out: the singular values below ``tolerance`` and those
    just above that belong to the same cluster (each within :data:`CROSSING_FACTOR` of the
    next smaller, below :data:`CLUSTER_CEILING`). Identical loops flattening at
    once (the N-four-bar's N windows) make such a cluster, spread over decades by their places
    in the chain: leaving out only its smallest members left the others to fail the error test
    one by one, each failure widening the crossing tenfold."""
    ordered = np.sort(sigma)
    count = int(np.sum(ordered < tolerance))
    while (0 < count < ordered.size and ordered[count] < CROSSING_FACTOR * ordered[count - 1]
           and ordered[count] < CLUSTER_CEILING):
        count += 1
    return count
