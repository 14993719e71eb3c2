"""Scalar functions of time for drivers and loads: value, first and second derivative.

The model's CasADi functions never see ``t``: they take the values and derivatives of every law as
inputs (see :mod:`hexapod.model.assemble`), so a law can be anything that returns ``f, f', f''`` for
an array of times. Drivers need laws that are at least C2 (a prescribed motion enters through its
second derivative).
"""

from hexapod.scene.laws.base import Constant, Law, LawOnJoint, Scaled, as_law, cycle_breaks
from hexapod.scene.laws.closed_form import Harmonic, Polynomial
from hexapod.scene.laws.expression import Expression
from hexapod.scene.laws.gait import Gait
from hexapod.scene.laws.guided import Guided
from hexapod.scene.laws.registry import LAW_TYPES, law_types
from hexapod.scene.laws.tabulated import Hermite, Spline

__all__ = ["LAW_TYPES", "Constant", "Expression", "Gait", "Guided", "Harmonic", "Hermite", "Law",
           "LawOnJoint", "Polynomial", "Scaled", "Spline", "as_law", "cycle_breaks", "law_types"]
