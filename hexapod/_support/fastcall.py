"""CasADi Functions called on NumPy arrays without the cost of conversions.

Calling a CasADi Function from Python converts every argument to a ``DM`` and every result back,
about 40 microseconds a call whatever the Function computes: more than the whole right-hand side
of a small mechanism. :class:`FastFunction` evaluates through CasADi's buffer interface
(``Function.buffer()``): the inputs and outputs live in NumPy arrays allocated once, and a call
copies the arguments in and the results out, about a microsecond of overhead.
"""

from __future__ import annotations

import casadi as ca
import numpy as np


class FastFunction:
    """``function`` with dense outputs, evaluated through preallocated buffers.

    A call takes the inputs positionally (arrays of any shape holding the input's entries, in
    CasADi's column-major order) and returns fresh arrays: vectors 1-D, matrices 2-D.
    Not reentrant (one set of buffers): build one per user if threads share a model.
    """

    def __init__(self, function: ca.Function):
        symbols = function.sx_in() if function.is_a("SXFunction") else function.mx_in()
        outputs = [ca.densify(x) for x in function.call(symbols)]
        self.function = ca.Function(function.name(), symbols, outputs, function.name_in(),
                                    function.name_out())
        self.name_in = tuple(function.name_in())
        self._inputs = [np.zeros(function.numel_in(i)) for i in range(function.n_in())]
        self._outputs = [np.zeros(function.numel_out(i)) for i in range(function.n_out())]
        self._shapes = [function.size_out(i) for i in range(function.n_out())]
        self._buffer, self._evaluate = self.function.buffer()
        for i, array in enumerate(self._inputs):
            self._buffer.set_arg(i, memoryview(array))
        for i, array in enumerate(self._outputs):
            self._buffer.set_res(i, memoryview(array))

    def __call__(self, *arguments) -> list[np.ndarray]:
        for target, value in zip(self._inputs, arguments, strict=True):
            target[:] = np.ravel(value, order="F")
        self._evaluate()
        out = []
        for array, (rows, columns) in zip(self._outputs, self._shapes, strict=True):
            if columns == 1:
                out.append(array.copy())
            else:
                out.append(array.reshape((rows, columns), order="F").copy())
        return out
