"""Write the ground reactions of the walking robot's built-in gaits, the loads of the single-leg
scenes (legs/data/<gait>-ground-reactions.csv): python3 scripts/make_walking_loads.py"""

import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small matrices: threads only cost

from scratch_cache import use_scratch_cache  # noqa: E402

from legs.loads import write_table  # noqa: E402

if __name__ == "__main__":
    use_scratch_cache()  # never the user's cache
    for gait in ("tripod",):
        start = time.perf_counter()
        path = write_table(gait)
        print(f"{path} written in {time.perf_counter() - start:.1f} s")
