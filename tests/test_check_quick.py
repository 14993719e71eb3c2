"""``hexapod check``: a run the CPU budget stops is reported as stopped by the budget (not as a
failure of the method), and each run's wall and CPU time are shown in the progress, the table
and the total. The quick suite itself takes about a minute: it is run by hand, not here."""

from __future__ import annotations

import pytest

import hexapod.benchmarks as m
from hexapod.benchmarks.check import (
    QUICK_BUDGET,
    _from_mechanism,
    outcome_figure,
    recommend,
    run_suite,
    runs_csv,
    suite_table,
    time_total,
)
from hexapod.cli import main


def test_a_run_stopped_by_the_budget_says_so_everywhere():
    case = _from_mechanism(m.stiff_slider(1e3, t_end=0.2))
    said: list[str] = []
    runs = run_suite([case], ["rk4-baumgarte"], budget=1e-9, progress=said.append)
    (run,) = runs
    assert run.status == "stopped" and "by the CPU budget of 1e-09 s" in run.reason
    assert not run.accurate and recommend(runs) == "none finished"
    assert run.cpu_time > 1e-9 and run.wall_time > 0
    assert "stopped by the CPU budget" in said[-1] and " s wall, " in said[-1] \
        and " s CPU" in said[-1]
    table = suite_table(runs)
    assert "CPU (s) | wall (s)" in table
    row = next(line for line in table.splitlines() if "| rk4-baumgarte |" in line)
    assert "| stopped " in row and "by the CPU budget of 1e-09 s |" in row
    assert time_total(runs).endswith("; 1 stopped by the CPU budget")
    assert "wall_time" in runs_csv(runs).splitlines()[0]
    texts = [t.get_text() for t in outcome_figure(runs).axes[0].texts]
    assert texts == ["stopped"]


def test_a_run_within_the_budget_finishes():
    case = _from_mechanism(m.stiff_slider(1e3, t_end=0.2))
    (run,) = run_suite([case], ["dopri5-projection"], budget=QUICK_BUDGET)
    assert run.status == "finished" and run.accurate
    assert time_total([run]).startswith("1 runs: ") and "stopped" not in time_total([run])


def test_quick_says_what_it_does_and_its_budget(capsys):
    with pytest.raises(SystemExit):
        main(["check", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "budget of 5 CPU seconds per run unless --budget is given" in help_text
    assert "reported as stopped by the budget (default 60, or 5 with --quick)" in help_text
    assert QUICK_BUDGET == 5.0
