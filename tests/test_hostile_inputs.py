"""The hostile command lines of the hardening issue (``tests/fuzz/fuzz_hostile.py`` lists them):
each ends with its expected status (1 for a file or a job, 2 for an argument) and one error
message naming the option, the key or the file, no traceback, within 30 s, and touches no
file (a device node, an input) nor leaves one behind."""

from __future__ import annotations

import pytest
from script_loader import load_script

hostile = load_script("tests/fuzz/fuzz_hostile.py")


@pytest.mark.parametrize("case", hostile.CASES, ids=[case.name for case in hostile.CASES])
def test_a_hostile_command_is_one_clear_error_and_harms_nothing(tmp_path, case):
    verdict, detail = hostile.run_case(case, tmp_path)
    assert verdict == "ok", detail
