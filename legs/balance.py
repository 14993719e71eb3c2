"""The whole robot's centre of pressure along a walk, and the trunk's sway planned with it.

The trunk planner (:mod:`legs.trunk_path`) predicts the centre of pressure with a lumped model
(the trunk's mass, each leg's at the middle of its hip and foot). The whole robot's differs by
centimetres where the legs' own inertia counts (a foot carried ahead of an ankle, Solo12's
legs), enough for a foot to slip or pull near a touch-down. With ``gait.trunk = "whole-body"``
the plan is corrected by the whole robot (:func:`refine_plan`): the walk's kinematics at the
plan's samples (the guides' motion, every body's position, velocity and acceleration) gives the
whole robot's zero-moment point (:func:`zero_moment_point`: where on the ground the ground's
wrench, every body's momentum rate less its weight, has no moment along the ground), whose
difference from the lumped model's prediction is added to the lumped model as a known term; the
sway is planned again, until the two agree within :data:`TOLERANCE`. The difference depends on
the sway only through the legs' motion relative to the trunk, so a few rounds settle it. The
guides' kinematics is assembled once; each round's trunk laws are swapped into it, its builds
shared (:meth:`hexapod.Model.with_laws`).
"""

from __future__ import annotations

import hashlib

import numpy as np

#: m: the whole body's centre of pressure and the plan's agree within this at every sample.
TOLERANCE = 5e-3
#: The most rounds of the correction.
ROUNDS = 4


def momentum_rates(model, result) -> tuple[np.ndarray, np.ndarray]:
    """The sums over the bodies of ``m (a - g)`` at each centre of mass and of their moments
    about the world's origin plus ``R (I w' + w x I w)`` (``w`` the body-frame angular
    velocity), each (N, 3), for the motion of ``result`` (an inverse dynamics of ``model``, or
    of its guides' kinematics): the wrench the ground and the other external forces give."""
    from hexapod.spatial import rotation_from_euler_parameters

    gravity = np.asarray(model.gravity, dtype=float)
    force = np.zeros((result.times.size, 3))
    moment = np.zeros_like(force)
    for body in model.bodies:
        q, v, a = result.q[:, body.q], result.v[:, body.v], result.v_dot[:, body.v]
        f = body.mass * (a[:, :3] - gravity)
        inertia = np.asarray(body.inertia, dtype=float)
        spin = a[:, 3:] @ inertia.T + np.cross(v[:, 3:], v[:, 3:] @ inertia.T)
        rotation = np.array([rotation_from_euler_parameters(e) for e in q[:, 3:]])
        force += f
        moment += np.cross(q[:, :3], f) + np.einsum("nij,nj->ni", rotation, spin)
    return force, moment


def zero_moment_point(model, result, axes) -> np.ndarray:
    """The world ``x, y`` (N, 2) of the zero-moment point of the motion of ``result`` (an
    inverse dynamics of ``model``, or of its guides' kinematics) on the ground plane through
    the origin whose axes are the rows of ``axes`` (``t_1``, ``t_2``, the normal ``n``): with
    ``F`` and ``M`` the :func:`momentum_rates`, the point ``a t_1 + b t_2`` with ``a =
    -M.t_2 / F.n`` and ``b = M.t_1 / F.n``."""
    force, moment = momentum_rates(model, result)
    t1, t2, n = np.asarray(axes, dtype=float)
    pushed = force @ n
    point = (-(moment @ t2) / pushed)[:, None] * t1 + ((moment @ t1) / pushed)[:, None] * t2
    return point[:, :2]


def refine_plan(scene, plan, replan, laws, to_plan) -> tuple:
    """The trunk's plan corrected by the whole robot (see the module's notes), the largest
    difference left (m), and the guides' kinematics with the plan's laws (for more work on
    the walk's motion without assembling it again).

    Parameters
    ----------
    scene : Scene
        The walking scene, its trunk guides ``trunk/x`` and ``trunk/y`` following ``plan``;
        their laws are replaced by the refined plan's.
    plan : TrunkPlan
        The lumped model's plan (its predicted centre of pressure at its samples).
    replan : callable
        ``replan(correction) -> TrunkPlan``, the plan with a known term added.
    laws : callable
        ``laws(plan) -> (x_law, y_law)``: the trunk's guides' laws for a plan.
    to_plan : callable
        ``to_plan(points, times) -> points``: world ``x, y`` in the plan's frame (a turning
        trunk's plan is that of a straight walk).
    """
    import hexapod as hx

    samples = plan.pressure.shape[0]
    times = np.arange(samples) * plan.period / samples
    axes = scene.ground.terrain.axes()
    kinematics = hx.assemble(scene).guidance.kinematics  # the guides as drivers
    index = {d.name: d.law for d in kinematics.drivers}  # the trunk's sway: never constant
    correction, model = np.zeros((samples, 2)), kinematics
    for done in range(ROUNDS + 1):
        result = hx.inverse_dynamics(model, times, check_limits=False)
        whole = to_plan(zero_moment_point(model, result, axes), times)
        gap = float(np.abs(whole - plan.pressure).max())
        if gap < TOLERANCE or done == ROUNDS:
            break
        correction = correction + whole - plan.pressure
        plan = replan(correction)
        trunk = dict(zip(("trunk/x", "trunk/y"), laws(plan), strict=True))
        changed = list(kinematics.laws)
        for name, law in trunk.items():
            scene.drivers[name].law = changed[index[name]] = law
        digest = hashlib.sha256(repr((kinematics.digest, done, trunk)).encode()).hexdigest()
        model = kinematics.with_laws(tuple(changed), digest, share_built=True)
    return plan, gap, model
