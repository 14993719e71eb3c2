"""The integrators by name (and short name), and the defaults of a simulation, written once and
importing nothing, so that the command line lists the methods in its help without loading CasADi
or SciPy.

:data:`METHODS` is where each class of :data:`hexapod.simulation.registry.INTEGRATORS` finds
what it is (order, index, adaptive, stabilisation): the classes read their entry,
``order, index, adaptive, stabilisation = METHODS[name]``, and the registry lists them in the
same order.
"""

from __future__ import annotations

from typing import NamedTuple

#: The method used when none is named: adaptive, constraints held to round-off.
DEFAULT_METHOD = "dop853-projection"
#: Default relative tolerance of the adaptive methods.
DEFAULT_RTOL = 1e-6
#: Default absolute tolerance of the adaptive methods (SI units of each coordinate).
DEFAULT_ATOL = 1e-8

#: The kinds of coordinates an absolute tolerance per kind names (``atol`` as a mapping), each
#: with the units of its coordinates. Euler parameters (unit 1) count as angles: a change ``d``
#: of them turns the body by about ``2 d`` rad.
ATOL_KINDS: dict[str, tuple[str, ...]] = {
    "position": ("m",), "angle": ("rad", "1"), "velocity": ("m/s",),
    "angular_velocity": ("rad/s",)}
#: The characteristic time (s) of a scene without gravity, which divides the default tolerances
#: per kind of positions and angles into those of their rates (with gravity: ``sqrt(L / g)``).
CHARACTERISTIC_TIME = 1.0


class Method(NamedTuple):
    """What an integrator is: the order of its solution, the index of the equations it
    integrates, whether its step is adaptive, and how it keeps the constraints."""

    order: int
    index: int
    adaptive: bool
    stabilisation: str

    def summary(self) -> str:
        """One line: order, index, step control and stabilisation."""
        step = "adaptive" if self.adaptive else "fixed step"
        return f"order {self.order}, index {self.index}, {step}, {self.stabilisation}"


_PROJECTION = "projection of positions and velocities after each step"
_NEWTON = "none needed: position constraints solved every step (Newton)"

#: The registered integrators by name, in the order studies list them.
METHODS: dict[str, Method] = {
    "rk4-baumgarte": Method(4, 1, False,
                            "Baumgarte (alpha = beta), Euler parameters renormalised"),
    "dopri5-projection": Method(5, 1, True, _PROJECTION),
    "dop853-projection": Method(8, 1, True, _PROJECTION),
    "generalized-alpha": Method(2, 2, False, "none needed: position and velocity constraints "
                                "solved every step (Newton, GGL)"),
    "rattle": Method(2, 3, False, _NEWTON + ", velocities projected onto Phi_v v = nu by the "
                     "second half kick"),
    "radau5-ggl": Method(5, 2, True, "GGL: position and velocity constraints, B Phi_v^T mu"),
    "idas-bdf": Method(5, 1, True, "Baumgarte terms in the DAE (alpha = beta, 10/s by default); "
                       "projection onto phi = 0 and Phi_v v = nu and a restart when the drift "
                       "passes drift_tol"),
}

#: The contact schemes: integrators of scenes with unilateral contacts (``ground-contact``
#: force elements), which the methods above do not integrate.
CONTACT_METHODS: dict[str, Method] = {
    "moreau-jean": Method(1, 2, False, "velocity-level bilateral rows and Signorini's "
                          "condition with Coulomb friction and impacts; positions projected "
                          "onto phi = 0 and out of the ground"),
    "event-driven": Method(8, 2, True, "DOP853 between contact events with the closed "
                           "contacts held at acceleration level; positions and velocities "
                           "projected onto the bilateral rows and the closed contacts"),
}

#: Every method by name: the smooth ones, then the contact schemes.
ALL_METHODS: dict[str, Method] = {**METHODS, **CONTACT_METHODS}

#: Short names accepted wherever a method is named (``--method``, ``simulate(method=...)``,
#: ``get_integrator``); a run records the registered name. ``rattle`` is its own short name.
ALIASES: dict[str, str] = {
    "rk4": "rk4-baumgarte",
    "dopri5": "dopri5-projection",
    "dop853": "dop853-projection",
    "radau": "radau5-ggl",
    "idas": "idas-bdf",
    "gen-alpha": "generalized-alpha",
}


def resolve_method(name: str) -> str:
    """The registered name of a method named by its name or its short name (an unknown name is
    returned as it is, for the caller to refuse)."""
    return ALIASES.get(name, name)


def aliases_of(name: str) -> list[str]:
    """The short names of a registered method."""
    return [alias for alias, full in ALIASES.items() if full == name]
