"""Results of a simulation: the saved states, how the run went, and the files they are written to.

Columns of ``results.csv`` (names built from the elements' names; SI units):

===================  ===================================================================
``t``                time, s
``q:<coordinate>``   positions: ``<body>.x, .y, .z`` (m), ``.e0`` ... ``.e3`` (Euler
                     parameters), ``.angle`` (rad, planar bodies)
``v:<velocity>``     velocities: ``<body>.vx, .vy, .vz`` (m/s), ``.wx', .wy', .wz'`` (rad/s,
                     body axes), ``.w`` (rad/s, planar bodies)
``vdot:<velocity>``  their time derivatives
``lambda:<row>``     Lagrange multipliers, one per constraint row (``<joint>/<row>``, drivers)
``tau:<joint>``,     with ``forces``: each joint's wrench, exerted by the parent on the child
``Fx:<joint>`` ...   about the joint origin in the child's joint frame, as ``hexapod inverse``
===================  ===================================================================

``results.npz`` holds the same arrays (``t, q, v, v_dot, lam`` and, with forces, ``force,
torque, effort``), the column names, the run's statistics (JSON) and, when known, ``source``:
the scene the run was made on (see :func:`scene_reference`), compressed.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hexapod.model.model import Model
from hexapod.simulation.integrators import Counters

WRENCH_COMPONENTS = ("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")


@dataclass
class SimulationResult:
    """The states saved by :func:`hexapod.simulation.loop.simulate` and the run's statistics.

    Attributes
    ----------
    t : ndarray (N,)
    q, v, v_dot, lam : ndarray (N, n_q), (N, n_v), (N, n_v), (N, n_c)
    force, torque, effort : ndarray (N, J, 3), (N, J, 3), (N, J), or None
        Joint wrenches (report convention), when asked for.
    status : str
        ``"finished"`` or ``"failed"`` (then ``message`` says when and why; the states up to
        the failure are kept).
    counters : Counters
    wall_time, cpu_time : float
        Seconds spent in the time loop.
    max_position_violation : float
        Largest ``|phi_i| / s_i`` over all accepted steps (``s_i``: the characteristic length
        for length rows, 1 for angle rows).
    max_velocity_violation : float
        Largest ``|Phi_v v - nu|_i / s_i`` over all accepted steps (1/s).
    energy : ndarray (N,) or None
        Kinetic plus potential energy at the saved states (J), when the scene conserves it.
    energy_drift : float or None
        Largest ``|E(t) - E(0)|`` over all accepted steps relative to the largest kinetic
        energy reached (so a pendulum released at rest, ``E = 0``, has a meaningful drift).
    """

    model: Model
    method: str
    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    v_dot: np.ndarray
    lam: np.ndarray
    status: str
    message: str
    counters: Counters
    wall_time: float
    cpu_time: float
    max_position_violation: float
    max_velocity_violation: float
    energy: np.ndarray | None = None
    energy_drift: float | None = None
    force: np.ndarray | None = None
    torque: np.ndarray | None = None
    effort: np.ndarray | None = None
    options: dict = field(default_factory=dict)
    #: the scene the run was made on, set by the caller (:func:`scene_reference`); written to
    #: ``results.npz`` as ``source`` when known, so that ``hexapod export`` can pose the bodies
    source: str = ""

    @property
    def success(self) -> bool:
        return self.status == "finished"

    def statistics(self) -> dict:
        """The run in numbers (JSON-ready)."""
        return {
            "scene": self.model.name, "method": self.method, "options": self.options,
            "status": self.status, "message": self.message,
            "t_start": float(self.t[0]), "t_end": float(self.t[-1]), "saved": int(self.t.size),
            **self.counters.as_dict(),
            "wall_time_s": self.wall_time, "cpu_time_s": self.cpu_time,
            "max_position_violation": self.max_position_violation,
            "max_velocity_violation_per_s": self.max_velocity_violation,
            "energy_conserved": self.model.energy_conserved,
            "energy_drift": self.energy_drift,
        }

    def columns(self) -> list[str]:
        model = self.model
        names = (["t"] + [f"q:{c}" for c in model.coordinate_names]
                 + [f"v:{c}" for c in model.velocity_names]
                 + [f"vdot:{c}" for c in model.velocity_names]
                 + [f"lambda:{r.name}" for r in model.rows])
        if self.force is not None:
            for joint in model.joints:
                if joint.kind in ("revolute", "prismatic"):
                    names.append(f"tau:{joint.name}")
                names += [f"{c}:{joint.name}" for c in WRENCH_COMPONENTS]
        return names

    def table(self) -> np.ndarray:
        parts = [self.t[:, None], self.q, self.v, self.v_dot, self.lam]
        if self.force is not None:
            for k, joint in enumerate(self.model.joints):
                if joint.kind in ("revolute", "prismatic"):
                    parts.append(self.effort[:, k, None])
                parts += [self.force[:, k], self.torque[:, k]]
        return np.hstack(parts)

    def csv_text(self) -> str:
        rows = self.table()
        line = ",".join(["%.17g"] * rows.shape[1])
        return ",".join(self.columns()) + "\n" + "".join(line % tuple(r) + "\n" for r in rows)

    def npz_bytes(self) -> bytes:
        arrays = {"t": self.t, "q": self.q, "v": self.v, "v_dot": self.v_dot, "lam": self.lam,
                  "coordinates": np.array(self.model.coordinate_names),
                  "velocities": np.array(self.model.velocity_names),
                  "rows": np.array([r.name for r in self.model.rows]),
                  "statistics": np.array(json.dumps(self.statistics()))}
        if self.source:
            arrays["source"] = np.array(self.source)
        if self.force is not None:
            arrays.update(force=self.force, torque=self.torque, effort=self.effort,
                          joints=np.array([j.name for j in self.model.joints]))
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **arrays)
        return buffer.getvalue()


def scene_reference(name_or_path: str) -> str:
    """How a result records the scene it was made on: a scene file's absolute path, or the
    name of a built-in scene as given."""
    path = Path(name_or_path)
    return str(path.resolve()) if path.is_file() else name_or_path
