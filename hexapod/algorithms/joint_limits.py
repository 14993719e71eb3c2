"""Whether a motion keeps each joint inside its range (the ``limits`` of a revolute or prismatic
joint: a scene file's, or a URDF's ``<limit>``).

Each joint with a range has its coordinate measured from the positions ``q`` as its driver's
row measures it (``Symbolic.ranged``, built by the assembly): the angle from the parent's frame
to the child's about the axis, or the displacement along it. An angle is known from ``q`` up to
whole turns: it is unwrapped along the samples, on the turn that puts the first sample inside
the range when one does (a range beyond ``±pi``), else on the principal one (``(-pi, pi]``).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from hexapod.errors import JointLimitError
from hexapod.model.model import Model

#: rad or m: a coordinate past its limit by no more than this is inside (the positions'
#: round-off: a knee held at its stop has not left its range).
TOLERANCE = 1e-9
#: How many of the other joints that leave their ranges the message names.
NAMED = 3


def _coordinates(model: Model) -> ca.Function:
    """``q -> theta`` of the joints with a range, in joint order."""
    s = model._sym  # the model's expressions: the ranged joints' coordinates
    return ca.Function("ranged_coordinates", [s.q], [s.ranged])


def ranged_coordinates(model: Model, q: np.ndarray) -> tuple[list[int], np.ndarray]:
    """The joints with a range and their coordinates along a motion.

    Parameters
    ----------
    model : Model
    q : ndarray (N, n_q)
        The positions at the samples.

    Returns
    -------
    joints : list of int
        The joints with a range (indices into ``model.joints``), in order.
    values : ndarray (len(joints), N)
        Their coordinates, rad or m; angles on the turn of the module's description.
    """
    joints = [j.index for j in model.joints if j.type.limits is not None]
    if not joints or q.shape[0] == 0:
        return joints, np.zeros((len(joints), q.shape[0]))
    function = model.built_once(("ranged coordinates",), _coordinates)
    n = q.shape[0]
    mapped = function.map(n, "serial") if n > 1 else function
    values = np.asarray(mapped(q.T).full()).reshape(-1, n)
    for row, index in zip(values, joints, strict=True):
        joint = model.joints[index].type
        if joint.coordinate_unit == "angle":
            row[:] = np.unwrap(row) + 2 * np.pi * _turn(row[0], *joint.limits)
    return joints, values


def _turn(angle: float, lower: float, upper: float) -> int:
    """The whole turns to add to the principal ``angle`` so that it lies in ``[lower,
    upper]``, the fewest; 0 when no number of turns does. In closed form: a range of
    ``+-1e9`` rad (a URDF's for a joint without stops) is a hundred million turns wide."""
    first = np.ceil((lower - TOLERANCE - angle) / (2 * np.pi))
    last = np.floor((upper + TOLERANCE - angle) / (2 * np.pi))
    return 0 if first > last else int(min(max(0.0, first), last))


def check_joint_limits(model: Model, times: np.ndarray, q: np.ndarray) -> None:
    """Raise when the motion ``q`` at ``times`` takes a joint out of its range.

    Parameters
    ----------
    model : Model
    times : ndarray (N,)
        The sample times, s.
    q : ndarray (N, n_q)
        The positions there.

    Raises
    ------
    JointLimitError
        Naming the joint that leaves its range first (the earliest sample; of several at that
        sample, the first in the model's order), the time, how far out it is and its range,
        and the next few others that leave theirs.
    """
    joints, values = ranged_coordinates(model, q)
    found = []  # (first sample outside, joint, its value there)
    for index, value in zip(joints, values, strict=True):
        lower, upper = model.joints[index].type.limits
        outside = (value < lower - TOLERANCE) | (value > upper + TOLERANCE)
        if outside.any():
            k = int(np.argmax(outside))
            found.append((k, index, float(value[k])))
    if not found:
        return
    found.sort()
    k, index, value = found[0]
    joint = model.joints[index]
    lower, upper = (float(x) for x in joint.type.limits)
    unit = "rad" if joint.type.coordinate_unit == "angle" else "m"
    side = f"{value - upper:.3g} {unit} above" if value > upper else \
        f"{lower - value:.3g} {unit} below"
    where = f" ({model.source})" if model.source else ""
    others = ", ".join(f"'{model.joints[j].name}' at t = {times[s]:.6g} s"
                       for s, j, _ in found[1:NAMED + 1])
    more = len(found) - 1 - NAMED
    others += f" and {more} more" if more > 0 else ""
    raise JointLimitError(
        f"model '{model.name}'{where}: joint '{joint.name}' leaves its range [{lower:g}, "
        f"{upper:g}] {unit} at t = {times[k]:.6g} s ({value:.6g} {unit}, {side})"
        + (f"; also leaving theirs: {others}" if others else ""),
        joint.name, float(times[k]), value, (lower, upper))
