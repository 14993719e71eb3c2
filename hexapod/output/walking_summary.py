"""The walking robot's sections of the report's summary: the ground-force policy in words, the
feet's ground reactions and whether the ground can give them (feasibility), and the trunk's
motion."""

from __future__ import annotations

import numpy as np

from hexapod.algorithms.inverse import InverseResult
from hexapod.model.model import Model
from hexapod.output.ground import FootLoads, TrunkMotion, describe_events, foot_events
from hexapod.output.summary_parts import Peak, g4, markdown_table


def policy_description(model: Model) -> str:
    """The ground-force policy of a model with contacts, in words, with its settings."""
    ground = model.ground
    if ground.policy == "min-wrench":
        return ("the least sum of |F|^2 + |T / l|^2 over every joint's wrench, the feet's "
                f"included, l = {model.characteristic_length:.4g} m")
    refs = ", ".join(f"`{k}` {v:g}" for k, v in ground.reference_efforts.items())
    effort = ("the least sum of (tau / tau_ref)^2 over the actuator efforts (reference "
              f"efforts {ground.default_reference:g}" + (f"; {refs}" if refs else "") + ")")
    if ground.policy == "min-effort":
        return effort
    cone = (f"a pyramid of {ground.faces} faces inscribed in the cone" if ground.faces
            else "the exact cone")
    return (f"{effort}, each foot's normal force at least its load-sharing weight times "
            f"{ground.min_normal:g} N and its tangential force inside the friction cone of "
            f"mu = {ground.mu:g} ({cone})")


def ground_section(model: Model, result: InverseResult, loads: FootLoads) -> list[str]:
    weight = loads.weight
    lines = ["", "## Ground reactions", "",
             f"Policy `{loads.policy}`: {policy_description(model)}. "
             + (f"Redundant rows (their multipliers chosen by the policy): "
                f"{', '.join(result.redundant_rows)}." if result.redundant_rows
                else "No redundant rows."),
             "",
             "The ground's force on each foot, world axes (`GRx:<leg>`, `GRy:<leg>`, "
             "`GRz:<leg>` in inverse.csv; zero in swing): normal force F_n = GRz, tangential "
             f"force \\|F_t\\| = \\|(GRx, GRy)\\|, friction ratio \\|F_t\\| / (mu F_n) with "
             f"mu = {loads.mu:g} (above 1 the foot needs more friction than mu). Robot weight "
             f"m \\|g\\| = {model.total_mass:.4g} kg x {np.linalg.norm(model.gravity):.4g} "
             f"m/s^2 = {weight:.4g} N. Per sample in ground.csv.", ""]
    rows = []
    t = loads.times
    for c, leg in enumerate(loads.legs):
        magnitude = np.linalg.norm(loads.force[:, c], axis=1)
        peak = Peak.of(t, magnitude)
        ratio = np.where(np.isfinite(loads.ratio[:, c]), loads.ratio[:, c], -np.inf)
        worst = int(np.argmax(ratio))
        stance = np.mean(loads.status[:, c] != "swing")
        rows.append([leg, f"{100 * stance:.0f}", g4(peak.value),
                     g4(peak.value / weight) if weight > 0 else "-", f"{peak.time:.4g}",
                     g4(float(loads.normal[:, c].max())), g4(float(loads.tangential[:, c].max())),
                     g4(float(ratio[worst])) if np.isfinite(ratio[worst]) else "-",
                     f"{t[worst]:.4g}" if np.isfinite(ratio[worst]) else "-"])
    lines += markdown_table(
        ["foot", "in stance (% of samples)", "peak \\|F\\| (N)", "peak \\|F\\| (body weights)",
         "at t (s)", "peak F_n (N)", "peak \\|F_t\\| (N)", "peak friction ratio", "at t (s)"],
        rows)
    return lines + _feasibility_lines(loads)


def _feasibility_lines(loads: FootLoads) -> list[str]:
    """Whether the ground can give the feet their forces, whatever the policy: a verdict, and
    for a foot that slips or pulls its counts, first time and worst margins."""
    events = foot_events(loads)
    if not events:
        return ["", "Feasible: at every sample every loaded foot's force presses on the ground "
                f"and lies inside the friction cone of mu = {loads.mu:g}."]
    bad = loads.infeasible
    lines = ["", f"**Infeasible**: at {int(bad.any(axis=1).sum())} of {bad.shape[0]} samples "
             "the ground cannot give these forces: a foot slips (tangential force beyond mu "
             "times the normal force) or the ground would have to pull it. A robot moving so "
             "would slip or leave the ground; its efforts are not ones to size motors by.", ""]
    rows = []
    for c, leg in enumerate(loads.legs):
        if not bad[:, c].any():
            continue
        first = float(loads.times[int(np.argmax(bad[:, c]))])
        ratio = loads.ratio[:, c][np.isfinite(loads.ratio[:, c])]
        rows.append([leg, str(int(np.sum(loads.status[:, c] == "slip"))),
                     str(int(np.sum(loads.status[:, c] == "pull"))), f"{first:.4g}",
                     g4(float(ratio.max())) if ratio.size else "-",
                     g4(float(loads.normal[:, c].min()))])
    lines += markdown_table(["foot", "slip samples", "pull samples", "first at t (s)",
                              "worst friction ratio", "least F_n (N)"], rows)
    return lines + ["", *(f"- {phrase}" for phrase in describe_events(events))]


def trunk_section(trunks: list[TrunkMotion]) -> list[str]:
    lines = ["", "## Trunk", "",
             "Pose (centre of mass, world; Euler parameters and roll, pitch, yaw) and velocity "
             "(centre of mass, angular; world axes) of each free body, per sample in "
             "trunk.csv.", ""]
    rows = []
    for m in trunks:
        low, high = m.position.min(axis=0), m.position.max(axis=0)
        angles = np.degrees(np.abs(m.angles).max(axis=0))
        rows.append([f"`{m.body}`", f"{low[0]:.4g} ... {high[0]:.4g}",
                     f"{low[1]:.4g} ... {high[1]:.4g}", f"{low[2]:.4g} ... {high[2]:.4g}",
                     " / ".join(f"{a:.3g}" for a in angles),
                     f"{m.velocity[:, 0].mean():.4g}",
                     g4(float(np.linalg.norm(m.angular_velocity, axis=1).max()))])
    return lines + markdown_table(
        ["body", "x (m)", "y (m)", "z (m)", "largest \\|roll\\| / \\|pitch\\| / \\|yaw\\| (deg)",
         "mean vx (m/s)", "largest \\|omega\\| (rad/s)"], rows)
