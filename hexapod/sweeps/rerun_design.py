"""The figures of merit and their gradients at values of parameters that move the motion (a
joint's position, the gait's period): each evaluation builds the study's scene again with the
values (:func:`hexapod.sweeps.cases.base_scene`) and runs it, its gradients exact there.

The gait's period is varied at fixed phase, as its derivative is taken
(:class:`~hexapod.algorithms.sensitivity.PeriodChange`): the samples are the same fractions of
the stride, their times scaled with the period (:func:`times_at`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hexapod.algorithms.sensitivity import PeriodChange
from hexapod.sweeps.metric_derivatives import SENSITIVE_FAMILIES, metric_sensitivities
from hexapod.sweeps.metrics import inverse_metrics


def scene_at(study, changes, values, source: str = "", length: float | None = None):
    """The study's scene with the parameters ``changes`` at ``values`` (SI; builder arguments
    or scene keys, in the scene's units); its characteristic length set to ``length`` (SI)
    when given (:func:`held_length`)."""
    from hexapod.sweeps.cases import StudyError, base_scene

    try:
        scene = base_scene(study, {c.name: float(v) / c.scene_scale
                                   for c, v in zip(changes, values, strict=True)})
    except StudyError as error:
        raise StudyError(f"{source}: {error}" if source else str(error)) from None
    if length is not None:
        scene.characteristic_length = length / scene.unit
    return scene


def held_length(changes, model) -> float | None:
    """The characteristic length to hold while ``changes`` vary: ``model``'s (the study's
    scene's, SI) with the duty factor or the stride among them, None otherwise. A walking
    scene measures it where its legs are at ``t = 0``, which these move though they change
    no segment's length:
    held, the reruns are what the derivatives (which take it as a constant) derive."""
    if any(getattr(c, "key", "") in ("gait.duty", "gait.stride") for c in changes):
        return float(model.characteristic_length)
    return None


def times_at(times: np.ndarray, changes, base_values, values) -> np.ndarray:
    """The samples at ``values``: ``times`` (those at ``base_values``) scaled by the period's
    ratio, so that they fall at the same fractions of the stride; as they are without a
    period among ``changes``."""
    ratio = 1.0
    for change, base, value in zip(changes, base_values, values, strict=True):
        if isinstance(change, PeriodChange):
            ratio = float(value) / float(base)
    return np.asarray(times, dtype=float) * ratio


def run_at(study, changes, times, base_values, values, source: str = "",
           length: float | None = None) -> tuple:
    """``(scene, model, result)``: the study's scene with the parameters ``changes`` at
    ``values`` (its characteristic length ``length`` when given), run at the samples
    ``times`` (those at ``base_values``) moved with the period."""
    from hexapod.algorithms.assembly import assemble
    from hexapod.algorithms.inverse import inverse_dynamics

    scene = scene_at(study, changes, values, source, length)
    model = assemble(scene)
    return scene, model, inverse_dynamics(model, times_at(times, changes, base_values, values))


def changes_at(scene, model, changes) -> tuple:
    """``changes`` at the values of ``scene`` (its ``model`` assembled): each parameter's
    change read again from the scene, the period from the model's laws."""
    from hexapod.sweeps.design_parameters import inertia_parameters

    named = iter(inertia_parameters(scene, [c.name for c in changes
                                            if not isinstance(c, PeriodChange)]))
    return tuple(PeriodChange(name=c.name, value=float(model.cycle_time()))
                 if isinstance(c, PeriodChange) else next(named) for c in changes)


@dataclass
class RerunDesign:
    """The figures of merit and their gradients at any values of parameters that move the
    motion: the study's scene built again with the values and run at each.

    Attributes
    ----------
    study : Study
    changes : tuple of InertiaChange, FrameChange or PeriodChange
        The parameters, at the study's values.
    times : ndarray
        The samples at the study's values.
    strides : float
    values : ndarray (P,)
        The parameters' values of the study's scene, SI.
    length : float or None
        The characteristic length held (:func:`held_length`), SI.
    """

    study: object
    changes: tuple
    times: np.ndarray
    strides: float
    values: np.ndarray
    length: float | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    def at(self, p: np.ndarray) -> tuple[dict, dict]:
        """``(metrics, derivatives)`` at the parameters' values ``p``."""
        from hexapod.algorithms.sensitivity import inverse_sensitivities
        from hexapod.sweeps.design_parameters import moved_model

        key = tuple(np.asarray(p, dtype=float).tolist())
        if key not in self._cache:
            self._cache.clear()
            scene, model, result = run_at(self.study, self.changes, self.times, self.values,
                                          np.array(key), length=self.length)
            changes = changes_at(scene, model, self.changes)
            sensitivity = inverse_sensitivities(model, result, changes,
                                                moved=moved_model(scene, model, changes))
            self._cache[key] = (
                inverse_metrics(model, result, SENSITIVE_FAMILIES, self.strides),
                metric_sensitivities(model, result, sensitivity, SENSITIVE_FAMILIES,
                                     self.strides))
        return self._cache[key]
