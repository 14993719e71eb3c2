"""The integrators: every method keeps the contract of :class:`Integrator` (see
:mod:`hexapod.simulation.registry` for the registry and the table of methods)."""

from hexapod.simulation.integrators.base import Counters, Integrator
from hexapod.simulation.integrators.embedded import (
    DormandPrince5,
    DormandPrince853,
    EmbeddedRungeKutta,
)
from hexapod.simulation.integrators.event_driven import EventDriven
from hexapod.simulation.integrators.explicit import RungeKutta4Baumgarte
from hexapod.simulation.integrators.generalized_alpha import LieGroupGeneralizedAlpha
from hexapod.simulation.integrators.moreau_jean import MoreauJean
from hexapod.simulation.integrators.radau import RadauIIA5GGL
from hexapod.simulation.integrators.rattle import Rattle
from hexapod.simulation.integrators.sundials import IdasBDF

__all__ = ["Counters", "DormandPrince5", "DormandPrince853", "EmbeddedRungeKutta", "EventDriven",
           "IdasBDF", "Integrator", "LieGroupGeneralizedAlpha", "MoreauJean", "RadauIIA5GGL",
           "Rattle",
           "RungeKutta4Baumgarte"]
