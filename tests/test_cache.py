"""The cache on disk (hexapod._support.cache) and the compiled CasADi Functions kept in it
(hexapod._support.compiled): where it is, entries whole or absent, concurrent processes,
damaged or untrusted entries, the size limit, cleaning, and nothing written when it is off.

Every test turns the cache on in a folder of its own (the execution setting, and
``HEXAPOD_CACHE_DIR`` for the processes it starts)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from hexapod._support import cache
from hexapod._support.compiled import (
    LIBRARY,
    NAME,
    compiled,
    compiled_key,
    compiler,
    find_compiled,
)
from hexapod._support.execution import executing
from hexapod.errors import HexapodError

ROOT = Path(__file__).resolve().parents[1]
needs_compiler = pytest.mark.skipif(compiler() is None, reason="no C compiler")


@pytest.fixture
def folder(tmp_path, monkeypatch) -> Path:
    """A cache folder of the test's own, the cache on, the default size limit."""
    path = tmp_path / "cache"
    monkeypatch.setenv("HEXAPOD_CACHE_DIR", str(path))
    monkeypatch.delenv("HEXAPOD_CACHE", raising=False)
    monkeypatch.delenv("HEXAPOD_CACHE_SIZE", raising=False)
    monkeypatch.delenv("HEXAPOD_NO_JIT", raising=False)
    monkeypatch.setattr(cache, "_warned", set())
    with executing(cache=path):
        yield path


class Builder:
    """A small Function's builder that counts its calls."""

    def __init__(self, name: str = "f", scale: float = 2.0):
        self.name, self.scale, self.calls = name, scale, 0

    def __call__(self) -> ca.Function:
        self.calls += 1
        x = ca.SX.sym("x", 3)
        return ca.Function(self.name, [x], [self.scale * ca.sin(x), ca.sumsqr(x)], ["x"],
                           ["y", "n"])


def values(function: ca.Function) -> list[np.ndarray]:
    return [np.asarray(y).ravel() for y in function([0.1, -0.4, 2.0])]


def store(name: str, data: bytes = b"0123456789" * 10) -> str:
    """Keep ``data`` as the entry of ``name`` (one file, ``data.bin``); its key."""
    key = cache.key(name)
    cache.keep(key, f"entry {name}", {"data.bin": data})
    return key


def entry_folders(root: Path) -> list[Path]:
    return sorted(p for p in (root / cache.LAYOUT).iterdir() if not p.name.startswith("."))


# ------------------------------------------------------------------ where it is


def test_the_library_uses_no_cache_unless_asked(tmp_path):
    assert cache.folder() is None
    with executing(cache=tmp_path):
        assert cache.folder() == tmp_path
    assert cache.folder() is None


def test_the_folder_the_environment_configures(tmp_path):
    home = Path.home()
    folder = cache.configured_folder
    assert folder({}) == home / ".cache" / "hexapod"
    assert folder({"XDG_CACHE_HOME": "/x/cache"}) == Path("/x/cache/hexapod")
    assert folder({"XDG_CACHE_HOME": "relative"}) == home / ".cache" / "hexapod"
    assert folder({"XDG_CACHE_HOME": "/x", "HEXAPOD_CACHE_DIR": str(tmp_path)}) == tmp_path
    for off in ("0", "off", "No", "false"):
        assert folder({"HEXAPOD_CACHE": off, "HEXAPOD_CACHE_DIR": str(tmp_path)}) is None
    assert folder({"HEXAPOD_CACHE": "1"}) == home / ".cache" / "hexapod"


def test_the_size_limit_the_environment_configures():
    assert cache.configured_size({}) == cache.size_limit() == 1024**3
    assert cache.configured_size({"HEXAPOD_CACHE_SIZE": "2G"}) == 2 * 1024**3
    assert cache.configured_size({"HEXAPOD_CACHE_SIZE": "300K"}) == 300 * 1024
    with pytest.raises(HexapodError, match="HEXAPOD_CACHE_SIZE='lots'"):
        cache.configured_size({"HEXAPOD_CACHE_SIZE": "lots"})


def test_keys_are_stable_across_processes_and_tell_their_parts_apart():
    here = cache.key("model", "tree")
    there = subprocess.run([sys.executable, "-c", "from hexapod._support import cache; "
                            "print(cache.key('model', 'tree'))"], capture_output=True,
                           text=True, check=True, cwd=ROOT).stdout.strip()
    assert here == there and len(here) == 64
    assert cache.key("model", "tree") != cache.key("model", "tree2")
    assert cache.key("ab", "c") != cache.key("a", "bc")


def test_code_for_the_processor_is_kept_under_its_features(monkeypatch):
    """Compiled for the processor's own instruction set (x86-64 Linux, where its features can
    be read), a library is kept under those features: a processor with others never loads
    it; without them, the portable flags alone."""
    import hexapod._support.compiled as module

    keys = set()
    try:
        for features in ("fpu sse2", "fpu sse2 avx2 fma", ""):
            monkeypatch.setattr(module, "_processor_features", lambda f=features: f)
            module.compiler_flags.cache_clear()
            keys.add(compiled_key("m", "/usr/bin/gcc"))
            native = set(module.NATIVE_FLAGS) <= set(module.compiler_flags())
            assert native == bool(features)
    finally:
        module.compiler_flags.cache_clear()
    assert len(keys) == 3


def test_keys_change_with_the_version_of_hexapod_and_of_casadi(monkeypatch):
    import hexapod._version

    key, library = cache.key("m"), compiled_key("m", "/usr/bin/gcc")
    monkeypatch.setattr(hexapod._version, "__version__", "99.0")
    cache._code_identity.cache_clear()
    try:
        assert cache.key("m") != key
    finally:
        cache._code_identity.cache_clear()
    monkeypatch.undo()
    assert cache.key("m") == key
    assert compiled_key("m", "/usr/bin/clang") != library
    monkeypatch.setattr(ca, "__version__", "0.0.1")
    assert compiled_key("m", "/usr/bin/gcc") != library


# ------------------------------------------------------------------ entries


def test_an_entry_is_kept_and_read_back_whole(folder):
    key = store("k1", b"what was built")
    path, files = cache.load(key)
    assert files == {"data.bin": b"what was built"} and path.name == key
    (entry,) = cache.entries(folder, describe=True)
    assert entry.what == "entry k1"
    meta = json.loads((entry.path / cache.META).read_text())
    assert set(meta["files"]) == {"data.bin"}
    assert (folder / "CACHEDIR.TAG").read_text().startswith("Signature: 8a477f597d28d172789f")
    assert not [p for p in (folder / cache.LAYOUT).iterdir() if p.name.startswith(".")]


@needs_compiler
def test_a_compiled_function_is_compiled_once(folder):
    build = Builder("g")
    first = compiled("k2", build)
    assert first.is_a("External") and build.calls == 1
    again = find_compiled("k2")
    assert again is not None and again.is_a("External")
    assert compiled("k2", build).is_a("External") and build.calls == 1
    for a, b in zip(values(first), values(Builder("g")()), strict=True):
        assert np.allclose(a, b, rtol=1e-15, atol=0)
    assert [p.name for p in (entry_folders(folder)[0]).iterdir()].count(LIBRARY) == 1
    assert find_compiled("other key") is None


def test_without_a_compiler_the_function_is_interpreted(folder, monkeypatch):
    monkeypatch.setenv("HEXAPOD_NO_JIT", "1")
    build = Builder()
    function = compiled("k3", build)
    assert function.is_a("SXFunction") and build.calls == 1
    assert not (folder / cache.LAYOUT).exists() or not entry_folders(folder)


@needs_compiler
def test_a_compiler_that_fails_is_a_warning_and_nothing_is_stored(folder, monkeypatch,
                                                                   tmp_path):
    broken = tmp_path / "bin" / "gcc"
    broken.parent.mkdir()
    broken.write_text("#!/bin/sh\necho 'gcc: fatal error: no space left' >&2\nexit 1\n")
    broken.chmod(0o755)
    monkeypatch.setenv("PATH", str(broken.parent))
    with pytest.warns(UserWarning, match="could not compile f .*no space left"):
        function = compiled("k4", Builder())
    assert function.is_a("SXFunction")
    assert not entry_folders(folder)


def test_when_the_cache_is_off_nothing_is_written(tmp_path, monkeypatch):
    """Without a cache in the execution setting (the library's default), whatever the
    environment says."""
    target, scratch = tmp_path / "cache", tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setenv("HEXAPOD_CACHE_DIR", str(target))
    monkeypatch.setenv("TMPDIR", str(scratch))
    monkeypatch.setattr("tempfile.tempdir", None)  # TMPDIR read again
    build = Builder()
    compiled("k5", build)
    compiled("k5", build)
    store("k5")
    assert build.calls == 2 and cache.load(cache.key("k5")) is None
    assert cache.entries() == [] and cache.clean() == (0, 0)
    assert not target.exists()
    assert list(scratch.iterdir()) == []  # the compiler's scratch folder is gone too


# ------------------------------------------------------------------ damaged entries


def _damage(path: Path, how: str) -> None:
    meta = path / cache.META
    payload = next(p for p in path.iterdir() if p.name != cache.META)
    if how == "garbage":
        payload.write_bytes(b"\x7fELF not at all" * 50)
    elif how == "truncated":
        payload.write_bytes(payload.read_bytes()[: payload.stat().st_size // 2])
    elif how == "meta garbled":
        meta.write_text("{ not json")
    elif how == "meta missing":
        meta.unlink()
    elif how == "foreign but consistent":  # the checksum matches, the content is not ours
        payload.write_bytes(b"something else entirely")
        listed = json.loads(meta.read_text())
        listed["files"][payload.name] = __import__("hashlib").sha256(
            b"something else entirely").hexdigest()
        meta.write_text(json.dumps(listed))
    elif how == "file listed outside":
        listed = json.loads(meta.read_text())
        listed["files"] = {"../escape": "0" * 64}
        meta.write_text(json.dumps(listed))
    elif how == "truncated but consistent":  # a bus error when loaded, were it not checked
        _rewrite(payload, payload.read_bytes()[: payload.stat().st_size // 2])
    elif how == "others may write":
        payload.chmod(0o666)
    elif how == "a link":
        target = path.parent.parent / "elsewhere"
        target.write_bytes(payload.read_bytes())
        payload.unlink()
        payload.symlink_to(target)
    elif how == "a named pipe":  # read without waiting for a writer that never comes
        data = payload.read_bytes()
        payload.unlink()
        os.mkfifo(payload)
        listed = json.loads(meta.read_text())
        listed["files"][payload.name] = __import__("hashlib").sha256(data).hexdigest()
        meta.write_text(json.dumps(listed))
    elif how == "not a C function's name":
        _rewrite(path / NAME, b"f; rm -rf /")


def _rewrite(path: Path, data: bytes) -> None:
    """Give ``path`` the content ``data`` and its checksum in the entry's meta.json."""
    path.write_bytes(data)
    meta = path.parent / cache.META
    listed = json.loads(meta.read_text())
    listed["files"][path.name] = __import__("hashlib").sha256(data).hexdigest()
    meta.write_text(json.dumps(listed))


#: What the storage sees (a consistent foreign library is the loader's to refuse, below).
DAMAGES = ("garbage", "truncated", "meta garbled", "meta missing", "file listed outside",
           "others may write", "a link", "a named pipe")


@pytest.mark.parametrize("how", DAMAGES)
def test_a_damaged_or_untrusted_entry_is_removed_with_a_warning(folder, how):
    key = store("k6", b"what was built")
    _damage(entry_folders(folder)[0], how)
    with pytest.warns(cache.CacheWarning, match=f"cache entry .*{key} not used"):
        assert cache.load(key) is None
    assert entry_folders(folder) == []
    store("k6", b"what was built")  # written again, whole
    assert cache.load(key)[1] == {"data.bin": b"what was built"}


def test_a_file_larger_than_the_size_limit_is_not_read(folder):
    key = store("k6b", b"x" * 5000)
    with executing(cache_size=4000), \
            pytest.warns(cache.CacheWarning, match="larger than the cache's size limit"):
        assert cache.load(key) is None


@needs_compiler
@pytest.mark.parametrize("how", ["garbage", "truncated", "foreign but consistent",
                                 "truncated but consistent", "not a C function's name"])
def test_a_damaged_library_is_compiled_again_never_loaded(folder, how):
    build = Builder("h")
    compiled("k7", build)
    _damage(entry_folders(folder)[0], how)
    with pytest.warns(cache.CacheWarning, match="not used"):
        function = compiled("k7", build)
    assert build.calls == 2 and function.is_a("External")
    for a, b in zip(values(function), values(Builder("h")()), strict=True):
        assert np.allclose(a, b, rtol=1e-15, atol=0)


def test_a_foreign_folder_or_file_in_the_cache_is_left_alone(folder):
    store("k8")
    layout = folder / cache.LAYOUT
    (layout / "notes.txt").write_text("mine")
    (layout / "photos").mkdir()
    (folder / "elsewhere.txt").write_text("mine too")
    assert len(cache.entries()) == 1
    assert cache.clean() == (1, pytest.approx(1, abs=10**7))
    assert (layout / "notes.txt").exists() and (layout / "photos").is_dir()
    assert (folder / "elsewhere.txt").exists()


@pytest.mark.skipif(not hasattr(os, "getuid"), reason="POSIX permissions")
def test_a_folder_others_may_write_in_is_not_used(folder):
    key = store("k9")
    (folder / cache.LAYOUT).chmod(0o777)
    with pytest.warns(cache.CacheWarning, match="others may write in it"):
        assert cache.load(key) is None  # not read from there


def test_a_folder_that_cannot_be_written_is_a_warning_and_the_work_goes_on(tmp_path,
                                                                           monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setattr(cache, "_warned", set())
    with pytest.warns(cache.CacheWarning, match="cannot write in the cache folder"), \
            executing(cache=blocker / "cache"):
        key = store("k10")
        assert cache.load(key) is None


# ------------------------------------------------------------------ processes at once

WORKER = textwrap.dedent("""
    import sys, time
    import casadi as ca
    from hexapod._support import cache
    from hexapod._support.compiled import compiled
    from hexapod._support.execution import executing
    setting = executing(**cache.configured())
    setting.__enter__()
    start = float(sys.argv[2])
    while time.time() < start:
        time.sleep(0.001)
    x = ca.SX.sym("x", 3)
    build = lambda: ca.Function("w", [x], [2 * ca.sin(x), ca.sumsqr(x)], ["x"], ["y", "n"])
    kind = sys.argv[1]
    if kind == "compiled":
        function = compiled("shared", build)
    else:  # the same data kept, read back
        cache.keep(cache.key("shared"), "w", {"data.bin": build().serialize()})
        data = cache.load(cache.key("shared"))[1]["data.bin"]
        function = ca.Function.deserialize(data.decode())
    print(kind, function.is_a("External"), float(function([0.1, -0.4, 2.0])[1]))
""")


@pytest.mark.parametrize("kind", ["kept",
                                  pytest.param("compiled", marks=needs_compiler)])
def test_processes_building_the_same_entry_at_once_all_succeed(folder, kind):
    start = time.time() + 1.0  # every process has loaded CasADi by then, most likely
    workers = [subprocess.Popen([sys.executable, "-c", WORKER, kind, str(start)], cwd=ROOT,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
               for _ in range(4)]
    outputs = [w.communicate(timeout=120) for w in workers]
    for worker, (out, err) in zip(workers, outputs, strict=True):
        assert worker.returncode == 0, err
        assert out.split()[2] == repr(0.1**2 + 0.4**2 + 4.0)
        assert out.split()[1] == str(kind == "compiled")
    (entry,) = entry_folders(folder)
    assert cache.load(entry.name) is not None
    assert not [p for p in (folder / cache.LAYOUT).iterdir() if p.name.startswith(".")]


READER = textwrap.dedent("""
    import hashlib, json, os, sys, time
    entry = sys.argv[1]
    seen = 0
    stop = time.time() + float(sys.argv[2])
    while time.time() < stop:
        try:
            folder = os.open(entry, os.O_RDONLY)  # this folder, even if renamed meanwhile
        except FileNotFoundError:  # not written yet, or removed
            continue
        try:
            def read(name):
                handle = os.open(name, os.O_RDONLY, dir_fd=folder)
                with os.fdopen(handle, "rb") as stream:
                    return stream.read()
            try:
                meta = json.loads(read("meta.json"))
                for name, checksum in meta["files"].items():
                    assert hashlib.sha256(read(name)).hexdigest() == checksum, "half an entry"
                seen += 1
            except FileNotFoundError:  # fine if the folder is no longer the entry (removed)
                try:
                    same = os.stat(entry).st_ino == os.fstat(folder).st_ino
                except FileNotFoundError:
                    same = False
                assert not same, "an entry without all its files was seen"
        finally:
            os.close(folder)
    print(seen)
""")

WRITER = textwrap.dedent("""
    import sys
    import casadi as ca
    from hexapod._support import cache
    from hexapod._support.execution import executing
    setting = executing(**cache.configured())
    setting.__enter__()
    x = ca.SX.sym("x", 40)
    big = ca.Function("big", [x], [ca.cumsum(ca.sin(x) * ca.cos(x.T @ x))]).serialize()
    for _ in range(int(sys.argv[1])):
        cache.discard(cache.key("churn"))
        cache.keep(cache.key("churn"), "churn", {"data.bin": big, "more.bin": big[::-1]})
""")


def test_readers_never_see_half_an_entry_while_others_write_and_remove_it(folder):
    key = store("churn")  # makes the folder; the writers replace the entry
    entry = folder / cache.LAYOUT / key
    readers = [subprocess.Popen([sys.executable, "-c", READER, str(entry), "2.5"], cwd=ROOT,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
               for _ in range(2)]
    writers = [subprocess.Popen([sys.executable, "-c", WRITER, "40"], cwd=ROOT,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
               for _ in range(2)]
    seen = []
    for process in readers + writers:
        out, err = process.communicate(timeout=120)
        assert process.returncode == 0, err
        seen.append(out)
    assert all(int(count) > 0 for count in seen[:2])  # the readers did read whole entries
    assert cache.load(key) is not None


# ------------------------------------------------------------------ size and cleaning


def _fill(folder: Path, count: int) -> list[str]:
    """``count`` entries, each used one minute after the one before."""
    keys = []
    for k in range(count):
        keys.append(store(f"fill{k}"))  # all of the same size
        os.utime(folder / cache.LAYOUT / keys[-1], (1e9 + 60 * k, 1e9 + 60 * k))
    return keys


def test_beyond_the_size_limit_the_least_recently_used_entries_go(folder):
    keys = _fill(folder, 4)
    size = cache.entries()[0].size
    assert cache.load(keys[0]) is not None  # the oldest is used now: it stays
    with executing(cache_size=4 * size + size // 2):  # room for 4
        store("fill4")
    left = {e.key for e in cache.entries()}
    assert left == {keys[0], keys[2], keys[3], cache.key("fill4")}
    with executing(cache_size=1):  # smaller than any entry: the limit holds
        store("fill5")
    assert cache.entries() == []


def test_clean_removes_everything_or_the_old_or_down_to_a_size(folder):
    keys = _fill(folder, 4)
    size = cache.entries()[0].size
    assert cache.clean(keep_size=2 * size) == (2, 2 * size)
    assert {e.key for e in cache.entries()} == set(keys[2:])
    os.utime(folder / cache.LAYOUT / keys[3])  # used now
    assert cache.clean(unused_for=3600) == (1, size)
    assert [e.key for e in cache.entries()] == [keys[3]]
    assert cache.clean() == (1, size)
    assert cache.entries() == []


def test_leftovers_of_processes_that_are_gone_are_removed(folder):
    store("k11")
    layout = folder / cache.LAYOUT
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    (layout / f".staging-{dead}-abc").mkdir()
    (layout / f".staging-{dead}-abc" / "library.so").write_bytes(b"half")
    (layout / f".trash-{dead}-def").mkdir()
    (layout / f".staging-{os.getpid()}-live").mkdir()  # a build in progress: kept
    cache.clean(unused_for=10**6)
    names = {p.name for p in layout.iterdir() if p.name.startswith(".")}
    assert names == {f".staging-{os.getpid()}-live"}


def test_the_cache_never_waits_for_the_disk(folder, monkeypatch):
    """Its files are written whole (renamed into place) but not flushed: an entry lost or
    damaged by a crash of the machine fails its checksums and is built again."""
    def no_sync(descriptor):
        raise AssertionError("the cache flushed a file to the disk")

    monkeypatch.setattr(os, "fsync", no_sync)
    assert cache.load(store("k13")) is not None


def test_a_full_disk_while_storing_is_a_warning_and_nothing_is_kept(folder, monkeypatch):
    def full(*args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(cache, "_publish", full)
    with pytest.warns(cache.CacheWarning, match="No space left on device"):
        store("k14")
    assert cache.entries() == []
    assert not [p for p in (folder / cache.LAYOUT).iterdir() if p.name.startswith(".")]



def test_a_file_that_cannot_be_written_is_a_warning_at_the_callers_line(folder, monkeypatch):
    """A write that fails inside an entry (write_atomically's error, a full disk) is a
    CacheWarning attributed to the code that asked to keep the entry, and nothing is
    kept."""
    def refused(path, *args, **kwargs):
        raise HexapodError(f"{path}: no space left on device")

    monkeypatch.setattr(cache, "write_atomically", refused)
    with pytest.warns(cache.CacheWarning, match="not kept in the cache") as caught:
        cache.keep(cache.key("k15"), "k15", {"data.bin": b"x"})
    assert caught[0].filename == __file__
    assert cache.entries() == []

INTERRUPTED = textwrap.dedent("""
    import signal, sys
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import casadi as ca
    from hexapod._support import cache
    from hexapod._support.compiled import compiled
    from hexapod._support.execution import executing
    setting = executing(**cache.configured())
    setting.__enter__()
    x = ca.SX.sym("x")
    print("compiling", flush=True)
    compiled("interrupted", lambda: ca.Function("slow", [x], [2 * x]))
""")


@pytest.mark.skipif(not hasattr(os, "killpg"), reason="POSIX process groups")
def test_an_interrupted_compilation_leaves_no_compiler_running_and_nothing_behind(
        folder, tmp_path):
    """The compiler (here a script that starts a long child, as gcc starts cc1) is stopped with
    every process it started; the staging folder goes."""
    import signal

    marker = f"0.{os.getpid()}{time.time_ns() % 10**6}"  # sleep adds it: 20 s and a little
    fake = tmp_path / "bin" / "gcc"
    fake.parent.mkdir()
    fake.write_text(f"#!/bin/sh\nsleep 20 {marker} &\nwait\n")
    fake.chmod(0o755)
    env = dict(os.environ, PATH=f"{fake.parent}{os.pathsep}{os.environ['PATH']}")
    process = subprocess.Popen([sys.executable, "-c", INTERRUPTED], cwd=ROOT, env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stdout.readline().strip() == "compiling"

    def sleeping() -> bool:
        return any(f"sleep 20 {marker}" in p.read_text(errors="replace").replace("\0", " ")
                   for p in Path("/proc").glob("[0-9]*/cmdline") if p.exists())

    deadline = time.time() + 30
    while not sleeping() and time.time() < deadline:  # the compiler's child has started
        time.sleep(0.05)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert "KeyboardInterrupt" in err
    deadline = time.time() + 10  # well before the compiler's child would end by itself (20 s)
    while sleeping() and time.time() < deadline:  # the killed child leaves the process table
        time.sleep(0.05)
    assert not sleeping()
    assert not list((folder / cache.LAYOUT).iterdir())
