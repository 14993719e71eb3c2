"""Small mechanisms shared by the tests, each built in the ways the tests compare."""

from __future__ import annotations

import numpy as np

import hexapod as hx


def solve_state(scene: hx.Scene, t: float = 0.0):
    """Assemble ``scene`` at ``t``: model, positions, velocities, accelerations and the workspace
    holding the multipliers."""
    model = hx.assemble(scene)
    data = model.create_data()
    q = hx.assemble_positions(model, data, t)
    v = hx.solve_velocities(model, data, t, q)
    v_dot = hx.forward_dynamics(model, data, t, q, v)
    return model, q, v, v_dot, data


# ------------------------------------------------------------------ simple pendulum

def rod_pendulum(dimension: int):
    """A 1 m, 1 kg rod about an end, released horizontal at rest (data/scenes/pendulum.toml, and
    its planar twin): the model and the small-oscillation frequency; energy 0 throughout, the
    centre of mass 0.5 m from the pivot."""
    from pathlib import Path

    from hexapod.scene.reader import read_scene

    if dimension == 3:
        scenes = Path(__file__).resolve().parents[1] / "data" / "scenes"
        model = hx.assemble(read_scene(scenes / "pendulum.toml"))
    else:
        scene = hx.Scene("planar-pendulum", 2)
        scene.add(hx.scene.PlanarBody("rod", 1.0, 0.0833, position=[0.5, 0.0]))
        scene.add(hx.scene.Revolute("pivot", "ground", "rod", origin=[0.0, 0.0]))
        model = hx.assemble(scene)
    return model, np.sqrt(9.81 * 0.5 / (0.0833 + 0.25))


PENDULUM = dict(mass=1.3, length=0.8, inertia=0.02)  # kg, m (pivot to centre of mass), kg m^2


def pendulum(form: str, theta: float, unit: str = "m", mass=None, inertia=None) -> hx.Scene:
    """A pendulum about the pivot at the origin, ``theta`` measured from the downward vertical.

    ``form`` is ``spatial`` (a rigid body swinging in the x-z plane about the y axis),
    ``planar`` (x-y plane) or ``particle-3d`` / ``particle-2d`` (a point mass on a rigid link).
    Lengths are written in ``unit``.
    """
    m = PENDULUM["mass"] if mass is None else mass
    Ic = PENDULUM["inertia"] if inertia is None else inertia
    k = hx.scene.LENGTH_UNITS[unit]
    lenu = PENDULUM["length"] / k
    inertia_u = Ic / k**2
    s, c = np.sin(theta), np.cos(theta)
    if form == "spatial":
        scene = hx.Scene("pendulum", 3, unit)
        # x right, z up; rotating about +y by theta takes -z (down) towards -x
        scene.add(hx.scene.SpatialBody("bob", m, [inertia_u, inertia_u, inertia_u],
                                       position=[-lenu * s, 0.0, -lenu * c],
                                       rotation=hx.spatial.rotation_about_axis([0, 1, 0], theta)))
        scene.add(hx.scene.Revolute("pivot", "ground", "bob", origin=[0, 0, 0], axis=[0, 1, 0]))
    elif form == "planar":
        scene = hx.Scene("pendulum", 2, unit)
        scene.add(hx.scene.PlanarBody("bob", m, inertia_u, position=[lenu * s, -lenu * c],
                                      angle=theta))
        scene.add(hx.scene.Revolute("pivot", "ground", "bob", origin=[0, 0]))
    elif form in ("particle-3d", "particle-2d"):
        dim = 3 if form == "particle-3d" else 2
        scene = hx.Scene("pendulum", dim, unit)
        position = [lenu * s, 0.0, -lenu * c] if dim == 3 else [lenu * s, -lenu * c]
        scene.add(hx.scene.Particle("bob", m, position=position))
        scene.add(hx.scene.Distance("rod", "ground", "bob",
                                    parent_frame=hx.spatial.Placement(np.zeros(dim))))
    else:
        raise ValueError(form)
    return scene


def pendulum_closed_form(theta, theta_dot, inertia=None, mass=None):
    """Angular acceleration and the force of the pivot on the pendulum, as (radial, tangential)
    components: radial along pivot -> centre of mass, tangential along increasing theta."""
    m = PENDULUM["mass"] if mass is None else mass
    Ic = PENDULUM["inertia"] if inertia is None else inertia
    l, g = PENDULUM["length"], 9.81
    I_O = Ic + m * l**2
    theta_dd = -m * g * l * np.sin(theta) / I_O
    radial = -m * l * theta_dot**2 - m * g * np.cos(theta)
    tangential = m * l * theta_dd + m * g * np.sin(theta)
    return theta_dd, radial, tangential


# ------------------------------------------------------------------ four-bar

FOUR_BAR = dict(ground=0.30, crank=0.10, coupler=0.25, rocker=0.20, density=2.0)  # m, kg/m


def four_bar_points(theta):
    """Pivots A, D and moving joints B, C of the four-bar at crank angle ``theta`` (plane)."""
    g, a, b, c = (FOUR_BAR[k] for k in ("ground", "crank", "coupler", "rocker"))
    A, D = np.zeros(2), np.array([g, 0.0])
    B = a * np.array([np.cos(theta), np.sin(theta)])
    # C on the circles (B, b) and (D, c), upper branch
    d = np.linalg.norm(D - B)
    x = (b**2 - c**2 + d**2) / (2 * d)
    h = np.sqrt(b**2 - x**2)
    e = (D - B) / d
    C = B + x * e + h * np.array([-e[1], e[0]])
    return A, B, C, D


def four_bar(dimension: int, theta: float, *, driven: bool = True, unit: str = "m",
             gravity=None, law=None) -> hx.Scene:
    """The four-bar A-B-C-D at crank angle ``theta``; in 3-D all four revolute axes are along z
    (three rows redundant). Joints in tree order, the rocker's ground pivot closing the loop."""
    k = hx.scene.LENGTH_UNITS[unit]
    A, B, C, D = (p / k for p in four_bar_points(theta))
    scene = hx.Scene("four-bar", dimension, unit)
    if gravity is not None:
        scene.gravity = np.asarray(gravity, dtype=float) / k
    rho = FOUR_BAR["density"]
    links = {"crank": (A, B), "coupler": (B, C), "rocker": (D, C)}
    for name, (P, R) in links.items():
        length_u = np.linalg.norm(R - P)
        mass = rho * length_u * k
        angle = np.arctan2(*(R - P)[::-1])
        transverse = mass * length_u**2 / 12
        centre = (P + R) / 2
        if dimension == 3:
            radius = 0.01 / k
            scene.add(hx.scene.SpatialBody(
                name, mass, [mass * radius**2 / 2, transverse, transverse],
                position=[*centre, 0.0], rotation=hx.spatial.rotation_about_axis([0, 0, 1], angle)))
        else:
            scene.add(hx.scene.PlanarBody(name, mass, transverse, position=centre, angle=angle))

    def at(p):
        return [*p, 0.0] if dimension == 3 else list(p)

    scene.add(hx.scene.Revolute("crank_pin", "ground", "crank", origin=at(A)))
    scene.add(hx.scene.Revolute("coupler_pin", "crank", "coupler", origin=at(B)))
    scene.add(hx.scene.Revolute("rocker_pin", "coupler", "rocker", origin=at(C)))
    scene.add(hx.scene.Revolute("rocker_ground", "rocker", "ground", origin=at(D)))
    if driven:
        scene.add(hx.scene.JointDriver("motor", "crank_pin",
                                       law or hx.scene.Polynomial([0.0, 2.0, -1.5])))
    return scene


# ------------------------------------------------------------------ random trees

def random_tree(seed: int, n_bodies: int, *, chain: bool = False, prismatic: float = 0.3,
                driven: bool = True) -> hx.Scene:
    """A random tree (or chain) of spatial bodies hanging from the ground: revolute and
    prismatic joints with random axes and offsets, random centres of mass and full rotated
    inertias; every joint driven by a harmonic law when ``driven``."""
    rng = np.random.default_rng(seed)
    scene = hx.Scene(f"tree-{seed}")
    points = {"ground": np.zeros(3)}
    for k in range(n_bodies):
        name = f"b{k}"
        parent = "ground" if k == 0 else (f"b{k - 1}" if chain else f"b{rng.integers(0, k)}")
        origin = points[parent] + rng.normal(size=3) * 0.3
        rotation = hx.spatial.rotation_about_axis(rng.normal(size=3), rng.uniform(0, np.pi))
        moments = np.sort(rng.uniform(0.02, 0.1, size=3))
        moments[2] = min(moments[2], moments[0] + moments[1])  # a physical inertia
        scene.add(hx.scene.SpatialBody(name, rng.uniform(0.5, 2.0), moments,
                                       com=rng.normal(size=3) * 0.2, position=origin,
                                       rotation=rotation,
                                       inertia_rotation=hx.spatial.rotation_about_axis(
                                           rng.normal(size=3), rng.uniform(0, 3))))
        cls = hx.scene.Prismatic if rng.uniform() < prismatic else hx.scene.Revolute
        axis = rng.normal(size=3) * rng.uniform(0.5, 3.0)  # not normalised on purpose
        scene.add(cls(f"j{k}", parent, name, origin=origin,
                      rotation=hx.spatial.rotation_about_axis(rng.normal(size=3),
                                                              rng.uniform(0, 3)),
                      axis=axis))
        law = hx.scene.Harmonic(offset=rng.normal() * 0.3, sin=[rng.uniform(0.2, 0.8)],
                                cos=[rng.normal() * 0.2], frequency=rng.uniform(0.3, 1.5))
        if driven:  # the law is drawn either way, so driven and free twins share a geometry
            scene.add(hx.scene.JointDriver(f"d{k}", f"j{k}", law))
        points[name] = origin + rng.normal(size=3) * 0.2
    return scene


# ------------------------------------------------------------------ a top on a spring

def sprung_top(damping: float, inertia=(0.002, 0.002, 0.004)) -> hx.Model:
    """A top on a spherical joint (spinning at 30 rad/s, tilted 0.5 rad) held by a spring from a
    point of its rim to a fixed point: gyroscopic terms, a spring potential, and, with damping,
    a force depending on the velocities."""
    scene = hx.Scene("sprung-top", 3)
    rotation = hx.spatial.rotation_about_axis([1.0, 0.0, 0.0], 0.5)
    scene.add(hx.scene.SpatialBody("top", 0.5, list(inertia), position=rotation @ [0, 0, 0.1],
                                   rotation=rotation, angular_velocity=[1.0, -2.0, 30.0]))
    scene.add(hx.scene.Spherical("tip", "ground", "top", origin=[0.0, 0.0, 0.0]))
    scene.add(hx.scene.SpringDamper("spring", "ground", "top", point_a=[0.3, 0.1, 0.2],
                                    point_b=[0.05, 0.0, 0.0], stiffness=40.0, damping=damping,
                                    free_length=0.2))
    return hx.assemble(scene)
