"""The project's scripts as modules, for the tests that exercise them."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def load_script(path: str):
    """The script at ``path`` (from the repository's root, e.g.
    ``"scripts/papers/make_figures.py"``) imported as the module named by its file, once per
    test session, its folder on ``sys.path`` for the modules it imports from beside it, as when
    it is run."""
    file = ROOT / path
    if file.stem in sys.modules:
        return sys.modules[file.stem]
    if str(file.parent) not in sys.path:  # a script imports its siblings, as when it is run
        sys.path.append(str(file.parent))
    spec = importlib.util.spec_from_file_location(file.stem, file)
    module = importlib.util.module_from_spec(spec)
    sys.modules[file.stem] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module
