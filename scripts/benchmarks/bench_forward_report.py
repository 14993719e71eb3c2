"""The report of ``scripts/benchmarks/bench_forward.py``: growth exponents, hexapod / Exudyn
ratios, the Markdown tables, the figure and strict JSON."""

from __future__ import annotations

import io

import numpy as np
from bench_forward_runs import REPRESENTATIVE_RTOL, REPRESENTATIVE_STEP, TARGET
from measure import growth_exponent, local_slopes

# ------------------------------------------------------------------ summaries

def _chain_costs(results: list[dict]) -> dict[str, np.ndarray]:
    """Per method, (bodies, CPU per step ms) over the chains where it was measured."""
    chains = [r for r in results if r["problem"]["chain"]]
    out = {}
    for method in sorted({m for r in chains for m in r["methods"]}):
        points = [(r["bodies"], r["methods"][method]["cpu_per_step_ms"]) for r in chains
                  if method in r["methods"]
                  and np.isfinite(r["methods"][method]["cpu_per_step_ms"])]
        if len(points) >= 2:
            out[method] = np.array(sorted(points))
    return out


def growth_exponents(results: list[dict]) -> dict[str, float]:
    """The least-squares slope of log(CPU per step) against log(bodies) over the chains."""
    return {method: growth_exponent(*points.T)
            for method, points in _chain_costs(results).items()}


def chain_slopes(results: list[dict]) -> dict[str, list[tuple[int, int, float]]]:
    """The slopes between consecutive chain sizes: ``(bodies, next bodies, slope)``."""
    return {method: [(int(a), int(b), slope) for a, b, slope in local_slopes(*points.T)]
            for method, points in _chain_costs(results).items()}


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


def method_row(r: dict, method: str, x: dict, reach_note: str = "") -> str:
    """One method's row of the table: cost per step and steps at the representative setting,
    its error there, CPU time to the target (with ``reach_note`` after it) and rungs run."""
    rep = x["representative"]
    steps = f" ({rep['steps']})" if rep["status"] == "finished" else f" ({rep['status']})"
    reach = f"{x['time_to_target_qualifier']} {fmt(x['time_to_target_s'])}".strip()
    return (f"| {r['problem']['key']} | {r['bodies']} | {x['library']} | {method} "
            f"| {fmt(x['cpu_per_step_ms'])}{steps} | {fmt(rep['error'], 2)} "
            f"| {reach + reach_note if x['time_to_target_qualifier'] else '-'} "
            f"| {len(x['rungs'])} |")


def markdown(results: list[dict], exponents: dict, args) -> str:
    lines = [f"Target: relative position error {TARGET:g}; representative setting: rtol = "
             f"{REPRESENTATIVE_RTOL:g} (adaptive), h = {REPRESENTATIVE_STEP * 1e3:g} ms (fixed); "
             f"CPU times best of {args.repeat}.", "",
             "| problem | bodies | library | method | CPU/step ms (steps) | error at setting "
             "| CPU to 1e-6 s | rungs |", "| --- | ---: | --- | --- | ---: | ---: | ---: | ---: |"]
    for r in results:
        lines += [method_row(r, method, x) for method, x in r["methods"].items()]
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
        lines += ["", "Slopes between consecutive sizes: " + "; ".join(
            f"{m} " + ", ".join(f"{a}-{b}: {slope:.2f}" for a, b, slope in slopes)
            for m, slopes in chain_slopes(results).items())]
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
