"""CasADi Functions called on NumPy arrays without the cost of conversions.

Calling a CasADi Function from Python converts every argument to a ``DM`` and every result back,
about 40 microseconds a call whatever the Function computes: more than the whole right-hand side
of a small mechanism. :class:`FastFunction` evaluates through CasADi's buffer interface
(``Function.buffer()``): the inputs and outputs live in NumPy arrays allocated once, and a call
copies the arguments in and the results out, about a microsecond of overhead. Where the installed
CasADi has no buffer interface, a plain call gives the same numbers, more slowly.

The buffers belong to one user (a :class:`hexapod.model.model.Data`): an evaluator is not
reentrant. The Functions themselves (:func:`dense_outputs`) are immutable and shared.
"""

from __future__ import annotations

import casadi as ca
import numpy as np


def dense_outputs(function: ca.Function) -> ca.Function:
    """``function`` with every output densified (one expression per zero: for small and
    moderately large outputs; see :class:`ScatteredFunction` for the others)."""
    symbols = function.sx_in() if function.is_a("SXFunction") else function.mx_in()
    outputs = [ca.densify(x) for x in function.call(symbols)]
    return ca.Function(function.name(), symbols, outputs, function.name_in(),
                       function.name_out())


class FastFunction:
    """A Function evaluated through preallocated buffers, its outputs dense (a Function with
    sparse outputs is densified first: give one made by :func:`dense_outputs` to build that
    once).

    A call takes the inputs positionally (arrays of any shape holding the input's entries, in
    CasADi's column-major order) and returns fresh arrays: vectors 1-D, matrices 2-D; raises
    ``RuntimeError`` when the evaluation fails, as a plain call does.
    """

    def __init__(self, function: ca.Function):
        if not all(function.sparsity_out(i).is_dense() for i in range(function.n_out())):
            function = dense_outputs(function)
        self.function = function
        self.name_in = tuple(function.name_in())
        self._inputs = [np.zeros(function.numel_in(i)) for i in range(function.n_in())]
        self._outputs = [np.zeros(function.numel_out(i)) for i in range(function.n_out())]
        self._shapes = [function.size_out(i) for i in range(function.n_out())]
        self._bound = _bound(function, self._inputs, self._outputs)

    def __call__(self, *arguments) -> list[np.ndarray]:
        for target, value in zip(self._inputs, arguments, strict=True):
            target[:] = np.ravel(value, order="F")
        _evaluate(self.function, self._bound, self._inputs, self._outputs)
        out = []
        for array, (rows, columns) in zip(self._outputs, self._shapes, strict=True):
            if columns == 1:
                out.append(array.copy())
            else:
                out.append(array.reshape((rows, columns), order="F").copy())
        return out


class ScatteredFunction:
    """A CasADi Function with sparse matrix outputs, called like a :class:`FastFunction` and
    giving the same dense arrays.

    ``FastFunction`` densifies the outputs symbolically: one expression per zero, which for the
    constraint Jacobian of a chain of a thousand bodies (30 million entries, nearly all zero)
    takes gigabytes and many seconds to build. Here the buffers hold the nonzeros only, and each
    call scatters them into a fresh zero array.
    """

    def __init__(self, function: ca.Function):
        self.function = function
        self.name_in = tuple(function.name_in())
        self._inputs = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self._outputs = [np.zeros(function.nnz_out(i)) for i in range(function.n_out())]
        self._shapes = [function.size_out(i) for i in range(function.n_out())]
        self._where = []  # flat (row-major) positions of each output's nonzeros
        for i, (_, columns) in enumerate(self._shapes):
            row, column = function.sparsity_out(i).get_triplet()
            self._where.append(np.asarray(row, dtype=np.int64) * columns
                               + np.asarray(column, dtype=np.int64))
        for i in range(function.n_in()):
            if function.nnz_in(i) != function.numel_in(i):  # pragma: no cover - inputs are dense
                raise ValueError(f"input {i} of {function.name()} is sparse")
        self._bound = _bound(function, self._inputs, self._outputs)
        self._compressed: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def _run(self, arguments) -> None:
        for target, value in zip(self._inputs, arguments, strict=True):
            target[:] = np.ravel(value, order="F")
        _evaluate(self.function, self._bound, self._inputs, self._outputs)

    def __call__(self, *arguments) -> list[np.ndarray]:
        self._run(arguments)
        out = []
        for values, where, (rows, columns) in zip(self._outputs, self._where, self._shapes,
                                                  strict=True):
            dense = np.zeros(rows * columns)
            dense[where] = values
            out.append(dense if columns == 1 else dense.reshape(rows, columns))
        return out

    def sparse(self, *arguments) -> list:
        """As a call, but the matrix outputs as SciPy CSR arrays built from their nonzeros
        (vectors stay dense 1-D arrays): no entry of a zero is written, so the cost is that of
        the nonzeros whatever the size of the matrix."""
        from scipy.sparse import csc_array

        self._run(arguments)
        out = []
        for i, (values, (rows, columns)) in enumerate(zip(self._outputs, self._shapes,
                                                            strict=True)):
            if columns == 1:
                dense = np.zeros(rows)
                dense[self._where[i]] = values
                out.append(dense)
                continue
            if i not in self._compressed:  # CasADi's compressed columns, read once
                pattern = self.function.sparsity_out(i)
                self._compressed[i] = (np.asarray(pattern.row(), dtype=np.int64),
                                       np.asarray(pattern.colind(), dtype=np.int64))
            out.append(csc_array((values.copy(), *self._compressed[i]),
                                 shape=(rows, columns)).tocsr())
        return out


class InPlaceFunction:
    """A Function evaluated from and into arrays the caller gives at each call: each
    C-contiguous and holding one input's or output's nonzeros in CasADi's column-major order
    (the samples of a mapped Function as the rows of a NumPy array, say). Through CasADi's
    buffer interface, made once; a plain call where there is none. Raises ``RuntimeError``
    when the evaluation fails, as a plain call does."""

    def __init__(self, function: ca.Function):
        self.function = function
        self._buffer = _buffer_of(function)

    def __call__(self, inputs: list[np.ndarray], outputs: list[np.ndarray]) -> None:
        if self._buffer is None:
            flat = [np.reshape(y, -1) for y in outputs]
            if not all(np.shares_memory(f, y) for f, y in zip(flat, outputs, strict=True)):
                raise ValueError("outputs must be contiguous arrays")
            _evaluate(self.function, None, [np.reshape(x, -1) for x in inputs], flat)
            return
        buffer, _ = self._buffer
        for i, array in enumerate(inputs):
            buffer.set_arg(i, memoryview(array))
        for i, array in enumerate(outputs):
            buffer.set_res(i, memoryview(array))
        _evaluate(self.function, self._buffer, inputs, outputs)


def _buffer_of(function: ca.Function):
    """CasADi's evaluation buffer of ``function`` and its evaluate function (the buffer must be
    kept alive while it is used), or None where CasADi has no buffer interface."""
    return function.buffer() if hasattr(function, "buffer") else None


def _bound(function: ca.Function, inputs: list[np.ndarray], outputs: list[np.ndarray]):
    """``function``'s evaluation buffer reading ``inputs`` and writing ``outputs`` in place
    (:func:`_buffer_of`), or None."""
    found = _buffer_of(function)
    if found is None:
        return None
    buffer, _ = found
    for i, array in enumerate(inputs):
        buffer.set_arg(i, memoryview(array))
    for i, array in enumerate(outputs):
        buffer.set_res(i, memoryview(array))
    return found


def _evaluate(function: ca.Function, bound, inputs: list[np.ndarray],
              outputs: list[np.ndarray]) -> None:
    """Evaluate ``function`` on ``inputs`` into ``outputs``; raise ``RuntimeError`` as a plain
    call does when the evaluation fails (a linear solve of a singular matrix): the outputs are
    then not written, and would be the last call's results."""
    if bound is None:  # a plain call: its results copied into the outputs (nonzeros only)
        results = function.call([ca.reshape(ca.DM(x), *function.size_in(i))
                                 for i, x in enumerate(inputs)])
        for target, result in zip(outputs, results, strict=True):
            target[:] = np.asarray(result.nonzeros(), dtype=float)
        return
    buffer, evaluate = bound
    evaluate()
    if buffer.ret():
        raise RuntimeError(f"evaluation of {function.name()} failed")
