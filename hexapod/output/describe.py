"""Plain descriptions of a model and of one state, as dictionaries (for JSON) and as text.

``describe_model`` is what ``hexapod info`` prints: the elements, what the model was built with,
the topology, the mobility counted and numerical, redundant rows and the condition number at
the initial pose, and on request the vector-network matrices. ``describe_state`` is what
``hexapod dynamics`` prints: accelerations, multipliers, joint wrenches and driver efforts.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from hexapod.algorithms.dynamics import forward_dynamics
from hexapod.algorithms.ground import ground_reactions
from hexapod.algorithms.kinematics import (
    assemble_positions,
    rank_split,
    scaled_residual,
    solve_velocities,
)
from hexapod.algorithms.liaison import driver_efforts, joint_wrenches
from hexapod.algorithms.topology import body_joint_graph, mobility, vector_network
from hexapod.model.model import GROUND_INDEX, Data, Model
from hexapod.scene.laws import Law

GROUND = "ground"


def _ground_settings(model: Model) -> dict | None:
    """The ground-force policy and its settings, for a model with foot contacts (else None)."""
    if not model.contacts:
        return None
    g = model.ground
    return {"policy": g.policy, "mu": g.mu, "faces": g.faces, "min_normal": g.min_normal,
            "contacts": [c.name for c in model.contacts]}


def _body(model: Model, index: int) -> str:
    return GROUND if index == GROUND_INDEX else model.bodies[index].name


def law_description(law: Law | None) -> dict:
    """A law's type and parameters."""
    if law is None:
        return {}
    fields = {f.name: getattr(law, f.name) for f in dataclasses.fields(law)
              if not f.name.startswith("_")}
    out: dict = {"type": law.kind}
    for key, value in fields.items():
        out[key] = law_description(value) if isinstance(value, Law) else (
            np.asarray(value).tolist() if isinstance(value, (tuple, np.ndarray)) else value)
    return out


def _solved_state(model: Model, t: float):
    """Positions, velocities and the workspace after forward dynamics at ``t``, with the
    condition number and the smallest singular value of the kept rows.

    Only the extreme singular values are computed (as ``forward_dynamics(condition=True)``
    would give them, without all the others): a large model's rank decision is a sparse QR
    whose extremes ARPACK finds in milliseconds where a dense SVD takes minutes."""
    data = model.create_data()
    q = assemble_positions(model, data, t)
    v = solve_velocities(model, data, t, q)
    forward_dynamics(model, data, t, q, v)
    split = rank_split(model, data.Phi_v, data.w)
    data.condition_number = split.condition_number(model.n_v)
    data.sigma_min = split.extreme_singular_values()[0]
    return q, v, data


def _pose(model: Model, q: np.ndarray, t: float, data: Data) -> dict:
    phi = scaled_residual(model, t, q)
    return {"t": t, "max_abs_phi": float(np.max(np.abs(phi))) if phi.size else 0.0,
            "condition_number": data.condition_number, "sigma_min": data.sigma_min,
            "characteristic_length_m": model.characteristic_length}


def describe_model(model: Model, t: float = 0.0, graph: bool = False) -> dict:
    """Everything ``hexapod info`` reports, at the pose assembled at time ``t``.

    Parameters
    ----------
    model : Model
    t : float
        The time the pose is assembled at, s.
    graph : bool
        Also the vector-network graph (:func:`hexapod.vector_network`), key ``vector_network``.

    Returns
    -------
    dict
        JSON-ready: the model's bodies, joints, drivers and force elements, its sizes, the
        topology, the mobility and the initial pose (``ground``: the ground-force settings of a
        model with contacts).

    Raises
    ------
    AssemblyError, SingularSystemError
        No pose satisfies the constraints at ``t``, or redundant constraints contradict each
        other there.
    """
    if model.guidance is not None:  # its guided joints' laws: the motion the guides give at t
        from hexapod.algorithms.inverse import inverse_dynamics, motion_model

        model = motion_model(model, inverse_dynamics(model, [t]))
    rows = [r.name for r in model.rows]
    drivers_on = {j.name: [model.rows[r].name for r in j.driver_rows] for j in model.joints}
    bodies = [{"name": b.name, "kind": b.kind, "mass": b.mass,
               "coordinates": list(model.coordinate_names[b.q]),
               "velocities": list(model.velocity_names[b.v])} for b in model.bodies]
    joints = [{"name": j.name, "type": j.kind, "parent": _body(model, j.parent),
               "child": _body(model, j.child), "rows": [rows[r] for r in j.rows],
               "loop_closing": j.loop_closing, "driven_by": drivers_on[j.name],
               "across": list(j.across)} for j in model.joints]
    drivers = [{"name": d.name, "kind": d.kind, "row": rows[d.row],
                "target": (model.joints[d.joint].name if d.kind == "joint"
                           else f"{model.bodies[d.body].name}.{d.coordinate}"
                           + ("" if d.frame < 0 else f" in {model.bodies[d.frame].name}")),
                "law": law_description(d.spec)} for d in model.drivers]
    forces = [{"name": f.name, "type": f.kind, "bodies": [_body(model, b) for b in f.bodies],
               "joint": None if f.joint is None else model.joints[f.joint].name}
              for f in model.forces]
    terms = (["gravity"] if np.any(model.gravity != 0) and model.bodies else []) + (
        ["gyroscopic"] if any(b.kind == "spatial" for b in model.bodies) else []) + [
        f.name for f in model.forces]
    topology = body_joint_graph(model)
    q, _, data = _solved_state(model, t)
    m = mobility(model, data, t, q)
    out = {
        "scene": model.name, "dimension": model.dimension,
        "mass": model.total_mass,
        "bodies": bodies, "joints": joints, "drivers": drivers, "forces": forces,
        "model": {"n_q": model.n_q, "n_v": model.n_v, "n_c": model.n_c,
                  "time_laws": model.n_w, "force_terms": terms,
                  "gravity": model.gravity.tolist()},
        "topology": {"vertices": len(topology.vertices), "edges": len(topology.joints),
                     "tree": list(topology.tree), "loop_closing": list(topology.cotree),
                     "components": topology.components,
                     "independent_loops": topology.independent_loops,
                     "loops": [list(loop.joints) for loop in topology.loops]},
        "mobility": {"counted": m.counted, "numerical": m.numerical,
                     "counted_with_drivers": m.counted_with_drivers,
                     "numerical_with_drivers": m.numerical_with_drivers,
                     "redundancy": m.redundancy, "redundant_rows": list(m.redundant_rows)},
        "initial_pose": _pose(model, q, t, data),
    }
    ground = _ground_settings(model)
    if ground is not None:
        out["ground"] = ground
    if graph:
        network = vector_network(model)
        out["vector_network"] = {
            "vertices": list(network.vertices),
            "edges": [dataclasses.asdict(e) for e in network.edges],
            "incidence": network.incidence.tolist(), "cutset": network.cutset.tolist(),
            "circuit": network.circuit.tolist(), "orthogonal": network.orthogonal()}
    return out


def describe_state(model: Model, t: float = 0.0) -> dict:
    """Everything ``hexapod dynamics`` reports at time ``t``.

    Parameters
    ----------
    model : Model
    t : float
        s.

    Returns
    -------
    dict
        JSON-ready: the sizes, the state and its mobility, every joint's wrench (report
        convention; a contact's ground force too), the driver efforts, the accelerations and
        the multipliers by name.

    Raises
    ------
    AssemblyError, SingularSystemError
        No consistent state at ``t``, or contradicting redundant constraints.
    """
    q, _, data = _solved_state(model, t)
    wrenches = joint_wrenches(model, data)
    m = mobility(model, data, t, q)
    out = {
        "scene": model.name, "t": t, "dimension": model.dimension,
        "counts": {"bodies": len(model.bodies), "joints": len(model.joints),
                   "drivers": len(model.drivers), "forces": len(model.forces),
                   "n_q": model.n_q, "n_v": model.n_v, "n_c": model.n_c, "laws": model.n_w},
        "dof": m.numerical, "dof_with_drivers": m.numerical_with_drivers,
        "redundant_rows": [model.rows[i].name for i in data.redundant_rows],
        "state": _pose(model, q, t, data),
        "joints": {j.name: {"type": j.kind, **values}
                   for j, values in zip(model.joints, wrenches.as_dict().values(), strict=True)},
        "driver_efforts": driver_efforts(model, data),
        "accelerations": dict(zip(model.velocity_names, data.v_dot.tolist(), strict=True)),
        "multipliers": {model.rows[i].name: float(data.lam[i]) for i in range(model.n_c)},
    }
    if model.contacts:  # each foot contact also says the ground's force on it, world axes
        forces = ground_reactions(model, data.lam) + 0.0  # zero in swing, not -0
        status = data.ground_status or ("",) * len(forces)
        for k, contact in enumerate(model.contacts):
            out["joints"][contact.name].update(
                ground_force=forces[k].tolist(), ground_status=status[k],
                policy=model.ground.policy, mu=model.ground.mu)
    return out


# ------------------------------------------------------------------ text

def _table(header: list[str], rows: list[list], indent: str = "  ") -> list[str]:
    cells = [[str(c) for c in header]] + [[str(c) for c in row] for row in rows]
    widths = [max(len(r[k]) for r in cells) for k in range(len(header))]
    return [indent + "  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip()
            for r in cells]


def _number(x) -> str:
    return "-" if x is None else f"{x:.4g}"


def _pose_lines(pose: dict, redundant: list[str], policy: str | None = None) -> list[str]:
    lines = [f"pose at t = {pose['t']:g} s: max |phi|/s = {pose['max_abs_phi']:.1e}",
             f"condition number (equilibrated saddle-point matrix): "
             f"{_number(pose['condition_number'])}; smallest singular value of the "
             f"equilibrated Phi_v: {_number(pose['sigma_min'])}"]
    if redundant and policy not in (None, "min-wrench"):
        lines.append(f"multipliers of redundant rows: the ground-force policy {policy}")
    elif redundant:
        lines.append(f"multipliers of redundant rows: least sum |F|^2 + |T/l|^2, "
                     f"l = {pose['characteristic_length_m']:.4g} m")
    return lines


def format_model(info: dict) -> str:
    """The text ``hexapod info`` prints, from :func:`describe_model`'s dictionary.

    Parameters
    ----------
    info : dict
        From :func:`describe_model`.

    Returns
    -------
    str
    """
    m, top, mob = info["model"], info["topology"], info["mobility"]
    out = [f"scene '{info['scene']}' ({info['dimension']}-D, SI units), total mass "
           f"{info['mass']:.6g} kg", "", "bodies"]
    out += _table(["name", "kind", "mass kg", "coordinates"],
                  [[b["name"], b["kind"], f"{b['mass']:.6g}",
                    " ".join(c.split(".")[-1] for c in b["coordinates"])]
                   for b in info["bodies"]])
    out += ["", "joints"]
    out += _table(["name", "type", "parent -> child", "rows", "loop", "driven by / across"],
                  [[j["name"], j["type"], f"{j['parent']} -> {j['child']}",
                    " ".join(r.split("/")[-1] for r in j["rows"]),
                    "closes" if j["loop_closing"] else "tree",
                    ", ".join(j["driven_by"] + j["across"]) or "-"] for j in info["joints"]])
    if info["drivers"]:
        out += ["", "drivers"]
        out += _table(["name", "target", "law"],
                      [[d["name"], d["target"], d["law"].get("type", "")]
                       for d in info["drivers"]])
    if info["forces"]:
        out += ["", "force elements"]
        out += _table(["name", "type", "acts on"],
                      [[f["name"], f["type"], f"joint {f['joint']}" if f["joint"]
                        else " - ".join(f["bodies"])] for f in info["forces"]])
    out += ["", f"model: n_q = {m['n_q']}, n_v = {m['n_v']}, n_c = {m['n_c']} rows, "
            f"{m['time_laws']} time laws; force terms: {', '.join(m['force_terms']) or 'none'}",
            f"topology: {top['vertices']} vertices (ground and bodies), {top['edges']} joints, "
            f"{top['components']} component(s), {top['independent_loops']} independent "
            f"loop(s)"]
    for loop in top["loops"]:
        out.append(f"  loop closed by {loop[0]}: {' - '.join(loop)}")
    out.append(f"degrees of freedom: {mob['counted']} counted (Grubler-Kutzbach), "
               f"{mob['numerical']} numerical (n_v - rank Phi_v); with the drivers "
               f"{mob['counted_with_drivers']} and {mob['numerical_with_drivers']}")
    out.append("redundant rows: " + (", ".join(mob["redundant_rows"]) or "none"))
    out += _pose_lines(info["initial_pose"], mob["redundant_rows"],
                       info["ground"]["policy"] if "ground" in info else None)
    if "ground" in info:
        out.append(_ground_line(info["ground"]))
    if "vector_network" in info:
        out += [""] + format_network(info["vector_network"])
    return "\n".join(out)


def _ground_line(ground: dict) -> str:
    cone = f"{ground['faces']}-face pyramid" if ground["faces"] else "exact cone"
    return (f"ground forces of {len(ground['contacts'])} foot contacts: policy "
            f"{ground['policy']}, mu = {ground['mu']:g} ({cone}), least normal force "
            f"{ground['min_normal']:g} N")


def format_network(net: dict) -> list[str]:
    edges = net["edges"]
    labels = [f"e{k + 1}" for k in range(len(edges))]
    branches = sum(e["tree"] for e in edges)
    out = [f"vector network (Richard, Anderson and Andrews): {len(net['vertices'])} vertices, "
           f"{len(edges)} edges, "
           f"{len(net['cutset'])} cutsets, {len(net['circuit'])} circuits; cutset and circuit "
           f"matrices orthogonal: {'yes' if net['orthogonal'] else 'NO'}", "edges"]
    out += _table(["", "name", "kind", "tail -> head", ""],
                  [[labels[k], e["name"], e["kind"], f"{e['tail']} -> {e['head']}",
                    "tree" if e["tree"] else "chord"] for k, e in enumerate(edges)])
    for title, matrix, names in (
            ("incidence matrix (rows: vertices)", net["incidence"], net["vertices"]),
            ("cutset matrix [U A] (rows: tree branches)", net["cutset"], labels[:branches]),
            ("circuit matrix [B U] (rows: chords)", net["circuit"], labels[branches:])):
        out += ["", title]
        out += _table([""] + labels, [[n] + [f"{x:+d}" if x else "0" for x in row]
                                      for n, row in zip(names, matrix, strict=True)])
    return out


def format_state(report: dict) -> str:
    """The text ``hexapod dynamics`` prints, from :func:`describe_state`'s dictionary.

    Parameters
    ----------
    report : dict
        From :func:`describe_state`.

    Returns
    -------
    str
    """
    c = report["counts"]
    out = [f"scene '{report['scene']}' ({report['dimension']}-D): {c['bodies']} bodies, "
           f"{c['joints']} joints, {c['drivers']} drivers, {c['forces']} force elements",
           f"model: n_q = {c['n_q']}, n_v = {c['n_v']}, n_c = {c['n_c']} rows, "
           f"{c['laws']} time laws",
           f"degrees of freedom: {report['dof']} (joints), {report['dof_with_drivers']} left "
           "by the drivers; redundant rows: " + (", ".join(report["redundant_rows"]) or "none")]
    feet = {name: j for name, j in report["joints"].items() if "ground_force" in j}
    out += _pose_lines(report["state"], report["redundant_rows"],
                       next(iter(feet.values()))["policy"] if feet else None)
    if feet:
        first = next(iter(feet.values()))
        out += ["", f"ground forces of {len(feet)} foot contacts by the policy "
                f"{first['policy']} (mu = {first['mu']:g}): the ground's force on each foot "
                "(world axes, N)"]
        out += _table(["contact", "GRx", "GRy", "GRz", "status"],
                      [[name, *(f"{x:.4g}" for x in j["ground_force"]), j["ground_status"]]
                       for name, j in feet.items()], indent="")
    out += ["", "joint wrenches: exerted by the parent on the child, about the joint origin, "
            "in the child's joint frame (N, N m)"]
    keys = ("tau", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz")
    rows = []
    for name, j in report["joints"].items():
        force = np.linalg.norm([j["Fx"], j["Fy"], j["Fz"]])
        values = [f"{j[k]:.4g}" if k in j else "-" for k in keys]
        rows.append([name, j["type"], *values[:4], f"{force:.4g}", *values[4:]])
    out += _table(["joint", "type", *keys[:4], "|F|", *keys[4:]], rows, indent="")
    return "\n".join(out)
