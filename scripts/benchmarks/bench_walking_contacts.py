"""The walking robot on real ground under joint control: CPU per simulated second of the
project's two contact schemes beside MuJoCo's ``mj_step`` on the same robot, in one run.

Protocol
--------
* Robot: the built-in free-trunk hexapod on the tripod gait (``legs.robot.hexapod_scene``),
  its inverse dynamics sampled until each joint's effort spline is within ``--tol``
  (``legs.efforts.adaptive_inverse``), then on real ground (``legs.replay.grounded_scene``):
  each joint driven by a controller (target the gait's law, feedforward the inverse efforts of
  one stride, repeated; gains ``--kp``, ``--kd``), each foot a unilateral point contact (Coulomb
  ``--mu``, plastic). Simulated over ``--strides`` strides from the first sample's state.
  The event-driven run takes the gains of the rule instead, critically damped on each joint's
  reflected inertia at ``--event-bandwidth`` Hz (``hexapod.simulation.critical_gains``): its
  explicit steps cannot follow ``kd`` over the distal joints' inertia at 1.4e5 /s (with
  ``--kp``, ``--kd`` it reached 5.5 ms in 60 s).
* The project: Moreau-Jean time-stepping at ``--step`` (``hexapod.simulate``, method
  ``moreau-jean``; with ``--compiled`` also with its kernels compiled to C, in a temporary
  cache); the event-driven scheme at ``rtol = 1e-6`` stopped by ``--budget`` CPU
  seconds and counted per simulated second up to where it got (with ``--compiled`` also
  with its two kernels compiled, each run with its own budget). The CPU is the time loop's
  (``SimulationResult.cpu_time``: the steps and saves; the laws' table and the kernels are
  built before).
* MuJoCo: the same robot from the same scene: its URDF (``hexapod.scene.urdf_text``: the trunk
  the root link) read by MuJoCo as the forward-dynamics benchmark reads it (inertias as
  written), a free joint on the trunk, the joints at the project's initial angles (checked:
  the bodies' centres of mass against the project's), a sphere of ``FOOT_RADIUS`` at each
  foot point and the ground plane below them (MuJoCo's soft contacts, ``condim = 3``,
  friction ``--mu``, ``solref`` (2 steps, 1): as stiff as MuJoCo advises for the step),
  the same controller as MuJoCo writes one (position and velocity actuators, implicitfast
  integrator; the feedforward as ``qfrc_applied``) stepped by ``mj_step`` at ``--mujoco-step``
  (the targets, their rates and the feedforward evaluated at each step's time before the
  loop), started from the same state. Its CPU is the loop's, controls included, and
  ``mj_step`` alone.
* Printed (Markdown, stdout): per run, the step, CPU per simulated second and its ratio to
  MuJoCo's, the trunk's position at the end against the prescribed one, the largest
  touch-down and lift-off lateness against the gait's schedule
  (``legs.replay.schedule_lateness``: a foot's first landing and last leaving around each
  scheduled one; the grazes, touches with no time on the ground, counted apart), the largest
  joint tracking error. Progress and the load on stderr. Nothing is written.

    python3 scripts/benchmarks/bench_walking_contacts.py [--strides 1] [--step 1e-3]
        [--kp 200] [--kd 2] [--event-bandwidth 150] [--tol 1e-8] [--mu 0.8] [--budget 120]
        [--mujoco-step 1e-3] [--compiled]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from measure import log, mujoco_warnings_to_stderr, one_blas_thread, start

one_blas_thread()  # before NumPy loads

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
import hexapod as hx  # noqa: E402
from legs.cockroach import STRIDE_PERIOD  # noqa: E402
from legs.efforts import adaptive_inverse  # noqa: E402
from legs.replay import (  # noqa: E402
    GROUND_KD,
    GROUND_KP,
    event_times,
    grazes,
    grounded_scene,
    schedule_lateness,
)
from legs.robot import hexapod_scene  # noqa: E402

#: the radius of MuJoCo's foot spheres (m): small against the leg, so that the contact point
#: is the project's foot point to within it
FOOT_RADIUS = 1e-3
#: MuJoCo's reading of the URDF (as scripts/benchmarks/bench_forward_mujoco_side.py reads it)
COMPILER = ('<mujoco><compiler balanceinertia="false" discardvisual="true" fusestatic="false" '
            'inertiafromgeom="false"/></mujoco>')


def project_run(grounded, driven, t_end: float, method: str, **options) -> dict:
    log(f"{method}: {t_end:g} s ...")
    result = hx.simulate(grounded, t_end, method=method, **options)
    reached = float(result.t[-1])
    worst = schedule_lateness(driven, event_times(result.events, with_grazes=False), reached)
    touch, lift = worst["touch-down"], worst["lift-off"]
    grazed = schedule_lateness(driven, event_times(result.events), reached)["touch-down"]
    trunk = [b.name for b in grounded.bodies].index("trunk")
    if result.message:
        log(f"{method}: {result.message}")
    return {"run": method, "status": result.status, "reached": reached,
            "cpu_per_s": result.cpu_time / max(reached, 1e-300),
            "trunk": result.q[-1][grounded.bodies[trunk].q][:3], "touch": touch,
            "lift": lift, "tracking": float(np.abs(result.tracking).max()),
            "grazes": len(grazes(result.events)), "grazed": grazed,
            "step": options.get("step") or f"rtol {options.get('rtol')}"}


class MujocoRobot:
    """The grounded scene in MuJoCo (see the module's description)."""

    def __init__(self, scene: hx.Scene, model: hx.Model, mu: float, step: float):
        import mujoco

        self.mj = mujoco
        mujoco_warnings_to_stderr(mujoco)
        spec = mujoco.MjSpec.from_string(
            hx.scene.urdf_text(scene).replace("</robot>", COMPILER + "\n</robot>"))
        spec.body("trunk").add_freejoint()
        self.trunk_pose = scene.in_si().pose("trunk")  # the root link's frame, world
        # the joints' angles at the start (a URDF's zero pose is the joints' zero, not the
        # scene's initial pose): the controllers' targets plus their errors there
        self.model = model
        self.controlled = [model.joints[f.joint].name for f in model.forces
                           if f.kind == "controller"]
        targets = law_columns(scene, model)[0]
        self.angles0 = (np.asarray(model.law_values(np.zeros(1))[0])[targets, 0]
                        + hx.simulation.tracking_errors(model, np.zeros(1), model.q0[None])[0])
        probe = spec.compile()
        data = mujoco.MjData(probe)
        self.place(probe, data)
        contacts = [f for f in model.forces if f.contact is not None]
        self.feet = []
        q0 = model.q0
        for element in contacts:
            body = model.bodies[element.bodies[0]]
            pose = model.body_pose(q0, body.index)
            world = pose.position + pose.rotation @ np.asarray(element.points[0], float)
            mj_body = mujoco.mj_name2id(probe, mujoco.mjtObj.mjOBJ_BODY, body.name)
            local = data.xmat[mj_body].reshape(3, 3).T @ (world - data.xpos[mj_body])
            geom = spec.body(body.name).add_geom()
            geom.type, geom.size[0], geom.pos = mujoco.mjtGeom.mjGEOM_SPHERE, FOOT_RADIUS, local
            geom.friction[0] = mu
            geom.solref[:] = [2 * step, 1.0]
            geom.name = element.name
            self.feet.append((element.name, world))
        # each controller as MuJoCo writes one: a position actuator (kp, its control the
        # target) and a velocity actuator (kd, its control the target's rate), whose damping
        # the implicitfast integrator takes implicitly (applied explicitly, the distal joints'
        # kd / I of 1.4e5 /s needs steps under 14 us); the feedforward is qfrc_applied
        for name, (kp, kd) in zip(self.controlled, law_columns(scene, model)[3], strict=True):
            for gain, bias in ((kp, [0.0, -kp, 0.0]), (kd, [0.0, 0.0, -kd])):
                actuator = spec.add_actuator()
                actuator.trntype = mujoco.mjtTrn.mjTRN_JOINT
                actuator.target = name
                actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
                actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
                actuator.gainprm[0] = gain
                actuator.biasprm[:3] = bias
        floor = spec.worldbody.add_geom()
        height = float(np.mean([c.contact.surface_point[2] for c in contacts]))
        floor.type, floor.size, floor.pos = mujoco.mjtGeom.mjGEOM_PLANE, [0, 0, 1], [
            0.0, 0.0, height - FOOT_RADIUS]
        floor.friction[0] = mu
        self.m = spec.compile()
        self.m.opt.gravity[:] = model.gravity
        self.m.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        self.d = mujoco.MjData(self.m)
        self.foot_geoms = np.array([mujoco.mj_name2id(self.m, mujoco.mjtObj.mjOBJ_GEOM, name)
                                    for name, _ in self.feet])
        self.trunk = mujoco.mj_name2id(self.m, mujoco.mjtObj.mjOBJ_BODY, "trunk")

    def place(self, m, d) -> None:
        """The free joint (the first: the trunk is the root) at the trunk's initial pose (a
        URDF does not place its root), the joints at the URDF's pose, and MuJoCo's forward
        pass there."""
        mj = self.mj
        mj.mj_resetData(m, d)
        d.qpos[:3] = self.trunk_pose.position
        mj.mju_mat2Quat(d.qpos[3:7], np.ascontiguousarray(self.trunk_pose.rotation).ravel())
        for name, angle in zip(self.controlled, self.angles0, strict=True):
            d.qpos[m.jnt_qposadr[mj.mj_name2id(m, mj.mjtObj.mjOBJ_JOINT, name)]] = angle
        mj.mj_forward(m, d)

    def pose_mismatch(self) -> float:
        """The largest distance (m) of a body's centre of mass in MuJoCo from the project's at
        the start: the same robot in the same pose (the URDF's inertial origins and joint
        frames against the project's model)."""
        m, d, mj = self.m, self.d, self.mj
        self.place(m, d)
        return max(float(np.linalg.norm(
            d.xipos[mj.mj_name2id(m, mj.mjtObj.mjOBJ_BODY, body.name)]
            - self.model.body_pose(self.model.q0, body.index).position))
            for body in self.model.bodies)

    def controllers(self, model: hx.Model):
        """Per controller of ``model``: its joint's qpos and dof addresses in MuJoCo."""
        mj, m = self.mj, self.m
        out = []
        for force in model.forces:
            if force.kind == "controller":
                joint = model.joints[force.joint].name
                jid = mj.mj_name2id(m, mj.mjtObj.mjOBJ_JOINT, joint)
                out.append((int(m.jnt_qposadr[jid]), int(m.jnt_dofadr[jid])))
        return np.array(out)


def law_columns(scene: hx.Scene, model: hx.Model) -> tuple[list, list, list, list]:
    """Per controller (in the model's order): the indices of its target, target rate and
    feedforward laws among the model's laws, and its gains (SI)."""
    index = {id(law): k for k, law in enumerate(model.laws)}
    rate_of = {id(law.law): k for k, law in enumerate(model.laws)
               if getattr(law, "kind", "") == "rate"}
    controllers = {e.name: e for e in scene.elements if getattr(e, "kind", "") == "controller"}
    targets, rates, feedforward, gains = [], [], [], []
    for force in model.forces:
        if force.kind == "controller":
            element = controllers[force.name]
            targets.append(index[id(element.target)])
            rates.append(rate_of[id(element.target)])
            feedforward.append(index[id(element.feedforward)])
            gains.append((element.kp / scene.unit, element.kd / scene.unit))
    return targets, rates, feedforward, gains


def mujoco_run(robot: MujocoRobot, scene: hx.Scene, model: hx.Model, driven, t_end: float,
               step: float) -> dict:
    mj, m, d = robot.mj, robot.m, robot.d
    m.opt.timestep = step
    steps = int(round(t_end / step))
    times = np.arange(steps) * step
    targets, rates, feedforward, _ = law_columns(scene, model)
    # the laws' values at each step's time, evaluated before the loop (as a table is)
    w = np.asarray(model.law_values(times)[0])
    target, rate, ff = w[targets].T, w[rates].T, w[feedforward].T
    addresses = robot.controllers(model)
    qpos_at, dof_at = addresses[:, 0], addresses[:, 1]
    tracking = 0.0
    # the same start: the trunk's pose is the URDF's (the root link frame), its velocity and
    # the joints' rates the project's initial ones
    robot.place(m, d)
    trunk = [b.name for b in model.bodies].index("trunk")
    body = model.bodies[trunk]
    v_com, omega_body = model.v0[body.v][:3], model.v0[body.v][3:]
    rotation = model.body_pose(model.q0, trunk).rotation
    omega = rotation @ omega_body
    origin = d.xpos[robot.trunk]
    d.qvel[:3] = v_com + np.cross(omega, origin - model.body_pose(model.q0, trunk).position)
    d.qvel[3:6] = d.xmat[robot.trunk].reshape(3, 3).T @ omega
    d.qvel[dof_at] = rate[0]
    mj.mj_forward(m, d)
    touching = np.zeros(len(robot.feet), bool)
    events: dict = {}
    cpu = time.process_time()
    for k in range(steps):
        d.ctrl[0::2], d.ctrl[1::2] = target[k], rate[k]
        d.qfrc_applied[dof_at] = ff[k]
        mj.mj_step(m, d)
        if k + 1 < steps:  # the error at the state reached, against the target there
            tracking = max(tracking, float(np.abs(d.qpos[qpos_at] - target[k + 1]).max()))
        now = np.isin(robot.foot_geoms, d.contact.geom[:d.ncon].ravel())
        for j in np.flatnonzero(now != touching):
            kind = "touch-down" if now[j] else "lift-off"
            events.setdefault(robot.feet[j][0], {}).setdefault(kind, []).append(d.time)
        touching = now
    cpu = time.process_time() - cpu
    bare = time.process_time()
    mj.mj_step(m, d, 1000)
    bare = (time.process_time() - bare) / (1000 * step)
    worst = schedule_lateness(driven, events, t_end)
    touch, lift = worst["touch-down"], worst["lift-off"]
    return {"run": "MuJoCo mj_step (soft contacts, implicitfast)", "status": "finished",
            "reached": t_end, "cpu_per_s": cpu / t_end, "bare_per_s": bare,
            "trunk": d.xipos[robot.trunk].copy(), "touch": touch, "lift": lift,
            "grazes": 0, "grazed": touch,
            "tracking": tracking, "step": step}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--strides", type=int, default=1)
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--kp", type=float, default=GROUND_KP)
    parser.add_argument("--kd", type=float, default=GROUND_KD)
    parser.add_argument("--mu", type=float, default=0.8)
    parser.add_argument("--event-bandwidth", type=float, default=150.0,
                        help="Hz: the event-driven run's gains, by the rule (default 150: at "
                             "100 the loop is marginal over strides, docs/walking.md)")
    parser.add_argument("--tol", type=float, default=1e-8,
                        help="the feedforward efforts' spline tolerance, relative (default "
                             "1e-8; the studies' default is EFFORT_TOL)")
    parser.add_argument("--budget", type=float, default=120.0,
                        help="CPU seconds for the event-driven run (default 120)")
    parser.add_argument("--mujoco-step", type=float, default=1e-3)
    parser.add_argument("--compiled", action="store_true",
                        help="also run both schemes with their kernels compiled to C")
    args = parser.parse_args()
    start("bench_walking_contacts")
    scene = hexapod_scene(gait="tripod", trunk="free", period=STRIDE_PERIOD)
    driven = hx.assemble(scene)
    inverse, _ = adaptive_inverse(driven, scene, 0.0, STRIDE_PERIOD, tol=args.tol)
    on_ground = grounded_scene(scene, inverse, kp=args.kp, kd=args.kd, mu=args.mu,
                               periodic=True)
    grounded = hx.assemble(on_ground)
    t_end = args.strides * STRIDE_PERIOD
    runs = [project_run(grounded, driven, t_end, "moreau-jean", step=args.step)]
    if args.compiled:  # its kernels compiled to C (the compiler's time is not the loop's)
        with tempfile.TemporaryDirectory() as cache, hx.executing(compiled=True, cache=cache):
            runs.append(project_run(grounded, driven, t_end, "moreau-jean", step=args.step))
        runs[-1]["run"] = "moreau-jean, compiled"
    kp, kd = hx.simulation.critical_gains(driven, inverse.q[0], args.event_bandwidth)
    by_rule = hx.assemble(grounded_scene(scene, inverse, kp=kp, kd=kd, mu=args.mu,
                                         periodic=True))
    runs.append(project_run(by_rule, driven, t_end, "event-driven", rtol=1e-6,
                            cpu_budget=args.budget))
    runs[-1]["gains"] = f"{args.event_bandwidth:g} Hz rule"
    if args.compiled:
        with tempfile.TemporaryDirectory() as cache, hx.executing(compiled=True, cache=cache):
            runs.append(project_run(by_rule, driven, t_end, "event-driven", rtol=1e-6,
                                    cpu_budget=args.budget))
        runs[-1].update(run="event-driven, compiled", gains=f"{args.event_bandwidth:g} Hz rule")
    log("MuJoCo ...")
    robot = MujocoRobot(on_ground, grounded, args.mu, args.mujoco_step)
    runs.append(mujoco_run(robot, on_ground, grounded, driven, t_end, args.mujoco_step))
    trunk = driven.bodies[[b.name for b in driven.bodies].index("trunk")].q
    start_q, end_q = inverse.q[0][trunk][:3], inverse.q[-1][trunk][:3]
    prescribed = start_q + args.strides * (end_q - start_q)  # a stride's advance, repeated
    reference = runs[-1]["cpu_per_s"]
    print(f"Walking hexapod on the ground, {args.strides} stride(s) of {STRIDE_PERIOD} s, "
          f"kp {args.kp:g} N m/rad, kd {args.kd:g} N m s/rad, mu {args.mu:g}; trunk "
          f"prescribed at the end {np.round(prescribed, 4)} m\n")
    print("| run | gains | step | reached (s) | CPU per simulated s | / MuJoCo | trunk at the "
          "end (m) | touch-downs within (ms) | grazes (touch-downs with them, ms) | lift-offs "
          "within (ms) | tracking error (mrad) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for run in runs:
        print(f"| {run['run']} ({run['status']}) | {run.get('gains', 'kp, kd')} | "
              f"{run['step']} | {run['reached']:.3f} | "
              f"{run['cpu_per_s']:.3g} s | {run['cpu_per_s'] / reference:.3g} | "
              f"{np.round(run['trunk'], 4)} | {1e3 * run['touch']:.2f} | {run['grazes']} "
              f"({1e3 * run['grazed']:.2f}) | "
              f"{1e3 * run['lift']:.2f} | {1e3 * run['tracking']:.3g} |")
    print(f"\nMuJoCo's bodies start with their centres of mass within "
          f"{robot.pose_mismatch():.2g} m of the project's (the same robot in the same pose).")
    print(f"MuJoCo's mj_step alone (no controller, no event bookkeeping): "
          f"{runs[-1]['bare_per_s']:.3g} s of CPU per simulated second.")


if __name__ == "__main__":
    main()
