"""Joints (kinematic pairs): one class per type, each answering every question the scene's
checks, the files, the assembly and the algorithms ask about it (:mod:`.base`), registered in
:data:`JOINT_TYPES` under the ``type`` scene files use. Adding a type is one module here (its
class, decorated with :func:`register`) and its import below (docs/extending.md); a type of a
user's own is registered from the user's module the same way."""

# the built-in types register in the order of these imports, which messages list them in
# isort: off
from hexapod.scene.joints.base import JOINT_TYPES, Joint, kinds_that, register, unregister
from hexapod.scene.joints.geometry import JointGeometry
from hexapod.scene.joints.revolute import Revolute
from hexapod.scene.joints.prismatic import Prismatic
from hexapod.scene.joints.spherical import Spherical
from hexapod.scene.joints.fixed import Fixed
from hexapod.scene.joints.distance import Distance
from hexapod.scene.joints.universal import Universal
from hexapod.scene.joints.cylindrical import Cylindrical
from hexapod.scene.joints.planar import PlanarJoint
from hexapod.scene.joints.point_on_plane import PointOnPlane
from hexapod.scene.joints.contact import Contact
# isort: on

__all__ = ["JOINT_TYPES", "Contact", "Cylindrical", "Distance", "Fixed", "Joint", "JointGeometry",
           "PlanarJoint", "PointOnPlane", "Prismatic", "Revolute", "Spherical", "Universal",
           "kinds_that", "register", "unregister"]
