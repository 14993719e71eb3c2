"""Buffered CasADi calls and their fallback: where CasADi offers no buffer interface, a plain
call gives the same numbers, dense and scattered, and a failed evaluation still raises."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from hexapod._support import fastcall


def _function() -> ca.Function:
    x, y = ca.SX.sym("x", 3), ca.SX.sym("y", 2, 2)
    sparse = ca.vertcat(ca.horzcat(x[0], 0), ca.horzcat(x[1] * x[2], 0), ca.horzcat(0, y[0, 1]))
    return ca.Function("f", [x, y], [sparse, ca.sin(x) + y[1, 0]])


@pytest.mark.parametrize("kind", ["FastFunction", "ScatteredFunction"])
def test_the_plain_call_fallback_gives_the_buffered_numbers(kind, monkeypatch):
    rng = np.random.default_rng(1)
    X, Y = rng.normal(size=3), rng.normal(size=(2, 2))
    buffered = getattr(fastcall, kind)(_function())(X, Y)
    monkeypatch.setattr(fastcall, "_bound", lambda *arguments: None)  # no buffer interface
    plain = getattr(fastcall, kind)(_function())
    for _ in range(2):  # the outputs are written again at each call
        for a, b in zip(plain(X, Y), buffered, strict=True):
            assert a.shape == b.shape and np.array_equal(a, b)


def test_the_fallback_raises_when_the_evaluation_fails(monkeypatch):
    monkeypatch.setattr(fastcall, "_bound", lambda *arguments: None)
    A, b = ca.MX.sym("A", 2, 2), ca.MX.sym("b", 2)
    fast = fastcall.FastFunction(ca.Function("solve", [A, b], [ca.solve(A, b, "qr")]))
    assert np.allclose(fast(np.diag([2.0, 4.0]), np.array([2.0, 2.0]))[0], [1.0, 0.5])
    with pytest.raises(RuntimeError):
        fast(np.zeros((2, 2)), np.array([1.0, 3.0]))
