"""Expressions of time for expression laws: a tokenizer, a parser and their CasADi translation.

The grammar is our own and small; user text is never handed to Python or CasADi to evaluate.
From the loosest binding to the tightest:

=====================  =====================================================================
``a || b``             either condition holds
``a && b``             both conditions hold
``! a``                the condition does not hold
``a < b`` ...          comparisons ``< <= > >= == !=`` (not chained)
``a + b``, ``a - b``   left-associative
``a * b``, ``a / b``   left-associative
``-a``, ``+a``         signs
``a ^ b``, ``a ** b``  power, right-associative: ``2^3^2 = 2^9``, ``-t^2 = -(t^2)``
=====================  =====================================================================

Operands are decimal numbers (``1``, ``2.5``, ``.5``, ``1e-3``), the time ``t``, the constants
``pi`` and ``e``, the names of the law's own constants, calls of :data:`FUNCTIONS` and
parenthesised expressions. Conditions (comparisons and what ``&&``, ``||`` and ``!`` make of
them) are only allowed as the first argument of ``if_else(condition, a, b)``.

Each error is an :class:`ExpressionError` naming the character (1-based) where it was found.
Hostile text is refused before it costs anything: at most :data:`LONGEST` characters, nesting at
most :data:`DEEPEST` levels (checked as the parser descends, so never a ``RecursionError``), and
the tree is translated without recursion (a sum of thousands of terms is a deep tree).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

#: The longest expression, in characters.
LONGEST = 10_000
#: The deepest nesting: each parenthesis, function call, sign, ``!`` and exponent counts a level.
DEEPEST = 100
#: The most constants a law may name.
MOST_CONSTANTS = 1000

#: The functions and their numbers of arguments. Only smooth functions (and ``abs``, ``min``,
#: ``max``, ``if_else``, whose kinks are the user's choice): no floor, ceil or sign.
FUNCTIONS: dict[str, int] = {
    "sin": 1, "cos": 1, "tan": 1, "asin": 1, "acos": 1, "atan": 1, "atan2": 2,
    "sinh": 1, "cosh": 1, "tanh": 1, "exp": 1, "log": 1, "sqrt": 1, "abs": 1,
    "min": 2, "max": 2, "if_else": 3,
}
#: The names every expression knows: the time and the two constants.
RESERVED = ("t", "pi", "e")

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_NUMBER = re.compile(r"(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_TAIL = re.compile(r"[A-Za-z0-9_.]*")  # what may not follow a number directly
_SPACE = re.compile(r"[ \t\r\n]+")
_OPERATORS = ("**", "<=", ">=", "==", "!=", "&&", "||", "+", "-", "*", "/", "^", "(", ")", ",",
              "<", ">", "!")
#: Binary operators: (binding level, right-associative).
_BINARY = {"||": (1, False), "&&": (2, False),
           "<": (4, False), "<=": (4, False), ">": (4, False), ">=": (4, False),
           "==": (4, False), "!=": (4, False),
           "+": (5, False), "-": (5, False), "*": (6, False), "/": (6, False),
           "^": (8, True), "**": (8, True)}
_NOT_LEVEL, _COMPARISON_LEVEL, _SIGN_LEVEL = 3, 4, 7
_CONDITIONS = frozenset(("||", "&&", "<", "<=", ">", ">=", "==", "!=", "!"))
_HINTS = {"=": " (a comparison is written '==')", "&": " (and is written '&&')",
          "|": " (or is written '||')"}


class ExpressionError(ValueError):
    """What is wrong with an expression and where: ``at character 9: unknown function ...``.

    Attributes
    ----------
    position : int
        The character (1-based) where the problem was found; one past the end for a missing end.
    reason : str
        What is wrong.
    """

    def __init__(self, position: int, reason: str):
        super().__init__(f"at character {position}: {reason}")
        self.position = position
        self.reason = reason


# ------------------------------------------------------------------ the tree

@dataclass(frozen=True)
class Number:
    value: float
    position: int


@dataclass(frozen=True)
class Name:
    """``t``, ``pi``, ``e`` or a constant of the law."""

    name: str
    position: int


@dataclass(frozen=True)
class Unary:
    """A sign (``-``, ``+``) or a negated condition (``!``)."""

    operator: str
    operand: Node
    position: int


@dataclass(frozen=True)
class Binary:
    """An arithmetic operator, a comparison or a logical operator; ``position`` is the
    operator's."""

    operator: str
    left: Node
    right: Node
    position: int


@dataclass(frozen=True)
class Call:
    function: str
    arguments: tuple[Node, ...]
    position: int


Node = Number | Name | Unary | Binary | Call


def is_condition(node: Node) -> bool:
    """Whether ``node`` is a condition (true or false) rather than a number."""
    return isinstance(node, (Unary, Binary)) and node.operator in _CONDITIONS


def _children(node: Node) -> tuple[Node, ...]:
    if isinstance(node, Unary):
        return (node.operand,)
    if isinstance(node, Binary):
        return (node.left, node.right)
    if isinstance(node, Call):
        return node.arguments
    return ()


# ------------------------------------------------------------------ tokens

@dataclass(frozen=True)
class _Token:
    kind: str  # "number", "name", "operator" or "end"
    text: str
    position: int  # 1-based
    value: float = 0.0

    def shown(self) -> str:
        return "the end of the expression" if self.kind == "end" else f"'{self.text}'"


def _tokens(text: str, largest: float) -> list[_Token]:
    out = []
    i, n = 0, len(text)
    while i < n:
        space = _SPACE.match(text, i)
        if space:
            i = space.end()
            continue
        number = _NUMBER.match(text, i)
        if number:
            end = number.end()
            tail = _TAIL.match(text, end).group()
            if tail:
                hint = "" if tail[0] in "eE." else " (a product is written 2*t, not 2t)"
                raise ExpressionError(i + 1, f"malformed number '{text[i:end]}{tail}'{hint}")
            value = float(number.group())
            if not math.isfinite(value):
                raise ExpressionError(i + 1, f"number {number.group()} is not finite (too large "
                                      "for a floating-point number)")
            if value > largest:
                limit = f"{largest:g}".replace("e+", "e")
                raise ExpressionError(i + 1, f"number {number.group()} is beyond the {limit} "
                                      "a law may hold")
            out.append(_Token("number", number.group(), i + 1, value))
            i = end
            continue
        name = _NAME.match(text, i)
        if name:
            out.append(_Token("name", name.group(), i + 1))
            i = name.end()
            continue
        operator = next((op for op in _OPERATORS if text.startswith(op, i)), None)
        if operator is None:
            c = text[i]
            shown = repr(c) if c.isprintable() else f"{c!r} (U+{ord(c):04X})"
            raise ExpressionError(i + 1, f"unexpected {shown}{_HINTS.get(c, '')}")
        out.append(_Token("operator", operator, i + 1))
        i += len(operator)
    out.append(_Token("end", "", n + 1))
    return out


# ------------------------------------------------------------------ the parser

class _Parser:
    """Precedence climbing over the token list; ``depth`` counts the levels of nesting."""

    def __init__(self, tokens: list[_Token], constants: frozenset[str]):
        self.tokens = tokens
        self.i = 0
        self.constants = constants
        self.depth = 0

    def peek(self) -> _Token:
        return self.tokens[self.i]

    def next(self) -> _Token:
        token = self.tokens[self.i]
        self.i += 1
        return token

    def enter(self, token: _Token) -> None:
        self.depth += 1
        if self.depth > DEEPEST:
            raise ExpressionError(token.position, f"nested more than {DEEPEST} levels deep "
                                  "(parentheses, function calls, signs and powers each count)")

    def whole(self) -> Node:
        tree = self.expression(0)
        token = self.peek()
        if token.kind != "end":
            if token.text == ")":
                raise ExpressionError(token.position, "unbalanced ')': no '(' to close")
            raise ExpressionError(token.position, "expected an operator or the end of the "
                                  f"expression, found {token.shown()}")
        return _value(tree)

    def expression(self, lowest: int) -> Node:
        left = self.prefix()
        while True:
            token = self.peek()
            if token.kind != "operator" or token.text not in _BINARY:
                return left
            level, right_associative = _BINARY[token.text]
            if level < lowest:
                return left
            self.next()
            if right_associative:
                self.enter(token)
                right = self.expression(_SIGN_LEVEL)  # an exponent may have a sign: 2^-t
                self.depth -= 1
            else:
                right = self.expression(level + 1)
            left = self.binary(token, left, right)

    def binary(self, token: _Token, left: Node, right: Node) -> Node:
        op = token.text
        if op in ("&&", "||"):
            for side in (left, right):
                if not is_condition(side):
                    raise ExpressionError(token.position, f"'{op}' joins conditions (such as "
                                          "t < 1), not numbers")
        else:
            if (_BINARY[op][0] == _COMPARISON_LEVEL and is_condition(left)
                    and _BINARY.get(left.operator, (0,))[0] == _COMPARISON_LEVEL):
                raise ExpressionError(token.position, "comparisons cannot be chained: write "
                                      "a < t && t < b")
            for side in (left, right):
                _value(side)
        return Binary(op, left, right, token.position)

    def prefix(self) -> Node:
        token = self.peek()
        if token.kind == "operator" and token.text in ("-", "+", "!"):
            self.next()
            self.enter(token)
            operand = self.expression(_NOT_LEVEL if token.text == "!" else _SIGN_LEVEL)
            self.depth -= 1
            if token.text == "!":
                if not is_condition(operand):
                    raise ExpressionError(token.position, "'!' negates a condition (such as "
                                          "t < 1), not a number")
            else:
                _value(operand)
            return Unary(token.text, operand, token.position)
        return self.primary()

    def primary(self) -> Node:
        token = self.next()
        if token.kind == "number":
            return Number(token.value, token.position)
        if token.kind == "name":
            if self.peek().text == "(":
                return self.call(token)
            if token.text in FUNCTIONS:
                raise ExpressionError(token.position, f"function '{token.text}' needs its "
                                      f"arguments in parentheses: {token.text}(...)")
            if token.text not in RESERVED and token.text not in self.constants:
                raise ExpressionError(token.position, f"unknown name '{token.text}' (not t, pi, "
                                      f"e or a constant{_listed(self.constants)})")
            return Name(token.text, token.position)
        if token.text == "(":
            self.enter(token)
            inner = self.expression(0)
            self.close(token, "')'")
            self.depth -= 1
            return inner
        if token.kind == "end":
            if self.i == 1:
                raise ExpressionError(1, "the expression is empty")
            raise ExpressionError(token.position, "expected a number, a name or '(', but the "
                                  "expression ends")
        if token.text == ")":
            raise ExpressionError(token.position, "unbalanced ')': no '(' to close"
                                  if not self._open() else "expected a number, a name or '(' "
                                  "before ')'")
        raise ExpressionError(token.position, f"expected a number, a name or '(', found "
                              f"{token.shown()}")

    def _open(self) -> bool:
        """Whether a '(' is open before the current token (a ')' then closes too early)."""
        balance = 0
        for token in self.tokens[:self.i - 1]:
            balance += (token.text == "(") - (token.text == ")")
        return balance > 0

    def call(self, name: _Token) -> Node:
        function = name.text
        if function not in FUNCTIONS:
            if function in self.constants or function in RESERVED:
                raise ExpressionError(name.position, f"'{function}' is not a function (to "
                                      f"multiply, write {function}*(...))")
            raise ExpressionError(name.position, f"unknown function '{function}' (known: "
                                  f"{', '.join(FUNCTIONS)})")
        opening = self.next()
        self.enter(opening)
        arguments = []
        if self.peek().text != ")":
            arguments.append(self.expression(0))
            while self.peek().text == ",":
                self.next()
                arguments.append(self.expression(0))
        self.close(opening, "',' or ')'" if arguments else "')'")
        self.depth -= 1
        expected = FUNCTIONS[function]
        if len(arguments) != expected:
            raise ExpressionError(name.position, f"'{function}' takes {_count(expected)}, got "
                                  f"{len(arguments)}")
        for k, argument in enumerate(arguments):
            if function == "if_else" and k == 0:
                if not is_condition(argument):
                    raise ExpressionError(name.position, "the first argument of if_else must "
                                          "be a condition, such as t < 1")
            else:
                _value(argument)
        return Call(function, tuple(arguments), name.position)

    def close(self, opening: _Token, expected: str) -> None:
        token = self.next()
        if token.text != ")":
            raise ExpressionError(token.position, f"expected {expected} to close the '(' at "
                                  f"character {opening.position}, found {token.shown()}")


def _count(n: int) -> str:
    return f"{n} argument" if n == 1 else f"{n} arguments"


def _listed(names: frozenset[str]) -> str:
    if not names:
        return ""
    shown = sorted(names)
    more = f", ... ({len(shown)} in all)" if len(shown) > 10 else ""
    return ": " + ", ".join(shown[:10]) + more


def _value(node: Node) -> Node:
    """``node``, which must be a number: a condition is refused outside if_else."""
    if is_condition(node):
        what = ("comparison" if _BINARY.get(node.operator, (0,))[0] == _COMPARISON_LEVEL
                else "condition")
        raise ExpressionError(node.position, f"{what} '{node.operator}' outside if_else: a "
                              "condition is only allowed as the first argument of "
                              "if_else(condition, a, b)")
    return node


def constant_problem(name) -> str:
    """Why ``name`` cannot name a constant ('' when it can)."""
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        return (f"constant name {name!r} is not a name (letters, digits and '_', not starting "
                "with a digit)")
    if name in RESERVED:
        return f"constant name '{name}' is taken by {'the time' if name == 't' else 'a constant'}"
    if name in FUNCTIONS:
        return f"constant name '{name}' is taken by a function"
    return ""


def parse(text: str, constants: Iterable[str] = (), largest: float = math.inf) -> Node:
    """The tree of ``text``, which may use the names ``constants``.

    Parameters
    ----------
    text : str
        The expression.
    constants : iterable of str
        The names of the law's constants (each valid: see :func:`constant_problem`).
    largest : float
        The largest number the text may hold.

    Raises
    ------
    ExpressionError
        The first problem found, with its character.
    """
    if len(text) > LONGEST:
        raise ExpressionError(LONGEST + 1, f"the expression is longer than {LONGEST:,} "
                              f"characters ({len(text):,})")
    return _Parser(_tokens(text, largest), frozenset(constants)).whole()


# ------------------------------------------------------------------ translation to CasADi

def _operations():
    import casadi as ca

    binary = {"+": lambda a, b: a + b, "-": lambda a, b: a - b, "*": lambda a, b: a * b,
              "/": lambda a, b: a / b, "^": ca.power, "**": ca.power,
              "<": ca.lt, "<=": ca.le, ">": ca.gt, ">=": ca.ge, "==": ca.eq, "!=": ca.ne,
              "&&": ca.logic_and, "||": ca.logic_or}
    unary = {"-": lambda a: -a, "+": lambda a: a, "!": ca.logic_not}
    functions = {"sin": ca.sin, "cos": ca.cos, "tan": ca.tan, "asin": ca.asin, "acos": ca.acos,
                 "atan": ca.atan, "atan2": ca.atan2, "sinh": ca.sinh, "cosh": ca.cosh,
                 "tanh": ca.tanh, "exp": ca.exp, "log": ca.log, "sqrt": ca.sqrt, "abs": ca.fabs,
                 "min": ca.fmin, "max": ca.fmax, "if_else": ca.if_else}
    return ca, binary, unary, functions


def to_casadi(tree: Node, t, constants: Mapping[str, float]):
    """The CasADi expression of ``tree`` in the symbol ``t`` (an ``SX``), the constants'
    values substituted. Walks the tree with a stack of its own: a long sum is a deep tree."""
    ca, binary, unary, functions = _operations()
    names = {"t": t, "pi": ca.SX(math.pi), "e": ca.SX(math.e),
             **{k: ca.SX(float(v)) for k, v in constants.items()}}
    results = []
    stack = [(tree, False)]
    while stack:
        node, ready = stack.pop()
        children = _children(node)
        if children and not ready:
            stack.append((node, True))
            stack.extend((child, False) for child in reversed(children))
            continue
        arguments = results[len(results) - len(children):]
        del results[len(results) - len(children):]
        if isinstance(node, Number):
            results.append(ca.SX(node.value))
        elif isinstance(node, Name):
            results.append(names[node.name])
        elif isinstance(node, Unary):
            results.append(unary[node.operator](*arguments))
        elif isinstance(node, Binary):
            results.append(binary[node.operator](*arguments))
        else:
            results.append(functions[node.function](*arguments))
    (expression,) = results
    return expression
