"""An SX Function evaluated over many independent samples at once by CasADi's MX virtual machine.

CasADi's SX virtual machine runs one scalar operation at a time: some 5 ns each on the walking
robot's inverse-dynamics step, most of it the dispatch of an operation whose kind the processor
cannot foresee (the same machine runs a chain of one kind of operation at some 2.6 ns each).
Where samples do not depend on each other, :func:`across_samples` writes the same algorithm as
an MX Function with one elementwise node per SX instruction acting on a row of ``n`` samples:
the dispatch is paid once per ``n`` samples, and the walking robot's steps cost some 1.5 to 3
ns per operation and sample at ``n = 32`` (its work vector, some 4,000 to 8,000 live values a
sample, stays in the processor's caches at that width; a wider row spills them).

Each sample goes through the very operations the SX Function applies, in the same order, so
the results are those of the SX Function bit for bit (tested); nothing is compiled. Built from
CasADi's documented instruction interface (``instruction_id``, ``instruction_input``,
``instruction_output``, ``instruction_constant``) and its operation-code constructors
(``MX.unary``, ``MX.binary``). Building costs about 5 us an instruction (half a second for the
walking robot's step of 100,000), once per Function and width.
"""

from __future__ import annotations

import casadi as ca
import numpy as np


def across_samples(function: ca.Function, n: int) -> ca.Function:
    """``function`` (an SX Function) over ``n`` samples: input ``i`` is the
    ``nnz_in(i) x n`` matrix of the samples' nonzeros (a sample a column, CasADi's
    column-major order: NumPy's C order of ``n x nnz_in(i)``), and so is each output.

    Raises
    ------
    ValueError
        When ``function`` is not an SX Function, or holds an instruction other than an
        elementwise operation (a call of another Function).
    """
    if not function.is_a("SXFunction"):
        raise ValueError(f"{function.name()}: an SX Function is needed "
                         f"(this one is a {function.class_name()})")
    inputs = [ca.MX.sym(function.name_in(i), function.nnz_in(i), n)
              for i in range(function.n_in())]
    rows = [[None] * function.nnz_out(i) for i in range(function.n_out())]
    work: dict[int, ca.MX] = {}
    constants: dict[float, ca.MX] = {}
    for k in range(function.n_instructions()):
        op = function.instruction_id(k)
        if op == ca.OP_INPUT:
            i, nz = function.instruction_input(k)
            work[function.instruction_output(k)[0]] = inputs[i][nz, :]
        elif op == ca.OP_OUTPUT:
            i, nz = function.instruction_output(k)
            rows[i][nz] = work[function.instruction_input(k)[0]]
        elif op == ca.OP_CONST:
            value = function.instruction_constant(k)
            work[function.instruction_output(k)[0]] = constants.setdefault(value, ca.MX(value))
        elif op == ca.OP_CALL:
            raise ValueError(f"{function.name()}: instruction {k} calls another Function")
        else:
            args = [work[j] for j in function.instruction_input(k)]
            work[function.instruction_output(k)[0]] = (
                ca.MX.unary(op, args[0]) if len(args) == 1 else ca.MX.binary(op, *args))
    outputs = [ca.vertcat(*[_row(y, n) for y in out]) if out else ca.MX(0, n) for out in rows]
    return ca.Function(f"{function.name()}_across_{n}", inputs, outputs,
                       function.name_in(), function.name_out())


def _row(y: ca.MX | None, n: int) -> ca.MX:
    """An output's row: a constant (or an output never written: zero) is the same in every
    sample."""
    if y is None:
        return ca.MX.zeros(1, n)
    return y if y.size2() == n else ca.repmat(y, 1, n)


def in_groups(evaluate, inputs: list[np.ndarray], outputs: list[np.ndarray], width: int) -> None:
    """``evaluate(group_inputs, group_outputs)`` (a Function over ``width`` samples, such as
    :func:`across_samples` gives, called on arrays with the samples first: an
    :class:`~hexapod._support.fastcall.InPlaceFunction`) over every sample of ``inputs`` into
    ``outputs`` (arrays with the samples first), ``width`` samples at a time; the last group
    filled up with copies of its last sample."""
    n = inputs[0].shape[0]
    for start in range(0, n, width):
        take = np.minimum(np.arange(start, start + width), n - 1)
        results = [np.empty((width, *y.shape[1:])) for y in outputs]
        evaluate([np.ascontiguousarray(x[take]) for x in inputs], results)
        count = min(width, n - start)
        for y, r in zip(outputs, results, strict=True):
            y[start:start + count] = r[:count]
