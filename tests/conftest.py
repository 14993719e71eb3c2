"""Test-session settings."""

import atexit
import os
import shutil
import tempfile

# The same BLAS threading as the command line (hexapod sets one OpenBLAS thread before NumPy is
# imported), so that results computed here and by a `hexapod` subprocess agree to the last bit.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

# The cache on disk (hexapod._support.cache) in a folder of the session's own, removed when it
# ends: tests never read or write the user's cache, and the commands they run in subprocesses
# inherit the setting. Tests of the cache itself point it at their own folders.
_CACHE = tempfile.mkdtemp(prefix="hexapod-test-cache-")
os.environ["HEXAPOD_CACHE_DIR"] = _CACHE
for _setting in ("HEXAPOD_CACHE", "HEXAPOD_CACHE_SIZE"):
    os.environ.pop(_setting, None)
atexit.register(shutil.rmtree, _CACHE, ignore_errors=True)
