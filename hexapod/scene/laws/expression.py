"""A law written as an expression of ``t`` in a scene file, parsed safely
(:mod:`hexapod.scene.expression`)."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from hexapod.scene.laws.base import LARGEST_NUMBER, Law, _size_problem


@dataclass(frozen=True)
class Expression(Law):
    """``f(t)`` written as an expression of ``t``, e.g. ``asin(r*sin(w*t))``.

    The grammar (numbers, ``t``, ``pi``, ``e``, the law's constants, ``+ - * / ^``, functions
    and ``if_else``) is that of :mod:`hexapod.scene.expression`; the text is parsed by our own
    parser, never evaluated by Python. The derivatives are exact: CasADi differentiates the
    expression twice, and the three are compiled once per law into one function.

    Parameters
    ----------
    expression : str
        The expression.
    constants : mapping or sequence of (name, value) pairs
        Named numbers the expression uses; stored as pairs sorted by name.
    period : float, optional
        The time after which the law repeats, as the user asserts it (not checked): the
        duration of one cycle of a report or a simulation.

    Notes
    -----
    The expression is checked when the law is, not evaluated: a value outside a function's
    domain (``asin`` of more than 1, ``log`` of a negative number) gives NaN at the times it
    occurs, and a run that meets it fails as non-finite. A driver needs a law that is C2:
    ``abs``, ``min``, ``max`` and ``if_else`` give kinks and jumps unless the pieces meet with
    equal values and first and second derivatives.
    """

    expression: str
    constants: tuple[tuple[str, float], ...] = ()
    period: float | None = None
    _function: object = field(default=None, init=False, repr=False, compare=False)
    _problems: tuple[str, ...] | None = field(default=None, init=False, repr=False,
                                              compare=False)
    kind = "expression"

    def __post_init__(self):
        pairs = (self.constants.items() if isinstance(self.constants, Mapping)
                 else self.constants)
        object.__setattr__(self, "constants", tuple(sorted(
            ((name, float(value)) for name, value in pairs), key=lambda pair: str(pair[0]))))
        if self.period is not None:
            object.__setattr__(self, "period", float(self.period))

    def __getstate__(self):
        # a compiled CasADi function stays behind: scenes are pickled to worker processes
        return {**self.__dict__, "_function": None}

    def _compiled(self):
        """The CasADi function ``t -> (f, f', f'')``, built on first use."""
        if self._function is None:
            problems = self.problems()
            if problems:
                raise ValueError("expression law is invalid: " + "; ".join(problems))
            import casadi as ca

            from hexapod.scene.expression import parse, to_casadi

            constants = dict(self.constants)
            t = ca.SX.sym("t")
            f = to_casadi(parse(self.expression, constants), t, constants)
            fd = ca.jacobian(f, t)
            object.__setattr__(self, "_function",
                               ca.Function("law", [t], [f, fd, ca.jacobian(fd, t)]))
        return self._function

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        function = self._compiled()
        if t.ndim == 0:
            return tuple(np.array(float(x)) for x in function(float(t)))
        if t.size == 0:
            return np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)
        # all samples in one call of the function mapped over them
        out = function.map(t.size)(t.reshape(1, -1))
        return tuple(x.full().reshape(t.shape) for x in out)

    def symbolic(self, t):
        return tuple(self._compiled()(t))

    def cycle_time(self):
        return self.period

    def _scaled(self, factor):
        return Expression(f"{float(factor)!r}*({self.expression})", self.constants, self.period)

    def problems(self):
        if self._problems is None:
            object.__setattr__(self, "_problems", tuple(self._find_problems()))
        return list(self._problems)

    def _find_problems(self) -> list[str]:
        # the parser is loaded by the scenes that use it: a leg driven by a motion file starts
        # without it
        from hexapod.scene.expression import (
            MOST_CONSTANTS,
            ExpressionError,
            constant_problem,
            parse,
        )

        out = []
        if len(self.constants) > MOST_CONSTANTS:
            out.append(f"constants: {len(self.constants)} given, at most {MOST_CONSTANTS}")
            names = []
        else:
            names = [name for name, _ in self.constants if not constant_problem(name)]
            out += [f"constants: {constant_problem(name)}" for name, _ in self.constants
                    if constant_problem(name)]
            out += [f"constants: '{name}' is given twice"
                    for name, count in Counter(names).items() if count > 1]
            for name, value in self.constants:
                if not math.isfinite(value):
                    out.append(f"constants: {name!r} is not finite: {value}")
                elif _size_problem(value):
                    out.append(f"constants: {name!r} {_size_problem(value)}")
        if self.period is not None and not (math.isfinite(self.period) and self.period > 0):
            out.append(f"period must be positive and finite, got {self.period}")
        elif self.period is not None and _size_problem(self.period):
            out.append(f"period {_size_problem(self.period)}")
        if not isinstance(self.expression, str):
            out.append(f"expression must be a string, got {self.expression!r}")
        else:
            try:
                parse(self.expression, names, largest=LARGEST_NUMBER)
            except ExpressionError as error:
                out.append(f"expression: {error}")
        return out
