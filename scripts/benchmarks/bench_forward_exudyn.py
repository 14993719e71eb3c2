"""The Exudyn side of ``scripts/benchmarks/bench_forward.py``: hexapod's assembled model rebuilt
in Exudyn, its runs, its tight solution, its explicit solvers' verdicts, and the benchmark of a
problem with it. Exudyn is optional: nothing here imports it before it is asked for."""

from __future__ import annotations

import time

import numpy as np
from bench_forward_problems import Reference
from bench_forward_runs import REPRESENTATIVE_STEP, STEP_LADDER, Run, best_of, walk
from measure import log

import hexapod as hx
from hexapod.spatial import rotation_from_euler_parameters

EXUDYN_TIGHT_STEPS = 8000  # Exudyn's tight solution: h = t_end / this, and half of it
EXUDYN_TIGHT_NEWTON = 1e-12  # its Newton tolerance (relative; 1e-8 by default, which limits
# the extrapolated solution to ~1e-9 .. 1e-8)
EXUDYN_METHODS = {  # name -> (solver type, description)
    "exudyn-ga-i3": ("GeneralizedAlpha", "generalized-alpha, index 3, spectral radius 0.9"),
    "exudyn-trap-i2": ("TrapezoidalIndex2", "trapezoidal rule (Newmark 1/4, 1/2), index 2"),
}
EXUDYN_EXPLICIT = ("DOPRI5", "RK67")


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


def exudyn_available() -> tuple[bool, str]:
    try:
        import exudyn
    except ImportError as error:
        return False, str(error)
    exudyn.config.printToConsole = False  # the table owns stdout
    return True, exudyn.__version__
