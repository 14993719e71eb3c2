"""The ``hexapod`` command.

Every error a user can cause ends with one message on stderr and a non-zero exit, never a
traceback (set ``HEXAPOD_DEBUG=1`` to see one for an internal error).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from importlib.metadata import entry_points
from pathlib import Path

import numpy as np

from hexapod.assembly import assemble
from hexapod.dynamics import forward_dynamics
from hexapod.errors import HexapodError, InputFileError
from hexapod.kinematics import (
    assemble_positions,
    degrees_of_freedom,
    scaled_residual,
    solve_velocities,
)
from hexapod.model import Data, Model
from hexapod.reactions import JointWrenches, driver_efforts, joint_wrenches
from hexapod.scene.reader import read_scene
from hexapod.scene.scene import Scene

DEFAULT_SCENE = "front-leg"


# ------------------------------------------------------------------ scenes

def builtin_scenes() -> dict:
    """Built-in scenes by name: entry points of the group ``hexapod.scenes``."""
    return {ep.name: ep for ep in entry_points(group="hexapod.scenes")}


def load_scene(name_or_path: str) -> Scene:
    """A scene from a TOML file, or a built-in scene by name."""
    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        return read_scene(path)
    scenes = builtin_scenes()
    if name_or_path in scenes:
        return scenes[name_or_path].load()()
    known = ", ".join(sorted(scenes)) or "none installed"
    raise InputFileError(f"{name_or_path}: no such scene file, and no built-in scene of that "
                         f"name (built-in: {known})")


# ------------------------------------------------------------------ dynamics

def _state_report(model: Model, t: float, condition: bool) -> dict:
    q = assemble_positions(model, t=t)
    v = solve_velocities(model, q, t)
    data = Data()
    forward_dynamics(model, data, t, q, v, condition=condition)
    wrenches = joint_wrenches(model, q, data.lam, data.Phi_v, data.Q_across)
    mobility = degrees_of_freedom(model, q, t)
    phi = scaled_residual(model, q, t)
    report = {
        "scene": model.name,
        "t": t,
        "dimension": model.dimension,
        "counts": {"bodies": len(model.bodies), "joints": len(model.joints),
                   "drivers": len(model.drivers), "forces": len(model.force_names),
                   "n_q": model.n_q, "n_v": model.n_v, "n_c": model.n_c, "laws": model.n_w},
        "dof": mobility["dof"],
        "dof_with_drivers": mobility["dof_with_drivers"],
        "redundant_rows": [model.rows[i].name for i in data.redundant_rows],
        "characteristic_length_m": model.characteristic_length,
        "max_abs_phi": float(np.max(np.abs(phi))) if phi.size else 0.0,
        "joints": wrenches.as_dict(),
        "driver_efforts": driver_efforts(model, data.lam),
        "accelerations": dict(zip(model.velocity_names, data.v_dot.tolist(), strict=True)),
        "multipliers": {model.rows[i].name: float(data.lam[i]) for i in range(model.n_c)},
    }
    if condition:
        report["condition_number"] = data.condition_number
        report["sigma_min"] = data.sigma_min
    return report | {"_wrenches": wrenches, "_model": model}


def _print_dynamics(report: dict) -> None:
    model: Model = report["_model"]
    wrenches: JointWrenches = report["_wrenches"]
    c = report["counts"]
    print(f"scene '{report['scene']}' ({report['dimension']}-D): {c['bodies']} bodies, "
          f"{c['joints']} joints, {c['drivers']} drivers, {c['forces']} force elements")
    print(f"model: n_q = {c['n_q']}, n_v = {c['n_v']}, n_c = {c['n_c']} rows, "
          f"{c['laws']} time laws")
    print(f"state at t = {report['t']:g} s: positions assembled, max |phi|/s = "
          f"{report['max_abs_phi']:.1e}")
    redundant = ", ".join(report["redundant_rows"]) or "none"
    print(f"degrees of freedom: {report['dof']} (joints), {report['dof_with_drivers']} left by "
          f"the drivers; redundant rows: {redundant}")
    if "condition_number" in report:
        print(f"condition number (equilibrated saddle-point matrix): "
              f"{report['condition_number']:.3e}; smallest singular value of the equilibrated "
              f"Phi_v: {report['sigma_min']:.3e}")
    if report["redundant_rows"]:
        print(f"multipliers of redundant rows: least sum |F|^2 + |T/l|^2, "
              f"l = {report['characteristic_length_m']:.4g} m")
    print()
    print("joint wrenches: exerted by the parent on the child, about the joint origin, "
          "in the child's joint frame (N, N m)")
    width = max([5] + [len(n) for n in wrenches.names])
    header = (f"{'joint':<{width}}  {'type':<9} {'tau':>11} {'Fx':>11} {'Fy':>11} {'Fz':>11} "
              f"{'|F|':>11} {'Tx':>11} {'Ty':>11} {'Tz':>11}")
    print(header)
    for k, joint in enumerate(model.joints):
        f, t = wrenches.force[k], wrenches.torque[k]
        tau = f"{wrenches.effort[k]:11.4g}" if np.isfinite(wrenches.effort[k]) else f"{'-':>11}"
        print(f"{joint.name:<{width}}  {joint.kind:<9} {tau} "
              + " ".join(f"{x:11.4g}" for x in (*f, np.linalg.norm(f), *t)))


def _jsonable(value):
    """Plain JSON: private keys dropped, non-finite numbers (e.g. the smallest singular value of
    a scene without constraints, infinite) written as null."""
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items() if not str(k).startswith("_")}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def cmd_dynamics(args) -> int:
    scene = load_scene(args.scene)
    model = assemble(scene)
    report = _state_report(model, args.t, condition=True)
    if args.json:
        json.dump(_jsonable(report), sys.stdout, indent=2, allow_nan=False)
        print()
    else:
        _print_dynamics(report)
    return 0


def cmd_validate(args) -> int:
    scene = load_scene(args.scene)
    scene.validate()
    print(f"{args.scene}: scene '{scene.name}' is valid ({len(scene.bodies)} bodies, "
          f"{len(scene.joints)} joints, {len(scene.drivers)} drivers, "
          f"{len(scene.forces)} force elements)")
    return 0


def cmd_scenes(args) -> int:
    scenes = builtin_scenes()
    if not scenes:
        print("no built-in scenes installed")
    for name in sorted(scenes):
        marker = " (default)" if name == DEFAULT_SCENE else ""
        print(f"{name}{marker}: {scenes[name].value}")
    return 0


# ------------------------------------------------------------------ main

def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hexapod",
        description="Constrained multibody dynamics in absolute coordinates for legged robots.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = sub.add_parser(
        "dynamics", help="forward dynamics at one instant: accelerations, multipliers, "
        "joint wrenches and driver efforts",
        description="Assemble SCENE at time T (positions by Newton's method, velocities "
        "projected), solve the saddle-point system and print the joint wrenches (exerted by "
        "the parent on the child, about the joint origin, in the child's joint frame), the "
        "driver efforts, degrees of freedom, redundant rows and the condition number.")
    p.add_argument("scene", nargs="?", default=DEFAULT_SCENE,
                   help=f"a TOML scene file or a built-in scene name (default: {DEFAULT_SCENE})")
    p.add_argument("--t", type=float, default=0.0, help="time in s (default 0)")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.set_defaults(run=cmd_dynamics)

    p = sub.add_parser("validate", help="check a scene and list every problem",
                       description="Read SCENE and report every problem found, or that it is "
                       "valid.")
    p.add_argument("scene", help="a TOML scene file or a built-in scene name")
    p.set_defaults(run=cmd_validate)

    p = sub.add_parser("scenes", help="list the built-in scenes",
                       description="List the built-in scenes, usable wherever a SCENE is asked.")
    p.set_defaults(run=cmd_scenes)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.run(args)
    except HexapodError as error:
        print(f"hexapod: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("hexapod: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into a reader that stopped (e.g. head): not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except Exception as error:  # an internal error: still one line unless debugging
        if os.environ.get("HEXAPOD_DEBUG"):
            raise
        print(f"hexapod: internal error: {type(error).__name__}: {error} "
              "(set HEXAPOD_DEBUG=1 for the traceback)", file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
