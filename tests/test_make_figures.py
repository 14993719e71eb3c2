"""scripts/papers/make_figures.py leaves the committed figures alone: by default it writes a fresh
folder; with --update it rewrites only the files whose content changed, and a timing-dependent
file only with --timings. The papers' scripts are replaced by a stand-in (they take minutes and
have their own tests)."""

from __future__ import annotations

from pathlib import Path

import pytest
from script_loader import load_script

make_figures = load_script("scripts/papers/make_figures.py")

CPU = "seed000/seed000_cpu_time.png"
assert CPU in make_figures.TIMINGS


def _files(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _write(folder: Path, files: dict[str, bytes]) -> None:
    for name, content in files.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(content)


@pytest.fixture
def committed(tmp_path):
    """A stand-in for figures/: a timing figure, a figure that will not change, one that will,
    one the run no longer makes, and the index."""
    folder = tmp_path / "figures"
    _write(folder, {CPU: b"old timings", "seed000/seed000_operations.png": b"same",
                    "seed001/fig7_F21.png": b"old curve", "seed001/gone.png": b"stale",
                    "README.md": b"old index"})
    return folder


def _fake_make(out: Path, only=None):
    """What the papers' scripts would write: new timings, one unchanged figure, a changed one
    and a new one."""
    _write(out, {CPU: b"new timings", "seed000/seed000_operations.png": b"same",
                 "seed001/fig7_F21.png": b"new curve", "seed001/fig7_tita.png": b"new"})
    return [("seed001", {"file": "fig7_F21.png", "reproduces": "Fig. 7", "parameters": "-",
                         "caption": "F21"})]


def test_update_rewrites_only_what_changed_and_keeps_timings(tmp_path, committed):
    made = tmp_path / "made"
    _fake_make(made)
    (made / "README.md").write_bytes(b"new index")
    before = {name: (committed / name).stat().st_mtime_ns for name in _files(committed)}
    report = make_figures.update(made, committed)
    assert report == {"written": ["README.md", "seed001/fig7_F21.png", "seed001/fig7_tita.png"],
                      "unchanged": ["seed000/seed000_operations.png"], "kept": [CPU],
                      "stale": ["seed001/gone.png"]}
    files = _files(committed)
    assert files[CPU] == b"old timings" and files["seed001/fig7_F21.png"] == b"new curve"
    assert files["seed001/gone.png"] == b"stale"  # listed, not removed
    for name in ("seed000/seed000_operations.png", CPU):  # not even touched
        assert (committed / name).stat().st_mtime_ns == before[name]
    assert make_figures.update(made, committed, timings=True)["written"] == [CPU]
    assert _files(committed)[CPU] == b"new timings"


def test_update_with_only_keeps_the_index(tmp_path, committed):
    made = tmp_path / "made"
    _write(made, {"README.md": b"partial index", "seed001/fig7_F21.png": b"old curve"})
    report = make_figures.update(made, committed, index=False)
    assert report["kept"] == ["README.md"] and report["unchanged"] == ["seed001/fig7_F21.png"]
    assert (committed / "README.md").read_bytes() == b"old index"


def test_default_run_writes_a_fresh_folder_not_the_committed_one(tmp_path, committed,
                                                                 monkeypatch, capsys):
    monkeypatch.setattr(make_figures, "make", _fake_make)
    monkeypatch.setattr(make_figures, "COMMITTED", committed)
    monkeypatch.chdir(tmp_path)
    before = _files(committed)
    assert make_figures.main([]) == 0
    assert _files(committed) == before
    out = _files(tmp_path / "figures-out")
    assert out[CPU] == b"new timings" and "fig7_F21.png" in out["README.md"].decode()
    assert capsys.readouterr().out.startswith("writing into figures-out/")
    assert make_figures.main(["--update", "--timings"]) == 0
    assert _files(committed)[CPU] == b"new timings"


@pytest.mark.parametrize("argv", [["--timings"], ["--update", "--out", "elsewhere"]])
def test_options_that_do_not_go_together(argv):
    with pytest.raises(SystemExit) as stop:
        make_figures.main(argv)
    assert stop.value.code == 2
