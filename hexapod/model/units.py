"""The units of a model's coordinates, velocities and constraint rows, by the names of
:attr:`Model.coordinate_names`, :attr:`Model.velocity_names` and the rows' kinds: what the
results' columns say and what the tolerances per kind of the integrators read."""

from __future__ import annotations

#: The unit and meaning of each component of a body's coordinates and velocities (the names of
#: :attr:`Model.coordinate_names` and :attr:`Model.velocity_names` after the body's name).
COORDINATE_UNITS = {
    **{c: ("m", f"position of the centre of mass, world {c}") for c in "xyz"},
    **{f"e{k}": ("1", f"Euler parameter e{k} of the body's rotation (e0 the scalar part)")
       for k in range(4)},
    "angle": ("rad", "angle of the planar body"),
}
VELOCITY_UNITS = {
    **{f"v{c}": ("m/s", f"velocity of the centre of mass, world {c}") for c in "xyz"},
    **{f"w{c}_body": ("rad/s", f"angular velocity, body {c} axis") for c in "xyz"},
    "w": ("rad/s", "angular velocity of the planar body"),
}
ACCELERATION_UNITS = {"m/s": "m/s^2", "rad/s": "rad/s^2"}
ROW_UNITS = {"length": ("N", "Lagrange multiplier of the constraint row (a force)"),
             "angle": ("N m", "Lagrange multiplier of the constraint row (a moment)")}


#: The suffix of a foot contact's name that its leg's name leaves out.
CONTACT_SUFFIX = "/ground"


def leg_name(contact: str) -> str:
    """The leg a contact belongs to: its name without the ``/ground`` suffix (the ground-force
    columns ``GRx:<leg>`` of the inverse dynamics and of a simulation with contacts)."""
    return contact[:-len(CONTACT_SUFFIX)] if contact.endswith(CONTACT_SUFFIX) else contact


def component(name: str) -> str:
    """``x`` of ``trunk.x`` (a body's name may hold dots; the component follows the last)."""
    return name.rpartition(".")[2]
