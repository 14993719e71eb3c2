"""An SX Function evaluated over samples by the MX virtual machine gives, sample by sample,
the very numbers of the SX Function (the same operations in the same order): every kind of
operation the engine's steps hold, constants, outputs that are constant or structurally zero,
and non-finite values kept where they arise."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from hexapod._support.across_samples import across_samples


def mixed() -> ca.Function:
    x, y = ca.SX.sym("x", 3), ca.SX.sym("y", 2)
    a = ca.sin(x[0]) * ca.cos(y[1]) - ca.sqrt(ca.fabs(x[1])) / (y[0] + 0.5)
    b = ca.fmax(a, x[2]) + ca.if_else(x[0] <= y[0], a * a, 2 * x[1])
    c = ca.fmin(ca.exp(-ca.fabs(b)), ca.logic_not(x[2] > 0.3)) + ca.atan2(x[1], y[1])
    d = ca.SX(4, 1)
    d[0], d[2] = b * c - 3.0, ca.tanh(a) + ca.log(ca.fabs(c) + 1.0)
    return ca.Function("mixed", [x, y], [ca.vertcat(a, b, c), d, ca.SX(2.5), 1.0 / (x[0] - x[0]
                       + y[0] - 0.25)], ["x", "y"], ["abc", "d", "constant", "pole"])


def test_every_sample_gets_the_sx_function_s_numbers_bit_for_bit():
    f, n = mixed(), 16
    rng = np.random.default_rng(3)
    x, y = rng.uniform(-1, 1, (3, n)), rng.uniform(-1, 1, (2, n))
    y[0, 5] = 0.25  # a pole: inf there, in both
    across = across_samples(f, n)
    results = across.call([x, y])
    assert across.name_out() == f.name_out()
    for k in range(n):
        one = f.call([x[:, k], y[:, k]])
        for i in range(f.n_out()):
            mine = np.asarray(results[i])[:, k]
            theirs = np.asarray(one[i].nonzeros(), dtype=float)
            assert mine.shape == theirs.shape, f.name_out(i)
            assert np.array_equal(mine, theirs, equal_nan=True), (f.name_out(i), k)
    assert np.isinf(np.asarray(results[3])[0, 5])


def test_a_function_that_is_not_sx_is_refused():
    x = ca.MX.sym("x")
    with pytest.raises(ValueError, match="an SX Function is needed"):
        across_samples(ca.Function("g", [x], [2 * x]), 4)
