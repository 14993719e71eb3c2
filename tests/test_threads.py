"""A frozen model, a workspace per thread: two threads running the same model with their own
``Data`` compute what one thread alone computes, and a workspace of another model is refused."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import hexapod as hx
from hexapod.errors import HexapodError

from mechanisms import four_bar


def _in_threads(work, count: int = 2) -> list:
    """``work(k)`` in ``count`` threads started together; their results, in order."""
    results, errors = [None] * count, []
    start = threading.Barrier(count)

    def run(k):
        try:
            start.wait()
            results[k] = work(k)
        except BaseException as error:  # noqa: BLE001 (reported below)
            errors.append(error)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(count)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    if errors:
        raise errors[0]
    return results


def test_two_threads_with_their_own_data_compute_the_same_inverse_dynamics():
    model = hx.assemble(hx.load_scene("front-leg"))
    times = np.linspace(0.0, 0.5, 101)
    alone = hx.inverse_dynamics(model, times)
    together = _in_threads(lambda k: hx.inverse_dynamics(model, times,
                                                         data=model.create_data()))
    for result in together:
        for key in ("force", "torque", "effort", "q", "v_dot"):
            assert np.array_equal(getattr(result, key), getattr(alone, key)), key


def test_two_threads_with_their_own_data_compute_the_same_forward_dynamics():
    """The exact path (rank decision, redundancy policy, wrenches) on a redundant 3-D four-bar,
    each thread at its own states, both through the same model's Functions."""
    model = hx.assemble(four_bar(3, 0.6))
    times = np.linspace(0.0, 1.0, 12)

    def states(data):
        out = []
        for t in times:
            q, v = hx.consistent_state(model, data, t)
            a = hx.forward_dynamics(model, data, t, q, v)
            out.append(np.concatenate([q, v, a, data.lam,
                                       hx.joint_wrenches(model, data).force.ravel()]))
        return np.array(out)

    alone = states(model.create_data())
    for result in _in_threads(lambda k: states(model.create_data())):
        assert np.array_equal(result, alone)


def test_two_threads_build_and_run_the_walking_robots_phase_path_together():
    """The batched closed-loop path across a touch-down (0.2 s): both threads start on a model
    that has built nothing, so they race to build its plans (built once, under the model's
    lock) and each runs them through its own buffers."""
    times = np.linspace(0.18, 0.22, 9)
    # both models fresh: a phase plan is built at the first state that needs it, so a model
    # that ran other samples first may differ in the last bits (measured 3e-14)
    alone = hx.inverse_dynamics(hx.assemble(hx.load_scene("hexapod")), times, method="phase")
    model = hx.assemble(hx.load_scene("hexapod"))
    together = _in_threads(lambda k: hx.inverse_dynamics(model, times, method="phase",
                                                         data=model.create_data()))
    for result in together:
        for key in ("force", "torque", "effort", "ground_force"):  # NaN: no effort
            np.testing.assert_array_equal(getattr(result, key), getattr(alone, key), key)


def test_two_threads_simulate_the_same_model_together():
    model = hx.assemble(four_bar(2, 0.6))
    alone = hx.simulate(model, 0.2, method="rk4", step=1e-3)
    for result in _in_threads(lambda k: hx.simulate(model, 0.2, method="rk4",
                                                     step=1e-3)):
        assert np.array_equal(result.q, alone.q)
        assert np.array_equal(result.v, alone.v)


def test_a_model_is_frozen_and_refuses_another_models_data():
    model = hx.assemble(hx.load_scene("front-leg"))
    other = hx.assemble(four_bar(2, 0.6))
    with pytest.raises(AttributeError, match="frozen"):
        model.name = "changed"
    model.check(model.create_data())
    with pytest.raises(HexapodError, match="another model"):
        hx.forward_dynamics(model, other.create_data(), 0.0, model.q0, model.v0)
