"""An SX Function evaluated on a block of samples at once: one NumPy operation per instruction.

CasADi's virtual machine runs an SX Function's instructions one sample after the other, some
3 to 5 ns an instruction. Over a block of ``b`` samples, each instruction can instead be one
NumPy operation on a row of ``b`` numbers: its cost is a call (about half a microsecond) plus a
vectorized loop. From some hundreds of samples on the whole block costs several times less
than the virtual machine (4 to 10 times for the tree-ordered inverse dynamics of a leg or a
hexapod at 1000 samples), within 1.5 to 2.5 times what optimized C code takes, with no
compiler. The operations and their order are the virtual machine's, so the results are the
same numbers (elementary functions such as ``sin`` may differ from the C library's in the last
bit).

The instructions are read once from the Function (``instruction_id`` and its siblings, about
3 us each through CasADi's Python bindings) into a :class:`Program`, which the cache on disk
keeps (:func:`cached_program`). A Function with an instruction NumPy has no
counterpart for (a call of another Function, for instance) has no program: :func:`program_of`
says so with None and the caller keeps the virtual machine.
"""

from __future__ import annotations

import io
import json
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import casadi as ca
import numpy as np

from hexapod._support import cache

#: Bytes of the work rows of one block (sets the block's size: the rows stay in the processor's
#: caches, and a large graph does not take gigabytes of memory).
WORK_BYTES = 32 * 2**20

#: The files of a program's cache entry.
CODE, CONSTANTS, LAYOUT = "code.npy", "constants.npy", "layout.json"

#: The instruction kinds of a program (the first column of :attr:`Program.code`).
_INPUT, _OUTPUT, _CONSTANT, _UNARY, _BINARY = range(5)


def _if_else_zero(condition, value, out):
    # CasADi's if_else_zero(c, x): x where c is nonzero, else 0, even where x is inf or nan
    np.copyto(out, np.where(condition != 0, value, 0.0))


_UNARY_OPS: dict[int, Callable] = {
    ca.OP_ASSIGN: np.copyto, ca.OP_NEG: np.negative, ca.OP_SQ: np.square,
    ca.OP_SQRT: np.sqrt, ca.OP_INV: np.reciprocal, ca.OP_FABS: np.fabs, ca.OP_SIGN: np.sign,
    ca.OP_EXP: np.exp, ca.OP_LOG: np.log, ca.OP_SIN: np.sin, ca.OP_COS: np.cos,
    ca.OP_TAN: np.tan, ca.OP_ASIN: np.arcsin, ca.OP_ACOS: np.arccos, ca.OP_ATAN: np.arctan,
    ca.OP_SINH: np.sinh, ca.OP_COSH: np.cosh, ca.OP_TANH: np.tanh, ca.OP_ASINH: np.arcsinh,
    ca.OP_ACOSH: np.arccosh, ca.OP_ATANH: np.arctanh, ca.OP_FLOOR: np.floor,
    ca.OP_CEIL: np.ceil, ca.OP_NOT: np.logical_not, ca.OP_EXPM1: np.expm1,
    ca.OP_LOG1P: np.log1p,
}
_BINARY_OPS: dict[int, Callable] = {
    ca.OP_ADD: np.add, ca.OP_SUB: np.subtract, ca.OP_MUL: np.multiply, ca.OP_DIV: np.divide,
    ca.OP_POW: np.power, ca.OP_CONSTPOW: np.power, ca.OP_FMIN: np.fmin,
    ca.OP_FMAX: np.fmax, ca.OP_ATAN2: np.arctan2, ca.OP_FMOD: np.fmod,
    ca.OP_COPYSIGN: np.copysign, ca.OP_HYPOT: np.hypot, ca.OP_LT: np.less,
    ca.OP_LE: np.less_equal, ca.OP_EQ: np.equal, ca.OP_NE: np.not_equal,
    ca.OP_AND: np.logical_and, ca.OP_OR: np.logical_or, ca.OP_IF_ELSE_ZERO: _if_else_zero,
}


@dataclass(frozen=True)
class Program:
    """The instructions of an SX Function, ready for :class:`BlockEvaluator`.

    ``code`` has one row per instruction: ``(kind, op, out, a, b)``. For an input, ``out`` is
    the work slot and ``(a, b)`` the input and its nonzero; for an output, ``out`` is the
    output and ``a`` its nonzero, ``b`` the work slot; otherwise ``out`` is the work slot, ``a``
    and ``b`` the operands' slots. ``constants`` holds each instruction's constant (0 where it
    has none)."""

    code: np.ndarray  # (instructions, 5) int64
    constants: np.ndarray  # (instructions,) float64
    work_size: int
    inputs: tuple[int, ...]  # number of nonzeros of each input
    outputs: tuple[tuple[int, int], ...]  # (rows, columns) of each output
    output_entries: tuple[tuple[int, ...], ...]  # each output nonzero's entry (column-major)

    def files(self) -> dict[str, bytes]:
        """The program as the files of a cache entry (:func:`Program.from_files` reads them)."""
        layout = {"work_size": self.work_size, "inputs": list(self.inputs),
                  "outputs": [list(shape) for shape in self.outputs],
                  "output_entries": [list(entries) for entries in self.output_entries]}
        return {CODE: _npy(self.code), CONSTANTS: _npy(self.constants),
                LAYOUT: json.dumps(layout).encode("utf-8")}

    @classmethod
    def from_files(cls, files: dict[str, bytes]) -> Program:
        """The program of :meth:`files` (ValueError, KeyError or TypeError when they do not
        hold one)."""
        layout = json.loads(files[LAYOUT])
        code = np.lib.format.read_array(io.BytesIO(files[CODE]), allow_pickle=False)
        constants = np.lib.format.read_array(io.BytesIO(files[CONSTANTS]), allow_pickle=False)
        if (code.ndim != 2 or code.shape[1] != 5 or code.dtype != np.int64
                or constants.shape != code.shape[:1]):
            raise ValueError("instructions and constants do not match")
        program = cls(code, constants, int(layout["work_size"]),
                      tuple(int(n) for n in layout["inputs"]),
                      tuple((int(r), int(c)) for r, c in layout["outputs"]),
                      tuple(tuple(int(e) for e in entries)
                            for entries in layout["output_entries"]))
        program._check()
        return program

    def _check(self) -> None:
        """ValueError unless every instruction names an operation of its kind and rows that
        exist (a program read back must not index out of its buffers)."""
        kind, op, out, a, b = self.code.T
        size = max(self.work_size, 1)

        def slot(x):
            return (0 <= x) & (x < size)

        inputs, entries = np.array(self.inputs, dtype=np.int64), self.output_entries
        ok = np.zeros(kind.size, dtype=bool)
        for k in np.flatnonzero(kind == _INPUT):
            ok[k] = slot(out[k]) and 0 <= a[k] < inputs.size and 0 <= b[k] < inputs[a[k]]
        for k in np.flatnonzero(kind == _OUTPUT):
            ok[k] = (0 <= out[k] < len(entries) and 0 <= a[k] < len(entries[out[k]])
                     and slot(b[k]))
        ok |= (kind == _CONSTANT) & slot(out)
        ok |= ((kind == _UNARY) & np.isin(op, list(_UNARY_OPS)) & slot(out) & slot(a))
        ok |= ((kind == _BINARY) & np.isin(op, list(_BINARY_OPS)) & slot(out) & slot(a)
               & slot(b))
        for (rows, columns), listed in zip(self.outputs, entries, strict=True):
            if any(not 0 <= e < rows * columns for e in listed):
                ok[:] = False
        if not ok.all():
            raise ValueError(f"instruction {int(np.argmin(ok))} names no row or operation")


def _npy(array: np.ndarray) -> bytes:
    stream = io.BytesIO()
    np.lib.format.write_array(stream, array, allow_pickle=False)
    return stream.getvalue()


def program_of(function: ca.Function) -> Program | None:
    """The :class:`Program` of an SX Function, or None when it is not an SX Function or has
    an instruction without a NumPy counterpart."""
    if not function.is_a("SXFunction"):
        return None
    n = function.n_instructions()
    code = np.zeros((n, 5), dtype=np.int64)
    constants = np.zeros(n)
    for k in range(n):
        op = function.instruction_id(k)
        out = function.instruction_output(k)
        args = function.instruction_input(k)
        if op == ca.OP_INPUT:
            code[k] = (_INPUT, op, out[0], args[0], args[1])
        elif op == ca.OP_OUTPUT:
            code[k] = (_OUTPUT, op, out[0], out[1], args[0])
        elif op == ca.OP_CONST:
            code[k] = (_CONSTANT, op, out[0], 0, 0)
            constants[k] = function.instruction_constant(k)
        elif op == ca.OP_TWICE:  # 2 x as x + x: the same number
            code[k] = (_BINARY, ca.OP_ADD, out[0], args[0], args[0])
        elif op in _UNARY_OPS:
            code[k] = (_UNARY, op, out[0], args[0], 0)
        elif op in _BINARY_OPS:
            code[k] = (_BINARY, op, out[0], args[0], args[1])
        else:
            return None
    outputs = tuple(function.size_out(i) for i in range(function.n_out()))
    entries = tuple(tuple(function.sparsity_out(i).find()) for i in range(function.n_out()))
    return Program(code, constants, function.sz_w(),
                   tuple(function.nnz_in(i) for i in range(function.n_in())), outputs, entries)


class BlockEvaluator:
    """A program bound to buffers of ``block`` samples: fill :attr:`inputs` (one
    ``(nonzeros, block)`` array per input), call, read :attr:`outputs` (one
    ``(rows * columns, block)`` array per output, entries column-major, structural zeros 0).

    Every instruction is a NumPy call with its operands and result bound beforehand
    (``functools.partial``, the result passed by position, which NumPy's functions take
    faster than by keyword), so a call of the evaluator is a loop over C calls."""

    def __init__(self, program: Program, block: int):
        self.block = block
        work = np.zeros((max(program.work_size, 1), block))
        rows = list(work)
        self.inputs = [np.zeros((n, block)) for n in program.inputs]
        self.outputs = [np.zeros((r * c, block)) for r, c in program.outputs]
        outputs = [[out[e] for e in entries]
                   for out, entries in zip(self.outputs, program.output_entries, strict=True)]
        inputs = [list(x) for x in self.inputs]
        steps = []
        for (kind, op, out, a, b), constant in zip(program.code.tolist(),
                                                   program.constants.tolist(), strict=True):
            if kind == _BINARY:
                steps.append(partial(_BINARY_OPS[op], rows[a], rows[b], rows[out]))
            elif kind == _UNARY:
                if op == ca.OP_ASSIGN:
                    steps.append(partial(np.copyto, rows[out], rows[a]))
                else:
                    steps.append(partial(_UNARY_OPS[op], rows[a], rows[out]))
            elif kind == _INPUT:
                steps.append(partial(np.copyto, rows[out], inputs[a][b]))
            elif kind == _OUTPUT:
                steps.append(partial(np.copyto, outputs[out][a], rows[b]))
            else:
                steps.append(partial(rows[out].fill, constant))
        self._steps = steps

    def __call__(self) -> None:
        for step in self._steps:
            step()


def block_size(work_size: int, samples: int) -> int:
    """The most samples of a block of a program whose work rows are ``work_size``: all
    ``samples`` when the rows fit in :data:`WORK_BYTES`."""
    return max(1, min(samples, WORK_BYTES // (8 * max(work_size, 1))))


def program_key(key: str) -> str:
    """The cache key of ``key``'s program."""
    return cache.key("array-program", key, f"casadi {ca.__version__}")


def cached_program(key: str | None, function: Callable[[], ca.Function | None], *,
                   what: str = "") -> Program | bool | None:
    """The program of ``key``'s Function: read from the cache when it holds it (``function`` is
    then not called), else read from the Function ``function()`` gives and kept there (``what``
    says what it is, for ``hexapod cache info``). False when the Function has no program (also
    remembered); None when ``function()`` gives None (the caller does not want the program read
    now; nothing is kept)."""
    entry_key = program_key(key) if key is not None else None
    found = cache.load(entry_key) if entry_key is not None else None
    if found is not None:
        try:
            if json.loads(found[1][LAYOUT]).get("unsupported"):
                return False
            return Program.from_files(found[1])
        except (KeyError, TypeError, ValueError):
            cache.discard(entry_key)
    source = function()
    if source is None:
        return None
    program = program_of(source)
    if entry_key is not None:
        files = program.files() if program is not None else {
            LAYOUT: json.dumps({"unsupported": True}).encode("utf-8")}
        cache.keep(entry_key, f"{what or source.name()}, as an array program", files,
                   stacklevel=2)
    return program if program is not None else False
