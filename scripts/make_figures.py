"""Regenerate the figures of the papers the project grew from, with an index.

    python3 scripts/make_figures.py               # every figure into figures/ (a few minutes)
    python3 scripts/make_figures.py --only seed002 --out /tmp/figures

Each paper has its own script in this directory (the file names ``seed000``, ``seed001`` and
``seed002`` stand for the three papers in the order of the README's references), which this one
runs in turn:

* ``seed000_efficiency.py``: the comparison by Vukobratović and Potkonjak of the three methods of
  forming ``W q_dd = P + V`` (basic theorems, Lagrange, Gibbs-Appell): counted operations and CPU
  time against the number of links, the absolute-coordinate engine on the same axes;
* ``seed001_figures.py``: Fig. 7 of Dumitru, Marin and Margine, the liaison force F21 of the left
  anterior leg under the gait law, and the same figure for every joint;
* ``seed002_figures.py``: Figs. 7-10 of Richard, Anderson and Andrews, the closed-loop pendulum of
  RESTRI against its one-degree-of-freedom Lagrange solution, with its vector-network graph and
  matrices.

Each writes into ``OUT/seedNNN/``; this script then writes ``OUT/README.md``, the index: every
figure, the paper figure it reproduces, its parameters and caption. Files are written to a
temporary directory first and moved into place when every script has succeeded, so a failed run
leaves the previous figures as they were.
"""

from __future__ import annotations

import argparse
import importlib.util
import shutil
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: seed -> (script, paper)
SEEDS = {
    "seed000": ("seed000_efficiency.py",
                "M. Vukobratović, V. Potkonjak, Contribution of the forming of computer methods "
                "for automatic modelling of spatial mechanisms motions, Mech. Mach. Theory 14 "
                "(1979) 179-188"),
    "seed001": ("seed001_figures.py",
                "N. Dumitru, M. Marin, A. Margine, Contributions to the analysis of the dynamic "
                "response of a hexapod type mobile robot (University of Craiova)"),
    "seed002": ("seed002_figures.py",
                "M. J. Richard, R. J. Anderson, G. C. Andrews, The vector-network method for the "
                "modelling of mechanical systems, Math. Comput. Simul. 31 (1989/90) 565-581"),
}

#: seed -> the heading of its section in the index
HEADINGS = {
    "seed000": "Vukobratović and Potkonjak (1979): forming the joint-coordinate model",
    "seed001": "Dumitru, Marin and Margine: the liaison forces of the front leg",
    "seed002": "Richard, Anderson and Andrews (1989/90): the closed-loop pendulum",
}


def _load(script: str):
    spec = importlib.util.spec_from_file_location(Path(script).stem, HERE / script)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def _seed000_entries(result: dict) -> list[dict]:
    """seed000's ``make`` returns its files; the index entries are written here."""
    captions = {
        "seed000_operations.png": (
            "Part II's comparison of the methods' efficiency (missing from our copy; "
            "reconstructed)",
            "Multiplications and additions of one forming of W and V by each method, counted by "
            "running it on counting scalars, against the number of links of a general chain."),
        "seed000_cpu_time.png": (
            "Part II's comparison of the methods' efficiency (missing from our copy; "
            "reconstructed)",
            "CPU time of one forming of W and V by each method, and of one forward-dynamics "
            "solve of the absolute-coordinate engine on the same chain, against the number of "
            "links."),
    }
    entries = []
    for path in result["files"]:
        name = Path(path).name
        if name in captions:
            reproduces, caption = captions[name]
            entries.append({"file": name, "reproduces": reproduces,
                            "parameters": "chains of 1-30 revolute links, random geometry "
                                          "(random seed 0)", "caption": caption})
    return entries


def make(out: Path, only: list[str] | None = None) -> list[tuple[str, dict]]:
    """Run the papers' scripts into ``out``; returns ``(seed, entry)`` for the index."""
    entries = []
    for seed, (script, _) in SEEDS.items():
        if only and seed not in only:
            continue
        start = time.perf_counter()
        print(f"{seed}: {script} ...", flush=True)
        result = _load(script).make(out / seed)
        made = _seed000_entries(result) if seed == "seed000" else result
        entries += [(seed, entry) for entry in made]
        print(f"{seed}: {len(made)} figures in {time.perf_counter() - start:.0f} s", flush=True)
    return entries


def index_text(entries: list[tuple[str, dict]]) -> str:
    lines = ["# Figures of the papers", "",
             "Regenerated by `python3 scripts/make_figures.py` from a clean checkout, which writes "
             "this index too: change the scripts, not this file. The three papers are listed in "
             "full in the [README's references](../README.md#references); the folder names "
             "`seed000/`, `seed001/` and `seed002/` stand for them in that order.", ""]
    for seed, (_, paper) in SEEDS.items():
        mine = [e for s, e in entries if s == seed]
        if not mine:
            continue
        lines += [f"## {HEADINGS[seed]} (`{seed}/`)", "", paper, "",
                  "| figure | reproduces | parameters |", "|---|---|---|"]
        for e in mine:
            parameters = e["parameters"]
            if isinstance(parameters, dict):
                parameters = ", ".join(f"{k} = {v}" for k, v in parameters.items())
            lines.append(f"| [{e['file']}]({seed}/{e['file']}) | {e['reproduces']} | "
                         f"{parameters} |")
        lines.append("")
        for e in mine:
            if e["file"].endswith(".png"):
                lines += [f"![{e['file']}]({seed}/{e['file']})", "", f"*{e['caption']}*", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(HERE.parent / "figures"), metavar="DIR")
    parser.add_argument("--only", nargs="+", choices=list(SEEDS), metavar="SEED")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out.parent, prefix=".figures-") as scratch:
        scratch = Path(scratch)
        entries = make(scratch, args.only)
        (scratch / "README.md").write_text(index_text(entries))
        out.mkdir(exist_ok=True)
        for seed in SEEDS:
            if (scratch / seed).is_dir():
                shutil.rmtree(out / seed, ignore_errors=True)
                shutil.move(scratch / seed, out / seed)
        if args.only and (out / "README.md").exists():
            print("wrote the figures of " + ", ".join(args.only) + "; the index lists only "
                  "them: run without --only to index every paper")
        shutil.move(scratch / "README.md", out / "README.md")
    print(f"wrote {out}/README.md and {len(entries)} entries")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
