"""The motion of the joints that follow a scene's guides, as laws of the model that carries their
efforts.

A guided model (:mod:`hexapod.scene.laws.guided`) holds the kinematics of its scene with the
guides as drivers (``model.guidance.kinematics``). Its positions, velocities and accelerations
at the samples, found by the engine's own solves, give each guided joint's coordinate, rate and
acceleration there (the joint coordinate of the joint's own driver row, differentiated along the
motion); a twin of the model takes them as laws exact at the samples (the quintic Hermite
interpolant of a motion file), and its inverse dynamics gives the joints' efforts with the guides
left out. Both models have the same bodies and coordinates, so the kinematics' positions are the
twin's to round-off.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod.model.model import Model
from hexapod.model.tabulation import sampled_laws


def _coordinates(model: Model) -> ca.Function:
    """``(q, v, v_dot) -> (theta, theta_dot, theta_ddot)`` of the guided joints."""
    s = model._sym  # the model's expressions: the guided joints' own coordinates
    v_dot = ca.SX.sym("v_dot", model.n_v)
    rate = ca.jtimes(s.guided, s.q, s.qdot)
    state, state_rate = ca.vertcat(s.q, s.v), ca.vertcat(s.qdot, v_dot)
    return ca.Function("guided_coordinates", [s.q, s.v, v_dot],
                       [s.guided, rate, ca.jtimes(rate, state, state_rate)])


def guided_coordinates(model: Model, q: np.ndarray, v: np.ndarray, v_dot: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The guided joints' coordinates, rates and accelerations (each (G, N)) along the motion
    ``q, v, v_dot`` (each (N, size)), the coordinates unwrapped along the samples."""
    function = model.built_once(("guided coordinates",), _coordinates)
    n = q.shape[0]
    mapped = function.map(n, "serial") if n > 1 else function
    theta, rate, acceleration = (np.asarray(x.full()).reshape(-1, n)
                                 for x in mapped(q.T, v.T, v_dot.T))
    return np.unwrap(theta, axis=1), rate, acceleration


def guided_twin(model: Model, times: np.ndarray, q: np.ndarray, v: np.ndarray,
                v_dot: np.ndarray) -> Model:
    """``model`` with its guided joints' laws the motion ``q, v, v_dot`` (at ``times``) gives
    them, exact at the samples; what it has built is shared (only the laws' values differ)."""
    laws = list(model.laws)
    for index, law in zip(model.guidance.laws,
                          sampled_laws(times, *guided_coordinates(model, q, v, v_dot)),
                          strict=True):
        laws[index] = law
    return model.with_laws(tuple(laws), model.digest, share_built=True)
