"""``docs/extending.md`` names files that exist: every repository path it writes in backticks
(a placeholder such as ``<type>.py`` stands for a new file: its folder must exist)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "extending.md"
#: what makes a backticked word a path: a folder separator or a file's suffix
SUFFIXES = (".py", ".md", ".toml", ".json", ".csv", ".txt", ".cfg")


def named_paths(text: str) -> list[str]:
    """The backticked words of ``text`` that are repository paths."""
    words = re.findall(r"`([^`\s]+)`", text)
    return [w for w in words if re.fullmatch(r"[\w.\-/<>]+", w)
            and ("/" in w or w.endswith(SUFFIXES)) and not w.startswith(("/", "."))]


def missing(paths: list[str], root: Path) -> list[str]:
    out = []
    for path in paths:
        target = root / path
        if "<" in path:  # a file to create: the folder it goes in exists
            target = root / path[:path.index("<")].rpartition("/")[0]
        if not target.exists():
            out.append(path)
    return out


def test_every_path_the_page_names_exists():
    paths = named_paths(PAGE.read_text(encoding="utf-8"))
    assert "hexapod/scene/joints/base.py" in paths  # the joint section's, at least
    assert missing(paths, ROOT) == []


def test_a_wrong_path_is_caught(tmp_path):
    (tmp_path / "here").mkdir()
    (tmp_path / "here" / "a.py").write_text("")
    text = ("`here/a.py` `here/<new>.py` `there/b.py` `gone.md` `x = 1` `hexapod.scene` "
            "`Joint`")
    paths = named_paths(text)
    assert paths == ["here/a.py", "here/<new>.py", "there/b.py", "gone.md"]
    assert missing(paths, tmp_path) == ["there/b.py", "gone.md"]
