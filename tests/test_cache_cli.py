"""``hexapod cache``: what the cache holds and cleaning it, each run in a cache folder of the
test's own; and ``hexapod inverse`` filling it."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import commands
import numpy as np
import pytest

from hexapod._support.compiled import compiler_flags

ROOT = Path(__file__).resolve().parents[1]
FIXTURE = ROOT / "tests" / "data" / "pinocchio-fixtures" / "chain-3"
#: Only compiled libraries are kept: the tests that fill the cache compile.
needs_compiler = pytest.mark.skipif(not (shutil.which("gcc") or shutil.which("cc")),
                                    reason="no C compiler")


def run(*args: str, cache: Path, cwd: Path, **settings: str) -> subprocess.CompletedProcess:
    """``hexapod ARGS`` with its cache in ``cache`` (the session has no other cache setting:
    conftest.py)."""
    return commands.hexapod(*args, cwd=cwd, HEXAPOD_CACHE_DIR=str(cache), **settings)


def inverse(tmp_path: Path, cache: Path, out: str = "out.csv") -> None:
    done = run("inverse", str(FIXTURE / "model.urdf"), "--motion", str(FIXTURE / "motion.csv"),
               "--out", out, "--compile", "yes", cache=cache, cwd=tmp_path)
    assert done.returncode == 0, done.stderr


def test_info_on_an_empty_cache(tmp_path):
    cache = tmp_path / "cache"
    done = run("cache", cache=cache, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [f"cache folder: {cache} (HEXAPOD_CACHE_DIR)",
                                        "entries: 0, 0 bytes of at most 1 GiB"]
    assert not cache.exists()  # looking writes nothing


@needs_compiler
def test_inverse_fills_the_cache_and_info_lists_it(tmp_path):
    cache = tmp_path / "cache"
    inverse(tmp_path, cache)
    first = (tmp_path / "out.csv").read_text()
    done = run("cache", "info", cache=cache, cwd=tmp_path, HEXAPOD_CACHE_SIZE="2G")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[1].startswith("entries: 1, ") and lines[1].endswith("of at most 2 GiB")
    held = sorted(line.split("  ")[-1] for line in lines[2:])
    assert held == ["tree-ordered inverse dynamics of 'random-11' (3 joints), compiled "
                    + " ".join(compiler_flags())]
    report = json.loads(run("cache", "info", "--json", cache=cache, cwd=tmp_path).stdout)
    assert report["folder"] == str(cache) and report["entries"] == 1
    assert report["size"] == sum(item["size"] for item in report["items"]) > 0
    inverse(tmp_path, cache, "again.csv")  # from the cache: the same numbers
    assert (tmp_path / "again.csv").read_text() == first
    assert json.loads(run("cache", "info", "--json", cache=cache,
                          cwd=tmp_path).stdout)["entries"] == 1


@needs_compiler
def test_compile_yes_leaves_compiled_code_that_the_next_run_loads(tmp_path):
    """--compile yes compiles the tree path in the first run and keeps the library; the next
    run loads it, compiles nothing, and both write the interpreter's numbers (run --compile
    no) to round-off."""
    cache = tmp_path / "cache"
    for out, choice in (("interpreted.csv", "no"), ("compiled.csv", "yes"), ("again.csv", "yes")):
        done = run("inverse", str(FIXTURE / "model.urdf"), "--motion",
                   str(FIXTURE / "motion.csv"), "--out", out, "--compile", choice, cache=cache,
                   cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        if out == "compiled.csv":
            entries = json.loads(run("cache", "info", "--json", cache=cache,
                                     cwd=tmp_path).stdout)["entries"]
            assert any(f"compiled {' '.join(compiler_flags())}" in line for line in
                       run("cache", "info", cache=cache, cwd=tmp_path).stdout.splitlines())
    assert json.loads(run("cache", "info", "--json", cache=cache,
                          cwd=tmp_path).stdout)["entries"] == entries  # nothing built again
    tables = [np.loadtxt(tmp_path / name, delimiter=",", skiprows=1)
              for name in ("interpreted.csv", "compiled.csv", "again.csv")]
    scale = np.abs(tables[0]).max()
    for table in tables[1:]:
        assert np.abs(table - tables[0]).max() <= 1e-12 * scale


def inverse_of(tmp_path: Path, cache: Path, fixture: str) -> None:
    folder = ROOT / "tests" / "data" / "pinocchio-fixtures" / fixture
    done = run("inverse", str(folder / "model.urdf"), "--motion", str(folder / "motion.csv"),
               "--out", f"{fixture}.csv", "--compile", "yes", cache=cache, cwd=tmp_path)
    assert done.returncode == 0, done.stderr


@needs_compiler
def test_clean(tmp_path):
    cache = tmp_path / "cache"
    inverse_of(tmp_path, cache, "chain-3")
    inverse_of(tmp_path, cache, "chain-6")
    # the same two entries again, for after the trim: a copy (times of use kept) compiles
    # nothing, where filling the cache again compiled both kernels a second time
    shutil.copytree(cache, tmp_path / "copy")
    kept = run("cache", "clean", "--older-than", "1", cache=cache, cwd=tmp_path)
    assert kept.returncode == 0 and kept.stdout.startswith("removed 0 entries (0 bytes)")
    trimmed = run("cache", "clean", "--max-size", "1K", cache=cache, cwd=tmp_path)
    assert trimmed.stdout.startswith("removed 2 entries (") and "0 left" in trimmed.stdout
    cache = tmp_path / "copy"
    items = json.loads(run("cache", "info", "--json", cache=cache, cwd=tmp_path).stdout)["items"]
    oldest, newest = items  # least recently used first: chain-3's, then chain-6's
    assert "(3 joints)" in oldest["what"] and "(6 joints)" in newest["what"]
    one = run("cache", "clean", "--max-size", str(newest["size"]), cache=cache, cwd=tmp_path)
    assert one.stdout.startswith("removed 1 entry (") and "; 1 left (" in one.stdout
    emptied = run("cache", "clean", cache=cache, cwd=tmp_path)
    assert emptied.stdout.startswith("removed 1 entry") and "; 0 left (0 bytes)" in emptied.stdout
    assert (cache / "CACHEDIR.TAG").exists()


def test_the_cache_turned_off(tmp_path):
    cache = tmp_path / "cache"
    inverse_off = run("inverse", str(FIXTURE / "model.urdf"), "--motion",
                      str(FIXTURE / "motion.csv"), "--out", "out.csv", cache=cache,
                      cwd=tmp_path, HEXAPOD_CACHE="0")
    assert inverse_off.returncode == 0, inverse_off.stderr
    assert not cache.exists()
    for action in ("info", "clean"):
        done = run("cache", action, cache=cache, cwd=tmp_path, HEXAPOD_CACHE="off")
        assert done.returncode == 0 and "the cache is off (turned off by HEXAPOD_CACHE=off)" \
            in done.stdout


@pytest.mark.parametrize("args", [("cache", "info"), ("cache", "--help")], ids=" ".join)
def test_the_cache_command_loads_no_heavy_library(tmp_path, args):
    done = commands.python("-X", "importtime", "-m", "hexapod", *args, cwd=tmp_path,
                           HEXAPOD_CACHE_DIR=str(tmp_path / "cache"))
    assert done.returncode == 0, done.stderr
    loaded = {line.rpartition("|")[2].strip().split(".")[0]
              for line in done.stderr.splitlines() if line.startswith("import time:")}
    assert "hexapod" in loaded and not loaded & {"numpy", "casadi", "scipy"}


def test_a_bad_size_setting_is_one_error_line(tmp_path):
    done = run("cache", cache=tmp_path / "cache", cwd=tmp_path, HEXAPOD_CACHE_SIZE="huge")
    assert done.returncode == 1 and done.stdout == ""
    assert done.stderr.strip() == ("hexapod: error: HEXAPOD_CACHE_SIZE='huge': not a memory "
                                   "size: 'huge' (write e.g. 16G, 512M)")


def test_a_script_keeps_the_cache_in_a_folder_of_its_own(tmp_path):
    """scripts/scratch_cache.py: a temporary folder, removed when the script ends; a folder the
    user names is used as named (the library itself writes nothing there)."""
    code = ("import os, sys; sys.path.insert(0, 'scripts'); "
            "from scratch_cache import use_scratch_cache; use_scratch_cache(); "
            "import hexapod as hx; from legs import front_leg_scene; "
            "hx.assemble(front_leg_scene()); print(os.environ['HEXAPOD_CACHE_DIR'])")
    env = {k: v for k, v in os.environ.items() if k != "HEXAPOD_CACHE_DIR"}
    env["HOME"] = str(tmp_path / "home")  # where the user's cache would be
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    used = Path(done.stdout.strip())
    assert used.name.startswith("hexapod-script-cache-") and not used.exists()
    assert not (tmp_path / "home").exists()
    env["HEXAPOD_CACHE_DIR"] = str(tmp_path / "named")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.stdout.strip() == str(tmp_path / "named")
    assert not (tmp_path / "named").exists()


def _entry(cache: Path, what: str) -> Path:
    """One cache entry made by hand, whose meta.json says ``what``."""
    from hexapod._support.cache import LAYOUT

    entry = cache / LAYOUT / ("a" * 64)
    entry.mkdir(parents=True)
    (entry / "meta.json").write_text(json.dumps({"what": what}))
    return entry


def test_info_escapes_the_control_characters_an_entry_holds(tmp_path, monkeypatch, capsys):
    from hexapod.cli.app import main

    cache = tmp_path / "cache"
    _entry(cache, "tree \x1b[31mred\x1b[0m\x07 of 'x'")
    monkeypatch.setenv("HEXAPOD_CACHE_DIR", str(cache))
    assert main(["cache", "info"]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out
    assert "tree \\x1b[31mred\\x1b[0m\\x07 of 'x'" in out


def test_clean_that_cannot_remove_says_so_and_fails(tmp_path, monkeypatch, capsys):
    """A cache the user may not write (simulated: the tests may run as root, whom permissions
    do not stop): the entries stay, and the command says so with status 1."""
    from hexapod.cli.app import main

    cache = tmp_path / "cache"
    entry = _entry(cache, "tree")
    monkeypatch.setenv("HEXAPOD_CACHE_DIR", str(cache))

    def refused(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(os, "rename", refused)
    assert main(["cache", "clean"]) == 1
    err = capsys.readouterr().err
    assert entry.is_dir()
    assert "could not remove 1 entry" in err and "removed 0 entries" in err
