"""Write the ground reactions of the walking robot's built-in gaits, the loads of the single-leg
scenes (``<gait>-ground-reactions.csv`` beside this file):

    python3 legs/data/make_walking_loads.py
"""

import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small matrices: threads only cost

from legs.loads import write_table  # noqa: E402

if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))  # scratch_cache
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    for gait in ("tripod",):
        start = time.perf_counter()
        path = write_table(gait)
        print(f"{path} written in {time.perf_counter() - start:.1f} s")
