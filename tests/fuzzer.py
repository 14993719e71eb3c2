"""The fuzzing script (``scripts/fuzz_inputs.py``) as a module, for the tests that share its
mutations and its TOML writer."""

from __future__ import annotations

from script_loader import load_script

fuzz = load_script("fuzz_inputs")
