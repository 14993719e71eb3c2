"""Forward dynamics against Exudyn: cost per step, CPU time to an accuracy, growth with size.

Protocol
--------
* Problems, every body released at rest under gravity (9.81 m/s^2), no driver, no other force:

  - ``front-leg``: the left front leg of ``legs`` (``front_leg_scene(gait=False)``: 6 spatial
    bodies, 6 revolute joints, the trunk fixed) falling from its initial pose, 0.5 s;
  - ``four-bar``: the four-bar of ``data/scenes/four_bar_3d.toml`` (crank 0.1 m 0.3 kg,
    coupler 0.5 m 1 kg, rocker 0.4 m 0.8 kg, slender bars, ground 0.4 m) built in the plane,
    the crank turned to +x (the file's pose is an equilibrium): pivots A (0, 0), B (0.1, 0),
    C (0.4, 0.4), D (0.4, 0) m; 3 planar bodies, 4 revolute joints, the rocker's ground pivot
    closing the loop, 1 degree of freedom, gravity along -y, 2 s;
  - ``chain-N``: the serial chains of ``bench_inverse.py`` (N spatial bodies of 1 kg, 0.1 m
    apart along x, revolute joints with random axes, seed 0) hanging from the ground, released
    from that horizontal pose, 0.5 s; N in ``--sizes`` (default 10 30 100 300).

* Error of a run: ``e = max_k max_i |r_i(t_k) - r_i_ref(t_k)| / max_k,i |r_i_ref(t_k)|``, with
  ``r_i`` the centre of mass of body i (the bodies' position coordinates in both libraries,
  Euclidean norm), ``t_k`` the end of every step the run returns, and the reference
  interpolated at ``t_k`` by quintic Hermite interpolation from its ``r, r_dot, r_ddot``.
* Reference: the same model integrated by hexapod's ``--reference-method`` (default
  ``dop853-projection``) at ``rtol = atol = 1e-12`` with steps of at most 2.5 ms,
  cached in ``OUT/references/`` and reused while the problem, the settings and hexapod's version
  are the same. Checked twice: its interpolation error (every other sample left out and
  interpolated from the rest; the real spacing is half that, so the figure is pessimistic) and,
  with Exudyn, against Exudyn's own tight solution (its index-2 trapezoidal rule at
  ``h = t_end / 8000`` and ``t_end / 16000`` with Newton's relative tolerance 1e-12,
  Richardson-extrapolated: the rule is symmetric, its error even in h), which must agree to
  about 1e-8 (measured: 1e-13 to 1e-9).
* Methods: every integrator in hexapod's registry (``--methods`` to choose). Adaptive ones on
  the ladder ``rtol = atol = 1e-3, 1e-4, ..., 1e-11`` (SI units: atol applies to metres,
  radians, Euler parameters and their rates alike), fixed-step ones on ``h = 4 ms / 2^k``.
  Exudyn (optional extra ``compare``), when ``import exudyn`` works: the same model built from
  hexapod's assembled model (``ObjectRigidBody`` on ``NodeRigidBodyEP``, Euler parameters with
  their normalisation as an algebraic equation; ``ObjectRigidBody2D`` in the plane; joints by
  ``CreateRevoluteJoint`` (``ObjectJointRevoluteZ``, 5 equations) or ``ObjectJointRevolute2D``,
  all with Lagrange multipliers), solved by its generalized-alpha at index 3 (spectral radius
  0.9, as hexapod's) and by its trapezoidal rule at index 2 (Newmark 1/4, 1/2 with velocity
  constraints), each with its default modified Newton method (the Jacobian is kept over steps
  while Newton converges fast enough), on the same step ladder, with Eigen's sparse LU (faster
  than its dense default at every size measured here, 10 to 300 bodies). Its explicit solvers
  (DOPRI5, RK67, ...) do not solve joint constraints: they refuse Euler-parameter nodes (an
  algebraic equation per node), and with rotation-vector nodes they either drop the joint
  equations (a warning; the bodies fall freely) or refuse them; the script tries DOPRI5 and
  RK67 once per problem and reports what they say.
* Same mechanism: Exudyn's initial accelerations (its solver's initialisation) against
  hexapod's saddle-point solve, relative to the largest, printed; must be ~1e-8 or better.
* (a) Cost per step: CPU time of the run at the representative setting (``rtol = 1e-6``; ``h =
  1 ms``) divided by its accepted steps. (b) CPU time to reach ``e = 1e-6``: the ladder is
  walked from the representative setting, tighter while ``e > 1e-6`` or looser while
  ``e <= 1e-6``, and the CPU time interpolated log-log between the two rungs that bracket
  1e-6; ``<=`` when the loosest rung run is already below (or its looser neighbour failed),
  ``>`` when no rung within the budget reaches it. (c) Growth exponent: least-squares slope of
  log(CPU per step) against log(bodies) over the chains.
* Timing: ``time.process_time`` around the integrator's start (hexapod: the consistent initial
  state; Exudyn: its solver's initialisation, initial accelerations included) and its steps;
  best of ``--repeat`` runs (a run of more than 10 s is not repeated). Not timed: the model's
  assembly, the construction of CasADi's Functions (a warm-up run of every method before any
  timing, reported as ``warm-up s``), Exudyn's ``mbs.Assemble()``, writing. Both libraries
  record the centre-of-mass positions after every step during the timed runs (hexapod: a copy;
  Exudyn: internal sensors, measured at under 1 % of a step). Exudyn's output files, renderer
  and console output are switched off; it runs on one thread, and so does BLAS
  (``OPENBLAS_NUM_THREADS=1`` unless set otherwise).
* Budget: a hexapod run is stopped when its CPU time passes ``--budget`` seconds (then it
  counts as not reaching the target, its steps still give the cost per step, and the ladder is
  walked looser); a rung whose predicted time (from the previous rung) exceeds the budget is
  not run.

Outputs in ``--out`` (default ``bench-forward/``): the Markdown table on stdout,
``bench_forward.json`` (every rung of every method; rewritten after each problem, with
``"complete": false`` until the end), ``bench_forward.png`` (CPU per step against
bodies over the chains with the fitted exponents, and CPU time to 1e-6 per problem) and the
references, each written atomically; progress on stderr.

    python3 scripts/bench_forward.py [--sizes 10 30 100 300] [--repeat 3] [--budget 900]
    python3 scripts/bench_forward.py --quick        # chains of 10 and 30, one run per rung
"""

from __future__ import annotations

import os

# One BLAS thread, set before NumPy loads OpenBLAS: the matrices are small, and on a shared
# machine idle BLAS threads spin (a 110 x 110 solve measured 30 ms instead of 0.3 ms);
# process_time counts every thread, and Exudyn runs on one.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import argparse  # noqa: E402
import hashlib  # noqa: E402
import io  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402
from hexapod import (  # noqa: E402
    INTEGRATORS,
    get_integrator,
    rotation_from_euler_parameters,
    write_atomically,
)
from legs import front_leg_scene  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_inverse import chain_scene  # noqa: E402  (the same chains in every benchmark)

TARGET = 1e-6  # relative position error of (b)
REPRESENTATIVE_RTOL = 1e-6
REPRESENTATIVE_STEP = 1e-3  # s
RTOL_LADDER = [10.0**-k for k in range(3, 12)]  # loose -> tight
STEP_LADDER = [4e-3 / 2**k for k in range(12)]  # 4 ms ... 2 us, loose -> tight
REFERENCE_RTOL = 1e-12
REFERENCE_MAX_STEP = 2.5e-3  # s, the reference's largest step (for the interpolation)
EXUDYN_TIGHT_STEPS = 8000  # Exudyn's tight solution: h = t_end / this, and half of it
EXUDYN_TIGHT_NEWTON = 1e-12  # its Newton tolerance (relative; 1e-8 by default, which limits
# the extrapolated solution to ~1e-9 .. 1e-8)
LONG_RUN = 10.0  # s of CPU: such a run is not repeated
EXUDYN_METHODS = {  # name -> (solver type, description)
    "exudyn-ga-i3": ("GeneralizedAlpha", "generalized-alpha, index 3, spectral radius 0.9"),
    "exudyn-trap-i2": ("TrapezoidalIndex2", "trapezoidal rule (Newmark 1/4, 1/2), index 2"),
}
EXUDYN_EXPLICIT = ("DOPRI5", "RK67")


def log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


# ------------------------------------------------------------------ problems

def four_bar_scene() -> hx.Scene:
    """The four-bar of ``data/scenes/four_bar_3d.toml`` (crank 0.1 m, coupler 0.5 m, rocker
    0.4 m, ground 0.4 m, slender bars) in the plane, free (1 DOF), with the crank turned to lie
    along +x: the scene file's pose (crank and rocker vertical) is an equilibrium."""
    scene = hx.Scene("four-bar", dimension=2, gravity=[0.0, -9.81])
    A, B, C, D = (np.array(p) for p in ([0.0, 0.0], [0.1, 0.0], [0.4, 0.4], [0.4, 0.0]))
    for name, mass, (P, R) in (("crank", 0.3, (A, B)), ("coupler", 1.0, (B, C)),
                               ("rocker", 0.8, (D, C))):
        length = float(np.linalg.norm(R - P))
        scene.add(hx.PlanarBody(name, mass, mass * length**2 / 12, position=(P + R) / 2,
                                angle=float(np.arctan2(*(R - P)[::-1]))))
    scene.add(hx.Revolute("A", "ground", "crank", origin=A))
    scene.add(hx.Revolute("B", "crank", "coupler", origin=B))
    scene.add(hx.Revolute("C", "coupler", "rocker", origin=C))
    scene.add(hx.Revolute("D", "ground", "rocker", origin=D))  # closes the loop
    return scene


@dataclass
class Problem:
    key: str
    title: str
    build: Callable[[], hx.Scene]
    t_end: float
    chain: int | None = None  # bodies, for the serial chains

    def spec(self) -> dict:
        return {"key": self.key, "title": self.title, "t_end": self.t_end, "chain": self.chain}


def problems(sizes: list[int]) -> list[Problem]:
    out = [Problem("front-leg", "front leg, falling", lambda: front_leg_scene(gait=False), 0.5),
           Problem("four-bar", "four-bar (planar), falling", four_bar_scene, 2.0)]
    for n in sizes:
        out.append(Problem(f"chain-{n}", f"chain of {n}, hanging", lambda n=n: chain_scene(n),
                           0.5, chain=n))
    return out


# ------------------------------------------------------------------ positions and errors

def position_indices(model: hx.Model) -> np.ndarray:
    """Indices in ``q`` (and, the same, in ``v``) of every body's centre of mass, (bodies, d)."""
    d = model.dimension
    return (np.array([[b.q.start + k for k in range(d)] for b in model.bodies]),
            np.array([[b.v.start + k for k in range(d)] for b in model.bodies]))


def hermite5(s: np.ndarray, h: np.ndarray, y0, y1, d0, d1, a0, a1) -> np.ndarray:
    """Quintic Hermite interpolation on [0, 1] (``s``) of an interval of length ``h``, from the
    values, first and second derivatives at both ends (error O(h^6))."""
    s2, s3 = s * s, s * s * s
    s4, s5 = s3 * s, s3 * s2
    H0 = 1 - 10 * s3 + 15 * s4 - 6 * s5
    H1 = s - 6 * s3 + 8 * s4 - 3 * s5
    H2 = 0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5
    H3 = 0.5 * s3 - s4 + 0.5 * s5
    H4 = -4 * s3 + 7 * s4 - 3 * s5
    H5 = 10 * s3 - 15 * s4 + 6 * s5
    shape = (-1,) + (1,) * (y0.ndim - 1)
    H0, H1, H2, H3, H4, H5, h = (x.reshape(shape) for x in (H0, H1, H2, H3, H4, H5, h))
    return (H0 * y0 + H5 * y1 + h * (H1 * d0 + H4 * d1) + h * h * (H2 * a0 + H3 * a1))


@dataclass
class Reference:
    """The reference motion of the centres of mass: ``r, rd, rdd`` (N, bodies, d) at ``t``."""

    t: np.ndarray
    r: np.ndarray
    rd: np.ndarray
    rdd: np.ndarray
    meta: dict = field(default_factory=dict)

    @property
    def scale(self) -> float:
        return float(np.linalg.norm(self.r, axis=-1).max())

    def at(self, times: np.ndarray, every: int = 1) -> np.ndarray:
        t, r, rd, rdd = (x[::every] for x in (self.t, self.r, self.rd, self.rdd))
        times = np.clip(np.asarray(times, dtype=float), t[0], t[-1])
        k = np.clip(np.searchsorted(t, times, side="right") - 1, 0, t.size - 2)
        h = t[k + 1] - t[k]
        s = (times - t[k]) / h
        return hermite5(s, h, r[k], r[k + 1], rd[k], rd[k + 1], rdd[k], rdd[k + 1])

    def error(self, times: np.ndarray, positions: np.ndarray) -> float:
        """The relative error ``e`` of the protocol."""
        gap = np.linalg.norm(positions - self.at(times), axis=-1)
        return float(gap.max() / self.scale)

    def interpolation_check(self) -> float:
        """The error of interpolating from every other sample at the samples left out,
        relative to the scale (at twice the reference's spacing: pessimistic)."""
        if self.t.size < 5:
            return float("nan")
        last = self.t.size - 1 - (self.t.size - 1) % 2  # keep the last point of the coarse set
        coarse = Reference(self.t[:last + 1], self.r[:last + 1], self.rd[:last + 1],
                           self.rdd[:last + 1])
        odd = np.arange(1, last, 2)
        gap = np.linalg.norm(self.r[odd] - coarse.at(self.t[odd], every=2), axis=-1)
        return float(gap.max() / self.scale)

    def npz_bytes(self) -> bytes:
        buffer = io.BytesIO()
        np.savez_compressed(buffer, t=self.t, r=self.r, rd=self.rd, rdd=self.rdd,
                            meta=np.array(json.dumps(self.meta)))
        return buffer.getvalue()


def write_bytes_atomically(path: Path, content: bytes) -> None:
    """Write through a temporary file in the same folder renamed over the target (as
    :func:`hexapod._support.files.write_atomically`, for bytes)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(content)
        os.replace(temporary, path)
    except BaseException:
        if os.path.exists(temporary):
            os.unlink(temporary)
        raise


def model_fingerprint(model: hx.Model) -> str:
    """A hash of what fixes the motion: initial state, masses, inertias, joint frames."""
    digest = hashlib.sha256()
    for array in [model.q0, model.v0, model.gravity]:
        digest.update(np.ascontiguousarray(array, dtype=float).tobytes())
    for b in model.bodies:
        digest.update(np.array([b.mass, *np.ravel(b.inertia)], dtype=float).tobytes())
    for j in model.joints:
        digest.update(j.kind.encode())
        for frame in (j.parent_frame, j.child_frame):
            digest.update(frame.position.tobytes() + np.ravel(frame.rotation).tobytes())
    return digest.hexdigest()[:16]


def reference(problem: Problem, model: hx.Model, method: str, folder: Path) -> Reference:
    """The cached reference of ``problem``, or a new one (written to ``folder`` at once)."""
    meta = {"problem": problem.spec(), "method": method, "rtol": REFERENCE_RTOL,
            "atol": REFERENCE_RTOL, "max_step": REFERENCE_MAX_STEP,
            "hexapod": hx.__version__, "model": model_fingerprint(model)}
    path = folder / f"{problem.key}.npz"
    if path.is_file():
        try:
            with np.load(path) as saved:
                cached = Reference(saved["t"], saved["r"], saved["rd"], saved["rdd"],
                                   json.loads(str(saved["meta"])))
        except (OSError, ValueError, KeyError) as error:
            log(f"  {path}: unreadable ({error}), computed again")
        else:
            if {k: cached.meta.get(k) for k in meta} == meta:
                log(f"  reference from {path}")
                return cached
            log(f"  {path}: made with other settings, computed again")
    log(f"  reference: {method} at rtol = {REFERENCE_RTOL:g} ...")
    q_index, v_index = position_indices(model)
    cls = get_integrator(method)
    cpu = time.process_time()
    integrator = cls(model, 0.0, problem.t_end, rtol=REFERENCE_RTOL, atol=REFERENCE_RTOL,
                     max_step=REFERENCE_MAX_STEP)
    samples = [(integrator.t, integrator.q[q_index], integrator.v[v_index],
                integrator.v_dot[v_index])]
    while integrator.status == "running":
        integrator.step()
        samples.append((integrator.t, integrator.q[q_index], integrator.v[v_index],
                        integrator.v_dot[v_index]))
    if integrator.status != "finished":
        raise RuntimeError(f"{problem.key}: the reference failed: {integrator.message}")
    t, r, rd, rdd = (np.array(x) for x in zip(*samples, strict=True))
    meta.update(steps=integrator.counters.steps, cpu_s=time.process_time() - cpu)
    result = Reference(t, r, rd, rdd, meta)
    write_bytes_atomically(path, result.npz_bytes())
    log(f"  reference: {integrator.counters.steps} steps, {meta['cpu_s']:.1f} s, saved to {path}")
    return result


# ------------------------------------------------------------------ runs

@dataclass
class Run:
    """One run of one method at one setting."""

    setting: float
    cpu: float = float("inf")
    steps: int = 0
    error: float = float("inf")
    status: str = "not run"
    message: str = ""
    counters: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.status == "finished" and np.isfinite(self.error)

    def as_dict(self) -> dict:
        return {"setting": self.setting, "cpu_s": self.cpu, "steps": self.steps,
                "cpu_per_step_ms": self.per_step_ms, "error": self.error,
                "status": self.status, "message": self.message, "counters": self.counters}

    @property
    def per_step_ms(self) -> float:
        return 1e3 * self.cpu / self.steps if self.steps else float("nan")


def run_hexapod(model: hx.Model, method: str, setting: float, t_end: float, ref: Reference,
                budget: float) -> Run:
    cls = get_integrator(method)
    kwargs = {"rtol": setting, "atol": setting} if cls.adaptive else {"step": setting}
    q_index, _ = position_indices(model)
    times, positions = [0.0], [model.q0[q_index]]
    cpu = time.process_time()
    integrator = cls(model, 0.0, t_end, **kwargs)
    while integrator.status == "running":
        integrator.step()
        times.append(integrator.t)
        positions.append(integrator.q[q_index])
        if time.process_time() - cpu > budget:
            integrator.status, integrator.message = "budget", f"stopped at t = {integrator.t:.4g} s"
            break
    cpu = time.process_time() - cpu
    run = Run(setting, cpu, integrator.counters.steps, status=integrator.status,
              message=integrator.message, counters=integrator.counters.as_dict())
    if run.status == "finished":
        run.error = ref.error(np.array(times), np.array(positions))
    return run


class ExudynModel:
    """hexapod's assembled model rebuilt in Exudyn: the same bodies at the same consistent
    initial state, the same joints, gravity as mass-proportional loads."""

    def __init__(self, model: hx.Model, q: np.ndarray, v: np.ndarray):
        import exudyn as exu
        import exudyn.itemInterface as eii
        from exudyn.rigidBodyUtilities import RigidBodyInertia

        if model.drivers or model.forces:
            raise NotImplementedError("drivers and force elements are not translated")
        self.exu, self.model = exu, model
        self.SC = exu.SystemContainer()
        mbs = self.mbs = self.SC.AddSystem()
        ground = mbs.AddObject(eii.ObjectGround())
        gravity = np.zeros(3)
        gravity[:model.dimension] = model.gravity
        self.objects, self.nodes = [], []
        for b in model.bodies:
            qb, vb = q[b.q], v[b.v]
            if b.kind == "spatial":
                R = rotation_from_euler_parameters(qb[3:])
                body = mbs.CreateRigidBody(
                    inertia=RigidBodyInertia(mass=b.mass, inertiaTensor=b.inertia),
                    referencePosition=qb[:3], referenceRotationMatrix=R,
                    initialVelocity=vb[:3], initialAngularVelocity=R @ vb[3:],
                    gravity=gravity, nodeType=exu.NodeType.RotationEulerParameters, show=False)
            elif b.kind == "planar":
                c, s = np.cos(qb[2]), np.sin(qb[2])
                inertia = np.eye(3) * b.inertia[0, 0]  # Exudyn's 2-D body reads only zz
                body = mbs.CreateRigidBody(
                    inertia=RigidBodyInertia(mass=b.mass, inertiaTensor=inertia),
                    referencePosition=[qb[0], qb[1], 0.0],
                    referenceRotationMatrix=np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]),
                    initialVelocity=[vb[0], vb[1], 0.0], initialAngularVelocity=[0, 0, vb[2]],
                    gravity=gravity, create2D=True, show=False)
            else:
                raise NotImplementedError(f"body kind {b.kind}")
            self.objects.append(body)
            self.nodes.append(mbs.GetObject(body)["nodeNumber"])
        for j in model.joints:
            if j.kind != "revolute":
                raise NotImplementedError(f"joint kind {j.kind}")
            items = [ground if j.parent < 0 else self.objects[j.parent], self.objects[j.child]]
            if model.dimension == 3:
                pose = model.body_pose(q, j.child) @ j.child_frame
                mbs.CreateRevoluteJoint(itemNumbers=items, position=pose.position,
                                        axis=pose.rotation @ j.axis, useGlobalFrame=True,
                                        show=False)
            else:
                markers = [mbs.AddMarker(eii.MarkerBodyPosition(
                    bodyNumber=item, localPosition=[*frame.position, 0.0]))
                    for item, frame in zip(items, (j.parent_frame, j.child_frame), strict=True)]
                mbs.AddObject(eii.ObjectJointRevolute2D(markerNumbers=markers))
        self.sensors = [mbs.AddSensor(eii.SensorNode(
            nodeNumber=n, outputVariableType=exu.OutputVariableType.Position,
            storeInternal=True, writeToFile=False)) for n in self.nodes]
        mbs.Assemble()

    def settings(self, t_end: float, steps: int):
        exu = self.exu
        ss = exu.SimulationSettings()
        ss.solution.file.write = False
        ss.solution.restart.write = False
        ss.solution.sensors.active = True
        ss.solution.sensors.writePeriod = 0.5 * t_end / steps  # every step
        ss.show.computationTime = False
        ss.show.statistics = False
        ss.parallel.numberOfThreads = 1
        ti = ss.timeIntegration
        ti.verboseMode = 0
        ti.verboseModeFile = 0
        ti.endTime = t_end
        ti.numberOfSteps = steps
        ti.automaticStepSize = False
        ti.generalizedAlpha.spectralRadius = 0.9
        ss.linearSolver.solverType = exu.LinearSolverType.EigenSparse
        return ss

    def initial_accelerations(self) -> np.ndarray:
        """Accelerations at the initial state in hexapod's velocity coordinates."""
        exu, mbs = self.exu, self.mbs
        solver = exu.MainSolverImplicitSecondOrder()
        ss = self.settings(1.0, 1)
        ss.solution.sensors.active = False
        solver.InitializeSolver(mbs, ss)
        acc = np.array(mbs.systemData.GetODE2Coordinates_tt())
        coordinates = np.array(mbs.systemData.GetODE2Coordinates()) + np.array(
            mbs.systemData.GetODE2Coordinates(exu.ConfigurationType.Reference))
        solver.FinalizeSolver(mbs, ss)
        out = []
        for b, node in zip(self.model.bodies, self.nodes, strict=True):
            k = mbs.GetNodeODE2Index(node)
            if b.kind == "spatial":
                e0, e = coordinates[k + 3], coordinates[k + 4:k + 7]
                skew = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
                G = np.column_stack([-e, -skew + e0 * np.eye(3)])
                out += [acc[k:k + 3], 2 * G @ acc[k + 3:k + 7]]  # omega'_dot = 2 G p_dd
            else:
                out.append(acc[k:k + 3])
        return np.concatenate(out)

    def solve(self, solver: str, t_end: float, steps: int, newton_tol: float | None = None
              ) -> tuple[float, dict, np.ndarray, np.ndarray]:
        """One run: CPU time, the solver's counts, times and positions (N, bodies, d);
        ``newton_tol``: Newton's relative tolerance (default: Exudyn's)."""
        exu, mbs = self.exu, self.mbs
        ss = self.settings(t_end, steps)
        if newton_tol is not None:
            ss.timeIntegration.newton.relativeTolerance = newton_tol
            ss.timeIntegration.newton.absoluteTolerance = 1e-2 * newton_tol
        cpu = time.process_time()
        mbs.SolveDynamic(ss, solverType=getattr(exu.DynamicSolverType, solver),
                         showHints=False, showCausingItems=False)
        cpu = time.process_time() - cpu
        it = mbs.sys["dynamicSolver"].it
        counts = {"steps": int(it.currentStepIndex) - 1, "newton": int(it.newtonStepsCount),
                  "jacobians": int(it.newtonJacobiCount)}
        data = [np.asarray(mbs.GetSensorStoredData(s)) for s in self.sensors]
        d = self.model.dimension
        return cpu, counts, data[0][:, 0], np.stack([x[:, 1:1 + d] for x in data], axis=1)

    def explicit_verdict(self, solver: str, t_end: float) -> str:
        """What an explicit solver does with this model (it cannot solve its constraints)."""
        exu = self.exu
        ss = self.settings(t_end, 100)
        ss.solution.sensors.active = False
        ss.timeIntegration.automaticStepSize = True
        try:
            self.mbs.SolveDynamic(ss, solverType=getattr(exu.DynamicSolverType, solver),
                                  showHints=False, showCausingItems=False)
        except Exception as error:  # Exudyn raises its own and RuntimeError-like errors
            text = str(error).strip().splitlines()[0].split(" [Python file")[0]
            return f"refused: {text[:160]}"
        return "ran, ignoring the constraints"


def run_exudyn(ex: ExudynModel, method: str, step: float, t_end: float, ref: Reference) -> Run:
    steps = int(round(t_end / step))
    solver = EXUDYN_METHODS[method][0]
    run = Run(step)
    cpu = time.process_time()
    try:
        run.cpu, run.counters, times, positions = ex.solve(solver, t_end, steps)
    except Exception as error:  # a failed solve: Exudyn's SolverError, or a RuntimeError
        text = str(error).strip().splitlines()[0].split(" [Python file")[0]
        run.cpu, run.status, run.message = time.process_time() - cpu, "failed", text[:200]
        return run
    run.steps, run.status = run.counters["steps"], "finished"
    run.error = ref.error(times, positions)
    return run


def best_of(repeat: int, once: Callable[[], Run]) -> Run:
    """The run with the least CPU time of ``repeat`` (one when a run is long or fails)."""
    best = once()
    for _ in range(repeat - 1):
        if not best.ok or best.cpu > LONG_RUN:
            break
        again = once()
        if again.cpu < best.cpu:
            best = again
    return best


# ------------------------------------------------------------------ the ladder and (b)

def walk(ladder: list[float], start: int, run: Callable[[float], Run], growth: float,
         budget: float) -> dict[int, Run]:
    """Run rungs from ``start``: tighter while the error is above the target, looser while
    below; stop at the bracket, the ladder's end, or the budget. ``growth``: the expected
    factor of CPU time from one rung to the next tighter one (to skip a rung predicted to
    exceed the budget)."""
    runs: dict[int, Run] = {}
    first = runs[start] = run(ladder[start])
    # looser from a run that reached the target or was stopped by the budget, else tighter
    looser = (first.ok and first.error <= TARGET) or first.status == "budget"
    direction = -1 if looser else 1
    i = start
    while 0 <= i + direction < len(ladder):
        previous = runs[i]
        i += direction
        if direction == 1 and previous.cpu * growth > budget:
            runs[i] = Run(ladder[i], status="skipped",
                          message=f"predicted {previous.cpu * growth:.0f} s > budget")
            break
        current = runs[i] = run(ladder[i])
        if direction == 1 and current.ok and current.error <= TARGET:
            break
        if direction == -1 and current.status != "budget" and not (
                current.ok and current.error <= TARGET):
            break
    return runs


def time_to_target(runs: dict[int, Run]) -> tuple[float, str]:
    """CPU time to reach ``TARGET``: (value, qualifier '=', '<=' or '>')."""
    done = sorted(runs.items())
    below = [i for i, r in done if r.ok and r.error <= TARGET]
    if not below:
        finished = [r.cpu for _, r in done if r.status in ("finished", "budget")]
        return (max(finished), ">") if finished else (float("nan"), "")
    i = min(below)  # the loosest rung that reaches the target
    tight = runs[i]
    loose = runs.get(i - 1)
    if loose is None or not loose.ok or not loose.error > TARGET:
        return tight.cpu, "<="
    x = (np.log(TARGET) - np.log(loose.error)) / (np.log(tight.error) - np.log(loose.error))
    return float(np.exp(np.log(loose.cpu) + x * (np.log(tight.cpu) - np.log(loose.cpu)))), "="


# ------------------------------------------------------------------ one problem

def bench_problem(problem: Problem, methods: list[str], args, exudyn_ok: bool) -> dict:
    log(f"{problem.key}: {problem.title}, {problem.t_end} s")
    tic = time.process_time()
    model = hx.assemble(problem.build())
    data = model.create_data()
    q, v = hx.consistent_state(model, data)
    v_dot = hx.forward_dynamics(model, data, 0.0, q, v)
    assembled = time.process_time() - tic
    tic = time.process_time()
    for method in methods:  # warm-up: CasADi builds its Functions on first use
        cls = get_integrator(method)
        integrator = cls(model, 0.0, problem.t_end, **(
            {"rtol": 1e-3, "atol": 1e-3} if cls.adaptive else {"step": problem.t_end / 100}))
        for _ in range(2):
            if integrator.status == "running":
                integrator.step()
    warm = time.process_time() - tic
    log(f"  {model!r}: assembled in {assembled:.2f} s, warm-up {warm:.2f} s")
    ref = reference(problem, model, args.reference_method, Path(args.out) / "references")
    result = {"problem": problem.spec(), "bodies": len(model.bodies), "n_q": model.n_q,
              "n_v": model.n_v, "n_c": model.n_c, "assemble_s": assembled, "warm_up_s": warm,
              "reference": {**ref.meta, "samples": int(ref.t.size), "scale_m": ref.scale,
                            "interpolation_check": ref.interpolation_check()},
              "methods": {}, "exudyn": None}
    log(f"  reference interpolation check: {result['reference']['interpolation_check']:.1e}")

    def ladder_of(fixed: bool) -> tuple[list[float], int]:
        if fixed:
            return STEP_LADDER, STEP_LADDER.index(REPRESENTATIVE_STEP)
        return RTOL_LADDER, RTOL_LADDER.index(REPRESENTATIVE_RTOL)

    def record(library: str, method: str, fixed: bool, runs: dict[int, Run],
               description: str = ""):
        ladder, start = ladder_of(fixed)
        value, qualifier = time_to_target(runs)
        representative = runs[start]
        result["methods"][method] = {
            "library": library, "adaptive": not fixed, "description": description,
            "representative": representative.as_dict(),
            # a run stopped by the budget still measured the cost of its steps
            "cpu_per_step_ms": (representative.per_step_ms
                                if representative.status in ("finished", "budget")
                                else float("nan")),
            "time_to_target_s": value, "time_to_target_qualifier": qualifier,
            "rungs": [r.as_dict() for _, r in sorted(runs.items())]}

    for method in methods:
        cls = get_integrator(method)
        fixed = not cls.adaptive
        ladder, start = ladder_of(fixed)

        def one(setting, method=method, fixed=fixed):
            run = best_of(args.repeat, lambda: run_hexapod(model, method, setting, problem.t_end,
                                                           ref, args.budget))
            log(f"  {method} {'h' if fixed else 'rtol'} = {setting:.3g}: {run.status}, "
                f"{run.steps} steps, {run.cpu:.3g} s, error {run.error:.2e}")
            return run
        # steps grow like tol^(-1/order) for adaptive methods, like 1/h for fixed ones
        growth = 2.0 if fixed else 10.0 ** (1.0 / max(cls.order, 1))
        record("hexapod", method, fixed, walk(ladder, start, one, growth, args.budget),
               cls.describe().get("description", ""))

    if exudyn_ok:
        result["exudyn"] = bench_exudyn(problem, model, q, v, v_dot, ref, args, record)
    return result


def bench_exudyn(problem, model, q, v, v_dot, ref, args, record) -> dict:
    try:
        ex = ExudynModel(model, q, v)
    except NotImplementedError as error:
        log(f"  Exudyn: not translated ({error})")
        return {"translated": False, "why": str(error)}
    acc = ex.initial_accelerations()
    agreement = float(np.abs(acc - v_dot).max() / np.abs(v_dot).max())
    log(f"  Exudyn initial accelerations against hexapod's: {agreement:.1e} (relative)")
    out = {"translated": True, "initial_acceleration_agreement": agreement, "explicit": {}}
    # Exudyn's tight solution: trapezoidal rule at index 2, Richardson-extrapolated
    cpu, tight = 0.0, []
    for steps in (EXUDYN_TIGHT_STEPS, 2 * EXUDYN_TIGHT_STEPS):
        seconds, _, times, positions = ex.solve("TrapezoidalIndex2", problem.t_end, steps,
                                                EXUDYN_TIGHT_NEWTON)
        cpu += seconds
        tight.append((times, positions))
    (t1, r1), (t2, r2) = tight
    # the samples of both runs at the same times (every step of the coarser run)
    k1 = np.round(t1 / problem.t_end * EXUDYN_TIGHT_STEPS).astype(int)
    k2 = np.round(t2 / problem.t_end * 2 * EXUDYN_TIGHT_STEPS).astype(int)
    even = k2 % 2 == 0
    _, keep, pick = np.intersect1d(k1, k2[even] // 2, return_indices=True)
    richardson = (4 * r2[even][pick] - r1[keep]) / 3
    out["tight"] = {"steps": [EXUDYN_TIGHT_STEPS, 2 * EXUDYN_TIGHT_STEPS], "cpu_s": cpu,
                    "plain_agreement": ref.error(t2, r2),
                    "agreement": ref.error(t1[keep], richardson)}
    log(f"  reference against Exudyn's tight solution: {out['tight']['agreement']:.1e} "
        f"(h = t_end / {2 * EXUDYN_TIGHT_STEPS} alone: {out['tight']['plain_agreement']:.1e})")
    for name in EXUDYN_EXPLICIT:
        out["explicit"][name] = ex.explicit_verdict(name, problem.t_end)
        log(f"  Exudyn {name}: {out['explicit'][name]}")
    start = STEP_LADDER.index(REPRESENTATIVE_STEP)
    for method, (_, description) in EXUDYN_METHODS.items():
        def one(step, method=method):
            run = best_of(args.repeat, lambda: run_exudyn(ex, method, step, problem.t_end, ref))
            log(f"  {method} h = {step:.3g}: {run.status}, {run.steps} steps, {run.cpu:.3g} s, "
                f"error {run.error:.2e}")
            return run
        record("exudyn", method, True, walk(STEP_LADDER, start, one, 2.0, args.budget),
               description)
    return out


# ------------------------------------------------------------------ summaries

def growth_exponents(results: list[dict]) -> dict[str, float]:
    chains = [r for r in results if r["problem"]["chain"]]
    out = {}
    methods = {m for r in chains for m in r["methods"]}
    for method in sorted(methods):
        points = [(r["bodies"], r["methods"][method]["cpu_per_step_ms"]) for r in chains
                  if method in r["methods"]
                  and np.isfinite(r["methods"][method]["cpu_per_step_ms"])]
        if len(points) >= 2:
            n, cost = np.log(np.array(points)).T
            out[method] = float(np.polyfit(n, cost, 1)[0])
    return out


def fmt(x: float, digits: int = 3) -> str:
    return "-" if x is None or not np.isfinite(x) else f"{x:.{digits}g}"


def ratios(result: dict) -> dict:
    """hexapod / Exudyn: time to the target (fastest against fastest) and cost per step
    (generalized-alpha against generalized-alpha, and cheapest against cheapest)."""
    methods = result["methods"]
    by = {lib: {m: x for m, x in methods.items() if x["library"] == lib}
          for lib in ("hexapod", "exudyn")}
    if not by["exudyn"]:
        return {}

    def fastest(lib, key, qualifiers=("=", "<=")):
        values = [(x[key], m) for m, x in by[lib].items() if np.isfinite(x[key])
                  and (key != "time_to_target_s" or x["time_to_target_qualifier"] in qualifiers)]
        return min(values) if values else (float("nan"), "")

    out = {}
    (h, hm), (e, em) = fastest("hexapod", "time_to_target_s"), fastest("exudyn",
                                                                       "time_to_target_s")
    if hm and em:  # qualifiers: '<=' marks an upper bound
        out["time_to_target"] = {
            "ratio": h / e, "hexapod": hm, "exudyn": em,
            "qualifiers": [methods[hm]["time_to_target_qualifier"],
                           methods[em]["time_to_target_qualifier"]]}
    (h, hm), (e, em) = fastest("hexapod", "cpu_per_step_ms"), fastest("exudyn", "cpu_per_step_ms")
    out["cost_per_step_cheapest"] = {"ratio": h / e, "hexapod": hm, "exudyn": em}
    if "generalized-alpha" in methods and "exudyn-ga-i3" in methods:
        out["cost_per_step_generalized_alpha"] = {
            "ratio": methods["generalized-alpha"]["cpu_per_step_ms"]
            / methods["exudyn-ga-i3"]["cpu_per_step_ms"],
            "hexapod": "generalized-alpha", "exudyn": "exudyn-ga-i3"}
    return out


def markdown(results: list[dict], exponents: dict, args) -> str:
    lines = [f"Target: relative position error {TARGET:g}; representative setting: rtol = "
             f"{REPRESENTATIVE_RTOL:g} (adaptive), h = {REPRESENTATIVE_STEP * 1e3:g} ms (fixed); "
             f"CPU times best of {args.repeat}.", "",
             "| problem | bodies | library | method | CPU/step ms (steps) | error at setting "
             "| CPU to 1e-6 s | rungs |", "| --- | ---: | --- | --- | ---: | ---: | ---: | ---: |"]
    for r in results:
        for method, x in r["methods"].items():
            rep = x["representative"]
            steps = f" ({rep['steps']})" if rep["status"] == "finished" else f" ({rep['status']})"
            reach = f"{x['time_to_target_qualifier']} {fmt(x['time_to_target_s'])}".strip()
            lines.append(f"| {r['problem']['key']} | {r['bodies']} | {x['library']} | {method} "
                         f"| {fmt(x['cpu_per_step_ms'])}{steps} | {fmt(rep['error'], 2)} "
                         f"| {reach if x['time_to_target_qualifier'] else '-'} "
                         f"| {len(x['rungs'])} |")
    lines += ["", "| problem | assemble s | warm-up s | reference steps | interpolation check "
              "| Exudyn initial accelerations | reference vs Exudyn tight | Exudyn explicit "
              "| time to 1e-6 hexapod/Exudyn | per step GA/GA | per step cheapest |",
              "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: |"]
    for r in results:
        ex = r["exudyn"] or {}
        rt = ratios(r)

        def ratio(key, rt=rt):
            if key not in rt:
                return "-"
            bound = {("<=", "="): "<= ", ("=", "<="): ">= ", ("<=", "<="): "bounds only: "}
            prefix = bound.get(tuple(rt[key].get("qualifiers", ())), "")
            return (f"{prefix}{rt[key]['ratio']:.3g} ({rt[key]['hexapod']} / "
                    f"{rt[key]['exudyn']})")
        verdicts = ex.get("explicit", {})  # the messages are in the JSON file
        explicit = "; ".join(f"{name} {text.split(':')[0]}" for name, text in verdicts.items())
        lines.append(
            f"| {r['problem']['key']} | {r['assemble_s']:.2f} | {r['warm_up_s']:.2f} "
            f"| {r['reference']['steps']} | {fmt(r['reference']['interpolation_check'], 2)} "
            f"| {fmt(ex.get('initial_acceleration_agreement', float('nan')), 2)} "
            f"| {fmt(ex.get('tight', {}).get('agreement', float('nan')), 2)} | {explicit or '-'} "
            f"| {ratio('time_to_target')} | {ratio('cost_per_step_generalized_alpha')} "
            f"| {ratio('cost_per_step_cheapest')} |")
    if exponents:
        lines += ["", "Growth exponent of CPU per step against bodies over the chains: "
                  + ", ".join(f"{m} {p:.2f}" for m, p in exponents.items())]
    return "\n".join(lines) + "\n"


def figure(results: list[dict], exponents: dict) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 4.8))
    left, right = fig.subplots(1, 2)
    chains = [r for r in results if r["problem"]["chain"]]
    methods = list(dict.fromkeys(m for r in results for m in r["methods"]))
    markers = dict(zip(methods, "osD^v<>ph*x+", strict=False))
    for k, method in enumerate(methods):  # colour k in both panels
        points = [(r["bodies"], r["methods"][method]["cpu_per_step_ms"]) for r in chains
                  if method in r["methods"]
                  and np.isfinite(r["methods"][method]["cpu_per_step_ms"])]
        if points:
            n, cost = np.array(points).T
            library = next(r["methods"][method]["library"] for r in results
                           if method in r["methods"])
            label = method + (f" (slope {exponents[method]:.2f})" if method in exponents else "")
            left.loglog(n, cost, marker=markers.get(method, "o"), color=f"C{k % 10}",
                        linestyle="--" if library == "exudyn" else "-", label=label)
    left.set_xlabel("bodies in the chain")
    left.set_ylabel("CPU time per step (ms)")
    left.set_title("Cost per step (rtol 1e-6, h = 1 ms)")
    left.grid(True, which="both", linewidth=0.4, alpha=0.6)
    if left.lines:
        left.legend(fontsize=7)
    width = 0.8 / max(1, len(methods))
    for k, method in enumerate(methods):
        x = np.arange(len(results)) + (k - (len(methods) - 1) / 2) * width
        for qualifier, alpha in (("=", 1.0), ("<=", 0.35)):  # upper bounds pale
            values = [r["methods"].get(method, {}).get("time_to_target_s", np.nan)
                      if r["methods"].get(method, {}).get("time_to_target_qualifier") == qualifier
                      else np.nan for r in results]
            right.bar(x, values, width, alpha=alpha, color=f"C{k % 10}",
                      label=method if qualifier == "=" else None,
                      hatch="//" if "exudyn" in method else None)
    right.set_yscale("log")
    right.set_xticks(np.arange(len(results)), [r["problem"]["key"] for r in results],
                     rotation=30, ha="right")
    right.set_ylabel(f"CPU time to relative error {TARGET:g} (s)")
    right.set_title("CPU time to reach the target (pale: upper bound; none: not reached)",
                    fontsize=10)
    right.grid(True, axis="y", which="both", linewidth=0.4, alpha=0.6)
    right.legend(fontsize=7)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=120)
    return buffer.getvalue()


def finite(obj):
    """``obj`` with non-finite numbers as None (strict JSON)."""
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [finite(v) for v in obj]
    if isinstance(obj, float | np.floating):
        return float(obj) if np.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


def exudyn_available() -> tuple[bool, str]:
    try:
        import exudyn
    except ImportError as error:
        return False, str(error)
    exudyn.config.printToConsole = False  # the table owns stdout
    return True, exudyn.__version__


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=None,
                        help="bodies of the serial chains (default 10 30 100 300)")
    parser.add_argument("--repeat", type=int, default=None, help="best of (default 3)")
    parser.add_argument("--budget", type=float, default=900.0,
                        help="largest CPU time of one run, s (default 900)")
    parser.add_argument("--methods", nargs="*", default=None,
                        help="hexapod methods (default: the whole registry)")
    parser.add_argument("--problems", nargs="*", default=None,
                        help="problem keys to run (default: all)")
    parser.add_argument("--reference-method", default="dop853-projection")
    parser.add_argument("--no-exudyn", action="store_true", help="hexapod alone")
    parser.add_argument("--quick", action="store_true",
                        help="chains of 10 and 30, one run per rung, budget 120 s")
    parser.add_argument("--out", default="bench-forward")
    args = parser.parse_args()
    if args.quick:
        args.sizes = args.sizes if args.sizes is not None else [10, 30]
        args.repeat = args.repeat or 1
        args.budget = min(args.budget, 120.0)
    args.sizes = args.sizes if args.sizes is not None else [10, 30, 100, 300]
    args.repeat = args.repeat or 3
    methods = args.methods or list(INTEGRATORS)
    for method in methods + [args.reference_method]:
        get_integrator(method)  # an unknown name fails here, before any work
    exudyn_ok, exudyn_version = (False, "not asked") if args.no_exudyn else exudyn_available()
    if not exudyn_ok:
        print(f"Exudyn is not available ({exudyn_version}): hexapod alone. "
              "(pip install \".[compare]\" for the comparison.)\n")
    todo = [p for p in problems(args.sizes) if not args.problems or p.key in args.problems]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()

    def report(results: list[dict], complete: bool) -> dict:
        exponents = growth_exponents(results)
        return {"complete": complete, "protocol": __doc__, "target": TARGET,
                "repeat": args.repeat, "budget_s": args.budget, "sizes": args.sizes,
                "methods": methods, "hexapod": hx.__version__,
                "exudyn": exudyn_version if exudyn_ok else None,
                "python": sys.version.split()[0], "numpy": np.__version__,
                "machine": platform.platform(), "processor": platform.processor(),
                "wall_time_s": time.perf_counter() - started,
                "growth_exponents": exponents, "problems": results,
                "ratios": {r["problem"]["key"]: ratios(r) for r in results},
                "table": markdown(results, exponents, args)}

    results = []
    for k, problem in enumerate(todo):
        results.append(bench_problem(problem, methods, args, exudyn_ok))
        if k + 1 < len(todo):  # what is done survives an interrupted run
            write_atomically(out / "bench_forward.json",
                             json.dumps(finite(report(results, False)), indent=1))
    final = report(results, True)
    print(final["table"])
    write_atomically(out / "bench_forward.json", json.dumps(finite(final), indent=1))
    write_bytes_atomically(out / "bench_forward.png",
                           figure(results, final["growth_exponents"]))
    log(f"wrote {out / 'bench_forward.json'} and {out / 'bench_forward.png'}")


if __name__ == "__main__":
    main()
