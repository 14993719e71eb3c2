"""Design by derivatives: a scene's figures of merit and their derivatives with respect to
parameters named by scene keys, from one inverse-dynamics run and its sensitivities.

:func:`sensitivity_run` is what ``hexapod sensitivity`` runs; ``docs/design.md`` is the user's
guide.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from hexapod.sweeps.cases import StudyError
from hexapod.sweeps.design_parameters import inertia_parameters, moved_model
from hexapod.sweeps.metric_derivatives import (
    SENSITIVE_FAMILIES,
    metric_sensitivities,
    sensitivity_rows,
)

if TYPE_CHECKING:
    from hexapod.model.model import Model
    from hexapod.scene.scene import Scene


@dataclass
class SensitivityRun:
    """The figures of merit of a scene and their derivatives.

    Attributes
    ----------
    model : Model
    result : InverseResult
        The inverse dynamics over the window.
    sensitivity : InverseSensitivity
        Its per-sample derivatives.
    strides : float
        The window in strides (the energy is per stride).
    metrics : dict
        Figure of merit -> value.
    derivatives : dict
        Figure of merit -> derivatives (P,), per parameter in ``sensitivity.parameters``.
    rows : list of dict
        The rows of ``sensitivities.csv``.
    run_time : float
        CPU seconds of the inverse dynamics and the derivatives.
    """

    model: object
    result: object
    sensitivity: object
    strides: float
    metrics: dict
    derivatives: dict
    rows: list
    run_time: float


def check_families(families: Sequence[str], source: str = "--metrics") -> tuple[str, ...]:
    """The families asked for, refused with one message when one has no derivative."""
    unknown = [f for f in families if f not in SENSITIVE_FAMILIES]
    if unknown:
        raise StudyError(f"{source}: no figure of merit {', '.join(map(repr, unknown))}; "
                         f"those with derivatives: {', '.join(SENSITIVE_FAMILIES)}")
    return tuple(families)


def sensitivity_run(scene: Scene, parameters: Sequence, *,
                    families: Sequence[str] = SENSITIVE_FAMILIES, samples: int = 501,
                    start: float = 0.0, duration: float | None = None, method: str = "auto",
                    progress: Callable[[str, int, int], None] | None = None,
                    model: Model | None = None) -> SensitivityRun:
    """The figures of merit of ``scene``'s inverse dynamics over a window and their exact
    derivatives with respect to ``parameters``.

    Parameters
    ----------
    scene : Scene
        A driven scene (every degree of freedom prescribed).
    parameters : sequence of str, or of parameters
        Scene keys, ``*`` matching any body or joint
        (:mod:`hexapod.sweeps.design_parameters`), or what
        :func:`~hexapod.sweeps.design_parameters.inertia_parameters` made of them.
    families : sequence of str
        Families of figures of merit
        (:data:`~hexapod.sweeps.metric_derivatives.SENSITIVE_FAMILIES`).
    samples : int
        Samples over the window, ends included.
    start, duration : float
        The window, s (default duration: one cycle of the scene's periodic laws, or 1 s).
    method : str
        The inverse-dynamics path (:func:`hexapod.algorithms.inverse.inverse_dynamics`).
    progress : callable, optional
        Called with ``(stage, done, total)``.
    model : Model, optional
        ``scene`` assembled, when it already is.

    Returns
    -------
    SensitivityRun

    Raises
    ------
    StudyError
        A parameter or family that names nothing (before any work).
    HexapodError
        The inverse dynamics fails; with the friction policy, the exact cone, or a sample
        where no forces are inside the cones.
    """
    from hexapod.algorithms.assembly import assemble
    from hexapod.algorithms.inverse import inverse_dynamics, motion_model
    from hexapod.algorithms.sensitivity import check_parameters, inverse_sensitivities
    from hexapod.sweeps.metrics import inverse_metrics

    families = check_families(families)
    changes = (inertia_parameters(scene, parameters)
               if all(isinstance(p, str) for p in parameters) else tuple(parameters))
    model = assemble(scene) if model is None else model
    moved = moved_model(scene, model, changes)
    check_parameters(model, changes, moved)  # before the run
    window, _ = model.time_window(duration)
    cycle = model.cycle_time()
    strides = window / cycle if cycle else 1.0
    times = start + np.linspace(0.0, window, samples)
    began = time.process_time()

    def stage(name):
        return None if progress is None else (lambda done, total: progress(name, done, total))

    result = inverse_dynamics(model, times, method=method, progress=stage("inverse dynamics"))
    model = motion_model(model, result)  # a guided scene's laws: the motion found
    sensitivity = inverse_sensitivities(model, result, changes, progress=stage("derivatives"),
                                        moved=moved)
    metrics = inverse_metrics(model, result, families, strides)
    derivatives = metric_sensitivities(model, result, sensitivity, families, strides)
    run_time = time.process_time() - began
    rows = sensitivity_rows(model, metrics, derivatives, changes)
    return SensitivityRun(model, result, sensitivity, strides, metrics, derivatives, rows,
                          run_time)
