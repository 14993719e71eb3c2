"""Results of a simulation: the saved states, how the run went, and the files they are written to.

Columns of ``results.csv`` (names built from the elements' names; SI units):

===================  ===================================================================
``t``                time, s
``q:<coordinate>``   positions: ``<body>.x, .y, .z`` (m), ``.e0`` ... ``.e3`` (Euler
                     parameters), ``.angle`` (rad, planar bodies)
``v:<velocity>``     velocities: ``<body>.vx, .vy, .vz`` (m/s, world axes), ``.wx_body,
                     .wy_body, .wz_body`` (rad/s, body axes), ``.w`` (rad/s, planar bodies)
``vdot:<velocity>``  their time derivatives
``lambda:<row>``     Lagrange multipliers, one per constraint row (``<joint>/<row>``, drivers):
                     N for a length row, N m for an angle row
``tau:<joint>``,     with ``forces``: each joint's wrench, exerted by the parent on the child
``Fx:<joint>`` ...   about the joint origin in the child's joint frame, as ``hexapod inverse``
``GRx:<leg>``        with unilateral contacts (a contact scheme): the force of the ground on
...                  the body at each contact, world axes, N (the step's impulse over the
                     step); named as the inverse dynamics' columns, by the contact's leg
                     (``L1`` for ``L1/ground``)
===================  ===================================================================

A contact scheme's run also has its contact events (:meth:`SimulationResult.events_csv_text`,
``events.csv``: ``t, kind, contact, Px, Py, Pz``; ``kind`` one of ``touch-down``, ``lift-off``,
``slip-start``, ``slip-end``, ``impact``; the impulse of an impact in world axes, N s, zero for
the other kinds).

Every column's unit and meaning come from :meth:`SimulationResult.column_units`, written beside
the CSV as ``units.json`` (:func:`units_json`; the naming scheme and the sidecar are described in
``docs/outputs.md``). ``results.npz`` holds the same arrays (``t, q, v, v_dot, lam`` and, with
forces, ``force, torque, effort``), the names (``coordinates``, ``velocities``, ``rows``,
``joints``) each with its units (``coordinate_units``, ``velocity_units`` and
``acceleration_units``, ``row_units``, ``effort_units``), the run's statistics (JSON) and, when
known, ``source``: the scene the run was made on (see :func:`scene_reference`), compressed.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from hexapod._support.signals import deferred
from hexapod.model.model import Model
from hexapod.model.units import (
    ACCELERATION_UNITS,
    COORDINATE_UNITS,
    ROW_UNITS,
    VELOCITY_UNITS,
    component,
    leg_name,
)
from hexapod.simulation.tracking import controller_names

if TYPE_CHECKING:  # the integrators load SciPy: 'hexapod inverse' writes results without them
    from hexapod.simulation.integrators import Counters

WRENCH_COMPONENTS = ("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")

#: A table's columns described: name -> (unit, what it holds). Units are SI strings, ``"1"`` for
#: a pure number, None for text; this is what ``units.json`` says of each column.
Columns = dict[str, tuple[str | None, str]]


#: the columns of ``events.csv`` (a contact scheme's run)
EVENT_COLUMNS: Columns = {
    "t": ("s", "the end of the step the event happened in"),
    "kind": (None, "touch-down, lift-off, slip-start, slip-end or impact"),
    "contact": (None, "the contact's name (its ground-contact force element)"),
    **{f"P{axis}": ("N s", f"impulse of the ground on the body at an impact, {axis} in world "
                           "axes (0 for the other kinds)") for axis in "xyz"}}


def state_columns(model: Model) -> Columns:
    """``q:``, ``v:``, ``vdot:`` and ``lambda:`` columns of a model, with units."""
    out: Columns = {}
    for name in model.coordinate_names:
        out[f"q:{name}"] = COORDINATE_UNITS[component(name)]
    for name in model.velocity_names:
        out[f"v:{name}"] = VELOCITY_UNITS[component(name)]
    for name in model.velocity_names:
        unit, what = VELOCITY_UNITS[component(name)]
        out[f"vdot:{name}"] = (ACCELERATION_UNITS[unit], f"time derivative of the {what}")
    for row in model.rows:
        out[f"lambda:{row.name}"] = ROW_UNITS[row.kind]
    return out


def wrench_columns(model: Model, frame: str = "joint") -> Columns:
    """Per joint in model order ``tau:<joint>`` (the joints with a coordinate) and
    ``Fx .. Tz:<joint>``: the wrench by the parent on the child about the joint origin, in the
    child's joint frame (or world axes, ``frame="world"``), as ``hexapod inverse`` writes it."""
    axes = "world axes" if frame == "world" else "the child's joint frame"
    out: Columns = {}
    for joint in model.joints:
        if joint.type.drivable:
            along = "about" if joint.type.coordinate_unit == "angle" else "along"
            out[f"tau:{joint.name}"] = (joint.type.effort_unit,
                                        f"effort {along} the joint's axis, parent on child")
        for c in WRENCH_COMPONENTS:
            out[f"{c}:{joint.name}"] = (
                ("N", f"force by the parent on the child, {c[1]} in {axes}") if c[0] == "F"
                else ("N m", f"moment by the parent on the child about the joint origin, {c[1]} "
                      f"in {axes}"))
    return out


def units_json(tables: dict[str, Columns]) -> str:
    """The units sidecar of CSV files (``units.json``, or ``OUT.units.json`` beside one file):
    per file, per column in order, ``{"unit": ..., "quantity": ...}``, a column a line."""
    files = []
    for name, columns in tables.items():
        lines = [f"  {json.dumps(c)}: {json.dumps({'unit': u, 'quantity': q})}"
                 for c, (u, q) in columns.items()]
        body = "\n" + ",\n".join(lines) + "\n }" if lines else "}"
        files.append(f" {json.dumps(name)}: {{{body}")
    return "{\n" + ",\n".join(files) + "\n}\n" if files else "{}\n"


@dataclass
class SimulationResult:
    """The states saved by :func:`hexapod.simulation.loop.simulate` and the run's statistics.

    Attributes
    ----------
    model : Model
        The model simulated.
    method : str
        The integrator's registered name.
    t : ndarray (N,)
        The saved times, s.
    q, v, v_dot, lam : ndarray (N, n_q), (N, n_v), (N, n_v), (N, n_c)
        The saved states, their accelerations and multipliers (SI).
    force, torque, effort : ndarray (N, J, 3), (N, J, 3), (N, J), or None
        Joint wrenches (report convention; N, N m), when asked for.
    status : str
        ``"finished"``, ``"failed"`` or ``"interrupted"`` (then ``message`` says when and why;
        the states up to there are kept).
    message : str
        Why the run stopped short (empty when it finished).
    counters : Counters
        Steps, evaluations, factorisations and Newton iterations.
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
    options : dict
        The run's settings: ``rtol``, ``atol`` (the absolute tolerance used per kind of
        coordinate: ``position`` m, ``angle`` rad, ``velocity`` m/s, ``angular_velocity``
        rad/s), ``step``, the method's own options and, with output times, ``output_times``
        (how many were asked).
    source : str
        The scene the run was made on, set by the caller (:func:`scene_reference`); written
        to ``results.npz`` so that ``hexapod export`` can pose the bodies (empty: unknown).
    t_bound, t_start, t_reached : float or None
        The end the run was asked to reach, its start, and the time it reached when that may
        differ from the last saved time (s; None: the last or first saved time).
    contact_forces : ndarray (N, m, d) or None
        With unilateral contacts: the ground's force on the body at each contact, world axes
        (N), at the saved states.
    events : list or None
        With unilateral contacts: their events
        (:class:`~hexapod.simulation.integrators.moreau_jean.ContactEvent`), in time order.
    tracking : ndarray (N, k) or None
        With joint controllers: each one's joint angle minus its target (rad), wrapped
        (:mod:`hexapod.simulation.tracking`).
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
    #: the end the run was asked to reach (s); None when not known
    t_bound: float | None = None
    #: the start of the run (s); None: the first saved time
    t_start: float | None = None
    #: the time the run reached (s), when it may differ from the last saved time (states saved
    #: at output times only); None: the last saved time
    t_reached: float | None = None
    contact_forces: np.ndarray | None = None
    events: list | None = None
    tracking: np.ndarray | None = None

    @property
    def success(self) -> bool:
        return self.status == "finished"

    def statistics(self) -> dict:
        """The run in numbers (JSON-ready)."""
        return {
            "scene": self.model.name, "method": self.method, "options": self.options,
            "status": self.status, "message": self.message,
            # whether the run is complete: the end asked for, the time reached and, when it
            # stopped short (failed or interrupted), why
            "t_start": float(self.t[0] if self.t_start is None else self.t_start),
            "t_end": float(self.t[-1] if self.t_bound is None else self.t_bound),
            "t_reached": float(self.t[-1] if self.t_reached is None else self.t_reached),
            "reason": self.message or None,
            "saved": int(self.t.size),
            **self.counters.as_dict(),
            "wall_time_s": self.wall_time, "cpu_time_s": self.cpu_time,
            "max_position_violation": self.max_position_violation,
            "max_velocity_violation_per_s": self.max_velocity_violation,
            "energy_conserved": self.model.energy_conserved,
            "energy_drift": self.energy_drift,
        }

    def column_units(self) -> Columns:
        """The columns of ``results.csv`` in order, each with its unit and meaning."""
        out: Columns = {"t": ("s", "time"), **state_columns(self.model)}
        if self.force is not None:
            out.update(wrench_columns(self.model))
        for name, column in zip(self.contact_names, self.ground_names(), strict=True):
            for axis in "xyz"[:self.model.dimension]:
                out[f"GR{axis}:{column}"] = ("N", f"force of the ground on the body at contact "
                                                  f"'{name}', {axis} in world axes")
        if self.tracking is not None:
            for name in controller_names(self.model):
                out[f"err:{name}"] = ("rad", f"tracking error of controller '{name}': its "
                                             "joint's angle minus its target, wrapped")
        return out

    @property
    def contact_names(self) -> tuple[str, ...]:
        """The unilateral contacts' names, in the order of ``contact_forces`` (none without)."""
        if self.contact_forces is None:
            return ()
        return tuple(f.name for f in self.model.forces if f.contact is not None)

    def ground_names(self) -> list[str]:
        """The name each contact's ground-force columns and figures carry: its leg's
        (``GRx:L1`` for the contact ``L1/ground``, as the inverse dynamics writes them), or the
        contact's own when two contacts would share a leg's name."""
        legs = [leg_name(name) for name in self.contact_names]
        return legs if len(set(legs)) == len(legs) else list(self.contact_names)

    def events_csv_text(self) -> str:
        """The contact events as CSV (``events.csv``): ``t, kind, contact, Px, Py, Pz``."""
        lines = ["t,kind,contact,Px,Py,Pz\n"]
        for event in self.events or ():
            impulse = np.zeros(3)
            impulse[:event.impulse.size] = event.impulse
            name = event.contact.replace('"', '""')
            lines.append(f'{event.t:.17g},{event.kind},"{name}",'
                         + ",".join(f"{x:.17g}" for x in impulse) + "\n")
        return "".join(lines)

    def columns(self) -> list[str]:
        return list(self.column_units())

    def table(self) -> np.ndarray:
        parts = [self.t[:, None], self.q, self.v, self.v_dot, self.lam]
        if self.force is not None:
            for k, joint in enumerate(self.model.joints):
                if joint.type.drivable:
                    parts.append(self.effort[:, k, None])
                parts += [self.force[:, k], self.torque[:, k]]
        if self.contact_forces is not None:
            parts.append(self.contact_forces.reshape(self.t.size, -1))
        if self.tracking is not None:
            parts.append(self.tracking)
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
                  **self._npz_units(),
                  "statistics": np.array(json.dumps(self.statistics()))}
        if self.source:
            arrays["source"] = np.array(self.source)
        if self.contact_forces is not None:
            arrays.update(contact_forces=self.contact_forces,
                          contacts=np.array(self.contact_names, dtype=str))
        if self.tracking is not None:
            arrays.update(tracking=self.tracking,
                          controllers=np.array(controller_names(self.model), dtype=str))
        if self.force is not None:
            arrays.update(force=self.force, torque=self.torque, effort=self.effort,
                          joints=np.array([j.name for j in self.model.joints]),
                          effort_units=np.array([j.type.effort_unit or ""
                                                 for j in self.model.joints]))
        buffer = io.BytesIO()
        # a signal inside ZipFile's constructor leaves an object whose finaliser prints a
        # traceback (an interrupted 'hexapod simulate' did); held back, it comes after
        with deferred():
            np.savez_compressed(buffer, **arrays)
        return buffer.getvalue()

    def _npz_units(self) -> dict[str, np.ndarray]:
        """The units of ``q``, ``v``, ``v_dot`` and ``lam``, one per column (as units.json)."""
        model = self.model
        velocity = [VELOCITY_UNITS[component(n)][0] for n in model.velocity_names]
        return {"coordinate_units": np.array([COORDINATE_UNITS[component(n)][0]
                                              for n in model.coordinate_names], dtype=str),
                "velocity_units": np.array(velocity, dtype=str),
                "acceleration_units": np.array([ACCELERATION_UNITS[u] for u in velocity],
                                               dtype=str),
                "row_units": np.array([ROW_UNITS[r.kind][0] for r in model.rows], dtype=str)}


def scene_reference(name_or_path: str) -> str:
    """How a result records the scene it was made on: a scene file's absolute path, or the
    name of a built-in scene as given."""
    path = Path(name_or_path)
    return str(path.resolve()) if path.is_file() else name_or_path
