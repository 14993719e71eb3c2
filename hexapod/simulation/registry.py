"""The integrator registry; the defaults of a simulation, written once in
:mod:`hexapod.simulation.methods` (with the summaries the command line shows), are re-exported.

==========================  =====  =====  ========  ========================================
name                        order  index  step      stabilisation
==========================  =====  =====  ========  ========================================
``rk4-baumgarte``           4      1      fixed     Baumgarte, Euler parameters renormalised
``dopri5-projection``       5      1      adaptive  projection onto phi = 0 and Phi_v v = nu
``dop853-projection``       8      1      adaptive  projection onto phi = 0 and Phi_v v = nu
``generalized-alpha``       2      2      fixed     position and velocity constraints solved
                                                    (Newton, GGL)
``rattle``                  2      3      fixed     position constraints solved (Newton),
                                                    symplectic
``radau5-ggl``              5      2      adaptive  GGL: phi = 0 and Phi_v v = nu, B Phi_v^T mu
``idas-bdf``                5      1      adaptive  Baumgarte terms in the DAE; projection and
                                                    restart when the drift passes a tolerance
==========================  =====  =====  ========  ========================================

The order, index and step control are :data:`hexapod.simulation.methods.METHODS`' (which the
classes read; ``tests/test_registry.py`` holds this table to it); ``idas-bdf`` varies its order
from 1 to 5.

Tests and studies iterate over :data:`INTEGRATORS` (name -> class, in the order studies list
them); :func:`get_integrator` accepts a name, a short name (:data:`ALIASES`: ``rk4``,
``dopri5``, ``dop853``, ``radau``, ``idas``, ``gen-alpha``) or a class (a user's own subclass of
:class:`~hexapod.simulation.integrators.base.Integrator`), and :func:`register` adds one.
"""

from __future__ import annotations

from hexapod.simulation.integrators import (
    DormandPrince5,
    DormandPrince853,
    EventDriven,
    IdasBDF,
    Integrator,
    LieGroupGeneralizedAlpha,
    MoreauJean,
    RadauIIA5GGL,
    Rattle,
    RungeKutta4Baumgarte,
)
from hexapod.simulation.methods import (
    ALIASES,
    DEFAULT_ATOL,
    DEFAULT_METHOD,
    DEFAULT_RTOL,
    resolve_method,
)

__all__ = ["ALIASES", "CONTACT_SCHEMES", "DEFAULT_ATOL", "DEFAULT_METHOD", "DEFAULT_RTOL",
           "INTEGRATORS", "default_method", "get_integrator", "register"]

#: Integrators by name, in the order studies list them.
INTEGRATORS: dict[str, type[Integrator]] = {}
#: The integrators of scenes with unilateral contacts, by name (the smooth methods of
#: :data:`INTEGRATORS` refuse such scenes).
CONTACT_SCHEMES: dict[str, type[Integrator]] = {MoreauJean.name: MoreauJean,
                                                 EventDriven.name: EventDriven}


def register(cls: type[Integrator]) -> type[Integrator]:
    """Add an integrator class to :data:`INTEGRATORS` under ``cls.name`` (usable as a decorator).

    Parameters
    ----------
    cls : type
        A subclass of :class:`~hexapod.simulation.integrators.Integrator` with a ``name``.

    Returns
    -------
    type
        ``cls``.

    Raises
    ------
    TypeError
        ``cls`` is not a subclass of ``Integrator`` with a ``name``.
    """
    if not (isinstance(cls, type) and issubclass(cls, Integrator)) or not cls.name:
        raise TypeError(f"{cls!r} is not a named subclass of Integrator")
    INTEGRATORS[cls.name] = cls
    return cls


def default_method(model) -> str:
    """The method a simulation of ``model`` uses when none is named: the contact scheme for a
    scene with unilateral contacts, else :data:`DEFAULT_METHOD`.

    Parameters
    ----------
    model : Model

    Returns
    -------
    str
        A registered name.
    """
    if any(f.contact is not None for f in model.forces):
        return next(iter(CONTACT_SCHEMES))
    return DEFAULT_METHOD


def get_integrator(method: str | type[Integrator]) -> type[Integrator]:
    """The integrator class for a registered name or its short name (:data:`ALIASES`:
    ``rk4``, ``dopri5``, ``dop853``, ``radau``, ``idas``, ``gen-alpha``), or ``method`` itself
    when it is a subclass of ``Integrator``.

    Parameters
    ----------
    method : str or type
        A name, a short name, or an ``Integrator`` subclass.

    Returns
    -------
    type
        The ``Integrator`` subclass.

    Raises
    ------
    ValueError
        ``method`` is neither a registered name, a short name nor an ``Integrator`` subclass.
    """
    if isinstance(method, type) and issubclass(method, Integrator):
        return method
    name = resolve_method(method) if isinstance(method, str) else method
    if name in CONTACT_SCHEMES:
        return CONTACT_SCHEMES[name]
    if name not in INTEGRATORS:
        raise ValueError(f"unknown integrator {method!r}: choose one of "
                         + ", ".join([*INTEGRATORS, *CONTACT_SCHEMES]) + " (or a short name: "
                         + ", ".join(ALIASES) + ")")
    return INTEGRATORS[name]


for _cls in (RungeKutta4Baumgarte, DormandPrince5, DormandPrince853, LieGroupGeneralizedAlpha,
             Rattle, RadauIIA5GGL, IdasBDF):
    register(_cls)
