"""The Python examples of the README and the getting-started page run from ``import hexapod``
alone, and the README's prints the number the main job (``hexapod report``) reports."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import pytest

from hexapod.cli import main

ROOT = Path(__file__).resolve().parent.parent
MARK = "<!-- checked by tests/test_docs.py -->"


def checked_blocks(path: Path) -> list[str]:
    """The ```python blocks that follow the marker."""
    text = path.read_text(encoding="utf-8")
    blocks = re.findall(re.escape(MARK) + r"\s*```python\n(.*?)```", text, flags=re.S)
    assert blocks, f"{path.name}: no Python block marked {MARK}"
    return blocks


def run_block(code: str, cwd: Path, monkeypatch) -> str:
    monkeypatch.chdir(cwd)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "<docs>", "exec"), {"__name__": "__docs__"})  # noqa: S102
    return out.getvalue()


@pytest.mark.parametrize("page", ["README.md", "docs/getting-started.md"])
def test_the_python_examples_run_on_the_public_api(page, tmp_path, monkeypatch):
    for code in checked_blocks(ROOT / page):
        imported = set(re.findall(r"^(?:from|import) (\w+)", code, flags=re.M))
        assert imported <= {"numpy", "hexapod"}, f"{page} imports {imported}"
        run_block(code, tmp_path, monkeypatch)


def test_the_readme_example_prints_what_the_report_reports(tmp_path, monkeypatch, capsys):
    (code,) = checked_blocks(ROOT / "README.md")
    printed = run_block(code, tmp_path, monkeypatch).splitlines()[0]
    assert main(["report", "--out", str(tmp_path / "report")]) == 0
    said = capsys.readouterr().out
    claim = re.search(r"largest joint force [0-9.e+-]+ N at \S+", said).group(0)
    assert printed == claim.rstrip(";")
