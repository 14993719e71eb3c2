"""The scene: a mutable description of bodies, joints, drivers and force elements.

A scene is planar (``dimension=2``) or spatial (``dimension=3``) and has one length unit; every
length, gravity included, is in that unit, and :func:`hexapod.assemble` converts to SI.
:meth:`Scene.validate` collects every problem and raises one :class:`~hexapod.errors.ModelError`.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from numpy.typing import ArrayLike

from hexapod.errors import ModelError, Problem
from hexapod.scene.bodies import Body, Particle, PlanarBody, SpatialBody
from hexapod.scene.contacts import GroundForces
from hexapod.scene.drivers import (
    COORDINATES,
    ORIENTATIONS,
    CoordinateDriver,
    JointDriver,
    PostureDriver,
    guidance_problems,
)
from hexapod.scene.element import (
    GROUND,
    Attachment,
    Element,
    line_problem,
    name_problem,
    quoted,
)
from hexapod.scene.forces import (
    AppliedForce,
    AppliedTorque,
    ForceElement,
    GroundContact,
    JointController,
    JointEffort,
    RotationalSpringDamper,
    SpringDamper,
)
from hexapod.scene.joints import Joint, kinds_that
from hexapod.scene.laws import Guided
from hexapod.spatial import Placement

#: Length units a scene may use, in metres.
LENGTH_UNITS = {"m": 1.0, "dm": 0.1, "cm": 0.01, "mm": 1e-3, "um": 1e-6, "in": 0.0254,
                "ft": 0.3048}

STANDARD_GRAVITY = 9.81  # m/s^2, the default gravity

# The largest magnitudes a scene may hold, in SI. Each is far beyond any legged machine (a body of
# a million tonnes on a leg a thousand kilometres long), and far enough below the floating-point
# range (1.8e308) that the products the equations form of a few of them (m g L, k L^2, I w^2, the
# squares of a least-squares solve) stay finite: beyond them a scene fails in the arithmetic
# (an overflow, a division by zero) instead of saying what is wrong.
#: gravity, m/s^2: 1e5 g
LARGEST_GRAVITY = 1e6
#: per quantity: the largest magnitude (SI) and its unit
LARGEST = {"length": (1e6, "m"), "speed": (1e6, "m/s"), "rate": (1e6, "rad/s"),
           "mass": (1e9, "kg"), "inertia": (1e21, "kg m^2"), "time": (1e9, "s"),
           "stiffness": (1e15, "N/m"), "damping": (1e15, "N s/m"),
           "torsional stiffness": (1e15, "N m/rad"), "torsional damping": (1e15, "N m s/rad")}
#: the quantity of each element attribute a magnitude is checked for
_QUANTITIES = {"position": "length", "com": "length", "origin": "length", "length": "length",
               "free_length": "length", "foothold": "length", "advance": "length",
               "centre": "length",
               "point": "length", "point_a": "length", "point_b": "length",
               "parent_frame": "length", "child_frame": "length", "velocity": "speed",
               "angular_velocity": "rate", "mass": "mass", "inertia": "inertia",
               "period": "time", "stiffness": "stiffness", "damping": "damping"}


class Scene:
    """A multibody system described by its elements.

    Parameters
    ----------
    name : str
        The scene's name, shown in messages and outputs.
    dimension : int
        3 for a spatial scene, 2 for a planar one.
    length_unit : str
        One of :data:`LENGTH_UNITS`. Masses are in kg, times in s, forces in N.
    gravity : array_like, optional
        In L/s^2. Default: 9.81 m/s^2 along -z in space, -y in the plane, converted to L/s^2.
    characteristic_length : float, optional
        The length ``l`` (L) of the redundancy policy, which minimises
        ``sum |F|^2 + |T / l|^2`` over the joint wrenches. Default: see :func:`hexapod.assemble`.
    source : str
        The file the scene was read from, named in messages; empty for a scene built in Python.
    report_forces : bool
        Ask simulations of this scene for the joint wrenches at the saved states.
    ground : GroundForces, optional
        How the forces of feet on the ground are shared when they are statically indeterminate
        (:class:`~hexapod.scene.contacts.GroundForces`; default ``min-wrench``).

    Attributes
    ----------
    actuators : ActuatorTable or None
        The driven joints' motors when the scene's file names them (a robot description's
        ``actuators``); ``hexapod report`` checks them as it checks ``--actuators``.
    """

    def __init__(self, name: str = "scene", dimension: int = 3, length_unit: str = "m",
                 gravity: ArrayLike | None = None, characteristic_length: float | None = None,
                 source: str = "", *, report_forces: bool = False,
                 ground: GroundForces | None = None):
        self.name = name
        self.ground = ground if ground is not None else GroundForces()
        self.actuators = None  # the driven joints' motors, when the scene's file names them
        self.report_forces = bool(report_forces)
        self.dimension = dimension
        self.length_unit = length_unit
        self.characteristic_length = characteristic_length
        self.source = source
        self._gravity = None if gravity is None else np.array(gravity, dtype=float).reshape(-1)
        self._elements: list[Element] = []

    # ---------------------------------------------------------------- contents

    @property
    def unit(self) -> float:
        """Metres per length unit."""
        return LENGTH_UNITS[self.length_unit]

    @property
    def gravity(self) -> np.ndarray:
        if self._gravity is not None:
            return self._gravity
        g = np.zeros(self.dimension)
        g[-1] = -STANDARD_GRAVITY / LENGTH_UNITS.get(self.length_unit, 1.0)
        return g

    @gravity.setter
    def gravity(self, value):
        self._gravity = np.array(value, dtype=float).reshape(-1)

    def _of(self, family: type) -> dict:
        out: dict = {}
        for element in self._elements:
            if isinstance(element, family):
                out.setdefault(element.name, element)
        return out

    @property
    def bodies(self) -> dict[str, Body]:
        return self._of(Body)

    @property
    def joints(self) -> dict[str, Joint]:
        return self._of(Joint)

    @property
    def drivers(self) -> dict[str, Element]:
        return self._of((JointDriver, CoordinateDriver, PostureDriver))

    @property
    def forces(self) -> dict[str, ForceElement]:
        return self._of(ForceElement)

    @property
    def elements(self) -> tuple[Element, ...]:
        return tuple(self._elements)

    def add(self, *elements: Element) -> Element:
        """Add elements in order; returns the last. Problems are reported by :meth:`validate`."""
        for element in elements:
            if not isinstance(element, Element):
                raise TypeError(f"cannot add {element!r} to a scene")
            self._elements.append(element)
        return elements[-1] if elements else None

    def with_elements(self, elements, source: str | None = None) -> Scene:
        """A copy holding ``elements`` (in order) instead of this scene's, every setting kept:
        its name, units, gravity, ground and actuators; its source too unless ``source`` is
        given (where the copy's contents now come from, for error messages)."""
        out = Scene(self.name, self.dimension, self.length_unit, self._gravity,
                    self.characteristic_length, self.source if source is None else source,
                    report_forces=self.report_forces, ground=self.ground)
        out.actuators = self.actuators
        out.add(*elements)
        return out

    def attach(self, sub: Scene, prefix: str, base: str = GROUND,
               placement: Placement | None = None) -> None:
        """Add a copy of ``sub`` with every name prefixed by ``prefix + "/"``.

        The sub-model's ground becomes the frame ``placement`` of body ``base`` (default: the
        world); its bodies' initial poses move with it; it is converted to this scene's unit.
        Its gravity is ignored, this scene's applies.
        """
        subject, part = f"scene {quoted(self.name)}", f"sub-model {quoted(sub.name)}"
        if sub.dimension != self.dimension:
            raise ModelError(subject, [Problem(
                part, f"is {sub.dimension}-D, the scene {self.dimension}-D")])
        why = name_problem(prefix)
        if why:
            raise ModelError(subject, [Problem(
                part, f"prefix {quoted(prefix)} is not a valid name: {why}")])
        placement = placement or Placement.identity(self.dimension)
        if base == GROUND:
            base_pose = Placement.identity(self.dimension)
        elif base in self.bodies:
            base_pose = self.bodies[base].pose
        else:
            raise ModelError(subject, [Problem(
                part, f"base body {quoted(base)} is not in the scene")])
        attachment = Attachment(prefix, base, placement, base_pose @ placement)
        for element in sub.scaled_elements(sub.unit / self.unit):
            self.add(element.attached(attachment))

    # ---------------------------------------------------------------- units

    def scaled_elements(self, factor: float) -> Iterator[Element]:
        """Copies of the elements with lengths multiplied by ``factor``.

        Driver laws and actuator efforts are lengths (or torques) only on some joint types,
        so the scene, which knows the joints, decides their factor: the joint's coordinate
        unit (a length) and its effort unit (a torque, N L).
        """
        joints = self.joints
        for element in self._elements:
            if isinstance(element, JointDriver):
                joint = joints.get(element.joint)
                yield element.scaled(factor if getattr(joint, "coordinate_unit", None)
                                     == "length" else 1.0)
            elif isinstance(element, JointEffort):
                joint = joints.get(element.joint)
                yield element.scaled(factor if getattr(joint, "effort_unit", None) == "N m"
                                     else 1.0)
            else:
                yield element.scaled(factor)

    def in_si(self) -> Scene:
        """A copy in metres (gravity and every length converted)."""
        factor = self.unit
        out = Scene(self.name, self.dimension, "m", self.gravity * factor,
                    None if self.characteristic_length is None
                    else self.characteristic_length * factor, self.source,
                    report_forces=self.report_forces, ground=self.ground.scaled(factor))
        out._elements = list(self.scaled_elements(factor))
        return out

    # ---------------------------------------------------------------- frames

    def pose(self, body: str) -> Placement:
        """Initial pose of a body's reference frame (identity for the ground)."""
        if body == GROUND:
            return Placement.identity(self.dimension)
        return self.bodies[body].pose

    def frame(self, body: str, ref) -> Placement:
        """A frame reference (None, marker, Placement or point) in ``body``'s reference frame."""
        if ref is None:
            return Placement.identity(self.dimension)
        if isinstance(ref, str):
            return self.bodies[body].markers[ref]
        if isinstance(ref, Placement):
            return ref
        return Placement(ref)

    def joint_frames(self, joint: Joint) -> tuple[Placement, Placement]:
        """The joint's frames on the parent and on the child, each in that body's reference
        frame (world for the ground). Raises ``KeyError`` for unknown names (see validate)."""
        if joint.origin is not None:
            world = Placement(joint.origin, joint.rotation)
            return (self.pose(joint.parent).inverse() @ world,
                    self.pose(joint.child).inverse() @ world)
        child = self.frame(joint.child, joint.child_frame)
        if joint.parent_frame is not None or joint.joins_two_points:
            # a distance joint's two points are apart: each defaults to its body's origin
            return self.frame(joint.parent, joint.parent_frame), child
        world = self.pose(joint.child) @ child
        return self.pose(joint.parent).inverse() @ world, child

    def point(self, body: str, ref) -> np.ndarray:
        """A point reference in ``body``'s reference frame (default: its centre of mass)."""
        if ref is None:
            return (np.zeros(self.dimension) if body == GROUND
                    else np.array(self.bodies[body].com, dtype=float))
        return self.frame(body, ref).position

    # ---------------------------------------------------------------- validation

    def validate(self) -> None:
        """Raise one :class:`ModelError` listing every problem, or return quietly."""
        problems = self.problems()
        if problems:
            where = f" ({self.source})" if self.source else ""
            raise ModelError(f"scene {quoted(self.name)}{where}", problems)

    def problems(self) -> list[Problem]:
        """Every problem of the scene: its own settings, each element, names and references."""
        out = self._scene_problems()
        for element in self._elements:
            out.extend(element.problems())
        out.extend(self._name_problems())
        out.extend(guidance_problems(self._elements, self._scene_problem))
        bodies = self.bodies
        for element in self._elements:
            out.extend(_ReferenceCheck(self, bodies, element).problems())
        if not out:  # in SI, which needs every element readable
            out.extend(magnitude_problems(self))
        return out

    def _scene_problem(self, key: str, message: str) -> Problem:
        return Problem("scene", message, f"{self.source}, scene.{key}" if self.source else key)

    def _scene_problems(self) -> list[Problem]:
        out = []
        why = line_problem(self.name)
        if why:
            out.append(self._scene_problem(
                "name", f"{quoted(self.name)} is not a valid scene name: {why}"))
        if self.dimension not in (2, 3):
            out.append(self._scene_problem("dimension", f"must be 2 or 3, got {self.dimension}"))
            return out
        if self.length_unit not in LENGTH_UNITS:
            out.append(self._scene_problem(
                "length_unit", f"unknown unit {self.length_unit!r}; use one of "
                + ", ".join(LENGTH_UNITS)))
        g = self.gravity
        if g.size != self.dimension or not np.all(np.isfinite(g)):
            out.append(self._scene_problem(
                "gravity", f"needs {self.dimension} finite numbers, got {g.tolist()}"))
        elif np.abs(g).max() * LENGTH_UNITS.get(self.length_unit, 1.0) > LARGEST_GRAVITY:
            out.append(self._scene_problem(
                "gravity", f"has a component of {_short(np.abs(g).max())} {self.length_unit}/"
                f"s^2, beyond the {_short(LARGEST_GRAVITY)} m/s^2 a scene may hold (1e5 g: no "
                "legged machine)"))
        length = self.characteristic_length
        if length is not None and not (np.isfinite(length) and length > 0):
            out.append(self._scene_problem("characteristic_length",
                                           f"must be positive, got {length}"))
        out.extend(self.ground.problems())
        driven = {getattr(d, "joint", None) for d in self._elements
                  if isinstance(d, JointDriver)}
        for name in self.ground.reference_efforts:
            if name not in driven:
                key = name if not name_problem(name) else quoted(name)
                out.append(self._scene_problem(
                    f"ground.reference_efforts.{key}",
                    f"no driven joint {quoted(name)} (reference efforts are given per driven "
                    "joint)"))
        return out

    def _name_problems(self) -> list[Problem]:
        out = []
        seen_bodies: set[str] = set()
        seen_others: dict[str, Element] = {}
        for element in self._elements:
            name = element.name
            why = name_problem(name)
            if why:
                out.append(element.problem("name", f"{quoted(name)} is not a valid name: {why}"))
                continue
            if name == GROUND:
                out.append(element.problem("name", "'ground' is reserved for the fixed frame"))
            if isinstance(element, Body):
                if name in seen_bodies:
                    out.append(element.problem("name", "duplicate body name"))
                seen_bodies.add(name)
            else:
                if name in seen_others:
                    out.append(element.problem(
                        "name", f"name already used by {seen_others[name].label}"))
                seen_others.setdefault(name, element)
        return out


class _ReferenceCheck:
    """The checks of one element against the rest of the scene."""

    def __init__(self, scene: Scene, bodies: dict[str, Body], element: Element):
        self.scene = scene
        self.bodies = bodies
        self.element = element
        self.out: list[Problem] = []

    def problems(self) -> list[Problem]:
        e = self.element
        if isinstance(e, Body):
            self._body(e)
        elif isinstance(e, Joint):
            self._joint(e)
        elif isinstance(e, JointDriver):
            self._driven_joint(e.joint, "joint", "a driver")
            driven = [d for d in self.scene.elements
                      if isinstance(d, JointDriver) and d.joint == e.joint]
            if driven and driven[0] is not e:
                self._add("joint", f"joint '{e.joint}' is already driven by '{driven[0].name}'")
        elif isinstance(e, CoordinateDriver):
            self._coordinate_driver(e)
        elif isinstance(e, PostureDriver):
            self._posture(e)
        elif isinstance(e, SpringDamper):
            self._point(e.body_a, e.point_a, "point_a", "body_a")
            self._point(e.body_b, e.point_b, "point_b", "body_b")
        elif isinstance(e, AppliedForce):
            # a load on the ground is reported by the element itself
            if self._body_ref(e.body, "body", ground_ok=True):
                self._point(e.body, e.point, "point", "body")
            self._components("force", e.force, self.scene.dimension)
        elif isinstance(e, AppliedTorque):
            if self._body_ref(e.body, "body", ground_ok=True) and isinstance(
                    self.bodies.get(e.body), Particle):
                self._add("body", f"particle '{e.body}' has no orientation: a torque on it "
                          "does nothing")
            self._components("torque", e.torque, 3 if self.scene.dimension == 3 else 1)
        elif isinstance(e, GroundContact):
            if self._body_ref(e.body, "body", ground_ok=True):
                self._point(e.body, e.point, "point", "body")
            for key in ("normal", "surface_point", "forward"):
                if getattr(e, key) is not None:
                    self._components(key, np.ravel(getattr(e, key)), self.scene.dimension)
            if e.armed_ahead_of is not None and not isinstance(
                    self.scene.forces.get(e.armed_ahead_of), GroundContact):
                self._add("armed_ahead_of", f"'{e.armed_ahead_of}' is not a ground-contact "
                          "force element of the scene")
        elif isinstance(e, JointEffort):
            self._driven_joint(e.joint, "joint", "an actuator effort")
        elif isinstance(e, (RotationalSpringDamper, JointController)):
            joint = self.scene.joints.get(e.joint)
            if joint is None:
                self._add("joint", f"unknown joint '{e.joint}'")
            elif not joint.turns:
                self._add("joint", f"a {joint.kind} joint has no axis to turn about "
                          f"({kinds_that(lambda t: t.turns)} joints have)")
            elif any(isinstance(self.bodies.get(b), Particle)
                     for b in (joint.parent, joint.child)):
                self._add("joint", f"joint '{e.joint}' joins a particle, which has no angle")
        return self.out

    def _add(self, key, message):
        self.out.append(self.element.problem(key, message))

    def _body(self, body: Body):
        dim = self.scene.dimension
        if isinstance(body, SpatialBody) and dim != 3:
            self._add("type", "a spatial body in a planar scene")
        if isinstance(body, PlanarBody) and dim != 2:
            self._add("type", "a planar body in a spatial scene")
        if isinstance(body, Particle) and body.dimension != dim:
            self._add("position", f"needs {dim} coordinates in a {dim}-D scene")
        for marker in body.markers:
            why = name_problem(marker)
            if why:
                self._add("markers", f"{quoted(marker)} is not a valid marker name: {why}")
        self._computable(body)

    def _computable(self, body: Body):
        """A positive mass or moment of inertia so small that, in SI, it is below the smallest
        normal floating-point number: the mass matrix could not be inverted (1e-320 kg um^2 is
        zero in kg m^2). Masses are not scaled; inertias scale with the unit squared."""
        tiny = np.finfo(float).tiny
        if np.isfinite(body.mass) and 0 < body.mass < tiny:
            self._add("mass", f"is too small to compute with ({body.mass:.3g} kg)")
        inertia = getattr(body, "inertia", None)
        unit = LENGTH_UNITS.get(self.scene.length_unit)
        if inertia is None or unit is None or not np.all(np.isfinite(inertia)):
            return
        smallest = np.linalg.eigvalsh(np.atleast_2d(inertia)).min()
        if smallest > 0 and smallest * unit**2 < tiny:  # not positive: reported by the body
            self._add("inertia", "is too small to compute with (smallest principal moment "
                      f"{smallest:.3g} kg {self.scene.length_unit}^2)")

    def _body_ref(self, name: str, key: str, ground_ok: bool = False) -> bool:
        if name == GROUND and ground_ok:
            return True
        if name not in self.bodies:
            self._add(key, f"unknown body '{name}'")
            return False
        return True

    def _frame(self, body: str, ref, key: str):
        if isinstance(ref, str):
            if body == GROUND:
                self._add(key, f"the ground has no markers (got '{ref}'); give coordinates")
            elif ref not in self.bodies[body].markers:
                self._add(key, f"body '{body}' has no marker '{ref}'")
        elif ref is not None:
            frame = ref if isinstance(ref, Placement) else Placement(ref)
            if frame.dimension != self.scene.dimension:
                self._add(key, f"needs {self.scene.dimension} coordinates")

    def _point(self, body: str, ref, key: str, body_key: str):
        if self._body_ref(body, body_key, ground_ok=True):
            self._frame(body, ref, key)

    def _components(self, key: str, laws, count: int):
        if len(laws) != count:
            self._add(key, f"needs {count} components in a {self.scene.dimension}-D scene, "
                      f"got {len(laws)}")

    def _joint(self, joint: Joint):
        dim = self.scene.dimension
        ok_parent = self._body_ref(joint.parent, "parent", ground_ok=True)
        ok_child = self._body_ref(joint.child, "child", ground_ok=True)
        if joint.parent == GROUND and joint.child == GROUND:
            self._add("child", "a joint between the ground and itself")
        if ok_parent:
            self._frame(joint.parent, joint.parent_frame, "parent_frame")
        if ok_child:
            self._frame(joint.child, joint.child_frame, "child_frame")
        if joint.origin is not None and joint.origin.size != dim:
            self._add("origin", f"needs {dim} coordinates")
        if joint.rotation is not None and joint.rotation.shape != (dim, dim):
            self._add("rotation", f"needs a {dim} x {dim} matrix")
        if joint.joins_two_points and joint.origin is not None:
            self._add("origin", f"a {joint.kind} joint joins two points: give parent_frame and "
                      "child_frame (or markers), not one origin")
        if dim == 2 and not joint.exists_in_plane:
            self._add("type", f"no {joint.kind} joint in the plane: use {joint.plane_hint}")
        for key in ("axis", "axis2"):
            axis = getattr(joint, key, None)
            if axis is None or key not in joint.file_keys(dim):
                continue  # a planar revolute turns about the plane's normal
            if axis.size != dim:
                self._add(key, f"needs {dim} components in a {dim}-D scene")
        ends = joint.particle_ends.get(dim, "")
        for key, name in (("parent", joint.parent), ("child", joint.child)):
            if isinstance(self.bodies.get(name), Particle) and key[0] not in ends:
                allowed = kinds_that(lambda t, end=key[0]: end in t.particle_ends.get(dim, ""))
                self._add(key, f"particle '{name}' has no orientation: as {key} of a joint "
                          f"it needs one of: {allowed}")

    def _driven_joint(self, name: str, key: str, what: str):
        joint = self.scene.joints.get(name)
        if joint is None:
            self._add(key, f"unknown joint '{name}'")
        elif not joint.drivable:
            self._add(key, f"a {joint.kind} joint cannot take {what} "
                      f"({kinds_that(lambda t: t.drivable)} joints can)")
        elif joint.coordinate_unit == "angle" and any(isinstance(self.bodies.get(b), Particle)
                                                      for b in (joint.parent, joint.child)):
            self._add(key, f"joint '{name}' joins a particle, which has no angle to drive")

    def _posture(self, driver: PostureDriver):
        if self._body_ref(driver.body, "body"):
            self._frame(driver.body, driver.point, "point")
        guided = {d.joint for d in self.scene.elements
                  if isinstance(d, JointDriver) and isinstance(d.law, Guided)}
        for name in driver.joints:
            joint = self.scene.joints.get(name)
            if joint is None or joint.kind != "revolute" or name not in guided:
                self._add("joints", f"'{name}' must be a revolute joint that follows the "
                          "guides (a joint driver of law 'guided')")

    def _coordinate_driver(self, driver: CoordinateDriver):
        if not self._body_ref(driver.body, "body") or driver.coordinate not in COORDINATES:
            return
        body = self.bodies[driver.body]
        if driver.coordinate == "angle" and not isinstance(body, PlanarBody):
            self._add("coordinate", "only a planar body has an 'angle' coordinate; drive a "
                      "revolute joint instead")
        if driver.coordinate == "z" and self.scene.dimension == 2:
            self._add("coordinate", "no 'z' in a planar scene")
        if driver.coordinate in ORIENTATIONS and not isinstance(body, SpatialBody):
            self._add("coordinate", f"only a spatial body has a {driver.coordinate} angle "
                      "(a planar body's is 'angle')")
        self._frame(driver.body, driver.point, "point")
        if driver.frame != "world" and driver.frame != driver.body:
            self._body_ref(driver.frame, "frame", ground_ok=True)


# ------------------------------------------------------------------ magnitudes


def magnitude_problems(scene: Scene) -> list[Problem]:
    """Numbers beyond the magnitudes a scene may hold (:data:`LARGEST`), compared in SI (the
    scene converted, so a length in micrometres is weighed in metres); reported at the key the
    element was written with. The scene must be otherwise valid."""
    out = []
    for element in scene.in_si().elements:
        torsional = "torsional " if element.kind == "rotational-spring" else ""
        for key, quantity in _QUANTITIES.items():
            value = getattr(element, key, None)
            if isinstance(value, Placement):
                value, key = value.position, f"{key}.position"
            if value is None or isinstance(value, str):
                continue
            if quantity in ("stiffness", "damping"):
                quantity = torsional + quantity
            largest, unit = LARGEST[quantity]
            size = float(np.max(np.abs(np.asarray(value, dtype=float)), initial=0.0))
            if size > largest:
                out.append(element.problem(key, f"is {_short(size)} {unit} in SI, beyond the "
                                           f"{_short(largest)} {unit} a scene may hold"))
        markers = getattr(element, "markers", {})
        for name, frame in markers.items():
            size = float(np.max(np.abs(frame.position), initial=0.0))
            if size > LARGEST["length"][0]:
                out.append(element.problem(f"markers.{name}", f"is {_short(size)} m from the "
                                           f"body in SI, beyond the {_short(LARGEST['length'][0])}"
                                           " m a scene may hold"))
    return out


def _short(value: float) -> str:
    """A magnitude in three digits, as a person writes it: 1e6, not 1e+06."""
    mantissa, e, exponent = f"{value:.3g}".partition("e")
    return f"{mantissa}e{int(exponent)}" if e else mantissa
