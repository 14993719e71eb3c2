"""Regenerate the figures of the papers the project grew from, with an index.

    python3 scripts/papers/make_figures.py                     # into ./figures-out/ (a minute)
    python3 scripts/papers/make_figures.py --only seed002 --out DIR
    python3 scripts/papers/make_figures.py --update            # the committed figures/, see below
    python3 scripts/papers/make_figures.py --update --timings  # ... the CPU-time figures too

By default the figures go into a fresh folder, ``figures-out/`` in the current directory (or
``--out DIR``), and the committed ``figures/`` is left alone. ``--update`` rewrites
``figures/`` instead, file by file and only where the content changed: a file whose bytes are
the same is not touched, and a timing-dependent file (:data:`TIMINGS`: CPU times measured on the
machine that runs the script, different on every run) that is already there is kept unless
``--timings`` is given too. A file of ``figures/`` that the run no longer makes is listed, not
removed. With ``--only``, ``--update`` leaves the index (``figures/README.md``) as it is.

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

import hexapod as hx

HERE = Path(__file__).resolve().parent
#: the committed figures, rewritten only with --update
COMMITTED = HERE.parents[1] / "figures"
#: the default output: a fresh folder in the current directory, not tracked
DEFAULT_OUT = Path("figures-out")
#: files (relative to the figures folder) whose content depends on the machine's timings
TIMINGS = frozenset({"seed000/seed000_cpu_time.png", "seed000/seed000_efficiency.csv"})

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
             "Regenerated by `python3 scripts/papers/make_figures.py --update` from a clean "
             "checkout, which writes this index too (only the files whose content changed; the "
             "CPU-time figure with `--timings`): change the scripts, not this file. The three "
             "papers are listed in "
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


def update(made: Path, target: Path, timings: bool = False,
           index: bool = True) -> dict[str, list[str]]:
    """Copy the files of ``made`` into ``target`` where their content changed; a timing-
    dependent file already in ``target`` only with ``timings``; the index only with ``index``.
    Returns the relative paths: ``written``, ``unchanged``, ``kept`` (timings or index left as
    they were) and ``stale`` (in a folder of ``target`` that was made, but not made)."""
    report: dict[str, list[str]] = {"written": [], "unchanged": [], "kept": [], "stale": []}
    files = sorted(p.relative_to(made).as_posix() for p in made.rglob("*") if p.is_file())
    for name in files:
        new, old = (made / name).read_bytes(), target / name
        if old.is_file() and old.read_bytes() == new:
            report["unchanged"].append(name)
        elif old.is_file() and ((name in TIMINGS and not timings)
                                or (name == "README.md" and not index)):
            report["kept"].append(name)
        else:
            old.parent.mkdir(parents=True, exist_ok=True)
            hx.output.write_atomically(old, new)
            report["written"].append(name)
    folders = {Path(name).parent for name in files} - {Path(".")}
    report["stale"] = sorted(p.relative_to(target).as_posix() for folder in folders
                             if (target / folder).is_dir() for p in (target / folder).iterdir()
                             if p.is_file() and p.relative_to(target).as_posix() not in files)
    return report


def _replace(made: Path, out: Path, only: list[str] | None) -> None:
    """Move the made seed folders and index into ``out`` (a folder of this script's output),
    each seed folder replacing its earlier version."""
    out.mkdir(parents=True, exist_ok=True)
    for seed in SEEDS:
        if (made / seed).is_dir():
            shutil.rmtree(out / seed, ignore_errors=True)
            shutil.move(made / seed, out / seed)
    if only and (out / "README.md").exists():
        print("wrote the figures of " + ", ".join(only) + "; the index lists only them: run "
              "without --only to index every paper")
    shutil.move(made / "README.md", out / "README.md")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        epilog="Without --update the committed figures/ is left alone.")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--out", type=Path, default=DEFAULT_OUT, metavar="DIR",
                       help=f"the folder to write (default: {DEFAULT_OUT}/ in the current "
                       "directory)")
    where.add_argument("--update", action="store_true",
                       help="rewrite the committed figures/, only the files whose content "
                       "changed, the timing-dependent ones only with --timings")
    parser.add_argument("--timings", action="store_true",
                        help="with --update: rewrite the timing-dependent figures too ("
                        + ", ".join(sorted(TIMINGS)) + ")")
    parser.add_argument("--only", nargs="+", choices=list(SEEDS), metavar="SEED")
    args = parser.parse_args(argv)
    if args.timings and not args.update:
        parser.error("--timings goes with --update")
    out = COMMITTED if args.update else args.out
    print(f"writing into {out}/" + (" (only the files that changed)" if args.update else
                                    " (the committed figures/ is rewritten only with --update)"),
          flush=True)
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out.parent, prefix=".figures-") as scratch:
        scratch = Path(scratch)
        entries = make(scratch, args.only)
        (scratch / "README.md").write_text(index_text(entries))
        if not args.update:
            _replace(scratch, out, args.only)
            print(f"wrote {out}/README.md and {len(entries)} entries")
            return 0
        report = update(scratch, out, args.timings, index=not args.only)
    for kind, names in report.items():
        if names:
            print(f"{kind} ({len(names)}): {', '.join(names)}")
    if report["kept"]:
        print("kept: the timing-dependent files (rewritten with --update --timings) or, with "
              "--only, the index")
    if report["stale"]:
        print("stale: no longer made by this script; remove them from the repository by hand")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    raise SystemExit(main())
