"""The joint-coordinate forms ``W(q) q_dd = P + V(q, q_d)`` of open chains of Vukobratović and
Potkonjak (1979) (layer 3): :class:`ChainModel` gives the recursive model of a tree of revolute
and prismatic joints taken from a :class:`~hexapod.model.Model`; :func:`form` builds ``W`` and
``V`` by the method of basic theorems, Lagrange's equations or Gibbs-Appell's, and
:func:`count_operations` counts their arithmetic."""

from hexapod.minimal.chain import ChainLink, ChainModel, ChainState
from hexapod.minimal.forming import METHODS, Layout, OpCount, count_operations, form, layout

__all__ = ["METHODS", "ChainLink", "ChainModel", "ChainState", "Layout", "OpCount",
           "count_operations", "form", "layout"]
