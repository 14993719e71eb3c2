"""The workspace of a model (:meth:`hexapod.model.model.Model.create_data`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class Data:
    """The workspace of one model (:meth:`Model.create_data`): the numbers of the last state an
    algorithm saw, and what belongs to a run rather than to the model.

    Algorithms fill the state fields they compute; ``None`` means not computed at this state
    (:meth:`at` clears them when the state changes). Besides them a workspace keeps the call
    buffers of the model's Functions (``calls``), the law values of the last run of samples
    (``laws``) and the objects a run builds and reuses (``built``: rank decisions and their
    plans). Each thread uses a workspace of its own; :meth:`Model.check` tells whether one was
    made for a given model.

    Attributes
    ----------
    t : float
        The state's time, s.
    q, v, v_dot : ndarray (n_q,), (n_v,), (n_v,)
        Positions, velocities and accelerations (SI; Euler parameters for orientations, body
        angular velocities).
    w, wd, wdd : ndarray (n_w,)
        The laws' values and derivatives at ``t``.
    Phi_v : ndarray (n_c, n_v)
        A SciPy CSR array for a large model (:mod:`hexapod.algorithms.saddle`).
    gamma, Q, lam : ndarray (n_c,), (n_v,), (n_c,)
        The acceleration right-hand side, the generalized applied forces and the multipliers.
    Q_across : ndarray (n_v, k)
        Generalized forces of the force elements acting across joints.
    independent_rows, redundant_rows : ndarray of int
        The rank decision's rows (indices into ``Model.rows``).
    inconsistency : float
        The relative violation of the redundant rows.
    condition_number, sigma_min : float
        Of the equilibrated saddle-point matrix; the smallest singular value of the
        equilibrated kept rows.
    singular_values : ndarray
        All of them, ascending.
    ground_status : tuple of str
        Per contact: ``swing``, ``ok``, or where the friction policy found no admissible force,
        ``slip`` (outside the friction cone) or ``pull`` (normal force below its minimum).
    model_sizes : tuple
        The sizes of the model the workspace was made for (:meth:`Model.check`).
    calls, laws, built : dict, tuple, dict
        What belongs to a run: the call buffers, the law values of the last run of samples,
        and the objects a run builds and reuses.
    """

    t: float | None = None
    q: np.ndarray | None = None
    v: np.ndarray | None = None
    w: np.ndarray | None = None
    wd: np.ndarray | None = None
    wdd: np.ndarray | None = None
    Phi_v: np.ndarray | None = None
    gamma: np.ndarray | None = None
    Q: np.ndarray | None = None
    v_dot: np.ndarray | None = None
    lam: np.ndarray | None = None
    Q_across: np.ndarray | None = None
    independent_rows: np.ndarray | None = None
    redundant_rows: np.ndarray | None = None
    inconsistency: float | None = None
    condition_number: float | None = None
    sigma_min: float | None = None
    singular_values: np.ndarray | None = None
    ground_status: tuple[str, ...] | None = None
    #: what the workspace was made for (:meth:`Model.check`), and what belongs to a run
    model_sizes: tuple = field(default=(), repr=False, compare=False)
    calls: dict = field(default_factory=dict, repr=False, compare=False)
    laws: tuple | None = field(default=None, repr=False, compare=False)
    built: dict = field(default_factory=dict, repr=False, compare=False)

    #: the fields :meth:`at` clears (those of a state)
    _RUN = frozenset({"model_sizes", "calls", "laws", "built"})

    def at(self, t: float, q: np.ndarray, v: np.ndarray | None = None) -> None:
        """Make ``(t, q)`` (and ``v`` when given) the state of this workspace: every field
        computed at another state is cleared, so that nothing of an earlier state is read as
        belonging to this one."""
        same = (self.t == t and self.q is not None and np.array_equal(self.q, q)
                and (v is None or self.v is not None and np.array_equal(self.v, v)))
        if not same:
            for name in self.__dataclass_fields__:
                if name not in self._RUN:
                    setattr(self, name, None)
        self.t, self.q = t, q
        if v is not None:
            self.v = v


def kept(data: Data | None, key: Any, make: Callable[[], Any]) -> Any:
    """What ``make()`` returns (call buffers: they belong to one user at a time), made once per
    workspace ``data`` and kept in it under ``key``; made afresh without a workspace."""
    if data is None:
        return make()
    found = data.calls.get(key)
    if found is None:
        found = data.calls[key] = make()
    return found
