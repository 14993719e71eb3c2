"""What a walking robot's report says about its feet and its trunk: the ground's force on each
foot, split into normal and tangential parts with the friction ratio, the stance intervals of
the gait, the trunk's pose and velocity, and their CSV tables (``ground.csv``, ``trunk.csv``).

Conventions: the ground's normal is world ``z`` (a :class:`~hexapod.scene.joints.Contact`), so
a foot's normal force is ``F_n = GRz`` and its tangential force ``|F_t| = |(GRx, GRy)|``; the
friction ratio is ``|F_t| / (mu F_n)``, with ``mu`` the scene's friction coefficient
(:class:`~hexapod.scene.contacts.GroundForces`), above 1 where the force needs more friction
than ``mu``. A foot is named by its contact's name without the ``/ground`` suffix (``L1``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from hexapod.algorithms.ground import INFEASIBLE_STATUSES, in_contact_axes, robot_weight
from hexapod.algorithms.inverse import InverseResult
from hexapod.algorithms.kinematics import body_poses
from hexapod.model.model import Model
from hexapod.model.units import COORDINATE_UNITS, VELOCITY_UNITS, leg_name
from hexapod.output.summary_parts import true_runs
from hexapod.simulation.results import Columns
from hexapod.spatial import rpy_from_rotation

#: The ground-force columns of the inverse-dynamics CSV, per foot.
GROUND_COMPONENTS = ("GRx", "GRy", "GRz")
#: Forces below this fraction of the robot's weight count as no load (no friction ratio).
NO_LOAD = 1e-9


#: The feet's statuses as numbers, in the inverse CSV's ``status:<leg>`` columns.
STATUS_CODES = {"swing": 0, "ok": 1, "slip": 2, "pull": 3}


def ground_columns(model: Model) -> Columns:
    """``GRx:<leg>``, ``GRy:<leg>``, ``GRz:<leg>`` per contact, then ``status:<leg>`` per
    contact, in model order (none without contacts), with their unit and meaning."""
    legs = [leg_name(contact.name) for contact in model.contacts]
    codes = ", ".join(f"{code} {name}" for name, code in STATUS_CODES.items())
    return {**{f"{c}:{leg}": ("N", f"the ground's force on the foot, world {c[-1]} (zero in "
                                   "swing)") for leg in legs for c in GROUND_COMPONENTS},
            **{f"status:{leg}": ("1", f"whether the ground can give the foot its force: "
                                      f"{codes} (outside the friction cone; the ground pulling "
                                      "the foot)") for leg in legs}}


def status_codes(status: np.ndarray) -> np.ndarray:
    """The statuses (``swing``, ``ok``, ``slip``, ``pull``) as their :data:`STATUS_CODES`."""
    out = np.zeros(np.shape(status))
    for name, code in STATUS_CODES.items():
        out[np.asarray(status) == name] = code
    return out


@dataclass(frozen=True)
class FootLoads:
    """The ground's force on each foot at every sample, and what it means for friction.

    Attributes
    ----------
    legs : tuple of str
        One name per contact (``L1`` for ``L1/ground``).
    times : ndarray (N,)
    force : ndarray (N, C, 3)
        The ground's force on the foot, world axes (N); zero in swing.
    normal, tangential : ndarray (N, C)
        ``F_n = GRz`` and ``|F_t| = |(GRx, GRy)|`` (N).
    ratio : ndarray (N, C)
        ``|F_t| / (mu F_n)``: NaN where the foot carries nothing (swing, touch-down,
        lift-off), infinite where the ground would pull a loaded foot (``F_n <= 0``).
    status : ndarray (N, C) of str
        Whether the ground can give each foot its force, whatever the policy: ``swing``,
        ``ok``, ``slip``, ``pull`` (:func:`hexapod.algorithms.ground.feet_status`).
    stance : list of list of (float, float)
        Per foot, its stance intervals within the samples' span.
    mu : float
    policy : str
    weight : float
        The robot's weight ``m |g|`` (N).
    """

    legs: tuple[str, ...]
    times: np.ndarray
    force: np.ndarray
    normal: np.ndarray
    tangential: np.ndarray
    ratio: np.ndarray
    status: np.ndarray
    stance: list
    mu: float
    policy: str
    weight: float

    @property
    def infeasible(self) -> np.ndarray:
        """``(N, C)`` bool: where a foot slips or pulls (the ground cannot give its force)."""
        return np.isin(self.status, INFEASIBLE_STATUSES)


def foot_loads(model: Model, result: InverseResult) -> FootLoads:
    """The feet's loads of an inverse-dynamics ``result`` of a model with contacts."""
    force = np.asarray(result.ground_force, dtype=float) + 0.0  # zero in swing, not -0
    local = in_contact_axes(model, force)  # normal last, about each ground's normal
    normal = local[..., 2]
    tangential = np.hypot(local[..., 0], local[..., 1])
    mu = float(model.ground.mu)
    weight = robot_weight(model)
    loaded = np.linalg.norm(force, axis=-1) > NO_LOAD * (weight if weight > 0 else 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(normal > 0, tangential / (mu * normal), np.inf)
    ratio = np.where(loaded, ratio, np.nan)
    t = result.times
    stance = [c.stances(float(t[0]), float(t[-1])) for c in model.contacts]
    return FootLoads(tuple(leg_name(c.name) for c in model.contacts), t, force, normal,
                     tangential, ratio, np.asarray(result.ground_status, dtype=str), stance, mu,
                     result.policy or model.ground.policy, weight)


#: The columns of ``ground.csv`` per foot: quantity -> (unit, meaning).
GROUND_CSV_QUANTITIES = {
    "Fn": ("N", "normal force of the ground on the foot (GRz)"),
    "Ft": ("N", "tangential force of the ground on the foot, |(GRx, GRy)|"),
    "ratio": ("1", "friction ratio |F_t| / (mu F_n); nan where the foot carries nothing"),
    "status": (None, "swing, ok, slip (outside the friction cone) or pull (the ground pulling "
               "the foot), whatever the policy"),
}


def ground_csv_columns(legs: tuple[str, ...]) -> Columns:
    """The columns of ``ground.csv`` in order, each with its unit and meaning."""
    return {"t": ("s", "time"), **{f"{c}:{leg}": described for leg in legs
                                   for c, described in GROUND_CSV_QUANTITIES.items()}}


def ground_csv_text(loads: FootLoads) -> str:
    """``ground.csv``: ``t``, then per foot ``Fn:<leg>``, ``Ft:<leg>`` (N), ``ratio:<leg>``
    (``nan`` where the foot carries nothing) and ``status:<leg>``."""
    lines = [",".join(ground_csv_columns(loads.legs))]
    for k, t in enumerate(loads.times):
        cells = [f"{t:.17g}"]
        for c in range(len(loads.legs)):
            cells += [f"{loads.normal[k, c]:.17g}", f"{loads.tangential[k, c]:.17g}",
                      f"{loads.ratio[k, c]:.17g}", str(loads.status[k, c])]
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class FootEvent:
    """A run of consecutive samples where a foot is in one trouble: ``slip`` or ``pull`` (its
    status)."""

    leg: str
    kind: str
    start: float
    stop: float
    samples: int

    @property
    def when(self) -> str:
        return (f"{self.start:.4g}" if self.samples == 1
                else f"{self.start:.4g} ... {self.stop:.4g} ({self.samples} samples)")

    def __str__(self) -> str:
        return f"{self.leg}: {self.kind} at t = {self.when} s"


def describe_events(events: list[FootEvent]) -> list[str]:
    """One phrase per foot and kind of trouble, with every run of samples:
    ``L1: slip at t = 0.3, 0.4 ... 0.45 (2 samples) s``."""
    grouped: dict[tuple[str, str], list[str]] = {}
    for event in events:
        grouped.setdefault((event.leg, event.kind), []).append(event.when)
    return [f"{leg}: {kind} at t = {', '.join(when)} s" for (leg, kind), when in grouped.items()]


def foot_events(loads: FootLoads) -> list[FootEvent]:
    """Every run of samples where a foot slips or pulls (its status), foot by foot in time
    order."""
    kinds = {kind: loads.status == kind for kind in INFEASIBLE_STATUSES}
    out = []
    for c, leg in enumerate(loads.legs):
        for kind, flags in kinds.items():
            out += [FootEvent(leg, kind, float(loads.times[k]), float(loads.times[end]),
                              end - k + 1) for k, end in true_runs(flags[:, c])]
    return out


# ------------------------------------------------------------------ the trunk

@dataclass(frozen=True)
class TrunkMotion:
    """A free body's pose and velocity at every sample.

    Attributes
    ----------
    body : str
    position : ndarray (N, 3)
        Its centre of mass, world (m).
    euler_parameters : ndarray (N, 4)
        ``e0 .. e3``, scalar first.
    angles : ndarray (N, 3)
        Roll, pitch, yaw (rad), ``R = Rz(yaw) Ry(pitch) Rx(roll)``.
    velocity : ndarray (N, 3)
        Velocity of the centre of mass, world axes (m/s).
    angular_velocity : ndarray (N, 3)
        World axes (rad/s).
    """

    body: str
    position: np.ndarray
    euler_parameters: np.ndarray
    angles: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray


def free_bodies(model: Model) -> list[int]:
    """The spatial bodies that are no joint's child: a walking robot's trunk."""
    children = {j.child for j in model.joints}
    return [b for b, body in enumerate(model.bodies)
            if body.kind == "spatial" and b not in children]


def trunk_motion(model: Model, q: np.ndarray, v: np.ndarray) -> list[TrunkMotion]:
    """The motion of every free body (:func:`free_bodies`) over samples ``q``, ``v``."""
    out = []
    _, rotation = body_poses(model, q)
    for b in free_bodies(model):
        body = model.bodies[b]
        qb, vb = q[:, body.q], v[:, body.v]
        angles = np.array([rpy_from_rotation(R) for R in rotation[:, b]]).reshape(-1, 3)
        omega = np.einsum("nab,nb->na", rotation[:, b], vb[:, 3:6])
        out.append(TrunkMotion(body.name, qb[:, :3], qb[:, 3:7], angles, vb[:, :3], omega))
    return out


#: The columns of ``trunk.csv`` per free body, in order: (quantity, component) -> (unit,
#: meaning). Positions and velocities are named as in ``results.csv`` (``q:trunk.x``,
#: ``v:trunk.vx``); the angular velocity is in world axes here (``v:trunk.wx``), in body axes
#: there (``v:trunk.wx_body``).
TRUNK_COLUMNS = {
    **{("q", c): COORDINATE_UNITS[c] for c in ("x", "y", "z", "e0", "e1", "e2", "e3")},
    **{("angle", c): ("rad", f"{c} angle of the body, R = Rz(yaw) Ry(pitch) Rx(roll)")
       for c in ("roll", "pitch", "yaw")},
    **{("v", f"v{c}"): VELOCITY_UNITS[f"v{c}"] for c in "xyz"},
    **{("v", f"w{c}"): ("rad/s", f"angular velocity, world {c} axis") for c in "xyz"},
}


def trunk_csv_columns(bodies: list[str]) -> Columns:
    """The columns of ``trunk.csv`` in order, each with its unit and meaning."""
    return {"t": ("s", "time"), **{f"{quantity}:{body}.{c}": described for body in bodies
                                   for (quantity, c), described in TRUNK_COLUMNS.items()}}


def trunk_csv_text(times: np.ndarray, trunks: list[TrunkMotion]) -> str:
    """``trunk.csv``: ``t``, then per free body ``q:<body>.x .. z`` (m), ``q:<body>.e0 .. e3``,
    ``angle:<body>.roll, pitch, yaw`` (rad), ``v:<body>.vx .. vz`` (m/s, world) and
    ``v:<body>.wx .. wz`` (rad/s, world axes)."""
    header = list(trunk_csv_columns([m.body for m in trunks]))
    table = np.hstack([times[:, None]] + [np.hstack([m.position, m.euler_parameters, m.angles,
                                                      m.velocity, m.angular_velocity])
                                          for m in trunks])
    line = ",".join(["%.17g"] * table.shape[1])
    return ",".join(header) + "\n" + "".join(line % tuple(row) + "\n" for row in table)


# ------------------------------------------------------------------ grouping by leg

def leg_groups(names: list[str], model: Model | None = None) -> dict[str, list[int]] | None:
    """Indices of ``names`` (joint names) grouped by leg: by the prefix before their first
    ``/`` (``L1/ctr`` is in ``L1``), else, given the ``model``, by limb (:func:`limbs`: a URDF
    robot's ``FL_hip``, ``FL_knee`` and its foot's contact together); names in no group in
    ``other``, last. None when there are fewer than two legs (a single leg, a mechanism)."""
    groups: dict[str, list[int]] = {}
    for k, name in enumerate(names):
        prefix, slash, _ = name.partition("/")
        groups.setdefault(prefix if slash else "other", []).append(k)
    if len([g for g in groups if g != "other"]) < 2:
        limb_of = limbs(model) if model is not None else {}
        groups = {}
        for k, name in enumerate(names):
            groups.setdefault(limb_of.get(name, "other"), []).append(k)
        if len([g for g in groups if g != "other"]) < 2:
            return None
    if "other" in groups:  # last
        groups["other"] = groups.pop("other")
    return groups


def limbs(model: Model) -> dict[str, str]:
    """Each joint's limb, by name: the subtrees hanging from the trunk (the body most joints
    hang from; the ground for a fixed base) through the tree's joints, a foot's contact with
    the limb of its foot. A limb is named after its foot's contact (``FL`` for
    ``FL/ground``), else after its joints' common prefix (``FL`` for ``FL_hip``, ``FL_knee``),
    else after its first joint. Joints between the trunk and the ground, loop
    closures and limbs of a single joint are in none."""
    tree = [j for j in model.joints if not j.loop_closing and j.kind != "contact"]
    parent_of = {j.child: j for j in tree}
    hanging: dict[int, int] = {}
    for joint in tree:
        hanging[joint.parent] = hanging.get(joint.parent, 0) + 1
    if not hanging:
        return {}
    trunk = max(hanging, key=lambda body: (hanging[body], -body))

    def first_joint(body: int):  # the joint from the trunk that starts the body's limb
        joint = None
        while body in parent_of and body != trunk:
            joint = parent_of[body]
            body = joint.parent
        return joint if body == trunk else None

    members: dict[int, list[str]] = {}
    for joint in model.joints:
        if joint.loop_closing and joint.kind != "contact":
            continue
        start = first_joint(joint.child)
        if start is not None:
            members.setdefault(start.index, []).append(joint.name)
    out = {}
    for start, names in members.items():
        if len(names) < 2:
            continue
        feet = [leg_name(c.name) for c in model.contacts if c.name in names]
        shared = os.path.commonprefix(names).rstrip("_-./ ")
        label = feet[0] if len(feet) == 1 else shared or model.joints[start].name
        out.update({name: label for name in names})
    return out


def joint_type(name: str) -> str:
    """A joint's name without its leg's prefix (``L1/ctr`` -> ``ctr``)."""
    return name.partition("/")[2] or name
