"""The three tests every joint must pass.

For each joint type, in space and in the plane, with spatial bodies, planar bodies, particles
and the ground as parent:

1. the residual vanishes at a pose built to satisfy the joint;
2. the null space of its ``Phi_v`` equals the motions it allows: the pair moving as one rigid
   body plus the joint's own relative motions, written here independently of the residuals
   (a wrong residual passes a finite-difference test of itself, not this one);
3. ``gamma`` (and ``nu``) match finite differences along an actual motion: both bodies on
   smooth Lie-group curves that keep the joint satisfied, with drivers whose laws follow it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

import hexapod as hx
from hexapod.spatial import (
    Placement,
    euler_parameters_from_rotation,
    orthonormal_complement,
    rotation_2d,
)

RNG_SEED = 20261122


def rot(axis, angle):
    return hx.spatial.rotation_about_axis(axis, angle)


def unit(rng, n):
    x = rng.normal(size=n)
    return x / np.linalg.norm(x)


def random_rotation(rng):
    return rot(unit(rng, 3), rng.uniform(0, np.pi))


# ------------------------------------------------------------------ smooth scalar motions

@dataclass(frozen=True)
class Wave:
    """``offset + amplitude sin(omega t + phase)`` and its use as a driver law."""

    offset: float
    amplitude: float
    omega: float
    phase: float = 0.0

    def __call__(self, t):
        return self.offset + self.amplitude * np.sin(self.omega * t + self.phase)

    def law(self):
        c, s = np.sin(self.phase), np.cos(self.phase)
        return hx.scene.Harmonic(offset=self.offset, cos=[self.amplitude * c],
                                 sin=[self.amplitude * s], frequency=self.omega / (2 * np.pi))


# ------------------------------------------------------------------ joint cases

@dataclass
class Case:
    """A joint between two bodies that follow smooth curves keeping the joint satisfied."""

    joint: str
    dimension: int
    parent: str  # "spatial", "planar", "particle" or "ground"
    child: str
    seed: int

    def __post_init__(self):
        rng = np.random.default_rng(self.seed)
        d = self.dimension
        self.rng = rng
        self.axis = unit(rng, 3) if d == 3 else unit(rng, 2)
        self.axis2 = unit(rng, 3) if d == 3 else None
        if d == 3:  # a universal joint's second axis is perpendicular to the first
            self.axis2 = np.cross(self.axis, self.axis2)
            self.axis2 /= np.linalg.norm(self.axis2)
        self.frame_p = self._frame(self.parent)
        self.frame_c = self._frame(self.child)
        self.length = rng.uniform(0.5, 1.5)
        self.com = {k: (np.zeros(d) if kind in ("particle", "ground") else rng.normal(size=d) * .3)
                    for k, kind in (("p", self.parent), ("c", self.child))}
        # parent motion
        self.p_waves = [Wave(rng.normal(), rng.uniform(.2, .6), rng.uniform(.5, 2)) for _ in
                        range(5)]
        self.p_axes = [unit(rng, 3), unit(rng, 3)]
        self.p_rotation0 = random_rotation(rng) if d == 3 else rng.uniform(-3, 3)
        # joint coordinate: a revolute angle that crosses +-pi, a displacement
        self.angle = Wave(2.6, 1.2, 1.7, 0.3)
        self.slide = Wave(0.2, 0.5, 1.3, 0.1)
        self.rel_waves = [Wave(rng.normal(), rng.uniform(.3, .9), rng.uniform(.5, 2)) for _ in
                          range(3)]
        self.rel_axes = [unit(rng, 3), unit(rng, 3)]

    def _frame(self, kind):
        rng = self.rng
        if kind == "particle":
            return Placement(np.zeros(self.dimension))
        rotation = random_rotation(rng) if self.dimension == 3 else rng.uniform(-3, 3)
        return Placement(rng.normal(size=self.dimension) * 0.5, rotation)

    # poses of the reference frames ------------------------------------------------------

    def parent_pose(self, t) -> Placement:
        d = self.dimension
        if self.parent == "ground":
            return Placement.identity(d)
        if self.child == "ground":  # the ground is the child: the parent moves about it
            world = self.frame_c @ self.relative(t).inverse() @ self.frame_p.inverse()
            return Placement(world.position) if self.parent == "particle" else world
        w = self.p_waves
        position = np.array([w[0](t), w[1](t), w[2](t)])[:d]
        if self.parent == "particle":
            return Placement(position)
        if d == 2:
            return Placement(position, self.p_rotation0 + w[3](t))
        R = self.p_rotation0 @ rot(self.p_axes[0], w[3](t)) @ rot(self.p_axes[1], w[4](t))
        return Placement(position, R)

    def relative(self, t) -> Placement:
        """The child joint frame in the parent joint frame: the joint's own motion."""
        d = self.dimension
        w = self.rel_waves
        if self.joint == "revolute":
            return Placement(np.zeros(d), rot(self.axis, self.angle(t)) if d == 3
                             else self.angle(t))
        if self.joint == "prismatic":
            return Placement(self.slide(t) * self.axis, np.eye(d))
        if self.joint == "fixed":
            return Placement.identity(d)
        if self.joint == "spherical":
            return Placement(np.zeros(3), rot(self.rel_axes[0], w[0](t))
                             @ rot(self.rel_axes[1], w[1](t)))
        if self.joint == "universal":  # about the parent's axis, then the child's
            return Placement(np.zeros(3), rot(self.axis, w[0](t)) @ rot(self.axis2, w[1](t)))
        if self.joint == "cylindrical":  # in the plane: a pin sliding and turning in a slot
            return Placement(self.slide(t) * self.axis, rot(self.axis, self.angle(t)) if d == 3
                             else self.angle(t))
        if self.joint in ("planar", "point-on-plane") and d == 3:
            u, v = orthonormal_complement(self.axis)
            offset = w[0](t) * u + w[1](t) * v  # in the plane normal to the axis
            if self.joint == "planar":
                return Placement(offset, rot(self.axis, w[2](t)))
            return Placement(offset, rot(self.rel_axes[0], w[2](t)) @ rot(self.rel_axes[1],
                                                                           w[0](t)))
        if self.joint == "point-on-plane":  # in the plane: a point on the line normal to axis
            line = np.array([-self.axis[1], self.axis[0]])
            return Placement(w[0](t) * line, w[1](t))
        # distance: the child point on a sphere (circle) about the parent point
        if d == 3:
            direction = rot(self.rel_axes[0], w[0](t)) @ rot(self.rel_axes[1], w[1](t)) @ [1, 0, 0]
            return Placement(self.length * direction, rot(self.rel_axes[1], w[2](t)))
        return Placement(self.length * np.array([np.cos(w[0](t)), np.sin(w[0](t))]), w[1](t))

    def child_pose(self, t) -> Placement:
        if self.child == "ground":
            return Placement.identity(self.dimension)
        world = self.parent_pose(t) @ self.frame_p @ self.relative(t)
        if self.child == "particle":
            return Placement(world.position)
        return world @ self.frame_c.inverse()

    def planar_angle(self, which, t):
        """Planar angle coordinate of the parent ("p") or child ("c"), unwrapped in t."""
        if which == "p":
            return self.p_rotation0 + self.p_waves[3](t)
        base = self.planar_angle("p", t) if self.parent == "planar" else 0.0
        rel = {"revolute": self.angle(t), "cylindrical": self.angle(t),
               "distance": self.rel_waves[1](t),
               "point-on-plane": self.rel_waves[1](t)}.get(self.joint, 0.0)
        return base + self.frame_p.angle + rel - self.frame_c.angle

    # the scene and its coordinates ------------------------------------------------------

    def _body(self, name, kind, pose, com):
        rng = np.random.default_rng([self.seed, ord(name)])
        mass = rng.uniform(0.5, 2.0)
        if kind == "spatial":
            moments = rng.uniform(0.5, 1.0, size=3)
            return hx.scene.SpatialBody(name, mass, moments, com=com, position=pose.position,
                                        rotation=pose.rotation,
                                        inertia_rotation=random_rotation(rng))
        if kind == "planar":
            return hx.scene.PlanarBody(name, mass, rng.uniform(.1, .5), com=com,
                                       position=pose.position, angle=pose.angle)
        return hx.scene.Particle(name, mass, position=pose.position)

    def scene(self, drive=True) -> hx.Scene:
        scene = hx.Scene(f"{self.joint}-case", dimension=self.dimension)
        parent = "ground" if self.parent == "ground" else "P"
        child = "ground" if self.child == "ground" else "C"
        if self.parent != "ground":
            scene.add(self._body("P", self.parent, self.parent_pose(0.0), self.com["p"]))
        if self.child != "ground":
            scene.add(self._body("C", self.child, self.child_pose(0.0), self.com["c"]))
        kwargs = dict(parent_frame=self.frame_p, child_frame=self.frame_c)
        cls = hx.scene.joints.JOINT_TYPES[self.joint]
        if self.joint in AXIAL or self.joint == "revolute" and self.dimension == 3:
            kwargs["axis"] = self.axis
        if self.joint == "universal":
            kwargs["axis2"] = self.axis2
        if self.joint == "distance":
            kwargs["length"] = self.length
        scene.add(cls("J", parent, child, **kwargs))
        if drive and self.joint in ("revolute", "prismatic"):
            law = (self.angle if self.joint == "revolute" else self.slide).law()
            scene.add(hx.scene.JointDriver("drive", "J", law))
        if drive and self.parent == "planar":
            wave = self.p_waves[3]
            law = Wave(self.p_rotation0 + wave.offset, wave.amplitude, wave.omega, wave.phase)
            scene.add(hx.scene.CoordinateDriver("hold", "P", "angle", law.law()))
        return scene

    def coordinates(self, model, t) -> np.ndarray:
        q = np.zeros(model.n_q)
        for info, kind, pose, com, which in (
                (self._info(model, "P"), self.parent, self.parent_pose(t), self.com["p"], "p"),
                (self._info(model, "C"), self.child, self.child_pose(t), self.com["c"], "c")):
            if info is None:
                continue
            centre = pose.position + pose.rotation @ com
            if kind == "spatial":
                q[info.q] = np.concatenate([centre, euler_parameters_from_rotation(
                    pose.rotation)])
            elif kind == "planar":
                q[info.q] = np.concatenate([centre, [self.planar_angle(which, t)]])
            else:
                q[info.q] = centre
        return q

    @staticmethod
    def _info(model, name):
        return model.bodies[model.body_index[name]] if name in model.body_index else None


AXIAL = ("prismatic", "cylindrical", "planar", "point-on-plane", "universal")

SPATIAL = [("revolute", "spatial", "spatial"), ("revolute", "ground", "spatial"),
           ("revolute", "spatial", "ground"), ("prismatic", "spatial", "spatial"),
           ("prismatic", "ground", "spatial"), ("spherical", "spatial", "spatial"),
           ("spherical", "particle", "particle"), ("spherical", "spatial", "particle"),
           ("fixed", "spatial", "spatial"), ("fixed", "ground", "spatial"),
           ("distance", "spatial", "spatial"), ("distance", "particle", "spatial"),
           ("distance", "particle", "particle"),
           ("universal", "spatial", "spatial"), ("universal", "ground", "spatial"),
           ("cylindrical", "spatial", "spatial"), ("cylindrical", "ground", "spatial"),
           ("cylindrical", "spatial", "ground"), ("planar", "spatial", "spatial"),
           ("planar", "ground", "spatial"), ("point-on-plane", "spatial", "spatial"),
           ("point-on-plane", "ground", "spatial"), ("point-on-plane", "ground", "particle")]
PLANAR = [("revolute", "planar", "planar"), ("revolute", "ground", "planar"),
          ("revolute", "particle", "planar"), ("revolute", "particle", "particle"),
          ("prismatic", "planar", "planar"), ("prismatic", "ground", "planar"),
          ("fixed", "planar", "planar"), ("distance", "planar", "planar"),
          ("distance", "particle", "particle"), ("distance", "ground", "particle"),
          ("cylindrical", "planar", "planar"), ("cylindrical", "ground", "particle"),
          ("point-on-plane", "planar", "planar"), ("point-on-plane", "ground", "planar"),
          ("point-on-plane", "ground", "particle")]
CASES = ([Case(j, 3, p, c, k) for k, (j, p, c) in enumerate(SPATIAL)]
         + [Case(j, 2, p, c, 100 + k) for k, (j, p, c) in enumerate(PLANAR)])


def case_id(case):
    return f"{case.joint}-{case.dimension}d-{case.parent}-{case.child}"


def _revolute_drivable(case):
    return not (case.joint == "revolute" and "particle" in (case.parent, case.child))


# ------------------------------------------------------------------ allowed motions

def _move(v, info, pose, linear, angular, about):
    """Set the velocities of one body moving with angular velocity ``angular`` about the point
    ``about`` plus a translation ``linear`` (world components)."""
    arm = pose.position - about
    if arm.size == 3:
        v_com = linear + np.cross(angular, arm)
    else:
        v_com = linear + angular * np.array([-arm[1], arm[0]])
    v[info.v.start:info.v.start + arm.size] = v_com
    if info.kind == "spatial":
        v[info.v.start + 3:info.v.stop] = pose.rotation.T @ angular
    elif info.kind == "planar":
        v[info.v.start + 2] = angular


def rigid_motion(case, model, q, linear, angular):
    """Velocities of every body when the whole pair moves as one rigid body with the twist
    (linear velocity of the world origin, angular velocity), both world components."""
    v = np.zeros(model.n_v)
    for info in model.bodies:
        _move(v, info, model.body_pose(q, info.index), linear, angular,
              np.zeros(case.dimension))
    return v


def child_motion(case, model, q, linear, angular, about):
    """The child alone moving with angular velocity ``angular`` about the point ``about`` plus a
    translation ``linear``: the parent stays still."""
    v = np.zeros(model.n_v)
    info = model.bodies[model.body_index["C"]]
    _move(v, info, model.body_pose(q, info.index), linear, angular, about)
    return v


def allowed_motions(case, model, q):
    d = case.dimension
    zero = np.zeros(d)
    moves = []
    if case.parent != "ground" and case.child != "ground":
        basis = np.eye(d)
        moves += [rigid_motion(case, model, q, e, np.zeros(3) if d == 3 else 0.0) for e in basis]
        spins = np.eye(3) if d == 3 else [1.0]
        moves += [rigid_motion(case, model, q, zero, w) for w in spins]
    t = 0.0
    joint_world = case.parent_pose(t) @ case.frame_p @ case.relative(t)
    origin = joint_world.position
    spins = np.eye(3) if d == 3 else [1.0]
    no_spin = np.zeros(3) if d == 3 else 0.0
    if case.joint == "revolute":
        axis = joint_world.rotation @ case.axis if d == 3 else 1.0
        moves.append(child_motion(case, model, q, zero, axis, origin))
    elif case.joint == "prismatic":
        axis = (case.parent_pose(t) @ case.frame_p).rotation @ case.axis
        moves.append(child_motion(case, model, q, axis, no_spin, origin))
    elif case.joint == "spherical":
        moves += [child_motion(case, model, q, zero, w, origin) for w in spins]
    elif case.joint == "universal":
        parent_axis = (case.parent_pose(t) @ case.frame_p).rotation @ case.axis
        moves += [child_motion(case, model, q, zero, w, origin)
                  for w in (parent_axis, joint_world.rotation @ case.axis2)]
    elif case.joint == "cylindrical":
        axis = (case.parent_pose(t) @ case.frame_p).rotation @ case.axis
        moves.append(child_motion(case, model, q, axis, no_spin, origin))
        if case.child != "particle":
            moves.append(child_motion(case, model, q, zero, axis if d == 3 else 1.0, origin))
    elif case.joint in ("planar", "point-on-plane"):
        parent_frame = (case.parent_pose(t) @ case.frame_p).rotation
        if d == 3:
            in_plane = [parent_frame @ e for e in orthonormal_complement(case.axis)]
        else:
            in_plane = [parent_frame @ np.array([-case.axis[1], case.axis[0]])]
        moves += [child_motion(case, model, q, e, no_spin, origin) for e in in_plane]
        if case.joint == "planar":
            moves.append(child_motion(case, model, q, zero, parent_frame @ case.axis, origin))
        elif case.child != "particle":
            moves += [child_motion(case, model, q, zero, w, origin) for w in spins]
    elif case.joint == "distance":
        parent_point = (case.parent_pose(t) @ case.frame_p).position
        gap = origin - parent_point
        normal_space = np.linalg.svd(gap[None, :])[2][1:]  # directions normal to the link
        moves += [child_motion(case, model, q, n, no_spin, origin) for n in normal_space]
        if case.child != "particle":
            moves += [child_motion(case, model, q, zero, w, origin) for w in spins]
    return moves


def rank(A, tol=1e-9):
    if A.size == 0:
        return 0
    s = np.linalg.svd(A, compute_uv=False)
    return int(np.sum(s > tol * max(s[0], 1e-300)))


# ------------------------------------------------------------------ the tests

@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_residual_vanishes_at_a_consistent_pose(case):
    model = hx.assemble(case.scene(drive=_revolute_drivable(case)))
    for t in (0.0, 0.61, 1.7):
        q = case.coordinates(model, t)
        w, _, _ = model.law_values(t)
        phi = model.call("phi", q=q, w=w)
        assert np.max(np.abs(phi)) < 1e-12, dict(zip([r.name for r in model.rows], phi,
                                                     strict=True))


# with the ground as child the parent carries the joint's motion: the same joint with the ground
# as parent covers the null space
@pytest.mark.parametrize("case", [c for c in CASES if c.child != "ground"], ids=case_id)
def test_null_space_equals_allowed_motions(case):
    model = hx.assemble(case.scene(drive=False))
    q = case.coordinates(model, 0.0)
    Phi_v = model.call("Phi_v", q=q, w=np.zeros(model.n_w))
    S = np.column_stack(allowed_motions(case, model, q) or [np.zeros(model.n_v)])
    # every allowed motion is in the null space ...
    assert np.linalg.norm(Phi_v @ S) <= 1e-10 * np.linalg.norm(Phi_v) * np.linalg.norm(S)
    # ... and the null space holds nothing else
    assert rank(Phi_v) == model.n_v - rank(S)


def _lie_differences(model, coordinates, t, h):
    """Body velocities and accelerations from 5-point stencils of ``q(t + k h) (-) q(t)``:
    for a Lie-group curve the log coordinates have derivative v and second derivative v_dot."""
    q0 = coordinates(t)
    d = {k: model.difference(coordinates(t + k * h), q0) for k in (-2, -1, 1, 2)}
    v = (-d[2] + 8 * d[1] - 8 * d[-1] + d[-2]) / (12 * h)
    v_dot = (-d[2] + 16 * d[1] + 16 * d[-1] - d[-2]) / (12 * h**2)
    return q0, v, v_dot


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_gamma_matches_finite_differences_along_a_motion(case):
    model = hx.assemble(case.scene(drive=_revolute_drivable(case)))
    for t in (0.37, 1.21):
        q, v, v_dot = _lie_differences(model, lambda s: case.coordinates(model, s), t, 2e-3)
        w, wd, wdd = model.law_values(t)
        Phi_v = model.call("Phi_v", q=q, w=w)
        nu = model.call("nu", q=q, w=w, wd=wd)
        gamma = model.call("gamma", q=q, v=v, w=w, wd=wd, wdd=wdd)
        # 5-point stencils with h = 2e-3 are accurate to ~1e-9 here (O(h^4) truncation with
        # rates up to ~3 rad/s, ~eps/h^2 rounding); a missing term of gamma is O(1)
        scale = 1.0 + np.abs(Phi_v) @ np.abs(v)
        assert np.max(np.abs(Phi_v @ v - nu) / scale) < 1e-8
        scale = 1.0 + np.abs(gamma) + np.abs(Phi_v) @ np.abs(v_dot)
        assert np.max(np.abs(Phi_v @ v_dot - gamma) / scale) < 1e-7


def test_revolute_driver_is_wrapped_past_pi():
    """The driven angle law crosses pi: the driver row stays zero and is smooth there."""
    case = Case("revolute", 3, "ground", "spatial", 7)
    model = hx.assemble(case.scene())
    times = np.linspace(0, 4, 81)
    assert np.ptp(case.angle(times)) > 2.0 and np.any(case.angle(times) > np.pi)
    for t in times:
        w, _, _ = model.law_values(t)
        phi = model.call("phi", q=case.coordinates(model, t), w=w)
        assert abs(phi[model.row_index["drive"]]) < 1e-12


def test_planar_scene_carries_three_coordinates_per_body():
    case = Case("revolute", 2, "planar", "planar", 3)
    model = hx.assemble(case.scene())
    assert model.n_q == model.n_v == 6
    assert all(b.kind == "planar" for b in model.bodies)


def test_rotation_2d_consistency():
    # the planar pose helper agrees with the 3-D rotation about z
    R3 = rot([0, 0, 1], 0.7)
    assert np.allclose(rotation_2d(0.7), R3[:2, :2])
