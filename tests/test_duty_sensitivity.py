"""Design sensitivities with respect to the gait's duty factor (``gait.duty``), its stride and
period kept: the feet's paths, the coupled joints, the footholds and the feet's load-sharing
weights all change with it (:mod:`legs.duty`).

References, independent of the derivative laws' closed forms:

* the laws themselves rebuilt with the duty moved, by the fourth-order central difference
  (step 1e-4: its truncation, some 1e-8 of the largest value at most where the stencil
  straddles a touch-down, the paths being C4 there) or, for the weights (C2), the second-order
  one (step 1e-6: 1.5e-9 measured);
* the robot rebuilt with the duty moved (its characteristic length held: see
  ``docs/design.md``), against central differences of whole runs;
* the motion's own geometry: a foot in stance moves back by half the stride per unit of duty,
  the trunk (a guide) does not move.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import hexapod as hx
from hexapod.scene.contacts import Foothold, stance_weight, stance_weight_rate
from hexapod.scene.joints import Contact
from hexapod.sweeps.design_parameters import inertia_parameters
from hexapod.sweeps.metric_derivatives import SENSITIVE_FAMILIES, metric_sensitivities
from hexapod.sweeps.metrics import inverse_metrics
from legs.carried import TrunkSway
from legs.robot import cockroach_description, walking_pattern
from legs.stepping import GaitCoupled
from legs.walker import StepPath, robot_scene

PERIOD = 0.5
TIMES = np.linspace(0.0, 2 * PERIOD, 4001)
#: Samples of the walking robot over a stride: both tripods' lift-offs (0, 0.25 s) and
#: touch-downs (0.2, 0.45 s) among them, none at a swing's middle, where the coupled joints
#: stop and the positive work has a kink (central differences converge there as the step,
#: not its square).
SAMPLES = np.array([0.0, 0.07, 0.2, 0.25, 0.33, 0.45])


def _stencil(law_at, h: float = 1e-4) -> np.ndarray:
    """The fourth-order central difference of ``law_at(delta)`` (a law with the duty moved by
    ``delta``): values, rates and accelerations at :data:`TIMES`."""
    def f(delta):
        return np.array(law_at(delta).evaluate(TIMES))

    return (-f(2 * h) + 8 * f(h) - 8 * f(-h) + f(-2 * h)) / (12 * h)


@pytest.mark.parametrize("law", [StepPath(0.3, 0.12, 0.0, 0.6, PERIOD, 0.25),
                                 StepPath(0.0, 0.0, 0.05, 0.7, PERIOD, 0.5),
                                 GaitCoupled(0.3, "lift", 0.6, PERIOD, 0.25),
                                 GaitCoupled(0.3, "reach", 0.75, PERIOD, 0.1)],
                         ids=["fore-aft", "height", "lift", "reach"])
def test_the_derivative_laws_against_the_laws_rebuilt(law):
    """Value, rate and acceleration, over two strides (swings and stances, each switch): the
    path rebuilt with its duty moved and its footholds moved back by half its advance."""
    value, derivative = law.design_parameter("gait.duty")
    assert value == law.duty
    if isinstance(law, StepPath):
        reference = _stencil(lambda d: replace(law, duty=law.duty + d,
                                               start=law.start - law.advance * d / 2))
    else:
        reference = _stencil(lambda d: replace(law, duty=law.duty + d))
    exact = np.array(derivative.evaluate(TIMES))
    for m in range(3):
        assert np.abs(exact[m] - reference[m]).max() <= 1e-7 * np.abs(reference[m]).max(), m


def test_the_weights_and_footholds_follow_the_duty():
    contact = Contact("foot", "ground", "tarsus", period=PERIOD, duty=0.6, lift_off=0.25,
                      foothold=[0.2, 0.1, 0.0], advance=[0.4, 0.0, 0.0])
    h = 1e-6
    reference = (stance_weight(replace(contact, duty=0.6 + h), TIMES)
                 - stance_weight(replace(contact, duty=0.6 - h), TIMES)) / (2 * h)
    exact = stance_weight_rate(contact, TIMES)
    assert np.abs(exact - reference).max() <= 1e-7 * np.abs(exact).max()
    assert np.abs(exact).max() > 1.0  # the ramps sampled
    shift = Foothold(contact, 0).design_parameter("gait.duty")[1].evaluate(TIMES)[0]
    assert np.all(shift == -0.2)
    assert Foothold(contact, 1).design_parameter("gait.duty")[1].evaluate(0.0)[0] == 0.0
    turning = Contact("foot", "ground", "tarsus", period=PERIOD, duty=0.6, turn=10.0)
    with pytest.raises(ValueError, match="turn"):
        Foothold(turning, 0).design_parameter("gait.duty")


def test_laws_whose_duty_is_not_derived_say_so():
    with pytest.raises(ValueError, match="planned from the feet's schedule"):
        TrunkSway(0.0, 0.1, (0.01,), (0.0,), PERIOD).design_parameter("gait.duty")
    assert TrunkSway(0.0, 0.1, period=PERIOD).design_parameter("gait.duty") is None  # level
    with pytest.raises(ValueError, match="steps of the ground"):
        StepPath(lift=0.05, rises_at=(1.0,), rises=(0.02,)).design_parameter("gait.duty")


def _robot(duty: float, length: float | None = None, stride: float | None = None) -> hx.Scene:
    """The built-in walking robot at ``duty``, its stride (or ``stride``) and period kept (its
    description's gait changed), and its characteristic length ``length`` when given."""
    description = cockroach_description(walking_pattern("tripod", None), PERIOD)
    gait = replace(description.gait, duty=duty)
    if stride is not None:
        gait = replace(gait, stride=stride)
    scene = robot_scene(replace(description, gait=gait))
    scene.characteristic_length = length
    return scene


@pytest.mark.slow  # two robots built again and run, 4 s
def test_the_stride_against_central_differences():
    """The stride (the period and duty kept: the speed changes) against the robot rebuilt at
    ``s (1 +- 1e-5)``, its characteristic length held: every force, effort and ground force
    within 1e-6 of the largest per unit relative change (the motion is smooth in it)."""
    scene = _robot(0.6)
    model = hx.assemble(scene)
    result = hx.inverse_dynamics(model, SAMPLES, frame="world")
    change, = inertia_parameters(scene, ["gait.stride"])
    sensitivity = hx.inverse_sensitivities(model, result, [change])
    h = 1e-5 * change.value
    ahead, behind = (hx.inverse_dynamics(hx.assemble(_robot(
        0.6, model.characteristic_length, change.value + s * h)), SAMPLES, frame="world")
        for s in (1.0, -1.0))
    for name in ("effort", "force", "torque", "ground_force"):
        value, exact = getattr(result, name), getattr(sensitivity, name)[..., 0]
        reference = (getattr(ahead, name) - getattr(behind, name)) / (2 * h)
        finite = np.isfinite(value)
        assert np.abs(change.value * (exact - reference)[finite]).max() <= \
            1e-6 * np.abs(value[finite]).max(), name


@pytest.mark.slow  # four robots built again and run, 8 s; bench_sensitivity checks 10 points
def test_the_duty_against_central_differences():
    """Every position, force, effort and ground force (1e-6 of the largest per unit relative
    change), and every figure of merit (1e-6 of its derivative), against the
    robot rebuilt at ``0.6 +- h`` (its characteristic length held), Richardson-extrapolated
    from ``h`` = 2e-5 and 1e-5. A plain difference's truncation is largest where a foot
    touches down at a sample (its weight's ramp, a cubic over 6 % of the stance, has third
    derivatives of order 1e4 in the duty): 2.6e-5 of the largest effort at h = 1e-5, falling
    as h^2, and round-off takes over below 1e-6."""
    scene = _robot(0.6)
    model = hx.assemble(scene)
    result = hx.inverse_dynamics(model, SAMPLES, frame="world")
    sensitivity = hx.inverse_sensitivities(model, result,
                                           inertia_parameters(scene, ["gait.duty"]))
    derivatives = metric_sensitivities(model, result, sensitivity)

    def run(duty: float):
        moved = hx.assemble(_robot(duty, model.characteristic_length))
        ahead = hx.inverse_dynamics(moved, SAMPLES, frame="world")
        return ahead, inverse_metrics(moved, ahead, SENSITIVE_FAMILIES, 1.0)

    def difference(h: float):
        (ahead, metrics_ahead), (behind, metrics_behind) = run(0.6 + h), run(0.6 - h)
        return ({name: (getattr(ahead, name) - getattr(behind, name)) / (2 * h)
                 for name in ("q", "effort", "force", "torque", "ground_force")},
                {column: (metrics_ahead[column] - metrics_behind[column]) / (2 * h)
                 for column in derivatives})

    (fine, fine_metrics), (coarse, coarse_metrics) = difference(1e-5), difference(2e-5)
    for name, plain in fine.items():
        value, exact = getattr(result, name), getattr(sensitivity, name)[..., 0]
        reference = (4 * plain - coarse[name]) / 3
        finite = np.isfinite(value)
        assert np.abs(0.6 * (exact - reference)[finite]).max() <= \
            1e-6 * np.abs(value[finite]).max(), name
    values = inverse_metrics(model, result, SENSITIVE_FAMILIES, 1.0)
    for column, exact in derivatives.items():
        reference = (4 * fine_metrics[column] - coarse_metrics[column]) / 3
        # relative to the derivative, or to the value per unit relative change if larger
        assert abs(exact[0] - reference) <= 1e-6 * max(abs(reference),
                                                       abs(values[column]) / 0.6), column


def test_all_feet_weights_in_one_pass_are_each_feets_own():
    """The ground-force policy reads every foot's stance and weight at a state in one pass
    (:class:`~hexapod.model.infos.ContactSchedules`): the same arithmetic as each contact's
    own on an array of times (the inverse dynamics' samples), bit for bit, at touch-downs,
    lift-offs and inside the ramps, a foot always down (duty 1) weighing 1; one contact at a
    scalar time differs by round-off (NumPy's scalar power: 1 ulp in a twentieth of cases)."""
    from types import SimpleNamespace

    from hexapod.model.infos import ContactSchedules
    from hexapod.scene.contacts import in_stance

    contacts = [Contact(f"c{k}", "ground", "foot", period=PERIOD, duty=duty, lift_off=lift,
                        ramp=ramp)
                for k, (duty, lift, ramp) in enumerate([(0.6, 0.0, 0.1), (0.6, 0.5, 0.25),
                                                         (0.75, 0.3, 0.1), (1.0, 0.0, 0.1)])]
    together = ContactSchedules([SimpleNamespace(schedule=c) for c in contacts])
    times = np.concatenate([TIMES, [0.2 * PERIOD, 0.4 * PERIOD, 0.15 * PERIOD]])
    each = np.array([stance_weight(c, times) for c in contacts])
    for k, t in enumerate(times):
        stance, weight = together(float(t))
        assert np.array_equal(stance, [bool(in_stance(c, t)) for c in contacts])
        assert np.array_equal(weight, each[:, k])
        assert np.allclose(weight, [float(stance_weight(c, t)) for c in contacts],
                           rtol=0, atol=1e-15)
    assert together(0.123)[1][-1] == 1.0
