"""The time loop: run an integrator to the end, save states, watch the constraints and the energy.

:func:`simulate` makes the initial state consistent (through the integrator), steps until the
end or a failure, saves every ``every``-th accepted step (and always the first and the last
state), measures at **every** accepted step the constraint residuals of positions and
velocities and, when the scene conserves energy, the energy drift, and returns a
:class:`~hexapod.simulation.results.SimulationResult`. A failure is a result too: ``status =
"failed"`` with the message and the states up to it.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable

import numpy as np

from hexapod.algorithms.liaison import wrenches_from_multipliers
from hexapod.errors import HexapodError
from hexapod.model.model import Model
from hexapod.simulation.integrators import Integrator
from hexapod.simulation.methods import DEFAULT_ATOL, DEFAULT_RTOL
from hexapod.simulation.registry import DEFAULT_METHOD, get_integrator
from hexapod.simulation.results import SimulationResult


def simulate(model: Model, t_end: float, *, method: str | type[Integrator] = DEFAULT_METHOD,
             t0: float = 0.0, q0: np.ndarray | None = None, v0: np.ndarray | None = None,
             rtol: float | None = None, atol: float | None = None, step: float | None = None,
             every: int = 1, forces: bool | None = None, max_steps: int = 10_000_000,
             cpu_budget: float | None = None,
             progress: Callable[[float, float], None] | None = None,
             options: dict | None = None) -> SimulationResult:
    """Integrate the motion of ``model`` from ``t0`` to ``t_end``.

    Parameters
    ----------
    method :
        A registered integrator name (:data:`hexapod.simulation.integrators.INTEGRATORS`) or class.
    rtol, atol, step :
        Tolerances of adaptive methods (default :data:`~hexapod.simulation.methods.DEFAULT_RTOL`
        and ``DEFAULT_ATOL``; a fixed-step method given them warns that it ignores them); the
        step of fixed-step methods (the first step of adaptive ones). See
        :class:`~hexapod.simulation.integrators.Integrator`.
    every :
        Save every ``every``-th accepted step (every ``every``-th state a method returns, for
        a method that returns states at output times and counts its own steps).
    forces :
        Also compute the joint wrenches at the saved states (report convention); default: as
        the scene asks (``[scene] report_forces``).
    cpu_budget :
        Stop the run, as failed, once its time loop has used this many CPU seconds (the states
        up to there are kept), as ``max_steps`` stops it after that many steps.
    progress :
        Called as ``progress(t, t_end)`` after each accepted step.
    options :
        Further keyword arguments of the integrator (e.g. ``rho_inf``, ``alpha``).

    Raises
    ------
    HexapodError
        When the initial state cannot be made consistent (the run has not started).
    """
    if every < 1:
        raise ValueError(f"every must be at least 1, got {every}")
    cls = get_integrator(method)
    options = {**_tolerances(cls, rtol, atol), "step": step, **(options or {})}
    integrator = cls(model, t0, t_end, q0, v0, **options)
    saved = {"t": [], "q": [], "v": [], "v_dot": [], "lam": []}
    energy_saved: list[float] = []
    conserved = model.energy_conserved
    energy0 = _energy(model, integrator.q, integrator.v)[1] if conserved else None
    worst = {"phi": 0.0, "velocity": 0.0, "drift": 0.0, "kinetic": 0.0}
    latest = {"energy": energy0}  # the energy of the state watched last, saved with it

    def watch() -> None:
        t, q, v = integrator.t, integrator.q, integrator.v
        if model.n_c:
            w, wd, _ = model.law_values(t)
            phi = model.call("phi", q=q, w=w) / model.row_scale
            rate = (model.call("Phi_v", q=q, w=w) @ v - model.call("nu", q=q, w=w, wd=wd))
            worst["phi"] = max(worst["phi"], float(np.abs(phi).max()))
            worst["velocity"] = max(worst["velocity"],
                                    float(np.abs(rate / model.row_scale).max()))
        if conserved:
            kinetic, total = _energy(model, q, v)
            worst["kinetic"] = max(worst["kinetic"], kinetic)
            worst["drift"] = max(worst["drift"], abs(total - energy0))
            latest["energy"] = total

    def save() -> None:
        # accelerations and multipliers may be solved only now (lazily): a state the solve
        # refuses ends the run as a failure, with the states saved before it
        try:
            values = {key: np.array(getattr(integrator, key), dtype=float, copy=True)
                      for key in saved}
        except HexapodError as error:
            integrator.status = "failed"
            integrator.message = (f"{cls.name}: failed at t = {integrator.t:.6g} s: {error}")
            return
        for key, value in values.items():
            saved[key].append(value)
        if conserved:
            energy_saved.append(latest["energy"])

    watch()
    save()
    returned = 0
    wall, cpu = time.perf_counter(), time.process_time()
    while integrator.status == "running":
        if integrator.counters.steps >= max_steps:
            integrator.status = "failed"
            integrator.message = (f"{cls.name}: stopped after {max_steps} steps at "
                                  f"t = {integrator.t:.6g} s (raise max_steps, or the step)")
            break
        if cpu_budget is not None and time.process_time() - cpu > cpu_budget:
            integrator.status = "failed"
            integrator.message = (f"{cls.name}: stopped by the CPU budget of {cpu_budget:g} s "
                                  f"at t = {integrator.t:.6g} s")
            break
        integrator.step()
        if integrator.status == "failed":
            break
        watch()
        returned += 1  # states returned, one per call (many steps for some methods)
        if integrator.status == "finished" or returned % every == 0:
            save()
        if progress is not None:
            progress(integrator.t, t_end)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    arrays = {key: np.array(values) for key, values in saved.items()}
    result = SimulationResult(
        model=model, method=cls.name, t=arrays["t"], q=arrays["q"], v=arrays["v"],
        v_dot=arrays["v_dot"], lam=arrays["lam"].reshape(len(saved["t"]), model.n_c),
        status=integrator.status, message=integrator.message, counters=integrator.counters,
        wall_time=wall, cpu_time=cpu, max_position_violation=worst["phi"],
        max_velocity_violation=worst["velocity"],
        energy=np.array(energy_saved) if conserved else None,
        energy_drift=(worst["drift"] / max(worst["kinetic"], np.finfo(float).tiny)
                      if conserved else None),
        options=options)
    if forces or (forces is None and model.report_forces):
        _add_wrenches(result)
    return result


def _tolerances(cls: type[Integrator], rtol: float | None, atol: float | None) -> dict:
    """The tolerances a run uses: the defaults where not given; a fixed-step method that was
    given some says it ignores them."""
    if not cls.adaptive and (rtol is not None or atol is not None):
        warnings.warn(f"{cls.name} is a fixed-step method: it ignores rtol and atol (set its "
                      "step with step=)", UserWarning, stacklevel=3)
    return {"rtol": DEFAULT_RTOL if rtol is None else rtol,
            "atol": DEFAULT_ATOL if atol is None else atol}


def _energy(model: Model, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """Kinetic and total energy (J)."""
    kinetic, potential = model.energy(q, v)
    return float(kinetic), float(kinetic) + float(potential)


def _add_wrenches(result: SimulationResult) -> None:
    """Joint wrenches at the saved states, from the saved multipliers."""
    model = result.model
    n, J = result.t.size, len(model.joints)
    force, torque, effort = np.zeros((n, J, 3)), np.zeros((n, J, 3)), np.zeros((n, J))
    for k in range(n):
        q, v = result.q[k], result.v[k]
        w, _, _ = model.law_values(result.t[k])
        Phi_v = model.call("Phi_v", q=q, w=w)
        Q_across = (model.call("Q_across", q=q, v=v, w=w) if model.Q_across is not None
                    else None)
        wrenches = wrenches_from_multipliers(model, q, result.lam[k], Phi_v, Q_across)
        force[k], torque[k], effort[k] = wrenches.force, wrenches.torque, wrenches.effort
    result.force, result.torque, result.effort = force, torque, effort

