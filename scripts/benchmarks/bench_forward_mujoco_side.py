"""The MuJoCo side of ``scripts/benchmarks/bench_forward_mujoco.py``: the mechanism read by
MuJoCo from the URDF hexapod writes, the checks that it is the same mechanism, MuJoCo's runs,
and the report (Markdown table and figure). MuJoCo is optional: nothing here imports it before
it is asked for."""

from __future__ import annotations

import io
import time

import numpy as np
from bench_forward_problems import Reference
from bench_forward_report import fmt, method_row
from bench_forward_runs import TARGET, Run
from measure import mujoco_warnings_to_stderr

import hexapod as hx
from hexapod.scene import urdf_text
from hexapod.spatial import rotation_from_euler_parameters

#: MuJoCo's reading of the URDF: the inertias as written (never recomputed from geometry nor
#: "balanced"), every link a body of its own (no fusion of the fixed ones), no visuals.
COMPILER = ('<mujoco><compiler balanceinertia="false" discardvisual="true" fusestatic="false" '
            'inertiafromgeom="false"/></mujoco>')
MUJOCO_METHODS = {  # name -> (integrator, description)
    "mujoco-rk4": ("mjINT_RK4", "MuJoCo's classical Runge-Kutta 4, fixed step"),
    "mujoco-euler": ("mjINT_EULER", "MuJoCo's default semi-implicit Euler, fixed step"),
}


def mujoco_available() -> tuple[bool, str]:
    try:
        import mujoco
    except ImportError as error:
        return False, str(error)
    return True, mujoco.__version__


class MujocoModel:
    """The scene's URDF (``hexapod.scene.urdf_text``) read by MuJoCo, set up as hexapod's model:
    the same gravity, no contact, no joint limit (the URDF's limits are +-1e9 rad anyway), and
    no damping, armature or friction loss (checked). MuJoCo's ``qpos0`` is the URDF's pose,
    which is hexapod's initial pose (checked by :meth:`agreement`)."""

    def __init__(self, scene: hx.Scene, model: hx.Model):
        import mujoco

        self.mj, self.hx_model = mujoco, model
        mujoco_warnings_to_stderr(mujoco)
        text = urdf_text(scene).replace("</robot>", COMPILER + "\n</robot>")
        m = self.m = mujoco.MjModel.from_xml_string(text)
        m.opt.gravity[:] = model.gravity
        m.opt.disableflags |= (mujoco.mjtDisableBit.mjDSBL_CONTACT
                               | mujoco.mjtDisableBit.mjDSBL_LIMIT)
        extras = {"damping": m.dof_damping, "armature": m.dof_armature,
                  "frictionloss": m.dof_frictionloss, "stiffness": m.jnt_stiffness}
        nonzero = [name for name, values in extras.items() if np.any(values)]
        if nonzero:
            raise NotImplementedError(f"MuJoCo's model has joint {', '.join(nonzero)}")
        if np.any(model.v0):
            raise NotImplementedError("the problems start at rest (qvel = 0 in MuJoCo)")
        self.ids = np.array([mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, b.name)
                             for b in model.bodies])
        if np.any(self.ids < 0):
            raise NotImplementedError("a body of hexapod's model is missing in MuJoCo's")
        self.d = mujoco.MjData(m)

    def describe(self) -> dict:
        m = self.m
        return {"nbody": int(m.nbody), "njnt": int(m.njnt), "nq": int(m.nq), "nv": int(m.nv),
                "gravity": m.opt.gravity.tolist()}

    def agreement(self, q: np.ndarray, v_dot: np.ndarray) -> dict:
        """MuJoCo's initial centres of mass (``xipos``) and their accelerations (world frame,
        ``mj_objectAcceleration`` after ``mj_rnePostConstraint``; MuJoCo counts gravity as an
        acceleration of the world, -g, which is added back) against hexapod's ``q`` and its
        saddle-point solve ``v_dot``: for a spatial body ``(a, omega'_dot)``, the angular part in
        the body frame, turned to the world by R (``d(R omega')/dt = R omega'_dot``); each
        largest difference relative to the largest value."""
        mj, m, d = self.mj, self.m, self.d
        mj.mj_resetData(m, d)
        mj.mj_forward(m, d)
        mj.mj_rnePostConstraint(m, d)
        bodies = self.hx_model.bodies
        ours_r = np.array([q[b.q][:3] for b in bodies])
        ours_a = np.array([v_dot[b.v][:3] for b in bodies])
        ours_w = np.array([rotation_from_euler_parameters(q[b.q][3:]) @ v_dot[b.v][3:]
                           for b in bodies])
        theirs = np.zeros((len(bodies), 6))
        for row, body in zip(theirs, self.ids, strict=True):
            mj.mj_objectAcceleration(m, d, mj.mjtObj.mjOBJ_BODY, body, row, 0)
        theirs[:, 3:] += m.opt.gravity

        def relative(a, b):
            return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))
        return {"positions": relative(d.xipos[self.ids], ours_r),
                "com_accelerations": relative(theirs[:, 3:], ours_a),
                "angular_accelerations": relative(theirs[:, :3], ours_w),
                "joint_accelerations_scale": float(np.abs(d.qacc).max())}

    def run(self, method: str, step: float, t_end: float, ref: Reference) -> Run:
        """One run at step ``step``: MuJoCo's own loop (``mj_step(m, d, nstep)``, in C) timed
        for ``cpu``, then the same steps again one call at a time from Python with the centres
        of mass copied after each (``cpu_recorded``), for the error; the two end states must be
        the same bit for bit (MuJoCo is deterministic)."""
        mj, m, d = self.mj, self.m, self.d
        m.opt.integrator = getattr(mj.mjtIntegrator, MUJOCO_METHODS[method][0])
        m.opt.timestep = step
        steps = int(round(t_end / step))
        mj.mj_resetData(m, d)
        cpu = time.process_time()
        mj.mj_step(m, d, steps)
        cpu = time.process_time() - cpu
        end = d.qpos.copy()
        positions = np.empty((steps + 1, len(self.ids), 3))
        mj.mj_resetData(m, d)
        mj.mj_forward(m, d)
        positions[0] = d.xipos[self.ids]
        ids = self.ids
        recorded = time.process_time()
        for k in range(1, steps + 1):
            mj.mj_step(m, d)
            positions[k] = d.xipos[ids]
        recorded = time.process_time() - recorded
        run = Run(step, cpu, steps, status="finished",
                  counters={"cpu_recorded_s": recorded, "t_end": float(d.time)})
        if not np.array_equal(end, d.qpos):
            run.status, run.message = "failed", "the two loops ended in different states"
        elif not np.all(np.isfinite(positions)):
            run.status, run.message = "failed", "not finite"
        else:
            run.error = ref.error(np.arange(steps + 1) * step, positions)
        return run


# ------------------------------------------------------------------ report

def fastest(result: dict, library: str, key: str = "time_to_target_s") -> tuple[float, str]:
    """The least ``key`` of a library's methods that reached the target (``=`` or ``<=``)."""
    values = [(x[key], m) for m, x in result["methods"].items()
              if x["library"] == library and np.isfinite(x[key])
              and x["time_to_target_qualifier"] in ("=", "<=")]
    return min(values) if values else (float("nan"), "")


def ratio_to_rk4(result: dict) -> dict:
    """hexapod's fastest time to the target over MuJoCo's RK4's, and whether it meets the
    project's aim (at most 2)."""
    rk4 = result["methods"].get("mujoco-rk4")
    ours, method = fastest(result, "hexapod")
    if not rk4 or not method or rk4["time_to_target_qualifier"] not in ("=", "<="):
        return {}
    ratio = ours / rk4["time_to_target_s"]
    qualifiers = (result["methods"][method]["time_to_target_qualifier"],
                  rk4["time_to_target_qualifier"])
    bound = {("<=", "="): "<= ", ("=", "<="): ">= ", ("<=", "<="): "~ "}.get(qualifiers, "")
    ours_rk4 = result["methods"].get("rk4-baumgarte", {}).get("cpu_per_step_ms", np.nan)
    return {"ratio": ratio, "hexapod": method, "bound": bound, "aim": 2.0,
            "meets_aim": bool(ratio <= 2.0) if bound in ("", "<= ") else None,
            # the same method at the same step (1 ms): the implementations' speeds alone
            "rk4_per_step": ours_rk4 / rk4["cpu_per_step_ms"]}


def markdown(results: list[dict], args, mujoco_version: str | None) -> str:
    mujoco = (f"MuJoCo {mujoco_version}, CPU of its own loop (`mj_step(m, d, nstep)`), and in "
              "brackets of a Python loop copying the centres of mass after each step"
              if mujoco_version else "MuJoCo not installed: hexapod alone")
    kernels = ("hexapod's kernels compiled to C" if getattr(args, "compile", False) else
               "hexapod's kernels in CasADi's virtual machine")
    lines = [f"Target: relative position error {TARGET:g} over the span; CPU times best of "
             f"{args.repeat}; {kernels}; {mujoco}.", "",
             "| problem | bodies | library | method | CPU/step ms (steps) | error at setting "
             "| CPU to 1e-6 s | rungs |", "| --- | ---: | --- | --- | ---: | ---: | ---: | ---: |"]
    for r in results:
        for method, x in r["methods"].items():
            recorded = x.get("time_to_target_recorded_s", np.nan)
            note = (f" ({fmt(recorded)})" if x["library"] == "mujoco" and np.isfinite(recorded)
                    else "")
            lines.append(method_row(r, method, x, note))
    lines += ["", "| problem | span s | initial positions | initial com accelerations "
              "| initial angular accelerations | reference vs MuJoCo RK4 at h = "
              f"{args.check_step * 1e6:g} us | hexapod best / MuJoCo RK4, time to 1e-6 "
              "| at most 2? |", "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |"]
    for r in results:
        mj = r["mujoco"] or {}
        agree = mj.get("agreement", {})
        rt = ratio_to_rk4(r)
        ratio = (f"{rt['bound']}{rt['ratio']:.3g} ({rt['hexapod']})" if rt else "-")
        verdict = ("-" if not rt else "unknown (bounds)" if rt["meets_aim"] is None
                   else "yes" if rt["meets_aim"] else "no")
        lines.append(
            f"| {r['problem']['key']} | {r['problem']['t_end']:g} "
            f"| {fmt(agree.get('positions', np.nan), 2)} "
            f"| {fmt(agree.get('com_accelerations', np.nan), 2)} "
            f"| {fmt(agree.get('angular_accelerations', np.nan), 2)} "
            f"| {fmt(mj.get('check_error', np.nan), 2)} | {ratio} | {verdict} |")
    return "\n".join(lines) + "\n"


def figure(results: list[dict]) -> bytes:
    """CPU time against error, every finished rung, one panel per problem."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    fig = Figure(figsize=(4.6 * max(1, len(results)), 4.4))
    axes = np.atleast_1d(fig.subplots(1, max(1, len(results))))
    methods = list(dict.fromkeys(m for r in results for m in r["methods"]))
    for ax, r in zip(axes, results, strict=False):
        for k, method in enumerate(methods):
            x = r["methods"].get(method)
            if not x:
                continue
            points = sorted((rung["error"], rung["cpu_s"]) for rung in x["rungs"]
                            if rung["status"] == "finished" and np.isfinite(rung["error"])
                            and rung["error"] > 0)
            if points:
                error, cpu = np.array(points).T
                ax.loglog(error, cpu, marker="osD^v<>ph*x+"[k % 12], color=f"C{k % 10}",
                          linestyle="--" if x["library"] == "mujoco" else "-", label=method)
        ax.axvline(TARGET, color="grey", linewidth=0.8)
        ax.set_xlabel("relative position error")
        ax.set_title(f"{r['problem']['key']} ({r['problem']['t_end']:g} s)")
        ax.grid(True, which="both", linewidth=0.4, alpha=0.6)
        ax.invert_xaxis()
    axes[0].set_ylabel("CPU time (s)")
    if axes[0].lines:
        axes[0].legend(fontsize=7)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=120)
    return buffer.getvalue()
