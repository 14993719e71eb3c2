"""The registry of integrators: every method keeps the contract of :class:`Integrator`.

==========================  =====  =====  =============================================
name                        order  index  stabilisation
==========================  =====  =====  =============================================
``rk4-baumgarte``           4      1      Baumgarte, Euler parameters renormalised
``dopri5-projection``       5      1      projection onto phi = 0 and Phi_v v = nu
``dop853-projection``       8      1      projection onto phi = 0 and Phi_v v = nu
``generalized-alpha``       2      3      position constraints solved (Newton)
``rattle``                  2      3      position constraints solved (Newton), symplectic
``radau5-ggl``              5      2      GGL: phi = 0 and Phi_v v = nu, B Phi_v^T mu
``idas-bdf``                1-5    1      Baumgarte terms in the DAE; projection and restart
                                          when the drift passes a tolerance
==========================  =====  =====  =============================================

Tests and studies iterate over :data:`INTEGRATORS`; :func:`get_integrator` accepts a name or a
class (a user's own subclass of :class:`Integrator`).
"""

from __future__ import annotations

from hexapod.integrators.base import Counters, Integrator
from hexapod.integrators.embedded import DormandPrince5, DormandPrince853, EmbeddedRungeKutta
from hexapod.integrators.explicit import RungeKutta4Baumgarte
from hexapod.integrators.generalized_alpha import LieGroupGeneralizedAlpha
from hexapod.integrators.radau import RadauIIA5GGL
from hexapod.integrators.rattle import Rattle
from hexapod.integrators.sundials import IdasBDF

#: Integrators by name, in the order studies list them.
INTEGRATORS: dict[str, type[Integrator]] = {}

#: The method used when none is named: adaptive, constraints held to round-off.
DEFAULT_METHOD = "dopri5-projection"


def register(cls: type[Integrator]) -> type[Integrator]:
    """Add an integrator class to the registry (usable as a decorator)."""
    if not (isinstance(cls, type) and issubclass(cls, Integrator)) or not cls.name:
        raise TypeError(f"{cls!r} is not a named subclass of Integrator")
    INTEGRATORS[cls.name] = cls
    return cls


def get_integrator(method: str | type[Integrator]) -> type[Integrator]:
    """The integrator class for a registered name, or ``method`` itself when it is a subclass of
    :class:`Integrator`."""
    if isinstance(method, type) and issubclass(method, Integrator):
        return method
    if method not in INTEGRATORS:
        raise ValueError(f"unknown integrator {method!r}: choose one of "
                         + ", ".join(INTEGRATORS))
    return INTEGRATORS[method]


for _cls in (RungeKutta4Baumgarte, DormandPrince5, DormandPrince853, LieGroupGeneralizedAlpha,
             Rattle, RadauIIA5GGL, IdasBDF):
    register(_cls)

__all__ = ["DEFAULT_METHOD", "INTEGRATORS", "Counters", "DormandPrince5", "DormandPrince853",
           "EmbeddedRungeKutta", "IdasBDF", "Integrator", "LieGroupGeneralizedAlpha",
           "RadauIIA5GGL", "Rattle", "RungeKutta4Baumgarte", "get_integrator", "register"]
