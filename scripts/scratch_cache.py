"""hexapod's cache on disk, for a script: a temporary folder of the script's own, removed when it
ends, so that a script never writes in the user's cache (``docs/cache.md``); a cache folder the
user names (``HEXAPOD_CACHE_DIR``) is used as named. The processes a script starts inherit it.
Not a script itself: the scripts call :func:`use_scratch_cache` first thing when they run.
"""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile


def use_scratch_cache() -> None:
    """Point ``HEXAPOD_CACHE_DIR`` at a new temporary folder, removed at exit, unless it is
    set."""
    if os.environ.get("HEXAPOD_CACHE_DIR", "").strip():
        return
    folder = tempfile.mkdtemp(prefix="hexapod-script-cache-")
    os.environ["HEXAPOD_CACHE_DIR"] = folder
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
