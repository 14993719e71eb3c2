"""How far each joint controller's joint is from its target along a run: the tracking errors
``err:<controller>`` of a simulation's output (the joint's coordinate minus the target,
wrapped to (-pi, pi]: the error the controller's proportional term acts on).

The errors are the model's own expressions (those its controllers' torques are built from),
evaluated at the saved states in one mapped call.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod.model.model import Model


def controller_names(model: Model) -> tuple[str, ...]:
    """The model's joint controllers, in the order of their tracking errors.

    Parameters
    ----------
    model : Model

    Returns
    -------
    tuple of str
    """
    return tuple(f.name for f in model.forces if f.kind == "controller")


def tracking_errors(model: Model, t: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Each controller's joint coordinate minus its target at the states ``(t, q)``.

    Parameters
    ----------
    model : Model
    t : ndarray, shape (N,)
    q : ndarray, shape (N, n_q)

    Returns
    -------
    ndarray, shape (N, k)
        ``k`` the controllers (:func:`controller_names`), rad.
    """
    names = controller_names(model)
    t = np.atleast_1d(np.asarray(t, dtype=float))
    if not names or not t.size:
        return np.zeros((t.size, len(names)))
    function = model.built_once(("tracking errors",), _function)
    w = np.array(model.law_values(t, model.create_data())[0]).reshape(model.n_w, t.size)
    values = function.map(t.size)(np.asarray(q, dtype=float).T, w)
    return np.array(values, dtype=float).reshape(len(names), t.size).T


def _function(model: Model) -> ca.Function:
    symbolic = model._sym  # the model's expressions: the controllers' own errors
    return ca.Function("tracking", [symbolic.q, symbolic.w], [symbolic.tracking],
                       ["q", "w"], ["error"])
