"""The fuzzing script (``scripts/fuzz_inputs.py``) as a module, for the tests that share its
mutations and its TOML writer."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _load():
    spec = importlib.util.spec_from_file_location("fuzz_inputs",
                                                  ROOT / "scripts" / "fuzz_inputs.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["fuzz_inputs"] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


fuzz = _load()
