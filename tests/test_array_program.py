"""The array program (one NumPy operation per instruction over a block of samples) against
CasADi's virtual machine, which it replaces for long runs of the tree path."""

from __future__ import annotations

import warnings

import casadi as ca
import numpy as np
import pytest

import hexapod as hx
from hexapod._support import array_program
from hexapod._support.array_program import BlockEvaluator, Program, cached_program, program_of
from hexapod.algorithms import inverse
from hexapod.algorithms.inverse import inverse_dynamics, tree_plan
from legs import front_leg_scene


def _every_operation() -> ca.Function:
    """An SX Function using every operation the program knows, on inputs in (0.1, 0.9)."""
    x, y = ca.SX.sym("x", 2), ca.SX.sym("y")
    a, b = x[0], x[1]
    unary = [-a, a**2, ca.sqrt(a), 1 / a, ca.fabs(a - 0.5), ca.sign(a - 0.5), ca.exp(a),
             ca.log(a), ca.sin(a), ca.cos(a), ca.tan(a), ca.asin(a), ca.acos(a), ca.atan(a),
             ca.sinh(a), ca.cosh(a), ca.tanh(a), ca.asinh(a), ca.acosh(1 + a), ca.atanh(a),
             ca.floor(10 * a), ca.ceil(10 * a), ca.logic_not(a > 0.5), ca.expm1(a),
             ca.log1p(a), 2 * a]
    binary = [a + b, a - b, a * b, a / b, a**b, a**3.5, ca.fmin(a, b), ca.fmax(a, b),
              ca.atan2(a, b), ca.fmod(10 * a, b), ca.copysign(a, b - 0.5), ca.hypot(a, b),
              a < b, a <= b, a == b, a != b, ca.logic_and(a > 0.3, b > 0.3),
              ca.logic_or(a > 0.7, b > 0.7), ca.if_else(a > b, a * y, 0)]
    # a sparse output: its structural zeros are written as zeros
    sparse = ca.SX(3, 2)
    sparse[0, 0], sparse[2, 1] = a * y, b + y
    return ca.Function("every", [x, y], [ca.vertcat(*unary), ca.vertcat(*binary), sparse])


def _virtual_machine(function: ca.Function, inputs: list[np.ndarray]) -> list[np.ndarray]:
    n = inputs[0].shape[1]
    out = function.map(n, "serial")(*inputs)
    return [np.asarray(ca.densify(o)).reshape(function.numel_out(i), n, order="F")
            for i, o in enumerate(out if isinstance(out, (list, tuple)) else [out])]


def test_every_operation_gives_the_virtual_machines_numbers():
    """Arithmetic is the same IEEE operation in the same order: the same bits; the elementary
    functions are NumPy's, within a few units in the last place of CasADi's (the C library's)."""
    function = _every_operation()
    program = program_of(function)
    assert program is not None
    ops = {int(op) for op in program.code[:, 1]}
    assert {ca.OP_IF_ELSE_ZERO, ca.OP_CONSTPOW, ca.OP_ATAN2, ca.OP_NOT} <= ops
    rng = np.random.default_rng(1)
    n = 300
    inputs = [rng.uniform(0.1, 0.9, (2, n)), rng.uniform(0.1, 0.9, (1, n))]
    evaluate = BlockEvaluator(program, n)
    for buffer, x in zip(evaluate.inputs, inputs, strict=True):
        buffer[:] = x
    evaluate()
    for ours, theirs in zip(evaluate.outputs, _virtual_machine(function, inputs), strict=True):
        assert ours.shape == theirs.shape
        assert np.allclose(ours, theirs, rtol=4e-16 * 8, atol=0), np.max(np.abs(ours - theirs))
    assert evaluate.outputs[2][1].tolist() == [0.0] * n  # a structural zero


def test_if_else_zero_gives_zero_where_the_branch_is_infinite():
    """CasADi's if_else(c, x, 0) is 0 where c is false even when x overflows: NumPy's product
    with a boolean would give nan there."""
    x = ca.SX.sym("x")
    function = ca.Function("f", [x], [ca.if_else(x > 0, 1 / x, 0)])
    evaluate = BlockEvaluator(program_of(function), 3)
    evaluate.inputs[0][:] = [[-1.0, 0.0, 2.0]]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="ignore"):
            evaluate()
    assert evaluate.outputs[0].tolist() == [[0.0, 0.0, 0.5]]


def test_a_function_without_a_numpy_counterpart_has_no_program():
    x = ca.MX.sym("x")
    assert program_of(ca.Function("f", [x], [ca.sin(x)])) is None  # not an SX Function
    inner = ca.Function("inner", [x], [x**2], {"never_inline": True})
    y = ca.SX.sym("y")
    called = ca.Function("outer", [y], [inner(y) + 1])
    assert program_of(called) is None  # a call of another Function


def test_the_program_is_kept_in_the_cache_and_read_back(tmp_path, monkeypatch):
    """Read from the Function once; later the cache gives the same program without asking for
    the Function; a damaged entry is read again from the Function."""
    monkeypatch.setenv("HEXAPOD_CACHE_DIR", str(tmp_path / "cache"))
    function = _every_operation()
    first = cached_program("test/every", lambda: function)
    again = cached_program("test/every", lambda: pytest.fail("the Function was asked for"))
    assert np.array_equal(first.code, again.code)
    assert np.array_equal(first.constants, again.constants)
    assert (first.work_size, first.inputs, first.outputs, first.output_entries) == (
        again.work_size, again.inputs, again.outputs, again.output_entries)
    entry = tmp_path / "cache" / "v1" / array_program.program_key("test/every")
    (entry / array_program.CODE).write_bytes(b"damaged")
    assert cached_program("test/every", lambda: function) is not None  # read again
    assert cached_program("test/none", lambda: None) is None  # not asked for now: not kept
    assert not (tmp_path / "cache" / "v1" / array_program.program_key("test/none")).exists()


@pytest.mark.parametrize("column, value", [(2, 10**6), (3, -1), (1, ca.OP_CALL)])
def test_a_program_read_back_must_name_rows_and_operations_that_exist(column, value):
    """A program's files that pass their checksums but name a row out of its buffers or an
    operation of no kind are refused (the cache then reads the program again), never
    evaluated out of bounds."""
    program = program_of(_every_operation())
    files = program.files()
    assert Program.from_files(files).code.shape == program.code.shape
    code = program.code.copy()
    k = int(np.flatnonzero(code[:, 0] == array_program._BINARY)[0])
    code[k, column] = value
    damaged = {**files, array_program.CODE: array_program._npy(code)}
    with pytest.raises(ValueError, match=f"instruction {k} "):
        Program.from_files(damaged)


def test_the_tree_path_evaluates_long_runs_as_arrays_with_the_virtual_machines_numbers(
        monkeypatch):
    """From ARRAY_FROM_SAMPLES samples the tree path evaluates the array program (in blocks of
    unequal memory bound here: 700 samples in blocks of at most 256); its numbers are the
    virtual machine's."""
    times = np.linspace(0.0, 1.2, 700)
    model = hx.assemble(front_leg_scene())
    plan = tree_plan(model)
    monkeypatch.setattr(array_program, "WORK_BYTES", 8 * 256 * plan.function.sz_w())
    monkeypatch.setattr(inverse, "ARRAY_FROM_SAMPLES", 200)
    arrays = inverse_dynamics(model, times, compile=False)
    assert plan.evaluates_arrays(times.size) and plan._program
    assert plan._array_evaluator_kept.block == 234  # three blocks of 234, 234 and 232 samples
    machine = inverse_dynamics(hx.assemble(front_leg_scene()), times, compile=False,
                               arrays=False)
    for key in ("force", "torque", "effort", "q", "v", "v_dot"):
        ours, theirs = getattr(arrays, key), getattr(machine, key)
        scale = np.max(np.abs(theirs))
        assert np.max(np.abs(ours - theirs)) <= 1e-14 * scale, key


def test_a_long_run_is_not_compiled_and_not_counted(tmp_path, monkeypatch):
    """A run long enough for the array program does not wait for a compiler, and does not
    count towards compiling quick code: the array program is faster."""
    monkeypatch.setenv("HEXAPOD_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(inverse, "COMPILE_FROM_SAMPLES", 600)
    for _ in range(3):
        plan = tree_plan(hx.assemble(front_leg_scene()))
        inverse_dynamics(plan.model, np.linspace(0.0, 1.2, inverse.ARRAY_FROM_SAMPLES))
        assert not plan.is_compiled and plan._program
    assert inverse.interpreted_samples(plan.key) == 0


def test_arrays_can_be_asked_for_or_refused():
    """``arrays=True`` evaluates the array program however few the samples; ``arrays=False``
    keeps the virtual machine however many (and counts its samples towards compiling)."""
    many = np.linspace(0.0, 1.2, 601)
    plan = tree_plan(hx.assemble(front_leg_scene()))
    asked = inverse_dynamics(plan.model, many[::15], arrays=True)
    assert plan._array_evaluator_kept.block == 41 and not plan.is_compiled
    plan = tree_plan(hx.assemble(front_leg_scene()))
    refused = inverse_dynamics(plan.model, many, compile=False, arrays=False)
    assert "_array_evaluator_kept" not in plan.__dict__
    assert np.allclose(refused.force[::15], asked.force, rtol=0, atol=1e-12)


def test_runs_of_many_sizes_keep_one_evaluator_and_the_same_numbers():
    """A run reuses the kept evaluator when it is at most twice as wide as its blocks (the
    extra columns hold another run's samples: they change nothing), else makes a new one."""
    many = np.linspace(0.0, 1.2, 1201)
    plan = tree_plan(hx.assemble(front_leg_scene()))
    whole = inverse_dynamics(plan.model, many, arrays=True)
    first = plan._array_evaluator_kept
    half = inverse_dynamics(plan.model, many[::2], arrays=True)  # 601 samples: reused
    assert plan._array_evaluator_kept is first
    inverse_dynamics(plan.model, many[::3], arrays=True)  # 401 samples: a new one
    assert plan._array_evaluator_kept is not first and plan._array_evaluator_kept.block == 401
    for key in ("force", "torque", "effort"):
        assert np.array_equal(getattr(half, key), getattr(whole, key)[::2]), key
