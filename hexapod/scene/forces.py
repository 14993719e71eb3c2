"""Force elements: spring-dampers, applied forces and torques, joint actuator efforts.

Gravity is a property of the scene. Points are marker names or coordinates in the body's
reference frame (world coordinates on the ground); a missing point means the centre of mass.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.errors import Problem
from hexapod.scene.element import (
    GROUND,
    Attachment,
    Element,
    check_finite,
    ground_ref,
    scaled_ref,
)
from hexapod.scene.laws import Law, LawOnJoint, as_law

FRAMES = ("world", "body")


class ForceElement(Element):
    family = "force"


def _laws(values) -> tuple[Law, ...]:
    if isinstance(values, Law) or np.ndim(values) == 0:
        values = [values]
    return tuple(as_law(v) for v in values)


def _non_negative(element: Element, keys: tuple[str, ...], out: list[Problem]) -> None:
    for key in keys:
        value = getattr(element, key)
        if check_finite(element, key, value, out) and value < 0:
            out.append(element.problem(key, f"must not be negative, got {value}"))


def _law_problems(element: Element, key: str, laws) -> list[Problem]:
    return [element.problem(f"{key}[{i}]", m) for i, law in enumerate(laws)
            for m in law.problems()]


@dataclass(eq=False)
class SpringDamper(ForceElement):
    """A translational spring-damper (and optional actuator) between two points.

    Tension ``f = stiffness (L - free_length) + damping dL/dt + force(t)`` pulls the points
    together when positive. ``free_length`` defaults to the distance at the initial pose.
    Units: stiffness N/L, damping N s/L, force N.

    Parameters
    ----------
    name : str
        The element's name, unique among the force elements.
    body_a, body_b : str
        The bodies of its two ends (``"ground"`` allowed).
    point_a, point_b : str or array_like, optional
        Its ends: a marker name or a point in the body's reference frame (world on the
        ground), L; default the centre of mass.
    stiffness : float
        N/L, at least 0.
    damping : float
        N s/L, at least 0.
    free_length : float, optional
        L; default: the distance at the initial pose.
    force : Law or float, optional
        An actuator's tension as a function of time, N.
    source : str
        Where the element was written, named in messages; empty when built in Python.
    """

    name: str
    body_a: str
    body_b: str
    point_a: object = None
    point_b: object = None
    stiffness: float = 0.0
    damping: float = 0.0
    free_length: float | None = None
    force: Law | None = None
    source: str = ""
    kind = "spring"

    def __post_init__(self):
        if self.force is not None:
            self.force = as_law(self.force)

    def problems(self):
        out: list[Problem] = []
        _non_negative(self, ("stiffness", "damping") + (
            ("free_length",) if self.free_length is not None else ()), out)
        for key in ("point_a", "point_b"):
            ref = getattr(self, key)
            if ref is not None and not isinstance(ref, str):
                check_finite(self, key, ref, out)
        if self.force is not None:
            out.extend(self.problem("force", m) for m in self.force.problems())
        if self.body_a == self.body_b:
            out.append(self.problem("body_b", "both ends are on the same body"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        out.point_a = scaled_ref(self.point_a, length)
        out.point_b = scaled_ref(self.point_b, length)
        out.stiffness = self.stiffness / length
        out.damping = self.damping / length
        if self.free_length is not None:
            out.free_length = self.free_length * length
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        out.body_a, out.body_b = attachment.body(self.body_a), attachment.body(self.body_b)
        out.point_a = ground_ref(self.point_a, self.body_a, attachment)
        out.point_b = ground_ref(self.point_b, self.body_b, attachment)
        return out


@dataclass(eq=False)
class AppliedForce(ForceElement):
    """A force (N) at a point of a body; components are numbers or laws of time, in ``frame``
    (``world`` or ``body``: the body's reference axes). World-frame loads of an attached
    sub-model stay in the world frame (a ground reaction does not turn with the trunk).

    Parameters
    ----------
    name : str
        The element's name, unique among the force elements.
    body : str
        The body loaded (not the ground).
    force : sequence of (Law or float)
        The components, N: 3 in space, 2 in the plane.
    point : str or array_like, optional
        Where it acts: a marker name or a point in the body's reference frame (L); default the
        centre of mass.
    frame : {"world", "body"}
        The axes of the components.
    source : str
        Where the element was written, named in messages; empty when built in Python.
    """

    name: str
    body: str
    force: tuple
    point: object = None
    frame: str = "world"
    source: str = ""
    kind = "applied-force"

    def __post_init__(self):
        self.force = _laws(self.force)

    def problems(self):
        out = _law_problems(self, "force", self.force)
        if self.frame not in FRAMES:
            out.append(self.problem("frame", f"must be 'world' or 'body', got {self.frame!r}"))
        if self.point is not None and not isinstance(self.point, str):
            check_finite(self, "point", self.point, out)
        if self.body == GROUND:
            out.append(self.problem("body", "a load on the ground does nothing"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        out.point = scaled_ref(self.point, length)
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        out.body = attachment.body(self.body)
        return out


@dataclass(eq=False)
class AppliedTorque(ForceElement):
    """A torque (N L) on a body; 3 components in space, 1 in the plane, in ``frame``.

    Parameters
    ----------
    name : str
        The element's name, unique among the force elements.
    body : str
        The body loaded (not the ground).
    torque : sequence of (Law or float)
        The components, N L: 3 in space, 1 in the plane.
    frame : {"world", "body"}
        The axes of the components.
    source : str
        Where the element was written, named in messages; empty when built in Python.
    """

    name: str
    body: str
    torque: tuple
    frame: str = "world"
    source: str = ""
    kind = "applied-torque"

    def __post_init__(self):
        self.torque = _laws(self.torque)

    def problems(self):
        out = _law_problems(self, "torque", self.torque)
        if self.frame not in FRAMES:
            out.append(self.problem("frame", f"must be 'world' or 'body', got {self.frame!r}"))
        if self.body == GROUND:
            out.append(self.problem("body", "a load on the ground does nothing"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        out.torque = tuple(law.scaled(length) for law in self.torque)
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        out.body = attachment.body(self.body)
        return out


@dataclass(eq=False)
class JointEffort(LawOnJoint, ForceElement):
    """An actuator effort along a joint's coordinate, exerted by the parent on the child:
    a torque (N L) about a revolute axis, a force (N) along a prismatic axis.

    Parameters
    ----------
    name : str
        The element's name, unique among the force elements.
    joint : str
        The joint it acts along (a type with a coordinate: revolute, prismatic).
    law : Law or float
        The effort as a function of time (N L or N).
    source : str
        Where the element was written, named in messages; empty when built in Python.
    """

    name: str
    joint: str
    law: Law
    source: str = ""
    kind = "effort"


@dataclass(eq=False)
class RotationalSpringDamper(ForceElement):
    """A torsion spring-damper (and optional actuator) across a revolute or cylindrical joint:
    the torque of the parent on the child about the joint axis is
    ``-stiffness * wrap(theta - free_angle) - damping * dtheta/dt + torque(t)``, with ``wrap``
    the angle difference brought into (-pi, pi]. Units: stiffness N L/rad, damping N L s/rad,
    torque N L.

    Parameters
    ----------
    name : str
        The element's name, unique among the force elements.
    joint : str
        The revolute or cylindrical joint it acts across.
    stiffness : float
        N L/rad, at least 0.
    damping : float
        N L s/rad, at least 0.
    free_angle : float
        The joint angle at which the spring is relaxed, rad.
    torque : Law or float, optional
        An actuator's torque as a function of time, N L.
    source : str
        Where the element was written, named in messages; empty when built in Python.
    """

    name: str
    joint: str
    stiffness: float = 0.0
    damping: float = 0.0
    free_angle: float = 0.0
    torque: Law | None = None
    source: str = ""
    kind = "rotational-spring"

    def __post_init__(self):
        if self.torque is not None:
            self.torque = as_law(self.torque)

    def problems(self):
        out: list[Problem] = []
        _non_negative(self, ("stiffness", "damping"), out)
        check_finite(self, "free_angle", self.free_angle, out)
        if self.torque is not None:
            out.extend(self.problem("torque", m) for m in self.torque.problems())
        return out

    def scaled(self, length):
        out = super().scaled(length)
        out.stiffness = self.stiffness * length
        out.damping = self.damping * length
        if self.torque is not None:
            out.torque = self.torque.scaled(length)
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        out.joint = attachment.name(self.joint)
        return out


@dataclass(eq=False)
class JointController(ForceElement):
    """A joint servo: the torque of the parent on the child about a revolute (or cylindrical)
    joint's axis that makes the joint follow ``target``,

        tau = feedforward(t) + kp wrap(target(t) - theta) + kd (target'(t) - theta'),

    limited by its actuator: ``|tau| <= max_effort``, and with ``no_load_speed`` the motor's
    torque-speed line, ``-max_effort (1 + w / w0) <= tau <= max_effort (1 - w / w0)`` at the
    joint speed ``w`` (a DC motor at its voltage limit: at ``w0`` it gives nothing more in the
    direction of motion). The actuator's numbers are the joint's: a motor's stall torque times
    its gear ratio, its no-load speed divided by it. Units: kp N L/rad, kd N L s/rad, efforts
    N L, speeds rad/s.

    Parameters
    ----------
    name : str
        The element's name, unique among the force elements.
    joint : str
        The revolute or cylindrical joint it drives.
    target : Law or float
        The joint angle to follow (rad), C2; its rate is the target speed.
    kp, kd : float
        Proportional and derivative gains, at least 0.
    feedforward : Law or float, optional
        The effort fed forward (N L), e.g. the inverse dynamics' effort of the same motion.
    max_effort : float, optional
        The actuator's largest effort (N L), positive; default unlimited.
    no_load_speed : float, optional
        With ``max_effort``: the speed at which the actuator's effort falls to zero (rad/s),
        positive; default none (a flat limit).
    source : str
        Where the element was written, named in messages; empty when built in Python.
    """

    name: str
    joint: str
    target: Law = 0.0
    kp: float = 0.0
    kd: float = 0.0
    feedforward: Law | None = None
    max_effort: float | None = None
    no_load_speed: float | None = None
    source: str = ""
    kind = "controller"

    def __post_init__(self):
        self.target = as_law(self.target)
        if self.feedforward is not None:
            self.feedforward = as_law(self.feedforward)

    def problems(self):
        out: list[Problem] = []
        _non_negative(self, ("kp", "kd"), out)
        out.extend(self.problem("target", m) for m in self.target.problems())
        if self.feedforward is not None:
            out.extend(self.problem("feedforward", m) for m in self.feedforward.problems())
        for key in ("max_effort", "no_load_speed"):
            value = getattr(self, key)
            if value is not None and check_finite(self, key, value, out) and not value > 0:
                out.append(self.problem(key, f"must be positive, got {value}"))
        if self.no_load_speed is not None and self.max_effort is None:
            out.append(self.problem("no_load_speed", "needs max_effort (the stall effort)"))
        return out

    def scaled(self, length):
        out = super().scaled(length)  # efforts in N L: N m = N L * length
        out.kp, out.kd = self.kp * length, self.kd * length
        if self.feedforward is not None:
            out.feedforward = self.feedforward.scaled(length)
        if self.max_effort is not None:
            out.max_effort = self.max_effort * length
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        out.joint = attachment.name(self.joint)
        return out


@dataclass(eq=False)
class GroundContact(ForceElement):
    """A unilateral point contact of a body with the ground surface (a plane), with Coulomb
    friction and Newton's impact law: the force of the ground on the point is decided at each
    step by a contact scheme (:mod:`hexapod.simulation.integrators.moreau_jean`), not by a law.

    The **gap** ``g = n . (P - S)`` of the point ``P`` from the plane through ``S`` with unit
    normal ``n`` (world) is positive when they are apart. Where it is closed the ground pushes
    (normal force at least 0, never pulls) and the tangential force stays inside the cone
    ``|F_t| <= mu F_n``; an approach at normal speed ``u`` rebounds at ``-restitution u``.

    Parameters
    ----------
    name : str
        The element's name, unique among the force elements.
    body : str
        The body that touches (not the ground).
    point : str or array_like, optional
        The touching point: a marker name or a point in the body's reference frame (L);
        default the centre of mass.
    normal : array_like, optional
        The plane's normal, world, pointing out of the ground (normalised; default ``+z`` in
        space, ``+y`` in the plane).
    surface_point : array_like, optional
        A point of the plane, world (L); default the origin.
    restitution : float
        Newton's coefficient of restitution, in [0, 1] (default 0: plastic).
    mu : float, optional
        The friction coefficient, at least 0; default the scene's ``[ground] mu``.
    armed_ahead_of : str, optional
        Another ground contact: this one may touch down only while its point is ahead of
        that one's along ``forward`` (a compass gait's swing foot, which passes the ground at
        mid-swing, is armed once it is ahead of the stance foot); default always armed.
    forward : array_like, optional
        The direction of "ahead", world (default the plane's first tangent).
    source : str
        Where the element was written, named in messages; empty when built in Python.
    """

    name: str
    body: str
    point: object = None
    normal: object = None
    surface_point: object = None
    restitution: float = 0.0
    mu: float | None = None
    armed_ahead_of: str | None = None
    forward: object = None
    source: str = ""
    kind = "ground-contact"

    def problems(self):
        out: list[Problem] = []
        if self.point is not None and not isinstance(self.point, str):
            check_finite(self, "point", self.point, out)
        for key in ("normal", "surface_point", "forward"):
            check_finite(self, key, getattr(self, key), out)
        for key in ("normal", "forward"):
            value = getattr(self, key)
            if value is not None and np.all(np.isfinite(np.asarray(value, float))) \
                    and not np.linalg.norm(np.asarray(value, dtype=float)) > 0:
                out.append(self.problem(key, "must not be zero"))
        if self.armed_ahead_of == self.name:
            out.append(self.problem("armed_ahead_of", "names the contact itself"))
        if check_finite(self, "restitution", self.restitution, out) and not (
                0.0 <= self.restitution <= 1.0):
            out.append(self.problem("restitution", f"must be in [0, 1], got "
                                    f"{self.restitution}"))
        if self.mu is not None:
            _non_negative(self, ("mu",), out)
        if self.body == GROUND:
            out.append(self.problem("body", "the ground cannot touch itself"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        out.point = scaled_ref(self.point, length)
        out.surface_point = scaled_ref(self.surface_point, length)
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        out.body = attachment.body(self.body)
        T = attachment.transform  # the plane is in the sub-model's world: into the scene's
        out.surface_point, out.normal = T.transform_point(self.plane(T.rotation.shape[0])[0]), \
            T.rotation @ self.plane(T.rotation.shape[0])[1]
        return out

    def plane(self, dimension: int) -> tuple[np.ndarray, np.ndarray]:
        """The plane's point and unit normal (world), the defaults filled in."""
        point = np.zeros(dimension) if self.surface_point is None else np.asarray(
            self.surface_point, dtype=float)
        normal = np.eye(dimension)[-1] if self.normal is None else np.asarray(
            self.normal, dtype=float)
        return point, normal / np.linalg.norm(normal)


FORCE_TYPES: dict[str, type[ForceElement]] = {
    cls.kind: cls for cls in (SpringDamper, AppliedForce, AppliedTorque, JointEffort,
                              RotationalSpringDamper, JointController, GroundContact)
}
