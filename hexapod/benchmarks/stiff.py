"""The stiff cases: springs far stiffer than the motion they sit in.

* :func:`stiff_slider`: a block on a spring of 1e3 to 1e9 N/m, against the damped oscillator
  in closed form;
* :func:`stiff_spring_pendulum`: a stiff spring inside a swinging linkage, against its
  two-degree-of-freedom Lagrange equations written out;
* :func:`flyball_governor`: IFToMM benchmark A05, against its symmetric reduction (Routh)
  integrated by Radau IIA.
"""

from __future__ import annotations

import numpy as np

from hexapod.benchmarks import jets
from hexapod.benchmarks.reference import (
    Case,
    G,
    MinimalModel,
    Spring,
    Trajectory,
    minimal_reference,
    rod_inertia,
)
from hexapod.scene import (
    Particle,
    PlanarBody,
    Prismatic,
    Revolute,
    Scene,
    SpatialBody,
    Spherical,
    SpringDamper,
)
from hexapod.spatial import rotation_about_axis

# ------------------------------------------------------------------ stiff: the slider


def stiff_slider(k: float, c: float = 0.0, *, amplitude: float = 0.01, mass: float = 1.0,
                 t_end: float = 0.5, gravity: bool = True) -> Case:
    """A block on a vertical prismatic joint, hung from a spring-damper of stiffness ``k``
    (N/m) and damping ``c`` (N s/m) anchored 1 m above, released ``amplitude`` below its
    equilibrium (gravity along the slide when ``gravity``).

    Reference: ``m u'' + c u' + k u = 0`` in closed form (under-, critically or over-damped),
    ``u`` the block's distance from its static equilibrium. With ``k = 1e9`` the period is
    0.2 ms: 2500 periods in half a second."""
    free_length = 1.0
    g = G if gravity else 0.0
    y_eq = -(free_length + mass * g / k)
    y0 = y_eq - amplitude
    scene = Scene(f"stiff-slider-k{k:.0e}" + (f"-c{c:.0e}" if c else ""), dimension=2)
    scene.gravity = np.array([0.0, -g])
    scene.add(PlanarBody("block", mass, mass * 0.1**2 / 6, position=[0.0, y0]))
    scene.add(Prismatic("slide", "ground", "block", origin=[0.0, y0], axis=[0.0, 1.0]))
    scene.add(SpringDamper("spring", "ground", "block", point_a=[0.0, 0.0], stiffness=k,
                           damping=c, free_length=free_length))
    omega = np.sqrt(k / mass)
    zeta = c / (2 * np.sqrt(k * mass))
    u0 = -amplitude

    def displacement(t):
        t = np.asarray(t, dtype=float)
        if zeta < 1.0:
            wd = omega * np.sqrt(1 - zeta**2)
            return np.exp(-zeta * omega * t) * u0 * (np.cos(wd * t)
                                                    + zeta * omega / wd * np.sin(wd * t))
        if zeta == 1.0:
            return u0 * (1 + omega * t) * np.exp(-omega * t)
        root = np.sqrt(zeta**2 - 1)
        r1, r2 = -omega * (zeta - root), -omega * (zeta + root)
        return u0 * (r1 * np.exp(r2 * t) - r2 * np.exp(r1 * t)) / (r1 - r2)

    def reference(times):
        times = np.atleast_1d(np.asarray(times, dtype=float))
        return np.column_stack([np.zeros_like(times), y_eq + displacement(times)])

    period = 2 * np.pi / omega
    return Case(
        scene.name, scene, t_end,
        f"spring of {k:.0e} N/m on 1 kg: period {period:.2g} s, {t_end / period:.0f} periods"
        + (f", damping ratio {zeta:.3g}" if c else " undamped"),
        "stiff", ("block",), reference, {"block": np.array([0.0, -k * u0 / mass])},
        length=amplitude, dof=1, counted_dof=1, energy_conserved=(c == 0.0),
        source="closed form of the linear oscillator")


def stiff_spring_pendulum(k: float = 1e6, *, t_end: float = 2.0) -> Case:
    """A stiff spring inside a constrained mechanism: a 1 m arm (1 kg) swings about a pivot; a
    0.5 kg slider on it (prismatic joint along the arm) is held 0.6 m from the pivot by a
    spring of stiffness ``k``. Released horizontal at rest: the swing stretches the spring by
    micrometres while it vibrates at ``sqrt(k / 0.5)`` rad/s.

    Reference: Lagrange's equations in the arm's angle ``th`` and the slider's distance ``s``
    from the pivot, written out (``I_A`` the arm's inertia about the pivot, ``m, I`` the
    slider's),

        (I_A + I + m s^2) th'' + 2 m s s' th' = -g cos(th) (m_arm / 2 + m s)
        m s'' - m s th'^2 = -m g sin(th) - k (s - L0),

    integrated by DOP853 at 1e-12 (Kane's equations of the same system give the initial
    accelerations, and the tests check that both agree)."""
    arm_mass, slider_mass, free_length = 1.0, 0.5, 0.6
    scene = Scene(f"stiff-spring-pendulum-k{k:.0e}", dimension=2)
    scene.add(PlanarBody("arm", arm_mass, arm_mass / 12, com=[0.5, 0.0], position=[0.0, 0.0]))
    scene.add(PlanarBody("slider", slider_mass, 1e-3, position=[free_length, 0.0]))
    scene.add(Revolute("pivot", "ground", "arm", origin=[0.0, 0.0]))
    scene.add(Prismatic("slot", "arm", "slider", origin=[free_length, 0.0], axis=[1.0, 0.0]))
    scene.add(SpringDamper("spring", "arm", "slider", point_a=[0.0, 0.0], stiffness=k,
                           free_length=free_length))

    def kinematics(x):
        theta, s = x[0], x[1]
        c, si = jets.cos(theta), jets.sin(theta)
        R = jets.planar_rotation(c, si)
        zero = 0.0 * theta
        direction = jets.stack([c, si, zero])
        return ({"arm": (direction * 0.5, R), "slider": (direction * s, R)},
                {"slider": direction * s})

    model = MinimalModel(kinematics, {"arm": (arm_mass, np.diag([0, 0, arm_mass / 12])),
                                       "slider": (slider_mass, np.diag([0, 0, 1e-3]))},
                          [0.0, -G, 0.0], (Spring(np.zeros(3), "slider", k, 0.0, free_length),))
    observed = ("arm", "slider")
    inertia_arm = arm_mass / 12 + arm_mass * 0.25

    def rates(_t, y):
        th, s, thd, sd = y
        thdd = (-G * np.cos(th) * (0.5 * arm_mass + slider_mass * s)
                - 2 * slider_mass * s * sd * thd) / (inertia_arm + 1e-3 + slider_mass * s * s)
        sdd = s * thd * thd - G * np.sin(th) - k * (s - free_length) / slider_mass
        return np.array([thd, sd, thdd, sdd])

    reference, accelerations = minimal_reference(model, [0.0, free_length], [0.0, 0.0], t_end,
                                                  observed, 2, rates=rates)
    return Case(scene.name, scene, t_end,
                f"spring of {k:.0e} N/m inside a swinging linkage: vibration at "
                f"{np.sqrt(k / slider_mass):.3g} rad/s on a 1 s swing", "stiff", observed,
                reference, accelerations, length=1.0, dof=2, counted_dof=2)


# ------------------------------------------------------------------ stiff: flyball governor

#: IFToMM / MBS benchmark A05 (stiff flyball governor), as implemented by the Padua group
#: (RehabEngGroup/MBSbenchmarksInOpenSim, src/A05-FlyballGovernor, after Gonzalez, Dopico,
#: Lugris & Cuadrado 2006): spindle and rods 1 x 0.01 x 0.01 m, sleeve 0.1 m cube, density
#: 3000 kg/m^3, 5 kg point masses at the rods' tips, spring-dampers 8e5 N/m, 4e4 N s/m, free
#: length 0.5 m, s = 0.5 m, alpha = 30 degrees, initial spin 2 pi rad/s, gravity 9.81 along
#: the spindle (down).
FLYBALL = dict(density=3000.0, rod=(1.0, 0.01), sleeve=0.1, ball=5.0, stiffness=8e5,
               damping=4e4, free_length=0.5, s=0.5, alpha=np.radians(30.0), spin=2 * np.pi,
               offset=0.05)


class _Flyball:
    """The governor reduced by its symmetries: both arms at the same angle ``beta`` from the
    spindle's upward axis (the mirror symmetry of the initial state is kept by the motion) and
    the spindle's angle cyclic (its angular momentum ``H`` about the axis is conserved, no
    torque acts). Routh's reduction leaves ``(s, beta)``:

        m_s s''           = -m_s g + 2 T cos(gamma)            (sleeve)
        2 I_p beta''      = -dV/dbeta + psi'^2 / 2 dI_z/dbeta - 2 T dL/dbeta
        psi'              = H / I_z(beta)

    with ``I_p`` the arm's inertia about its pin, ``I_z`` the whole governor's about the
    spindle, ``T = k (L - L0) + c L'`` each spring's tension and ``L(s, beta)`` its length
    (from the sleeve's edge to the arm's middle). Written by hand, independent of the 3-D
    model."""

    def __init__(self):
        p = FLYBALL
        length, side = p["rod"]
        self.m_rod = p["density"] * length * side**2
        self.m_sleeve = p["density"] * p["sleeve"] ** 3
        self.m_ball = p["ball"]
        self.I_t = self.m_rod * (length**2 + side**2) / 12  # rod transverse, about its centre
        self.I_a = self.m_rod * side**2 / 6
        self.I_spindle = self.m_rod * side**2 / 6  # about its own axis
        self.I_sleeve_z = self.m_sleeve * p["sleeve"] ** 2 / 6
        self.I_pin = self.I_t + self.m_rod * 0.25 + self.m_ball
        self.e = p["offset"]
        self.k, self.c, self.L0 = p["stiffness"], p["damping"], p["free_length"]

    def inertia_z(self, beta):
        """I_z and dI_z/dbeta."""
        sb, cb = np.sin(beta), np.cos(beta)
        rc, rb = self.e + 0.5 * sb, self.e + sb
        rod = self.I_t * sb**2 + self.I_a * cb**2 + self.m_rod * rc**2 + self.m_ball * rb**2
        d_rod = (2 * (self.I_t - self.I_a) * sb * cb + self.m_rod * rc * cb
                 + 2 * self.m_ball * rb * cb)
        return self.I_spindle + self.I_sleeve_z + 2 * rod, 2 * d_rod

    def spring(self, s, beta):
        """Length, dL/ds, dL/dbeta (sleeve edge (e, s) to arm middle, in the arm's plane)."""
        dx = 0.5 * np.sin(beta)
        dz = 1.0 + 0.5 * np.cos(beta) - s
        L = np.hypot(dx, dz)
        return L, -dz / L, (dx * 0.5 * np.cos(beta) - dz * 0.5 * np.sin(beta)) / L

    def rates(self, _t, y, H):
        s, beta, sd, bd = y[0], y[1], y[2], y[3]
        Iz, dIz = self.inertia_z(beta)
        psid = H / Iz
        L, dLs, dLb = self.spring(s, beta)
        tension = self.k * (L - self.L0) + self.c * (dLs * sd + dLb * bd)
        dV = -2 * G * (0.5 * self.m_rod + self.m_ball) * np.sin(beta)
        sdd = (-self.m_sleeve * G - 2 * tension * dLs) / self.m_sleeve
        bdd = (-dV + 0.5 * psid**2 * dIz - 2 * tension * dLb) / (2 * self.I_pin)
        return np.array([sd, bd, sdd, bdd, psid])


def flyball_governor(t_end: float = 10.0) -> Case:
    """IFToMM benchmark A05, the stiff flyball governor (data: :data:`FLYBALL`).

    A spindle turns freely about the vertical (revolute to the ground at its foot, initial spin
    2 pi rad/s); a sleeve slides on it (prismatic, turning with it); two arms hinge at its top,
    0.05 m either side, each carrying a 5 kg ball at its tip (a particle on a spherical joint);
    instead of rigid coupler rods, spring-dampers of 8e5 N/m and 4e4 N s/m join each side of
    the sleeve to the middle of its arm. Initially the arms make 30 degrees with the
    horizontal, the couplers are at their free length 0.5 m and the sleeve is 0.5 m above the
    spindle's foot. The dampers make eigenvalues near -1e4 1/s next to the seconds of the
    governor's motion.

    Reference: the symmetric reduction :class:`_Flyball` (Routh) integrated by Radau IIA at
    ``rtol = 1e-12``; the benchmark's published s(t) (Gonzalez et al. 2006) is not stored
    here. The observable is the sleeve and both balls."""
    p = FLYBALL
    length, side = p["rod"]
    m_rod = p["density"] * length * side**2
    m_sleeve = p["density"] * p["sleeve"] ** 3
    I_sleeve = m_sleeve * p["sleeve"] ** 2 / 6
    beta0 = np.pi / 2 + p["alpha"]  # arm direction from the spindle's upward axis
    spin = np.array([0.0, 0.0, p["spin"]])
    e = p["offset"]
    scene = Scene("flyball-governor", dimension=3)
    scene.gravity = np.array([0.0, 0.0, -G])
    spindle_inertia = rod_inertia(m_rod, length, 2, side)
    scene.add(SpatialBody("spindle", m_rod, np.diag(spindle_inertia), position=[0, 0, 0.5],
                          angular_velocity=spin))
    scene.add(SpatialBody("sleeve", m_sleeve, [I_sleeve] * 3, position=[0, 0, p["s"]],
                          angular_velocity=spin))
    scene.add(Revolute("spindle_pin", "ground", "spindle", origin=[0, 0, 0], axis=[0, 0, 1]))
    scene.add(Prismatic("sleeve_slide", "spindle", "sleeve", origin=[0, 0, p["s"]],
                        axis=[0, 0, 1]))
    for k, sign in ((1, 1.0), (2, -1.0)):
        R = rotation_about_axis([0, 1, 0], sign * beta0)
        pivot = np.array([sign * e, 0.0, 1.0])
        centre, tip = pivot + R @ [0, 0, 0.5], pivot + R @ [0, 0, 1.0]
        scene.add(SpatialBody(f"arm_{k}", m_rod, np.diag(rod_inertia(m_rod, length, 2, side)),
                              position=centre, rotation=R, angular_velocity=spin,
                              velocity=np.cross(spin, centre)))
        scene.add(Particle(f"ball_{k}", p["ball"], position=tip, velocity=np.cross(spin, tip)))
        scene.add(Revolute(f"arm_pin_{k}", "spindle", f"arm_{k}", origin=pivot,
                           axis=[0, 1, 0]))
        scene.add(Spherical(f"ball_joint_{k}", f"arm_{k}", f"ball_{k}", origin=tip))
        scene.add(SpringDamper(f"coupler_{k}", "sleeve", f"arm_{k}", point_a=[sign * e, 0, 0],
                               point_b=[0, 0, 0], stiffness=p["stiffness"],
                               damping=p["damping"], free_length=p["free_length"]))

    reduced = _Flyball()
    Iz0, _ = reduced.inertia_z(beta0)
    H = Iz0 * p["spin"]

    def observe(y):
        s, beta, psi = y[0], y[1], y[4]
        out = [np.array([0.0, 0.0, s])]
        turn = rotation_about_axis([0, 0, 1], psi)
        for sign in (1.0, -1.0):
            tip = np.array([sign * (e + np.sin(beta)), 0.0, 1.0 + np.cos(beta)])
            out.append(turn @ tip)
        return np.concatenate(out)

    def rates(t, y):
        return reduced.rates(t, y, H)

    def jacobian(t, y):
        # by central differences (Newton's matrix of Radau; the angle psi is cyclic)
        out = np.zeros((5, 5))
        for j in range(4):
            h = 1e-7 * max(1.0, abs(y[j]))
            up, down = y.copy(), y.copy()
            up[j] += h
            down[j] -= h
            out[:, j] = (rates(t, up) - rates(t, down)) / (2 * h)
        return out

    reference = Trajectory(rates, [p["s"], beta0, 0.0, 0.0, 0.0], t_end, observe,
                            method="Radau", rtol=1e-12, atol=1e-12, jacobian=jacobian)
    full = _flyball_minimal(m_rod, m_sleeve, I_sleeve, spindle_inertia)
    x0, xd0 = np.array([0.0, p["s"], 0.0, 0.0]), np.array([p["spin"], 0.0, 0.0, 0.0])
    accelerations = full.com_accelerations(x0, xd0)
    return Case(scene.name, scene, t_end,
                "couplers replaced by 8e5 N/m, 4e4 N s/m spring-dampers: damped modes near "
                "-1e4 1/s on a 10 s motion", "stiff",
                ("sleeve", "ball_1", "ball_2"), reference, accelerations, length=1.0, dof=4,
                counted_dof=4, energy_conserved=False,
                source="IFToMM/MBS benchmark A05 (Gonzalez et al. 2006), data as in "
                       "RehabEngGroup/MBSbenchmarksInOpenSim src/A05-FlyballGovernor",
                notes=["the benchmark's reference s(t) is not stored: the reference is the "
                       "symmetric reduction (Routh), integrated by Radau IIA at 1e-12",
                       "balls are particles on spherical joints at the arms' tips (the "
                       "benchmark welds point masses)"])


def _flyball_minimal(m_rod, m_sleeve, I_sleeve, spindle_inertia) -> MinimalModel:
    """The governor in its four joint coordinates (spindle angle, sleeve height, both arms'
    angles from the initial pose) by Kane's method: the full model, without symmetry."""
    p = FLYBALL
    beta0, e = np.pi / 2 + p["alpha"], p["offset"]
    rod = rod_inertia(m_rod, p["rod"][0], 2, p["rod"][1])
    zero3 = np.zeros((3, 3))

    def kinematics(x):
        psi, s = x[0], x[1]
        R = jets.rotation([0, 0, 1], psi)
        frames = {"spindle": (R @ np.array([0.0, 0.0, 0.5]), R),
                  "sleeve": (jets.stack([0.0 * s, 0.0 * s, s]), R)}
        points = {}
        for k, sign in ((1, 1.0), (2, -1.0)):
            Ra = R @ jets.rotation([0, 1, 0], sign * (beta0 + x[1 + k]))
            pivot = R @ np.array([sign * e, 0.0, 1.0])
            frames[f"arm_{k}"] = (pivot + Ra @ np.array([0, 0, 0.5]), Ra)
            frames[f"ball_{k}"] = (pivot + Ra @ np.array([0, 0, 1.0]), Ra)
            points[f"arm_{k}"] = frames[f"arm_{k}"][0]
            points[f"edge_{k}"] = frames["sleeve"][0] + R @ np.array([sign * e, 0.0, 0.0])
        return frames, points

    bodies = {"spindle": (m_rod, spindle_inertia), "sleeve": (m_sleeve, np.eye(3) * I_sleeve),
              "arm_1": (m_rod, rod), "arm_2": (m_rod, rod),
              "ball_1": (p["ball"], zero3), "ball_2": (p["ball"], zero3)}
    springs = tuple(Spring(f"edge_{k}", f"arm_{k}", p["stiffness"], p["damping"],
                            p["free_length"]) for k in (1, 2))
    return MinimalModel(kinematics, bodies, [0.0, 0.0, -G], springs)
