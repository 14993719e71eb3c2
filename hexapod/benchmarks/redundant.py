"""The redundant case: Bricard's mechanism (IFToMM benchmark A04), an over-constrained loop
with one redundant row at every pose. (The spatial N-four-bar, ``n_four_bar(dimension=3)`` of
:mod:`hexapod.benchmarks.singular`, is redundant as well.)
"""

from __future__ import annotations

import numpy as np

from hexapod.benchmarks import jets
from hexapod.benchmarks.reference import (
    Case,
    G,
    MinimalModel,
    OneDof,
    minimal_reference,
    rod_inertia,
)
from hexapod.scene import Revolute, Scene, SpatialBody

#: Bricard's mechanism, IFToMM benchmark A04, as in RehabEngGroup/MBSbenchmarksInOpenSim
#: (src/A04-BricardsMechanism): five bars of 1 m and 1 kg, square section 0.1 m, joined in a
#: loop with the ground by six revolute joints at O, P1 ... P5 (the corners of a unit cube
#: visited by the loop), each axis normal to both bars it joins; gravity 9.81 along -y,
#: released at rest, 10 s.
BRICARD_POINTS = np.array([[0, 0, 0], [1, 0, 0], [1, -1, 0], [1, -1, 1], [0, -1, 1],
                           [0, 0, 1]], dtype=float)
BRICARD_AXES = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]],
                        dtype=float)


def _bricard_minimal() -> MinimalModel:
    """The Bricard loop in the angle ``t`` of its ground joint O. Opening the loop at P5, the
    chain's joint angles (from the initial pose) are ``(t, u, t, u, t)`` with
    ``sin t + sin u + sin t sin u = 0`` (found for this linkage by solving the closure
    numerically and checked to round-off; the threefold symmetry of the skew hexagon gives
    the repetition), so ``u = -arcsin(sin t / (1 + sin t))`` on the branch through the
    initial pose: valid for ``-pi/6 < t < 7 pi / 6``, which the motion from rest keeps to."""
    bars = np.diff(np.vstack([BRICARD_POINTS, BRICARD_POINTS[:1]]), axis=0)[:5]
    inertia = {}
    for k in range(5):
        axis = int(np.argmax(np.abs(bars[k])))
        inertia[f"bar_{k + 1}"] = (1.0, rod_inertia(1.0, 1.0, axis, 0.1))

    def kinematics(x):
        t = x[0]
        s = jets.sin(t)
        u = -jets.arcsin(s / (1.0 + s))
        angles = (t, u, t, u, t)
        R = jets.Jet.constant(np.eye(3))
        start = jets.Jet.constant(np.zeros(3))
        frames, points = {}, {}
        for k in range(5):
            R = R @ jets.rotation(BRICARD_AXES[k], angles[k])
            end = start + R @ bars[k]
            frames[f"bar_{k + 1}"] = ((start + end) * 0.5, R)
            points[f"P{k + 1}"] = end
            start = end
        return frames, points

    return MinimalModel(kinematics, inertia, [0.0, -G, 0.0])


def bricard(t_end: float = 10.0) -> Case:
    """IFToMM benchmark A04, Bricard's mechanism (data: :data:`BRICARD_POINTS`): five bars and
    the ground in a loop of six revolute joints. Grubler-Kutzbach counts 5 x 6 - 6 x 5 = 0
    degrees of freedom; the special axes leave one, so one row of the 30 is redundant at every
    pose (the engine names a row of the loop-closing joint P5).

    Reference: Lagrange's equation on the closed-form configuration curve
    (:func:`_bricard_minimal`, tabulated by :class:`OneDof`), DOP853 at 1e-12. Observable:
    the five bars' centres of mass (the benchmark reports the point P3, the joint of bars 3
    and 4 here)."""
    scene = Scene("bricard", dimension=3)
    scene.gravity = np.array([0.0, -G, 0.0])
    names = [f"bar_{k}" for k in range(1, 6)]
    for k, name in enumerate(names):
        a, b = BRICARD_POINTS[k], BRICARD_POINTS[k + 1]
        axis = int(np.argmax(np.abs(b - a)))
        scene.add(SpatialBody(name, 1.0, np.diag(rod_inertia(1.0, 1.0, axis, 0.1)),
                              position=(a + b) / 2))
    parents = ["ground"] + names
    children = names + ["ground"]
    labels = ["O", "P1", "P2", "P3", "P4", "P5"]
    for k in range(6):
        scene.add(Revolute(labels[k], parents[k], children[k], origin=BRICARD_POINTS[k],
                           axis=BRICARD_AXES[k]))
    model = _bricard_minimal()
    # released at rest at t = 0 it swings to t = pi and back (the potential is symmetric)
    reference, accelerations = minimal_reference(model, [0.0], [0.0], t_end, tuple(names), 3,
                                                  rates=OneDof(model, -0.15, np.pi + 0.15).rates)
    return Case(scene.name, scene, t_end,
                "over-constrained loop: Grubler counts 0 degrees of freedom, there is 1 and a "
                "redundant row at every pose", "redundant", tuple(names), reference,
                accelerations, length=1.0, dof=1, counted_dof=0, redundant=1,
                source="IFToMM/MBS benchmark A04 (Gonzalez et al. 2006), geometry as in "
                       "RehabEngGroup/MBSbenchmarksInOpenSim src/A04-BricardsMechanism",
                notes=["the benchmark's published P3(t) is not stored; the reference is the "
                       "1-DOF Lagrange equation on the closed-form configuration curve"])
