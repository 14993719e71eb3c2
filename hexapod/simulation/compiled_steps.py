"""The compiled loop on the integrator's side: a run of DOPRI5, DOP853 or RK4 advanced in batches
of steps by a :class:`~hexapod.simulation.compiled_loop.LoopKernel`, its state written back
after each call, the steps it accepted handed to the time loop as a :class:`Batch`;
:class:`CompiledLoop`, what such an integrator adds to the contract.

:class:`CompiledStepper` sizes each call to last about :data:`CALL_SECONDS`, so that progress,
the CPU budget, the limits and signals, checked between calls, stay responsive; after a
handover it lets the integrator take the next step in Python (then twice as many each time the
kernel hands over again at once, so that a model the kernel cannot serve for a while, a rank
changed for good, does not pay for a refused attempt at every step); and in mode ``"auto"`` it
compiles the kernel to C once its pace foresees more than :data:`COMPILE_AFTER` seconds in the
virtual machine.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from hexapod._support import signals
from hexapod._support.compiled import compiler, find_compiled
from hexapod.simulation.compiled_loop import (
    ATTEMPTS,
    CHECK,
    COUNTERS,
    FINISHED,
    FLAGS,
    HANDOVER,
    HEAD,
    Layout,
    LoopKernel,
    unsupported,
)
from hexapod.simulation.integrators.base import SINGULAR_BAND, Counters


@dataclass
class Batch:
    """The steps one call of the compiled loop accepted, in order (``k`` of them, possibly
    none), with what the time loop watches at each.

    Attributes
    ----------
    t : ndarray (k,)
    q, v, v_dot : ndarray (k, n_q), (k, n_v), (k, n_v)
    lam : ndarray (k, n_c) or None
        The multipliers of the compiled solve at each state, when every row is kept (they
        are then unique, the policy's); None otherwise (the saved states solve theirs).
    phi, velocity : ndarray (k,)
        The largest scaled residuals of ``phi`` and ``Phi_v v - nu`` at each state.
    kinetic, energy : ndarray (k,)
        Kinetic and total energy (J; zero when the scene does not conserve energy).
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    v_dot: np.ndarray
    lam: np.ndarray | None
    phi: np.ndarray
    velocity: np.ndarray
    kinetic: np.ndarray
    energy: np.ndarray

    def __len__(self) -> int:
        return self.t.size


#: a call of the kernel should last about this long (s of CPU), so that progress, the CPU
#: budget and signals, checked between calls, stay responsive
CALL_SECONDS = 0.05
#: in mode ``"auto"``, the kernel is compiled to C once its virtual machine is foreseen to need
#: more than this many CPU seconds to the end of the run, and more than :data:`COMPILE_PAYOFF`
#: times what the compiler is foreseen to take (:meth:`LoopKernel.compile_seconds`: about a
#: second for a small mechanism, 13 s for a chain of 18 spatial bodies). C runs the steps of
#: the one-body pendulum 3.5 times as fast as the virtual machine, those of the chain 2.4 times
COMPILE_AFTER = 2.0
COMPILE_PAYOFF = 2.0


class CompiledStepper:
    """The compiled loop of one integrator run: builds its kernel, runs it for a batch of
    steps from the integrator's state and writes the state back.

    Parameters
    ----------
    integrator : Integrator
        One with a compiled loop (:class:`CompiledLoop`).
    mode : str
        ``"c"``: the kernel compiled to C at once; ``"vm"``: evaluated by CasADi's virtual
        machine; ``"auto"``: the virtual machine, then C once the run is foreseen to need more
        than :data:`COMPILE_AFTER` seconds of it (see :data:`hexapod.simulation.methods.LOOPS`).
    """

    def __init__(self, integrator, mode: str):
        self.integrator, self.mode = integrator, mode
        self.compile = mode == "c"
        self.decided = mode != "auto"  # whether to compile, in mode "auto"
        self.looked = False  # whether the cache on disk was searched for the compiled kernel
        self.per_call = 4  # attempts asked of the first call, then set by the pace
        self.streak = 0  # handovers in a row without a step accepted in between
        self.python_steps = 0  # steps to take in Python before the next call
        self.work = [0.0, 0.0]  # CPU seconds in the kernel and simulated seconds it advanced
        #: what the compiled loop did: the kernels it ran (``"vm"``, ``"c"``, in order), its
        #: calls, the steps it accepted, its handovers to Python, the CPU seconds of its calls
        self.statistics = {"kernels": [], "calls": 0, "steps": 0, "handovers": 0, "cpu_s": 0.0}

    def kernel(self) -> LoopKernel:
        """The kernel for the integrator's kept rows, compiled to C when decided (each built
        once per model)."""
        it = self.integrator
        rows = np.asarray(it._compiled.rows, dtype=int)
        key = ("loop", it.name, tuple(int(r) for r in rows), *it._kernel_options())
        kernel = it.model.built_once(key, lambda m: it._loop_kernel(rows))
        if kernel.cache_key is None and it.model.digest:
            kernel.cache_key = "/".join([it.model.digest, *map(str, key)])
        if not (self.decided or self.looked):  # a run of this model compiled it before?
            self.looked = True
            if find_compiled(kernel.cache_key, FLAGS) is not None:
                self.compile = self.decided = True
        if not self.compile:
            return kernel
        return it.model.built_once(("compiled", *key), lambda m: kernel.compiled_copy())

    def advance(self, t_stop: float, steps_cap: float, tried_cap: float) -> Batch | None:
        """Accepted steps from the integrator's state until the end of the run, a step past
        ``t_stop``, ``steps_cap`` steps or ``tried_cap`` steps tried (accepted or rejected);
        None when the next step is Python's (after a handover, see the module)."""
        it = self.integrator
        if self.python_steps > 0 or it._crossing is not None:
            self.python_steps = max(0, self.python_steps - 1)
            return None
        kernel = self.kernel()
        kind = "c" if kernel.compiled else "vm"
        if kind not in self.statistics["kernels"]:
            self.statistics["kernels"].append(kind)
        counters = it.counters
        tried = counters.steps + counters.rejected
        settings = np.concatenate([[it.t_bound, it.max_step, it.rtol, t_stop, steps_cap,
                                    min(tried_cap, tried + self.per_call)], it.atol_vector])
        before = (it.t, it.q, it.v, it.v_dot)
        # the call and the writing back whole: a signal is delivered after them
        with signals.deferred():
            cpu = time.process_time()
            try:
                out, trace = kernel.run(self._carry(kernel.layout), settings)
            except RuntimeError:  # the virtual machine's factorisation failed: Python's step
                return self._handed_over(0)
            self._pace(time.process_time() - cpu, out, tried, it.t_bound - it.t)
            return self._write_back(kernel.layout, out, trace, before)

    def _carry(self, L: Layout) -> np.ndarray:
        """The carried vector from the integrator's state, step and counters."""
        it = self.integrator
        carry = np.zeros(L.carry)
        for name in COUNTERS:
            carry[HEAD[name]] = getattr(it.counters, name)
        carry[HEAD["t"]], carry[HEAD["h"]] = it.t, it.h
        carry[HEAD["accepted_step"]] = it._accepted_step
        carry[L.q], carry[L.v], carry[L.v_dot] = it.q, it.v, it.v_dot
        return carry

    def _pace(self, seconds: float, out: np.ndarray, tried: int, span: float) -> None:
        """Size the next call to last about :data:`CALL_SECONDS`; in mode ``"auto"``, compile
        the kernel once the virtual machine's pace foresees more than :data:`COMPILE_AFTER`
        seconds to the end of the run."""
        attempts = out[HEAD["steps"]] + out[HEAD["rejected"]] - tried
        if attempts > 0 and seconds > 0:
            self.per_call = int(min(ATTEMPTS, max(1, CALL_SECONDS * attempts / seconds)))
        it = self.integrator
        self.statistics["calls"] += 1
        self.statistics["cpu_s"] += seconds
        self.work[0] += seconds
        self.work[1] += span - (it.t_bound - out[HEAD["t"]])
        if self.decided or not self.work[1] > 0:
            return
        foreseen = self.work[0] / self.work[1] * (it.t_bound - out[HEAD["t"]])
        if foreseen > COMPILE_AFTER:  # decided once: the pace hardly changes
            self.decided = True
            self.compile = compiler() is not None and (
                foreseen > COMPILE_PAYOFF * self.kernel().compile_seconds())

    def _write_back(self, L: Layout, out: np.ndarray, trace: np.ndarray,
                    before: tuple) -> Batch | None:
        """The integrator's state, step and counters from the carry; the accepted steps as a
        :class:`Batch` (None when the first attempt was handed over: Python takes it)."""
        it = self.integrator
        for name in COUNTERS:
            setattr(it.counters, name, int(out[HEAD[name]]))
        it.h = float(out[HEAD["h"]])
        rows = trace[trace[:, 0] == 1.0]
        if rows.shape[0]:
            it.t = float(out[HEAD["t"]])
            it.q, it.v, it.v_dot = out[L.q].copy(), out[L.v].copy(), out[L.v_dot].copy()
            it.lam = None
            it._accepted_step = float(out[HEAD["accepted_step"]])
            # the last step's start, from which its dense output is built when asked
            start = before if rows.shape[0] == 1 else (
                rows[-2, 1], rows[-2, L.row_q], rows[-2, L.row_v], rows[-2, L.row_v_dot])
            it._dense_from(start, it._accepted_step)
            self.statistics["steps"] += rows.shape[0]
            # the largest kinetic energy, which the fixed steps' energy test measures against
            it._kinetic_peak = max(it._kinetic_peak,
                                   float(rows[:, L.row_watch][:, 2].max(initial=0.0)))
        code = int(out[HEAD["code"]])
        if code == CHECK and not self._far_from_singular(out):
            code = HANDOVER
        if code == FINISHED:
            it.status = "finished"
        elif code == HANDOVER:
            self._handed_over(rows.shape[0])
            if not rows.shape[0]:
                return None
        watched = rows[:, L.row_watch]
        return Batch(rows[:, 1], rows[:, L.row_q], rows[:, L.row_v], rows[:, L.row_v_dot],
                     rows[:, L.row_lam] if it._compiled.complete else None,
                     watched[:, 0], watched[:, 1], watched[:, 2], watched[:, 3])

    def _far_from_singular(self, out: np.ndarray) -> bool:
        """After a step rejected by a kernel that leaves the rank decision to Python
        (:data:`~hexapod.simulation.compiled_loop.CHECK`): whether the state is clear of
        singular poses, as :meth:`Integrator._cross_singular` decides first (its smallest
        singular value not below ``SINGULAR_BAND``; its rank decision was counted by the
        kernel). If not, the rejection is undone, for Python to take the step again and decide
        on a crossing."""
        it = self.integrator
        counted = (it.counters.jacobians, it.counters.factorisations)
        sigma = it._smallest_singular_value()
        it.counters.jacobians, it.counters.factorisations = counted
        if sigma >= SINGULAR_BAND:
            return True
        counters, stages = it.counters, self.kernel().stage_count
        counters.rejected -= 1
        counters.rhs -= stages - 1
        counters.jacobians -= 1
        counters.factorisations -= 1
        it.h = float(out[HEAD["h_rejected"]])
        return False

    def _handed_over(self, accepted: int) -> None:
        """After a handover, with ``accepted`` steps before it in the call: Python takes the
        next step, and twice as many each time the kernel hands over again at once."""
        self.statistics["handovers"] += 1
        self.streak = self.streak + 1 if not accepted else 1
        self.python_steps = 2 ** min(self.streak - 1, 10)
        if not accepted:  # the step about to be taken in Python is the first of them
            self.python_steps -= 1


class CompiledLoop:
    """What an integrator with a compiled time loop adds to the contract (a mixin, before
    :class:`Integrator` in the bases): the option ``loop``, :meth:`advance`,
    :meth:`loop_statistics`. It implements :meth:`_loop_kernel` (its kernel for a row set),
    :meth:`_kernel_options` (what else the kernel depends on) and, for its dense output after
    a batch, :meth:`_rebuild_dense_step`."""

    def _setup_loop(self, loop: str) -> None:
        """Choose the loop (after the integrator's consistent start) and build its kernel
        before the run, as the other kernels are. Only the classes whose steps the kernel
        reproduces run in it (those that set ``kernel_reproduces`` in their own body): a
        subclass may take its steps otherwise (a test's integrator that spoils its
        accelerations), and keeps the Python loop."""
        #: why the steps run in Python ("" when they run in the compiled loop)
        self.loop_reason = "asked for" if loop == "python" else unsupported(self.model)
        if not self.loop_reason and not type(self).__dict__.get("kernel_reproduces"):
            self.loop_reason = (f"{type(self).__name__} is not a class whose steps the "
                                "compiled loop reproduces")
        self._loop_mode = loop
        self._stepper = None if self.loop_reason else CompiledStepper(self, loop)
        if self._stepper is not None:
            self._stepper.kernel()  # compiled to C now for loop="c"
        self._dense_step = self._dense_start = None

    def advance(self, *, t_stop: float = np.inf, steps_cap: float = np.inf,
                tried_cap: float = np.inf) -> Batch | None:
        """Many accepted steps in one call of the compiled loop (see :class:`CompiledStepper`):
        until the end, the first step past ``t_stop``, ``steps_cap`` accepted steps, or
        ``tried_cap`` steps tried (accepted or rejected, counted from the start of the run).
        None when the next step is to be taken by :meth:`step` (the compiled loop handed it
        over, or the model keeps the Python loop: :attr:`loop_reason`)."""
        if self._stepper is None or self.status != "running":
            return None
        return self._stepper.advance(t_stop, steps_cap, tried_cap)

    def loop_statistics(self) -> dict:
        """How the steps were taken, for the result's ``options["loop"]``: the mode asked
        (:data:`~hexapod.simulation.methods.LOOPS`), the kernels the compiled loop ran
        (``"vm"``, ``"c"``), its calls, the steps it accepted (the others were taken in Python:
        the handovers and the crossings of singular poses), its handovers, the CPU seconds of
        its calls (``cpu_s``) and why the steps ran in Python when they all did (``reason``)."""
        if self._stepper is None:
            return {"mode": self._loop_mode, "kernels": [], "calls": 0, "steps": 0,
                    "handovers": 0, "cpu_s": 0.0, "reason": self.loop_reason}
        return {"mode": self._loop_mode, **self._stepper.statistics, "reason": ""}

    def _kernel_options(self) -> tuple:
        """What the kernel depends on besides the model, the method and the rows."""
        return ()

    def _loop_kernel(self, rows: np.ndarray) -> LoopKernel:
        raise NotImplementedError

    def _dense_from(self, start: tuple, h: float) -> None:
        """The last step was taken by the compiled loop from ``start = (t, q, v, v_dot)`` over
        ``h``: its dense output is built from there when asked (:meth:`_last_step`)."""
        self._dense_step, self._dense_start = None, (start, h)

    def _last_step(self) -> tuple:
        """The last accepted step as the dense output reads it (``_dense_step``); after the
        compiled loop, its stages evaluated again, not counted (the loop counted them when it
        took the step)."""
        if self._dense_step is None:
            counters = Counters(**self.counters.as_dict())
            self._dense_step = self._rebuild_dense_step(*self._dense_start)
            self.counters = counters
        return self._dense_step

    def _rebuild_dense_step(self, start: tuple, h: float) -> tuple:
        raise NotImplementedError
