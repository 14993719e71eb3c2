"""Buffered CasADi calls and their fallback: where CasADi offers no buffer interface, a plain
call gives the same numbers, dense, scattered and in place on the caller's arrays, and a failed
evaluation still raises."""

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
    monkeypatch.setattr(fastcall, "_buffer_of", lambda function: None)  # no buffer interface
    plain = getattr(fastcall, kind)(_function())
    for _ in range(2):  # the outputs are written again at each call
        for a, b in zip(plain(X, Y), buffered, strict=True):
            assert a.shape == b.shape and np.array_equal(a, b)


def test_the_fallback_raises_when_the_evaluation_fails(monkeypatch):
    monkeypatch.setattr(fastcall, "_buffer_of", lambda function: None)
    A, b = ca.MX.sym("A", 2, 2), ca.MX.sym("b", 2)
    fast = fastcall.FastFunction(ca.Function("solve", [A, b], [ca.solve(A, b, "qr")]))
    assert np.allclose(fast(np.diag([2.0, 4.0]), np.array([2.0, 2.0]))[0], [1.0, 0.5])
    with pytest.raises(RuntimeError):
        fast(np.zeros((2, 2)), np.array([1.0, 3.0]))


@pytest.mark.parametrize("buffered", [True, False])
def test_in_place_on_slices_of_the_callers_arrays(buffered, monkeypatch):
    """A Function mapped over samples, evaluated on row blocks of arrays with the samples as
    rows (as the tree path does): each block's outputs land in its rows, as single calls give."""
    if not buffered:
        monkeypatch.setattr(fastcall, "_buffer_of", lambda function: None)
    x, y = ca.SX.sym("x", 3), ca.SX.sym("y", 2)
    single = ca.Function("g", [x, y], [ca.vertcat(x[0] * y[1], ca.sin(x[2])), ca.dot(x, x)])
    rng = np.random.default_rng(2)
    X, Y = rng.normal(size=(7, 3)), rng.normal(size=(7, 2))
    A, B = np.full((7, 2), np.nan), np.full((7, 1), np.nan)
    mapped = fastcall.InPlaceFunction(single.map(4, "serial"))
    mapped([X[:4], Y[:4]], [A[:4], B[:4]])
    fastcall.InPlaceFunction(single.map(3, "serial"))([X[4:], Y[4:]], [A[4:], B[4:]])
    for k in range(7):
        a, b = single(X[k], Y[k])
        assert np.array_equal(A[k], a.full().ravel()) and B[k, 0] == float(b)
    A_rows = A[:4].copy()
    mapped([X[3:], Y[3:]], [A[:4], B[:4]])  # the same buffer on other arrays
    assert np.array_equal(A[0], A_rows[3])
