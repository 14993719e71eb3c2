"""The motion a model's drivers prescribe over many samples: positions, velocities and
accelerations, without the dynamics.

A kinematics run: a guided model's guides' kinematics (:mod:`hexapod.algorithms.guided`) needs
the motion they give, not the multipliers, the redundancy policy or the wrenches of an inverse
dynamics run (two thirds of the work of the phase path's plans, and of building them). The same
paths as :func:`hexapod.algorithms.inverse.inverse_dynamics`: each sample exactly (Newton's
method from the sample before, then the velocity and acceleration solves) below
:data:`PHASE_FROM_SAMPLES` samples, else the phase path's compiled
plans (:func:`hexapod.algorithms.phase_inverse.phase_motion`), whose samples are checked and
redone exactly where their checks fail.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from hexapod._support import signals
from hexapod.algorithms.sample_inverse import exact_motion
from hexapod.model.model import Data, Model

#: Samples from which the phase path's plans pay, here and for ``inverse_dynamics(...,
#: method="auto")`` of closed loops and contacts: below, building them costs about as much
#: as solving each sample exactly (some two seconds for the walking hexapod, whose samples
#: cost 70 ms each on the saddle path).
PHASE_FROM_SAMPLES = 32


def prescribed_motion(model: Model, times: ArrayLike, *, data: Data | None = None,
                      progress: Callable[[int, int], None] | None = None) -> tuple:
    """Positions, velocities and accelerations ``(q, v, v_dot)`` (each (N, size)) of the motion
    the drivers of ``model`` prescribe at ``times``, continuous along them (each sample's
    Newton solve starts from the one before).

    Parameters
    ----------
    model : Model
        Its drivers fix every degree of freedom.
    times : array_like (N,)
        Sample times, s.
    data : Data, optional
        A workspace of ``model`` (default: a new one).
    progress : callable, optional
        Called as ``progress(done, total)`` as samples are done.

    Returns
    -------
    q, v, v_dot : ndarray

    Raises
    ------
    SingularSystemError
        When the drivers leave degrees of freedom free.
    AssemblyError
        When the positions cannot be found at a sample.
    """
    times = np.atleast_1d(np.asarray(times, dtype=float))
    if data is None:
        data = model.create_data()
    model.check(data)
    if times.size >= PHASE_FROM_SAMPLES:
        from hexapod.algorithms.phase_inverse import phase_motion  # loaded when it runs

        w, wd, wdd = (x.reshape(model.n_w, times.size) for x in model.law_values(times, data))
        return phase_motion(model, data, times, w, wd, wdd, progress=progress)
    n = times.size
    q, v, v_dot = np.zeros((n, model.n_q)), np.zeros((n, model.n_v)), np.zeros((n, model.n_v))
    for k, t in enumerate(times):
        sample = (exact_motion(model, data, t, model.q0, t) if k == 0 else
                  exact_motion(model, data, times[k - 1], q[k - 1], t, (v[k - 1], v_dot[k - 1])))
        q[k], v[k], v_dot[k] = sample.q, sample.v, sample.v_dot
        if signals.received() is not None:  # an interruption a library call swallowed
            raise KeyboardInterrupt
        if progress is not None:
            progress(k + 1, n)
    return q, v, v_dot
