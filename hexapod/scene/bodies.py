"""Bodies: spatial rigid bodies, planar rigid bodies and particles, with named markers.

A body has a **reference frame** (its pose in the world at the initial guess is ``position`` and
``rotation``), a centre of mass ``com`` given in that frame, and markers (named frames fixed to the
body, given in that frame). The engine works with the centre of mass and the body's axes (absolute
coordinates), so the reference frame is only a convenience for describing it, as a URDF link frame
is.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np

from hexapod.errors import Problem
from hexapod.scene.element import Attachment, Element, check_finite, check_frame, vector
from hexapod.spatial import Placement, is_rotation, rotation_2d


def inertia_tensor(value) -> np.ndarray:
    """A 3 x 3 inertia tensor from a 3 x 3 matrix, 3 principal moments, or the 6 entries
    ``(xx, yy, zz, xy, xz, yz)`` of the tensor (as URDF's ``ixx ... iyz``)."""
    array = np.array(value, dtype=float)
    if array.shape == (3, 3):
        return array
    if array.shape == (3,):
        return np.diag(array)
    if array.shape == (6,):
        xx, yy, zz, xy, xz, yz = array
        return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    raise ValueError(
        f"inertia must be a 3 x 3 matrix, 3 principal moments or 6 entries, got {value!r}"
    )


def _markers(markers, dimension: int) -> dict[str, Placement]:
    out = {}
    for name, frame in dict(markers or {}).items():
        out[name] = frame if isinstance(frame, Placement) else Placement(vector(frame, dimension))
    return out


class Body(Element):
    """Common part of the three body kinds."""

    family = "body"
    dimension: int
    mass: float
    markers: dict[str, Placement]

    def problems(self) -> list[Problem]:
        out: list[Problem] = []
        if check_finite(self, "mass", self.mass, out) and not self.mass > 0:
            out.append(self.problem("mass", f"must be positive, got {self.mass}"))
        for key in ("position", "com", "velocity", "angular_velocity", "angle"):
            if hasattr(self, key):
                check_finite(self, key, getattr(self, key), out)
        if self.payload is not None and check_finite(self, "payload", self.payload, out) and \
                not 0.0 <= self.payload < self.mass:
            out.append(self.problem("payload", f"must be in [0, mass = {self.mass:g}), got "
                                    f"{self.payload}"))
        for name, frame in self.markers.items():
            check_frame(self, f"markers.{name}", frame, out)
            if frame.dimension != self.dimension:
                out.append(self.problem(f"markers.{name}",
                                        f"needs {self.dimension} coordinates"))
        return out

    @property
    def com_pose(self) -> Placement:
        """Centre-of-mass frame in the world at the initial guess."""
        return Placement(self.position + self.rotation @ self.com, self.rotation)

    @property
    def pose(self) -> Placement:
        """Reference frame in the world at the initial guess."""
        return Placement(self.position, self.rotation)

    def marker_in_com_frame(self, frame: Placement) -> Placement:
        """A frame given in the reference frame, re-expressed in the centre-of-mass frame."""
        return Placement(frame.position - self.com, frame.rotation)

    def _scaled_common(self, length: float):
        out = copy.copy(self)
        out.markers = {k: m.scaled(length) for k, m in self.markers.items()}
        out.position = self.position * length
        out.velocity = self.velocity * length
        if hasattr(self, "com"):
            out.com = self.com * length
        return out


@dataclass(eq=False)
class SpatialBody(Body):
    """A rigid body in space: 7 coordinates (centre of mass, Euler parameters), 6 velocities.

    Parameters
    ----------
    name : str
        The body's name, unique among the bodies.
    mass : float
        kg.
    inertia : array_like
        Inertia tensor about the centre of mass (kg L^2), in the axes of ``inertia_rotation``
        (default: the reference frame's axes): a symmetric positive-definite 3 x 3 matrix, its 3
        principal moments, or ``(xx, yy, zz, xy, xz, yz)``.
    com : array_like, shape (3,)
        Centre of mass in the reference frame (L).
    position, rotation : array_like, shape (3,) and (3, 3)
        Pose of the reference frame in the world at the initial guess (L; rotation body -> world).
    inertia_rotation : array_like, shape (3, 3), optional
        The axes ``inertia`` is given in, in the reference frame (default: its own axes).
    velocity, angular_velocity : array_like, shape (3,)
        Initial velocity of the reference frame's origin and angular velocity, both in world
        axes (like ``position``, the velocity belongs to the reference frame).
    markers : dict
        Named frames (:class:`~hexapod.spatial.Placement`) or points in the reference frame.
    mesh : str
        A mesh file (any format meshio reads) that ``hexapod export`` draws for the body, its
        points in the reference frame (L); a relative path is taken from the scene file's
        directory. Optional: without it the body is drawn as its box of inertia.
    payload : float, optional
        Of ``mass``, the load the body carries at its centre of mass (kg), as a robot builder's
        ``payload`` puts it on the trunk: what the design parameter ``payload`` names. None:
        the body carries none.
    source : str
        Where the body was written (file and entry), named in messages; empty for a body built
        in Python.

    L is the scene's length unit (:attr:`Scene.length_unit`).
    """

    name: str
    mass: float
    inertia: np.ndarray
    com: np.ndarray = None  # type: ignore[assignment]
    position: np.ndarray = None  # type: ignore[assignment]
    rotation: np.ndarray = None  # type: ignore[assignment]
    inertia_rotation: np.ndarray = None  # type: ignore[assignment]
    velocity: np.ndarray = None  # type: ignore[assignment]
    angular_velocity: np.ndarray = None  # type: ignore[assignment]
    markers: dict = field(default_factory=dict)
    mesh: str = ""
    payload: float | None = None
    source: str = ""
    dimension = 3
    kind = "spatial"

    def __post_init__(self):
        self.mass = float(self.mass)
        self.inertia = inertia_tensor(self.inertia)
        self.com = vector(self.com, 3, np.zeros(3))
        self.position = vector(self.position, 3, np.zeros(3))
        self.rotation = np.eye(3) if self.rotation is None else np.array(self.rotation, float)
        self.inertia_rotation = (np.eye(3) if self.inertia_rotation is None
                                 else np.array(self.inertia_rotation, float))
        self.velocity = vector(self.velocity, 3, np.zeros(3))
        self.angular_velocity = vector(self.angular_velocity, 3, np.zeros(3))
        self.markers = _markers(self.markers, 3)

    @property
    def body_inertia(self) -> np.ndarray:
        """Inertia tensor about the centre of mass in the body (reference-frame) axes."""
        R = self.inertia_rotation
        return R @ self.inertia @ R.T

    def problems(self):
        out = super().problems()
        for key in ("rotation", "inertia_rotation"):
            if check_finite(self, key, getattr(self, key), out) and not is_rotation(
                getattr(self, key)
            ):
                out.append(self.problem(key, "is not a proper rotation matrix"))
        if check_finite(self, "inertia", self.inertia, out):
            out.extend(self._inertia_problems())
        return out

    def _inertia_problems(self) -> list[Problem]:
        J = self.inertia
        scale = max(np.max(np.abs(J)), 1e-300)
        if np.max(np.abs(J - J.T)) > 1e-9 * scale:
            return [self.problem("inertia", "is not symmetric")]
        moments = np.linalg.eigvalsh(J)
        if moments[0] <= 0:
            return [self.problem("inertia", "is not positive definite (principal moments "
                                 f"{np.array2string(moments, precision=4)})")]
        if moments[0] + moments[1] < moments[2] * (1 - 1e-9):
            return [self.problem("inertia", "is not physical: the principal moments "
                                 f"{np.array2string(moments, precision=4)} violate the triangle "
                                 "inequality I1 + I2 >= I3")]
        return []

    def scaled(self, length):
        out = self._scaled_common(length)
        out.inertia = self.inertia * length**2
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        T = attachment.transform
        out.position = T.transform_point(self.position)
        out.rotation = T.rotation @ self.rotation
        out.velocity = T.rotation @ self.velocity
        out.angular_velocity = T.rotation @ self.angular_velocity
        return out


@dataclass(eq=False)
class PlanarBody(Body):
    """A rigid body in the plane: coordinates ``(x, y, angle)`` of its centre of mass.

    ``inertia`` is the moment of inertia about the centre of mass (kg L^2); ``position`` and
    ``angle`` give the reference frame in the world at the initial guess; ``com`` is in that frame;
    ``velocity`` is that of the reference frame's origin, ``angular_velocity`` in rad/s.

    Parameters
    ----------
    name : str
        The body's name, unique among the bodies.
    mass : float
        kg.
    inertia : float
        Moment of inertia about the centre of mass, kg L^2.
    com : array_like, shape (2,)
        Centre of mass in the reference frame (L).
    position : array_like, shape (2,)
        The reference frame's origin in the world at the initial guess (L).
    angle : float
        The reference frame's angle at the initial guess, rad.
    velocity : array_like, shape (2,)
        Initial velocity of the reference frame's origin (L/s).
    angular_velocity : float
        Initial angular velocity, rad/s.
    markers, mesh, payload, source :
        As for a :class:`SpatialBody`, in the plane.
    """

    name: str
    mass: float
    inertia: float
    com: np.ndarray = None  # type: ignore[assignment]
    position: np.ndarray = None  # type: ignore[assignment]
    angle: float = 0.0
    velocity: np.ndarray = None  # type: ignore[assignment]
    angular_velocity: float = 0.0
    markers: dict = field(default_factory=dict)
    mesh: str = ""
    payload: float | None = None
    source: str = ""
    dimension = 2
    kind = "planar"

    def __post_init__(self):
        self.mass = float(self.mass)
        self.inertia = float(self.inertia)
        self.angle = float(self.angle)
        self.angular_velocity = float(self.angular_velocity)
        self.com = vector(self.com, 2, np.zeros(2))
        self.position = vector(self.position, 2, np.zeros(2))
        self.velocity = vector(self.velocity, 2, np.zeros(2))
        self.markers = _markers(self.markers, 2)

    @property
    def rotation(self) -> np.ndarray:
        return rotation_2d(self.angle)

    @property
    def body_inertia(self) -> float:
        return self.inertia

    def problems(self):
        out = super().problems()
        if check_finite(self, "inertia", self.inertia, out) and not self.inertia > 0:
            out.append(self.problem("inertia", f"must be positive, got {self.inertia}"))
        return out

    def scaled(self, length):
        out = self._scaled_common(length)
        out.inertia = self.inertia * length**2
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        T = attachment.transform
        out.position = T.transform_point(self.position)
        out.angle = self.angle + T.angle
        out.velocity = T.rotation @ self.velocity
        return out


@dataclass(eq=False)
class Particle(Body):
    """A point mass: its position only (3 coordinates in space, 2 in the plane).

    The dimension follows ``position`` (2 or 3 numbers), which is therefore required. A particle
    has no orientation: markers on it are points that translate with it.

    Parameters
    ----------
    name : str
        The particle's name, unique among the bodies.
    mass : float
        kg.
    position : array_like, shape (3,) or (2,)
        Its position in the world at the initial guess (L).
    velocity : array_like, shape (3,) or (2,), optional
        Its initial velocity (L/s; default zero).
    markers : dict
        Named points, relative to the particle (L).
    mesh, payload, source :
        As for a :class:`SpatialBody`.
    """

    name: str
    mass: float
    position: np.ndarray
    velocity: np.ndarray = None  # type: ignore[assignment]
    markers: dict = field(default_factory=dict)
    mesh: str = ""
    payload: float | None = None
    source: str = ""
    kind = "particle"

    def __post_init__(self):
        self.mass = float(self.mass)
        self.position = vector(self.position, (2, 3))
        self.velocity = vector(self.velocity, self.position.size, np.zeros(self.position.size))
        self.markers = _markers(self.markers, self.position.size)

    @property
    def dimension(self) -> int:  # type: ignore[override]
        return self.position.size

    @property
    def com(self) -> np.ndarray:
        return np.zeros(self.dimension)

    @property
    def rotation(self) -> np.ndarray:
        return np.eye(self.dimension)

    @property
    def com_pose(self) -> Placement:
        return Placement(self.position)

    @property
    def pose(self) -> Placement:
        return Placement(self.position)

    def problems(self):
        out = super().problems()
        for name, frame in self.markers.items():
            if not np.allclose(frame.rotation, np.eye(self.dimension)):
                out.append(self.problem(f"markers.{name}",
                                        "a particle has no orientation: give a point only"))
        return out

    def scaled(self, length):
        out = copy.copy(self)
        out.markers = {k: m.scaled(length) for k, m in self.markers.items()}
        out.position = self.position * length
        out.velocity = self.velocity * length
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        T = attachment.transform
        out.position = T.transform_point(self.position)
        out.velocity = T.rotation @ self.velocity
        return out
