"""A library call writes nothing its caller did not ask for: with a read-only home, no cache
folder set and empty working and temporary folders, importing hexapod, assembling the walking
robot and running its inverse dynamics (the phase path, and the exact path of its first
sample), and the front leg's (the tree path), leaves every folder as it was; Python's audit
events show no file opened for writing, no folder made and nothing renamed or removed; and the
sources are not listed to make a cache key."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

PROGRAM = textwrap.dedent("""
    import sys

    written = []

    def audit(event, args):
        if event == "open" and args[1] is not None and any(c in str(args[1]) for c in "wax+"):
            written.append((event, str(args[0])))
        elif event == "open" and isinstance(args[2], int) and args[2] & 0o3:  # os.open flags
            written.append((event, str(args[0])))
        elif event in ("os.mkdir", "os.rename", "os.remove", "os.rmdir", "shutil.rmtree",
                       "os.symlink", "os.link", "os.truncate", "tempfile.mkstemp",
                       "tempfile.mkdtemp"):
            written.append((event, str(args[0])))

    sys.addaudithook(audit)
    import numpy as np
    import hexapod as hx

    model = hx.assemble(hx.load_scene("hexapod"))
    result = hx.inverse_dynamics(model, np.linspace(0.0, 0.1, 40))
    assert result.method == "phase" and np.all(np.isfinite(result.force))
    leg = hx.inverse_dynamics(hx.assemble(hx.load_scene("front-leg")), np.linspace(0, 0.1, 9))
    assert leg.method == "tree" and np.all(np.isfinite(leg.force))
    from hexapod._support.cache import _code_identity  # the cache keys' stat of every source
    assert _code_identity.cache_info().misses == 0, "a cache key was made with no cache"
    print(repr(written))
""")


def _listing(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def test_the_library_writes_nothing_anywhere(tmp_path):
    home, work, scratch = tmp_path / "home", tmp_path / "work", tmp_path / "tmp"
    for folder in (home, work, scratch):
        folder.mkdir()
    (home / ".config").mkdir()
    home.chmod(stat.S_IRUSR | stat.S_IXUSR)
    (home / ".config").chmod(stat.S_IRUSR | stat.S_IXUSR)
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("HEXAPOD_", "XDG_", "MPL"))}
    env.update(HOME=str(home), TMPDIR=str(scratch), PYTHONDONTWRITEBYTECODE="1",
               PYTHONPATH=os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]))
    try:
        done = subprocess.run([sys.executable, "-c", PROGRAM], cwd=work, env=env,
                              capture_output=True, text=True, timeout=600)
    finally:
        home.chmod(stat.S_IRWXU)
        (home / ".config").chmod(stat.S_IRWXU)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "[]", done.stdout
    assert "warning" not in done.stderr.lower(), done.stderr
    for folder in (home, work, scratch):
        assert _listing(folder) == ([".config"] if folder == home else []), folder
