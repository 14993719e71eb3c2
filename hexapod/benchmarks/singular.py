"""The singular cases: motions through poses where the joints' Jacobian loses rank, or where
a leg's Jacobian does.

* :func:`n_four_bar`: IFToMM benchmark A02, a row of parallelograms that lie flat twice per
  turn (also its spatial, redundant form);
* :func:`four_bar_dead_points`: an anti-parallelogram through its change points, free or
  driven;
* :func:`stretched_leg`: a two-link leg through its straight pose, free or driven.
"""

from __future__ import annotations

import numpy as np

from hexapod.benchmarks import jets
from hexapod.benchmarks.reference import (
    Case,
    G,
    MinimalModel,
    OneDof,
    Trajectory,
    minimal_reference,
)
from hexapod.scene import (
    Harmonic,
    JointDriver,
    PlanarBody,
    Polynomial,
    Prismatic,
    Revolute,
    Scene,
    SpatialBody,
)
from hexapod.spatial import rotation_about_axis

# ------------------------------------------------------------------ singular: N four-bar


def n_four_bar(n: int = 10, *, t_end: float = 10.0, dimension: int = 2,
               start_angle: float = 0.0, start_rate: float = 1.0) -> Case:
    """IFToMM benchmark A02, the N-four-bar mechanism: ``n`` parallelogram windows in a row,
    2 n + 1 uniform rods of 1 m and 1 kg (n + 1 cranks hinged to the ground 1 m apart, n
    couplers joining their tips), gravity 9.81 along -y. Initially the cranks are vertical
    (up) and the first crank's tip ``B0`` moves at 1 m/s along +x. The mechanism falls and
    turns over and over: twice per turn all rods lie on the ground line, where the joints'
    Jacobian loses n ranks (n + 1 instantaneous degrees of freedom) and each window may fold
    into an anti-parallelogram. With ``dimension=3`` the same chain of spatial bodies on
    revolute joints along z: 3 redundant rows per window (category "redundant").

    Reference: every crank turns by the same angle ``theta`` (clockwise from the vertical)
    and the couplers translate, so
    ``[(n + 1) m l^2 / 3 + n m l^2] theta'' = [(n + 1) m g l / 2 + n m g l] sin theta``,
    integrated by DOP853 at 1e-12. The observable is every rod's centre of mass, which shows
    a jump to another branch. The benchmark library's A02 has 40 windows (``n_four_bar(40)``),
    the OpenSim implementation 2; 10 s as there.

    ``start_angle`` and ``start_rate`` (rad, rad/s) start the mechanism elsewhere on the same
    motion's family: every crank at ``theta = start_angle`` turning at ``start_rate`` (the
    benchmark: 0 and 1, ``B0`` at 1 m/s)."""
    m, l = 1.0, 1.0
    scene = Scene(f"n-four-bar-{n}" + ("-3d" if dimension == 3 else ""), dimension=dimension)
    scene.gravity = np.array([0.0, -G] + ([0.0] if dimension == 3 else []))
    inertia = m * l**2 / 12

    def add_rod(name, centre, angle, velocity, omega):
        if dimension == 2:
            scene.add(PlanarBody(name, m, inertia, position=centre, angle=angle,
                                 velocity=velocity, angular_velocity=omega))
        else:
            scene.add(SpatialBody(name, m, [inertia * 1e-3, inertia, inertia],
                                  position=[*centre, 0.0],
                                  rotation=rotation_about_axis([0, 0, 1], angle),
                                  velocity=[*velocity, 0.0], angular_velocity=[0, 0, omega]))

    def at(p):
        return [*p, 0.0] if dimension == 3 else list(p)

    # every crank at theta clockwise from straight up, the couplers level: a point at r along a
    # crank sits at (r sin theta, r cos theta) from its hinge and moves at r theta' (cos, -sin)
    s0, c0, w0 = np.sin(start_angle), np.cos(start_angle), start_rate
    for i in range(n + 1):
        add_rod(f"crank_{i}", [i + 0.5 * l * s0, 0.5 * l * c0], np.pi / 2 - start_angle,
                [0.5 * l * w0 * c0, -0.5 * l * w0 * s0], -w0)
        if i < n:
            add_rod(f"coupler_{i}", [i + 0.5 + l * s0, l * c0], 0.0,
                    [l * w0 * c0, -l * w0 * s0], 0.0)
    scene.add(Revolute("A_0", "ground", "crank_0", origin=at([0.0, 0.0])))
    for i in range(n):
        scene.add(Revolute(f"B_{i}", f"crank_{i}", f"coupler_{i}",
                           origin=at([i + l * s0, l * c0])))
        scene.add(Revolute(f"C_{i}", f"coupler_{i}", f"crank_{i + 1}",
                           origin=at([i + 1 + l * s0, l * c0])))
        scene.add(Revolute(f"A_{i + 1}", "ground", f"crank_{i + 1}", origin=at([i + 1, 0.0])))
    inertia_total = (n + 1) * m * l**2 / 3 + n * m * l**2
    torque = (n + 1) * m * G * l / 2 + n * m * G * l
    rate = torque / inertia_total
    observed = tuple(f"{kind}_{i}" for i in range(n + 1) for kind in ("crank", "coupler")
                     if kind == "crank" or i < n)
    width = dimension

    def positions(theta):
        s, c = np.sin(theta), np.cos(theta)
        out = []
        for name in observed:
            kind, i = name.split("_")
            if kind == "crank":
                point = [int(i) + 0.5 * l * s, 0.5 * l * c]
            else:
                point = [int(i) + 0.5 + l * s, l * c]
            out.extend(point + [0.0] * (width - 2))
        return np.array(out)

    reference = Trajectory(lambda _t, y: np.array([y[1], rate * np.sin(y[0])]),
                           [start_angle, start_rate], t_end, lambda y: positions(y[0]))
    accelerations = {}
    theta_dd = rate * s0
    for name in observed:
        kind, _ = name.split("_")
        r = 0.5 * l if kind == "crank" else l
        # position (i + r sin theta, r cos theta): acceleration r (theta'' cos - theta'^2 sin,
        # -theta'' sin - theta'^2 cos)
        accelerations[name] = np.array([r * (theta_dd * c0 - w0**2 * s0),
                                        -r * (theta_dd * s0 + w0**2 * c0)]
                                       + [0.0] * (width - 2))
    counted = 1 if dimension == 2 else 6 * (2 * n + 1) - 5 * (3 * n + 1)
    return Case(scene.name, scene, t_end,
                f"{n} parallelogram windows pass through the flat pose where the Jacobian "
                f"loses {n} ranks" + (f"; {3 * n} redundant rows" if dimension == 3 else ""),
                "singular" if dimension == 2 else "redundant", observed, reference,
                accelerations, length=float(n + 1), dof=1, counted_dof=counted,
                redundant=0 if dimension == 2 else 3 * n,
                source="IFToMM/MBS benchmark A02 (Gonzalez et al. 2006; data as in "
                       "RehabEngGroup/MBSbenchmarksInOpenSim src/A02-NFourBarMechanism)")


# ------------------------------------------------------------------ singular: anti-parallelogram

#: The anti-parallelogram (crossed) four-bar: cranks AB = DC = 0.2 m, ground AD = coupler
#: BC = 0.5 m, uniform rods of 2 kg/m. A Grashof change-point linkage (0.2 + 0.5 = 0.2 + 0.5).
ANTI_PARALLELOGRAM = dict(crank=0.2, ground=0.5, density=2.0)


def _anti_parallelogram_points(theta):
    """B and C of the crossed branch at crank angle ``theta`` (jets or numbers): C is A
    mirrored in the perpendicular bisector of BD, ``C = (d^2 - a^2) (D - B) / |D - B|^2``."""
    a, d = ANTI_PARALLELOGRAM["crank"], ANTI_PARALLELOGRAM["ground"]
    if isinstance(theta, jets.Jet):
        B = jets.stack([a * jets.cos(theta), a * jets.sin(theta), 0.0 * theta])
        w = np.array([d, 0.0, 0.0]) - B
        C = w * ((d * d - a * a) / (w[0] * w[0] + w[1] * w[1]))
        return B, C
    B = a * np.array([np.cos(theta), np.sin(theta), 0.0])
    w = np.array([d, 0.0, 0.0]) - B
    return B, (d * d - a * a) * w / (w @ w)


def four_bar_dead_points(driven: bool = False, *, t_end: float | None = None) -> Case:
    """A four-bar that passes through its change points, where the Jacobian loses rank and a
    second branch crosses: the anti-parallelogram of :data:`ANTI_PARALLELOGRAM` (crank A-B,
    coupler B-C, rocker D-C, ground A-D), whose crossed configurations meet the parallelogram
    ones when all four joints are on the ground line (crank angle 0 and pi).

    Free (``driven=False``): released at rest with the crank vertical (theta = pi/2), under
    gravity; it swings through theta = 0 twice per period. Driven: the crank turns at 1
    revolution per second from pi/2 (a constant-rate driver) through pi and 2 pi.
    At those instants the two branches have different rocker rates, so the exact motion stays
    on the crossed branch; a method that lets the rank-deficient step choose can jump.

    Reference: on the crossed branch C(theta) is rational in cos and sin (see
    :func:`_anti_parallelogram_points`): the free motion by Lagrange's equation in theta
    (Kane, DOP853 at 1e-12), the driven one in closed form."""
    p = ANTI_PARALLELOGRAM
    a, d, rho = p["crank"], p["ground"], p["density"]
    theta0 = np.pi / 2
    omega = 2 * np.pi if driven else 0.0
    t_end = (1.0 if driven else 2.0) if t_end is None else t_end
    B, C = _anti_parallelogram_points(theta0)
    D = np.array([d, 0.0, 0.0])
    masses = {"crank": rho * a, "coupler": rho * d, "rocker": rho * a}
    scene = Scene("anti-parallelogram" + ("-driven" if driven else ""), dimension=2)

    def angle(u):
        return float(np.arctan2(u[1], u[0]))

    # initial velocities (driven: the crank's rate; the rest follows from the kinematics)
    x0 = np.array([theta0])
    model = _anti_parallelogram_minimal(masses)
    frames, _ = model.kinematics(jets.Jet.variables(x0, [omega]))
    for name, start, end in (("crank", np.zeros(3), B), ("coupler", B, C), ("rocker", D, C)):
        length = float(np.linalg.norm(end - start))
        p_jet, R = frames[name]
        w = jets.vee(R.c1[-1] @ R.c0.T)[2]
        scene.add(PlanarBody(name, masses[name], masses[name] * length**2 / 12,
                             position=((start + end) / 2)[:2], angle=angle(end - start),
                             velocity=p_jet.c1[-1][:2], angular_velocity=w))
    scene.add(Revolute("A", "ground", "crank", origin=[0.0, 0.0]))
    scene.add(Revolute("B", "crank", "coupler", origin=B[:2]))
    scene.add(Revolute("C", "coupler", "rocker", origin=C[:2]))
    scene.add(Revolute("D", "rocker", "ground", origin=D[:2]))
    observed = ("crank", "coupler", "rocker")
    if driven:
        scene.add(JointDriver("motor", "A", Polynomial([0.0, omega])))

        def reference(times):
            times = np.atleast_1d(np.asarray(times, dtype=float))
            out = []
            for t in times:
                positions = model.com_positions([theta0 + omega * t])
                out.append(np.concatenate([positions[b][:2] for b in observed]))
            return np.array(out)

        accelerations = {k: a_[:2] for k, a_ in _driven_accelerations(model, theta0,
                                                                      omega).items()}
    else:
        # from rest at pi/2 it swings down through 0 to about -0.3 rad and back
        reference, accelerations = minimal_reference(
            model, x0, [0.0], t_end, observed, 2, rates=OneDof(model, -1.0, 2.0).rates)
    return Case(scene.name, scene, t_end,
                "change-point four-bar: at theta = 0, pi the Jacobian loses a rank and the "
                "parallelogram branch crosses" + (" (crank driven)" if driven else ""),
                "singular", observed, reference, accelerations, length=d, dof=1,
                counted_dof=1, dof_with_drivers=0 if driven else 1,
                energy_conserved=not driven,
                source="designed for the suite (anti-parallelogram, Grashof change point)")


def _anti_parallelogram_minimal(masses) -> MinimalModel:
    a, d = ANTI_PARALLELOGRAM["crank"], ANTI_PARALLELOGRAM["ground"]
    D = np.array([d, 0.0, 0.0])

    def kinematics(x):
        theta = x[0]
        B, C = _anti_parallelogram_points(theta)
        crank = jets.planar_rotation(jets.cos(theta), jets.sin(theta))
        u = (C - B) * (1.0 / d)
        r = (C - D) * (1.0 / a)
        frames = {"crank": (B * 0.5, crank),
                  "coupler": ((B + C) * 0.5, jets.planar_rotation(u[0], u[1])),
                  "rocker": ((C + D) * 0.5, jets.planar_rotation(r[0], r[1]))}
        return frames, {}

    bodies = {name: (mass, np.diag([0.0, 0.0, mass * length**2 / 12]))
              for (name, mass), length in zip(masses.items(), (a, d, a), strict=True)}
    return MinimalModel(kinematics, bodies, [0.0, -G, 0.0])


def _driven_accelerations(model: MinimalModel, x0: float, rate: float) -> dict:
    """Centre-of-mass accelerations of a 1-DOF model whose coordinate turns at a constant
    rate."""
    frames, _ = model.kinematics(jets.Jet.variables([x0], [rate]))
    return {name: 2 * frames[name][0].c2 for name in model.bodies}


# ------------------------------------------------------------------ singular: stretched leg

#: The hanging leg: thigh and shank 0.2 m (0.1 kg and 0.05 kg, uniform rods), trunk 1 kg.
STRETCHED_LEG = dict(length=0.2, thigh=0.1, shank=0.05, trunk=1.0)


def stretched_leg(driven: bool = False, *, theta0: float = 0.5,
                  t_end: float | None = None) -> Case:
    """A two-link leg through its fully stretched pose: an insect hanging from the ceiling.
    The foot is pinned to the ceiling at the origin; the trunk hangs below it on a vertical
    slider (x = 0); thigh (hip to knee) and shank (knee to foot) are equally long
    (:data:`STRETCHED_LEG`). With ``theta`` the shank's angle from the downward vertical, the
    knee is at ``l (sin theta, -cos theta)`` and the hip at ``(0, -2 l cos theta)``.

    At theta = 0 the leg is straight: the hip's height is stationary (second order in theta),
    the leg's foot-to-hip Jacobian is singular and the inverse kinematics (theta from the
    trunk's height) has infinite slope. The joints' Jacobian in absolute coordinates keeps
    full rank there (the knee may still move sideways). Free (default): released at rest with
    the knee bent by ``theta0``, it swings through the straight pose twice per period.
    Driven: the slider follows ``y(t) = -2 l cos(omega (t - t_end / 2))`` (omega = 2 pi rad/s,
    0.4 s: the knee from -72 to 72 degrees), which passes the straight pose at ``t_end / 2``;
    there the driver's row and the joints' become dependent (the knee's sideways motion is
    free for an instant) and the motion continues with the knee flipping to the other side,
    ``theta = omega (t - t_end / 2)`` (the only continuation with continuous velocities).

    Reference: free, Lagrange's equation in theta written out (DOP853 at 1e-12; Kane's
    equations give the initial accelerations, and the tests check both agree); driven, the
    closed form above."""
    p = STRETCHED_LEG
    l = p["length"]
    masses = {"trunk": p["trunk"], "thigh": p["thigh"], "shank": p["shank"]}
    omega = 2 * np.pi
    t_end = (0.4 if driven else 2.0) if t_end is None else t_end
    t_mid = t_end / 2
    if driven:
        theta0 = -omega * t_mid
    scene = Scene("stretched-leg" + ("-driven" if driven else ""), dimension=2)
    model = _stretched_leg_minimal(masses)
    rate0 = omega if driven else 0.0
    frames, _ = model.kinematics(jets.Jet.variables([theta0], [rate0]))
    inertias = {"trunk": 0.01, "thigh": p["thigh"] * l**2 / 12, "shank": p["shank"] * l**2 / 12}
    for name in ("trunk", "thigh", "shank"):
        pos, R = frames[name]
        scene.add(PlanarBody(name, masses[name], inertias[name], position=pos.c0[:2],
                             angle=float(np.arctan2(R.c0[1, 0], R.c0[0, 0])),
                             velocity=pos.c1[-1][:2],
                             angular_velocity=jets.vee(R.c1[-1] @ R.c0.T)[2]))
    hip = [0.0, -2 * l * np.cos(theta0)]
    knee = [l * np.sin(theta0), -l * np.cos(theta0)]
    scene.add(Prismatic("slider", "ground", "trunk", origin=hip, axis=[0.0, 1.0]))
    scene.add(Revolute("hip", "trunk", "thigh", origin=hip))
    scene.add(Revolute("knee", "thigh", "shank", origin=knee))
    scene.add(Revolute("foot", "shank", "ground", origin=[0.0, 0.0]))
    observed = ("trunk", "thigh", "shank")
    if driven:
        # slider displacement from the initial pose: -2 l cos(omega (t - t_mid)) - hip_y(0)
        scene.add(JointDriver("lift", "slider",
                              Harmonic(offset=-hip[1], cos=[-2 * l], frequency=1.0,
                                       t0=t_mid)))

        def reference(times):
            times = np.atleast_1d(np.asarray(times, dtype=float))
            out = []
            for t in times:
                positions = model.com_positions([omega * (t - t_mid)])
                out.append(np.concatenate([positions[b][:2] for b in observed]))
            return np.array(out)

        accelerations = {k: a[:2] for k, a in _driven_accelerations(model, theta0,
                                                                    omega).items()}
    else:
        mt, ms, M = p["thigh"], p["shank"], p["trunk"]
        inertia0 = (mt + ms) * l * l / 12 + (mt + ms) * l * l / 4  # both rods, at theta = 0
        potential = G * l * (2 * M + 1.5 * mt + 0.5 * ms)

        def rates(_t, y):
            # m(th) th'' + m'(th) th'^2 / 2 + V'(th) = 0, with
            # m = (m_t + m_s) l^2 / 12 + M (2 l s)^2 + m_t l^2 (c^2 / 4 + 9 s^2 / 4)
            #     + m_s l^2 / 4,  V = -g l c (2 M + 3 m_t / 2 + m_s / 2)
            th, thd = y
            sn, cs = np.sin(th), np.cos(th)
            m = inertia0 + (4 * M + 2 * mt) * l * l * sn * sn
            dm = 2 * (4 * M + 2 * mt) * l * l * sn * cs
            return np.array([thd, -(0.5 * dm * thd * thd + potential * sn) / m])

        reference, accelerations = minimal_reference(model, [theta0], [0.0], t_end, observed,
                                                      2, rates=rates)
    return Case(scene.name, scene, t_end,
                "leg through its straight pose: the hip's height is stationary, the leg's "
                "Jacobian singular" + (" and the driven slider's row dependent" if driven
                                       else ""),
                "singular", observed, reference, accelerations, length=2 * l, dof=1,
                counted_dof=1, dof_with_drivers=0 if driven else 1,
                energy_conserved=not driven)


def _stretched_leg_minimal(masses) -> MinimalModel:
    l = STRETCHED_LEG["length"]

    def kinematics(x):
        theta = x[0]
        s, c = jets.sin(theta), jets.cos(theta)
        zero = 0.0 * theta
        hip = jets.stack([zero, c * (-2 * l), zero])
        knee = jets.stack([s * l, c * (-l), zero])
        # thigh from knee to hip: direction (-sin, -cos); shank from foot to knee: (sin, -cos)
        frames = {"trunk": (hip, jets.Jet.constant(np.eye(3))),
                  "thigh": ((hip + knee) * 0.5, jets.planar_rotation(-s, -c)),
                  "shank": (knee * 0.5, jets.planar_rotation(s, -c))}
        return frames, {}

    l2 = l**2
    bodies = {"trunk": (masses["trunk"], np.diag([0.0, 0.0, 0.01])),
              "thigh": (masses["thigh"], np.diag([0.0, 0.0, masses["thigh"] * l2 / 12])),
              "shank": (masses["shank"], np.diag([0.0, 0.0, masses["shank"] * l2 / 12]))}
    return MinimalModel(kinematics, bodies, [0.0, -G, 0.0])
