"""What the time loop measures at every accepted step (constraint residuals, energy) and the
states it saves.

The saved states are kept as blocks of rows (a state a block of one), joined once the run is
over (:meth:`Watch.arrays`).
"""

from __future__ import annotations

import numpy as np

from hexapod.errors import HexapodError, IntegrationError
from hexapod.model.model import Model
from hexapod.simulation.integrators import Integrator

#: what is saved of each state, with its size per state (None: a scalar)
_KEYS = ("t", "q", "v", "v_dot", "lam")


def energy(model: Model, q: np.ndarray, v: np.ndarray, data=None) -> tuple[float, float]:
    """Kinetic and total energy (J); through ``data``'s call buffers when given."""
    kinetic, potential = (model.energy(q, v) if data is None else
                          model.fast("energy", data)(q, v))
    return float(kinetic[0]), float(kinetic[0]) + float(potential[0])


class Watch:
    """What the loop measures at every accepted step and the states it saves.

    Parameters
    ----------
    model, integrator :
        The run's; the initial state is watched, and saved unless output times are given
        that do not begin there.
    grid : ndarray, optional
        The output times.
    """

    def __init__(self, model: Model, integrator: Integrator, grid: np.ndarray | None = None):
        self.model, self.integrator = model, integrator
        self.grid = grid  # the output times, if given
        self.next = 0  # the output time to save next
        # a contact scheme's states carry their contact forces too
        self.keys = _KEYS + (("contact_forces",) if hasattr(integrator, "contact_forces")
                             else ())
        self.saved: dict[str, list[np.ndarray]] = {key: [] for key in self.keys}
        self.energy_saved: list[float] = []
        self.conserved = model.energy_conserved
        self.energy0 = (energy(model, integrator.q, integrator.v)[1] if self.conserved
                        else None)
        self.worst = {"phi": 0.0, "velocity": 0.0, "drift": 0.0, "kinetic": 0.0}
        self.latest = self.energy0  # the energy of the state watched last, saved with it
        self.watch()
        if grid is None or grid[0] == integrator.t:
            self.save()
            self.next = 1

    def watch(self) -> None:
        """Measure the integrator's current state."""
        model, integrator, worst = self.model, self.integrator, self.worst
        t, q, v = integrator.t, integrator.q, integrator.v
        measured = integrator.state_residuals() if model.n_c else None
        if measured is not None:  # by the projection that returned this state
            worst["phi"] = max(worst["phi"], measured[0])
            worst["velocity"] = max(worst["velocity"], measured[1])
        elif model.n_c:
            data = integrator.data  # its call buffers: the integrator is between steps
            w, wd, _ = model.law_values(t, data)
            phi = model.call("phi", data, q=q, w=w) / model.row_scale
            rate = (model.call("Phi_v", data, q=q, w=w) @ v
                    - model.call("nu", data, q=q, w=w, wd=wd))
            worst["phi"] = max(worst["phi"], float(np.abs(phi).max()))
            worst["velocity"] = max(worst["velocity"],
                                    float(np.abs(rate / model.row_scale).max()))
        if self.conserved:
            kinetic, potential = integrator.state_energy()
            total = kinetic + potential
            worst["kinetic"] = max(worst["kinetic"], kinetic)
            worst["drift"] = max(worst["drift"], abs(total - self.energy0))
            self.latest = total

    def save(self) -> None:
        """Save the current state; accelerations and multipliers may be solved only now
        (lazily): a state the solve refuses, or one whose accelerations or multipliers are not
        finite, ends the run as a failure, with the states saved before it."""
        integrator = self.integrator
        try:
            values = {key: np.array(getattr(integrator, key), dtype=float, copy=True)
                      for key in self.keys}
        except HexapodError as error:
            integrator.status = "failed"
            integrator.message = (f"{integrator.name}: failed at t = {integrator.t:.6g} s: "
                                  f"{error}")
            return
        self._keep(values, self.latest if self.conserved else np.nan)

    def save_grid(self) -> None:
        """Save the states at the output times the last step passed, each from the method's
        continuous extension of the step (or, for a method that counts its own steps, the
        state it returned there), made consistent (:meth:`Integrator.dense_state`). A state
        that cannot be made consistent ends the run as a failure."""
        integrator, grid = self.integrator, self.grid
        t = integrator.t
        interpolant = None
        while self.next < grid.size and grid[self.next] <= t:
            at = float(grid[self.next])
            try:
                if not integrator.counts_own_steps:
                    interpolant = interpolant or integrator.dense_output()
                    q, v = interpolant(at)
                elif at == t or abs(at - t) <= 1e-12 * max(1.0, abs(t)):
                    q, v = integrator.q, integrator.v
                else:
                    raise IntegrationError(f"the method returned no state at {at:.10g} s")
                q, v, v_dot, lam = integrator.dense_state(at, q, v)
            except (HexapodError, np.linalg.LinAlgError) as error:
                integrator.status = "failed"
                integrator.message = (f"{integrator.name}: failed at the output time t = "
                                      f"{at:.6g} s: {error}")
                return
            self.next += 1
            level = energy(self.model, q, v)[1] if self.conserved else np.nan
            self._keep({"t": np.array(at), "q": q, "v": v, "v_dot": v_dot,
                        "lam": np.asarray(lam, dtype=float)}, level)
            if integrator.status == "failed":
                return

    def _keep(self, values: dict, level: float) -> None:
        """Append one state, unless its accelerations or multipliers are not finite (then the
        run ends as a failure)."""
        integrator = self.integrator
        for key, what in (("v_dot", "accelerations"), ("lam", "multipliers")):
            if not np.isfinite(values[key]).all():
                integrator.status = "failed"
                integrator.message = (f"{integrator.name}: non-finite {what} at t = "
                                      f"{float(values['t']):.6g} s (an overflow: the "
                                      "scene's forces or laws are too large, or the motion is "
                                      "unstable)")
                return
        for key in self.keys:
            self.saved[key].append(values[key])
        if self.conserved:
            self.energy_saved.append(level)

    def complete(self) -> None:
        """Only whole states: an interruption inside a save may have left one in part."""
        lists = [*self.saved.values()] + ([self.energy_saved] if self.conserved else [])
        count = min(len(states) for states in lists)
        for states in lists:
            del states[count:]

    def arrays(self) -> tuple[dict[str, np.ndarray], np.ndarray | None]:
        """The saved states as arrays (``t`` (n,), the others (n, size)), and their energies
        when the scene conserves it."""
        model = self.model
        sizes = {"t": (), "q": (model.n_q,), "v": (model.n_v,), "v_dot": (model.n_v,),
                 "lam": (model.n_c,),
                 "contact_forces": np.shape(getattr(self.integrator, "contact_forces", ()))}
        out = {}
        for key, blocks in self.saved.items():
            out[key] = (np.array(blocks, dtype=float) if blocks
                        else np.zeros((0, *sizes[key])))
        levels = None
        if self.conserved:
            levels = np.array(self.energy_saved, dtype=float)
        return out, levels

