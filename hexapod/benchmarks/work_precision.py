"""The work-precision study: every integrator over a ladder of tolerances or steps, its error
against a reference and its CPU time, on four problems.

=============  ===============================================  ============================
problem        model                                            reference
=============  ===============================================  ============================
``andrews``    Andrews' squeezing mechanism: 7 planar bodies,   the published y(0.03) of the
               10 revolute joints, a stiff spring, 0.03 s       Test Set for IVP Solvers
``seed002``    the closed-loop pendulum of Richard, Anderson    its 1-DOF Lagrange equation
               and Andrews (particles)
``pendulum``   a spatial pendulum released horizontal, 100      the exact solution (Jacobi
               periods                                          elliptic functions)
``front-leg``  the front leg falling, its six joints free       the recursive joint-
                                                                coordinate model
                                                                (Vukobratović and Potkonjak)
=============  ===============================================  ============================

The error is relative, in positions. For Andrews' mechanism it is the Test Set's measure at the
end, ``max_i |q_i - q_ref,i| / |q_ref,i|`` over the seven angles; for the others the largest
distance between a body's position and the reference over all accepted steps, divided by the
largest distance of the reference positions from the origin (the size of the motion). A
method's cost is the CPU time of its time loop (:attr:`SimulationResult.cpu_time`).

Adaptive methods run with ``rtol = atol / scale`` from 1e-3 down; fixed-step methods with
``t_end / N``, ``N`` doubling. A ladder stops when a run fails, when its error reaches the
reference's own precision, when a run costs more than the budget, or after two failed runs
in a row (a coarse step may be unstable where a finer one is not).
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hexapod._support.files import read_text
from hexapod.algorithms.assembly import assemble
from hexapod.benchmarks.pendulums import ClosedLoopPendulum, pendulum_exact, pendulum_period
from hexapod.catalog import PROBLEMS
from hexapod.errors import HexapodError, InputFileError
from hexapod.model.model import Model
from hexapod.scene import Scene
from hexapod.scene.reader import read_scene
from hexapod.simulation.loop import simulate
from hexapod.simulation.registry import INTEGRATORS
from hexapod.simulation.results import units_json

#: the angles of Andrews' mechanism from the bodies' absolute angles, in the Test Set's order
#: (beta, Theta, gamma, Phi, delta, Omega, epsilon)
ANDREWS_BODIES = ("crank", "rod2", "triangle", "rod4", "link5", "rod6", "link7")


@dataclass
class PrecisionProblem:
    """One problem of the study.

    ``error(result)`` is the relative position error of a run; ``floor`` the precision of the
    reference (errors below it measure the reference); ``scale`` sets ``atol = rtol * scale``;
    ``steps`` the coarsest fixed-step count.
    """

    name: str
    title: str
    model: Model
    t_end: float
    error: Callable
    floor: float
    scale: float = 1.0
    steps: int = 50
    notes: list[str] = field(default_factory=list)


@dataclass
class Run:
    """One method at one setting on one problem."""

    problem: str
    method: str
    setting: str  # "rtol=1e-06" or "h=0.001"
    status: str
    cpu_time: float
    steps: int
    rhs: int
    error: float
    max_position_violation: float
    max_velocity_violation: float
    energy_drift: float | None
    message: str = ""

    def as_dict(self) -> dict:
        return dict(self.__dict__)


#: ``runs.csv`` of ``hexapod bench``: a column per field of :class:`Run` (unit, meaning).
RUN_COLUMNS = {
    "problem": (None, "the problem"), "method": (None, "the integrator"),
    "setting": (None, "its tolerance (rtol=...) or step (h=...)"),
    "status": (None, "finished or failed"), "cpu_time": ("s", "CPU time of the time loop"),
    "steps": ("1", "accepted steps"), "rhs": ("1", "right-hand side evaluations"),
    "error": ("1", "relative error in positions against the reference"),
    "max_position_violation": ("1", "largest scaled constraint residual |phi_i| / s_i"),
    "max_velocity_violation": ("1/s", "largest scaled velocity residual"),
    "energy_drift": ("1", "energy drift relative to the largest kinetic energy (empty when "
                     "energy is not conserved)"),
    "message": (None, "why a run failed"),
}


def runs_csv_text(runs: list[Run]) -> str:
    """``runs.csv``: one row per run, the columns of :data:`RUN_COLUMNS`."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(RUN_COLUMNS), lineterminator="\n")
    writer.writeheader()
    writer.writerows(r.as_dict() for r in runs)
    return buffer.getvalue()


def units_json_text() -> str:
    """``units.json`` of ``hexapod bench``: every column of ``runs.csv``, unit and meaning."""
    return units_json({"runs.csv": RUN_COLUMNS})


# ------------------------------------------------------------------ the problems

def _read(path: Path) -> dict:
    try:
        return json.loads(read_text(path, "JSON file"))
    except json.JSONDecodeError as error:
        raise InputFileError(f"{path}: not valid JSON ({error})") from None


def andrews_angles(model: Model, q: np.ndarray) -> np.ndarray:
    """The Test Set's seven angles from the absolute coordinates (rows of ``q``)."""
    q = np.atleast_2d(q)
    phi = np.column_stack([q[:, model.coordinate_names.index(f"{b}.angle")]
                           for b in ANDREWS_BODIES])
    return np.column_stack([phi[:, 0], phi[:, 1] - phi[:, 0], phi[:, 2], phi[:, 3] - phi[:, 4],
                            phi[:, 4], phi[:, 5] - phi[:, 6], phi[:, 6]])


def andrews_problem(data_dir: Path) -> PrecisionProblem:
    """Andrews' squeezing mechanism over [0, 0.03] s against the published y(0.03)."""
    model = assemble(read_scene(data_dir / "scenes" / "andrews.toml"))
    benchmark = _read(data_dir / "benchmarks" / "andrews.json")
    reference = np.array(benchmark["reference_t0_03"]["y"][:7])

    def error(result) -> float:
        if result.t[-1] < 0.03 - 1e-12:
            return np.inf
        return float(np.max(np.abs(andrews_angles(model, result.q[-1])[0] - reference)
                            / np.abs(reference)))

    return PrecisionProblem("andrews", "Andrews' squeezing mechanism (7 bodies, 0.03 s)", model,
                            0.03, error, floor=3e-10, scale=1.0, steps=200,
                            notes=["published y(0.03), correct to about 1e-10 in positions"])


def seed002_problem(data_dir: Path, t_end: float = 15.0) -> PrecisionProblem:
    """The closed-loop pendulum of Richard, Anderson and Andrews against its Lagrange equation
    (metres)."""
    model = assemble(read_scene(data_dir / "scenes" / "closed_pendulum_seed002.toml"))
    motion = ClosedLoopPendulum(p1=(0.4, 0.4), p2=(1.2, 0.5), anchor2=(0.7, 0.0)).solve(
        t_end, rtol=1e-13, atol=1e-13)
    m1, m2 = (model.bodies[model.body_index[n]].q for n in ("m1", "m2"))
    size = 1.3  # m: the largest distance of a particle from the origin, about

    def error(result) -> float:
        p1, p2, _ = motion(result.t)
        worst = max(np.abs(result.q[:, m1] - p1).max(), np.abs(result.q[:, m2] - p2).max())
        return float(worst / size) if result.success else np.inf

    title = f"closed-loop pendulum of Richard, Anderson and Andrews ({t_end:g} s)"
    return PrecisionProblem("seed002", title, model, t_end, error, floor=1e-12, scale=1.0,
                            steps=500)


def pendulum_problem(data_dir: Path, periods: int = 100) -> PrecisionProblem:
    """The pendulum of ``data/scenes/pendulum.toml`` released horizontal, over ``periods``
    periods, against the exact solution."""
    model = assemble(read_scene(data_dir / "scenes" / "pendulum.toml"))
    g, arm, inertia_o = 9.81, 0.5, 0.0833 + 0.25
    omega0, psi0 = np.sqrt(g * arm / inertia_o), np.pi / 2
    period = pendulum_period(psi0, omega0)

    def error(result) -> float:
        psi, _ = pendulum_exact(result.t, psi0, omega0)
        exact = np.column_stack([arm * np.sin(psi), np.zeros_like(psi), -arm * np.cos(psi)])
        worst = np.linalg.norm(result.q[:, :3] - exact, axis=1).max()
        return float(worst / arm) if result.success else np.inf

    title = f"pendulum, {periods} periods ({periods * period:.0f} s)"
    return PrecisionProblem("pendulum", title, model, periods * period, error, floor=1e-12,
                            scale=1.0, steps=20 * periods)


def released(scene: Scene) -> Scene:
    """The scene's bodies and joints only: drivers, loads and springs left out, so that the
    mechanism falls freely under gravity from its initial pose."""
    free = Scene(f"{scene.name}-released", scene.dimension, scene.length_unit)
    free.gravity = scene.gravity
    free.add(*scene.bodies.values(), *scene.joints.values())
    return free


def front_leg_problem(leg: Scene, t_end: float = 0.5) -> PrecisionProblem:
    """The front leg (``leg``: the built-in scene) released from its initial pose, its six
    joints free, against the recursive joint-coordinate model integrated by SciPy's DOP853
    at 1e-12."""
    from scipy.integrate import solve_ivp

    from hexapod.minimal.chain import ChainModel

    model = assemble(released(leg))
    chain = ChainModel.from_model(model)
    dof = chain.dof

    def rates(_t, state):
        q, q_d = state[:dof], state[dof:]
        return np.concatenate([q_d, chain.forward(q, q_d, np.zeros(dof))])

    solution = solve_ivp(rates, (0.0, t_end), np.zeros(2 * dof), method="DOP853", rtol=1e-12,
                         atol=1e-12, dense_output=True)
    bodies = [model.joints[model.joint_index[name]].child for name in chain.names]
    columns = np.concatenate([np.arange(model.bodies[b].q.start, model.bodies[b].q.start + 3)
                              for b in bodies])
    start = chain.kinematics(np.zeros(dof), np.zeros(dof)).r
    if not np.allclose(start.reshape(-1), model.q0[columns], atol=1e-12):
        raise HexapodError("the recursive model's zero pose is not the scene's initial pose")
    size = float(np.linalg.norm(start, axis=1).max())

    def reference(t: np.ndarray) -> np.ndarray:
        states = solution.sol(t)
        return np.array([chain.kinematics(s[:dof], s[dof:]).r.reshape(-1) for s in states.T])

    def error(result) -> float:
        worst = np.abs(result.q[:, columns] - reference(result.t)).max()
        return float(worst / size) if result.success else np.inf

    return PrecisionProblem("front-leg", f"front leg falling, six free joints ({t_end:g} s)", model,
                   t_end, error, floor=1e-11, scale=size, steps=100)


def build_problems(names=PROBLEMS, data_dir: str | Path = "data", quick: bool = False,
                   leg: Scene | None = None) -> list[PrecisionProblem]:
    """The problems by name; ``quick``: shorter horizons (tests and a first look). ``data_dir``
    holds ``scenes/`` and ``benchmarks/`` (the project's ``data``); ``leg`` is the scene the
    front-leg problem releases (the built-in ``front-leg``)."""
    data_dir = Path(data_dir)
    if "front-leg" in names and leg is None:
        raise ValueError("the front-leg problem needs the leg's scene (the built-in front-leg)")
    makers = {
        "andrews": lambda: andrews_problem(data_dir),
        "seed002": lambda: seed002_problem(data_dir, 3.0 if quick else 15.0),
        "pendulum": lambda: pendulum_problem(data_dir, 5 if quick else 100),
        "front-leg": lambda: front_leg_problem(leg, 0.1 if quick else 0.5),
    }
    unknown = [n for n in names if n not in makers]
    if unknown:
        raise ValueError(f"unknown problem(s) {', '.join(unknown)}: choose from "
                         + ", ".join(PROBLEMS))
    return [makers[n]() for n in names]


def andrews_joint_e(model: Model, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The forces rod 2 exerts at joint E on the triangle, rod 4 and rod 6 (world axes), in the
    order of the Test Set's multipliers lambda1..6."""
    from hexapod.algorithms.dynamics import forward_dynamics
    from hexapod.algorithms.liaison import joint_wrenches

    data = model.create_data()
    forward_dynamics(model, data, t, q, v)
    wrenches = joint_wrenches(model, data, frame="world")
    return np.concatenate([wrenches.force[model.joint_index[j]][:2] for j in ("E3", "E4", "E6")])


def andrews_check(data_dir: str | Path = "data", rtol: float = 1e-12) -> tuple[str, dict]:
    """Our own reference of Andrews' mechanism (DOP853 at ``rtol``) against the published one:
    the positions at 0.03 s, and the forces at joint E against the published multipliers at
    0 and 0.03 s. Markdown, and the numbers."""
    data_dir = Path(data_dir)
    model = assemble(read_scene(data_dir / "scenes" / "andrews.toml"))
    benchmark = _read(data_dir / "benchmarks" / "andrews.json")
    published = {0.0: np.array(benchmark["initial"]["y"]),
                 0.03: np.array(benchmark["reference_t0_03"]["y"])}
    result = simulate(model, 0.03, method="dop853-projection", rtol=rtol, atol=rtol * 1e-2,
                      every=10**9, forces=False)
    if not result.success:
        raise HexapodError(f"the reference run of Andrews' mechanism failed: {result.message}")
    angles = andrews_angles(model, result.q[-1])[0]
    numbers = {"positions": float(np.max(np.abs(angles - published[0.03][:7])
                                         / np.abs(published[0.03][:7])))}
    lines = [f"Own reference (dop853-projection, rtol {rtol:.0e}) against the published y(0.03): "
             f"largest relative difference of the seven angles {numbers['positions']:.1e}.", "",
             "| t (s) | forces at E by rod 2, world (N) | published lambda1..6 | "
             "largest difference / largest multiplier |", "|---|---|---|---|"]
    for k, t in enumerate((0.0, 0.03)):
        index = 0 if k == 0 else -1
        forces = andrews_joint_e(model, t, result.q[index], result.v[index])
        lam = published[t][21:27]
        numbers[f"forces_t{t:g}"] = float(np.abs(forces - lam).max() / np.abs(lam).max())
        lines.append(f"| {t:g} | {' '.join(f'{x:.7g}' for x in forces)} | "
                     f"{' '.join(f'{x:.7g}' for x in lam)} | {numbers[f'forces_t{t:g}']:.1e} |")
    return "\n".join(lines) + "\n", numbers


# ------------------------------------------------------------------ the ladders

def ladder(cls, problem: PrecisionProblem, quick: bool = False) -> list[dict]:
    """Settings from coarse to fine: tolerances (adaptive), steps (fixed)."""
    if cls.adaptive:
        exponents = range(3, 11) if quick else range(3, 14)
        return [{"rtol": 10.0**-k, "atol": 10.0**-k * problem.scale} for k in exponents]
    counts = [problem.steps * 2**k for k in range(0, 6 if quick else 10)]
    return [{"step": problem.t_end / n} for n in counts]


def _label(setting: dict) -> str:
    if "step" in setting:
        return f"h={setting['step']:.3g}"
    return f"rtol={setting['rtol']:.0e}"


def run_method(problem: PrecisionProblem, method: str, *, quick: bool = False, budget: float = 30.0,
               progress: Callable[[str], None] | None = None) -> list[Run]:
    """One method over its ladder on one problem."""
    cls = INTEGRATORS[method]
    runs: list[Run] = []
    for setting in ladder(cls, problem, quick):
        if progress:
            progress(f"{problem.name}: {method} {_label(setting)}")
        result = simulate(problem.model, problem.t_end, method=method, every=1, forces=False,
                          **setting)
        error = problem.error(result) if result.success else np.inf
        runs.append(Run(problem.name, method, _label(setting), result.status, result.cpu_time,
                        result.counters.steps, result.counters.rhs, error,
                        result.max_position_violation, result.max_velocity_violation,
                        result.energy_drift, result.message))
        if error < 3 * problem.floor or result.cpu_time > budget:
            break
        # a coarse step may be unstable (failed) where a finer one is not: give up after two
        # failures in a row
        if not result.success and len(runs) > 1 and runs[-2].status != "finished":
            break
    return runs


def run_study(problems: list[PrecisionProblem], methods=None, *, quick: bool = False,
              budget: float = 30.0, progress: Callable[[str], None] | None = None) -> list[Run]:
    """Every method (default: the registry) over its ladder on every problem."""
    runs: list[Run] = []
    for problem in problems:
        for method in methods or INTEGRATORS:
            runs += run_method(problem, method, quick=quick, budget=budget, progress=progress)
    return runs


def cpu_to_reach(runs: list[Run], target: float) -> float | None:
    """CPU time to reach a relative error ``target``: interpolated log-log between the cheapest
    run below the target and the dearest above it; None when no run reaches it."""
    done = sorted((r for r in runs if np.isfinite(r.error)), key=lambda r: r.cpu_time)
    below = [r for r in done if r.error <= target]
    if not below:
        return None
    hit = below[0]
    above = [r for r in done if r.error > target and r.cpu_time <= hit.cpu_time]
    if not above:
        return hit.cpu_time
    miss = above[-1]
    if hit.error == miss.error or hit.cpu_time <= 0 or miss.cpu_time <= 0:
        return hit.cpu_time
    slope = (np.log(hit.cpu_time) - np.log(miss.cpu_time)) / (np.log(hit.error)
                                                               - np.log(miss.error))
    return float(np.exp(np.log(miss.cpu_time) + slope * (np.log(target) - np.log(miss.error))))


# ------------------------------------------------------------------ reports

def table(runs: list[Run], targets=(1e-6, 1e-9)) -> str:
    """Markdown: per problem and method, the CPU time to reach each target, the best error,
    and the steps and drifts of the run that reached it."""
    lines = ["| problem | method | " + " | ".join(f"CPU s to {t:.0e}" for t in targets)
             + " | best error | its CPU s | max abs(phi) | energy drift |",
             "|---|---|" + "---|" * (len(targets) + 4)]
    for problem in dict.fromkeys(r.problem for r in runs):
        for method in dict.fromkeys(r.method for r in runs if r.problem == problem):
            mine = [r for r in runs if r.problem == problem and r.method == method]
            finite = [r for r in mine if np.isfinite(r.error)]
            reach = [cpu_to_reach(mine, t) for t in targets]
            cells = ["-" if c is None else f"{c:.3g}" for c in reach]
            if finite:
                best = min(finite, key=lambda r: r.error)
                drift = "-" if best.energy_drift is None else f"{best.energy_drift:.1e}"
                cells += [f"{best.error:.1e}", f"{best.cpu_time:.3g}",
                          f"{best.max_position_violation:.1e}", drift]
            else:
                cells += ["failed", "-", "-", "-"]
            lines.append(f"| {problem} | {method} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def work_precision_figure(runs: list[Run], problems: list[PrecisionProblem], targets=(1e-6, 1e-9)):
    """Error against CPU time, log-log, one panel per problem, one line per method."""
    from matplotlib.figure import Figure

    columns = min(2, len(problems))
    rows = (len(problems) + columns - 1) // columns
    figure = Figure(figsize=(6.2 * columns, 4.6 * rows))
    axes = figure.subplots(rows, columns, squeeze=False)
    methods = list(dict.fromkeys(r.method for r in runs))
    markers = dict(zip(methods, "os^vD<>ph*", strict=False))
    for ax, problem in zip(axes.flat, problems, strict=False):
        for method in methods:
            mine = [r for r in runs if r.problem == problem.name and r.method == method
                    and np.isfinite(r.error) and r.cpu_time > 0]
            if mine:
                ax.loglog([r.cpu_time for r in mine], [max(r.error, 1e-16) for r in mine],
                          marker=markers[method], label=method)
        for target in targets:
            ax.axhline(target, color="0.6", lw=0.8, ls=":")
        ax.axhline(problem.floor, color="tab:red", lw=0.8, ls="--",
                   label="precision of the reference")
        ax.set_title(problem.title, fontsize=10)
        ax.set_xlabel("CPU time (s)")
        ax.set_ylabel("relative error in positions")
        ax.grid(True, which="both", alpha=0.3)
    for ax in list(axes.flat)[len(problems):]:
        ax.set_visible(False)
    axes.flat[0].legend(fontsize=8)
    figure.suptitle("Error against run time (work-precision)")
    figure.tight_layout()
    return figure


def drift_figure(problem: PrecisionProblem, settings: dict[str, dict]):
    """Constraint drift and energy error against time, one run per method (``settings``: method
    -> keyword arguments of :func:`simulate`)."""
    from matplotlib.figure import Figure

    model = problem.model
    figure = Figure(figsize=(7.5, 6.5))
    top, bottom = figure.subplots(2, 1, sharex=True)
    for method, setting in settings.items():
        result = simulate(model, problem.t_end, method=method, forces=False, **setting)
        w = model.law_values(result.t)[0].T if model.n_w else None
        values = {"q": result.q} | ({"w": w} if w is not None else {})
        phi = model.call_samples("phi", **values) / model.row_scale
        # running maxima: the envelope of each error, so that its growth shows
        top.semilogy(result.t, np.maximum.accumulate(np.maximum(np.abs(phi).max(axis=1),
                                                                1e-17)),
                     label=f"{method} ({_label(setting)})")
        if result.energy is not None:
            kinetic = 0.5 * np.einsum("ni,ni->n", result.v, result.v @ model.mass.dense())
            scale = max(float(np.max(kinetic)), np.finfo(float).tiny)
            error = np.abs(result.energy - result.energy[0]) / scale
            bottom.semilogy(result.t, np.maximum.accumulate(np.maximum(error, 1e-17)),
                            label=method)
    top.set_ylabel("largest max |phi_i| / s_i so far")
    top.set_title(f"{problem.title}: constraint drift", fontsize=10)
    bottom.set_ylabel("largest |E - E(0)| / max kinetic so far")
    bottom.set_xlabel("t (s)")
    bottom.set_title("energy error", fontsize=10)
    if model.energy_conserved:
        bottom.legend(fontsize=8)
    else:
        bottom.text(0.5, 0.5, "the scene does work on the system: no energy to conserve",
                    transform=bottom.transAxes, ha="center", color="0.4")
    top.legend(fontsize=8)
    for ax in (top, bottom):
        ax.grid(True, which="both", alpha=0.3)
    figure.tight_layout()
    return figure
