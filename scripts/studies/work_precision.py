"""The work-precision study: every integrator, error against CPU time, on four problems.

    python scripts/studies/work_precision.py           # the full study (20-30 CPU minutes)
    python scripts/studies/work_precision.py --quick   # shorter horizons and ladders (minutes)
    python scripts/studies/work_precision.py --problems andrews --methods dop853-projection

The same as ``hexapod bench`` run from the project's root (it finds ``data/`` from this file,
wherever it is run from): writes ``work-precision/`` with the table (``work_precision.md``),
every run (``runs.csv``), the error against CPU time (``work_precision.png``) and, per problem,
the constraint drift and energy error against time (``drift_<problem>.png``). The method, the
problems and their references are described in docs/work-precision.md.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    from hexapod.cli import main

    arguments = sys.argv[1:]
    if "--data" not in arguments:
        arguments += ["--data", str(ROOT / "data")]
    sys.exit(main(["bench", *arguments]))
