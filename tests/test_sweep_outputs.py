"""A study's output folder is never harmed: links in it are not followed, files it did not write
are kept (the run refused before any work, naming them), the earlier study stays whole until the
new one is complete (a scheduler that cannot be reached or never answers, a signal, a failure),
tampered case files are computed again, and what cannot run is one line naming the file, key,
option or address: never a traceback, never a hang."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import textwrap
import threading
import time
from pathlib import Path

import commands
import pytest
from test_sweeps import study_file

from hexapod.errors import HexapodError, InputFileError
from hexapod.sweeps import read_study, run_study
from hexapod.sweeps.cases import StudyError
from hexapod.sweeps.spec import Parameter, Study

#: A cheap study: three cases of the spun pendulum, one metric family (one figure).
SMALL = """
    [study]
    name = "small"
    scene = "pendulum.toml"
    [vary."body.bob.mass"]
    values = [1.0, 2.0, 4.0]
    [job]
    samples = 5
    metrics = ["peak_effort"]
"""
#: Seconds a scheduler has to answer in these tests.
WAIT = 0.5


def contents(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` (links not followed) by relative path."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and not p.is_symlink()}


@pytest.fixture(scope="module")
def small_study(tmp_path_factory) -> Path:
    """SMALL's complete output folder, computed once for the module (0.2 s a run)."""
    folder = tmp_path_factory.mktemp("small")
    run_study(read_study(study_file(folder, SMALL)), out=folder / "out")
    return folder / "out"


@pytest.fixture
def earlier(tmp_path, small_study):
    """A complete study in ``tmp_path/out``: (its study file, the folder, its files). The folder
    is a copy of the module's run of the same study file, which is what a run here writes (the
    cases and tables are the same numbers; study.json names the other copy of the file)."""
    path = study_file(tmp_path, SMALL)
    out = tmp_path / "out"
    shutil.copytree(small_study, out)
    return path, out, contents(out)


def other_study(tmp_path, masses=(1.5, 2.5, 3.5, 4.5, 5.5)):
    return study_file(tmp_path, SMALL.replace("[1.0, 2.0, 4.0]", str(list(masses))),
                      "other.toml")


def leftovers(tmp_path) -> list[str]:
    return [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]


# ------------------------------------------------------------------ what the study did not write


def test_links_in_the_folder_are_refused_and_never_followed(tmp_path, earlier):
    path, out, _ = earlier
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "data.json").write_text("{}")
    (mine / "plot.png").write_bytes(b"png")
    for sub in ("cases", "figures"):
        os.rename(out / sub, tmp_path / f"{sub}-moved")
        os.symlink(mine, out / sub)
    with pytest.raises(InputFileError, match=r"cases \(a symbolic link\), figures \(a symbolic"):
        run_study(read_study(path), out=out)
    assert contents(mine) == {"data.json": b"{}", "plot.png": b"png"}
    assert (out / "study.csv").is_file() and leftovers(tmp_path) == []


@pytest.mark.parametrize("name", ["figures/mine.png", "cases/notes.txt", "cases/mine.json",
                                  "figures/drawing.svg"])
def test_the_users_files_in_cases_and_figures_are_kept(tmp_path, earlier, name):
    path, out, before = earlier
    (out / name).write_text("mine")
    for resume in (False, True):
        with pytest.raises(InputFileError, match=f"did not write \\({name}\\)"):
            run_study(read_study(path), out=out, resume=resume)
    assert contents(out) == before | {name: b"mine"}


@pytest.mark.parametrize("name", ["study.csv", "study.json", "cases/0123456789abcdef0123.json"])
def test_an_output_file_that_is_a_folder_is_one_line_naming_it(tmp_path, earlier, name):
    path, out, _ = earlier
    (out / name).unlink(missing_ok=True)
    (out / name).mkdir()
    for resume in ([], ["--resume"]):
        done = commands.in_process("sweep", str(path), "--in-process", "--out", str(out),
                                   *resume, cwd=tmp_path)
        assert done.returncode == 1, done.stderr
        assert done.stderr.count("\n") == 1 and f"{name} (a folder)" in done.stderr
    assert (out / name).is_dir()


# ------------------------------------------------------------------ the earlier study stays whole


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


class Server:
    """A TCP server on 127.0.0.1 (an ephemeral port) that accepts every connection and then
    sends ``reply`` (nothing: it stays silent), in a thread."""

    def __init__(self, reply: bytes = b""):
        self.socket = socket.create_server(("127.0.0.1", 0))
        self.address = f"tcp://127.0.0.1:{self.socket.getsockname()[1]}"
        self.reply, self.accepted = reply, []
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while True:
            try:
                connection, _ = self.socket.accept()
            except OSError:  # shut down
                return
            self.accepted.append(connection)
            if self.reply:
                connection.sendall(self.reply)

    def __enter__(self) -> Server:
        return self

    def __exit__(self, *exc) -> None:
        try:
            self.socket.shutdown(socket.SHUT_RDWR)  # wakes the accept (Linux)
        except OSError:
            pass
        self.socket.close()
        for connection in self.accepted:
            connection.close()
        self.thread.join(timeout=5)


pytest.importorskip("distributed")


@pytest.mark.parametrize("reply, words", [
    (b"", "accepted the connection but gave no answer as a Dask scheduler within 0.5 s"),
    (b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n", "not as a Dask scheduler"),
])
def test_a_scheduler_that_never_answers_is_an_error_within_the_timeout(tmp_path, earlier,
                                                                      reply, words):
    path, out, before = earlier
    with Server(reply) as server:
        started = time.monotonic()
        with pytest.raises(StudyError) as error:
            run_study(read_study(other_study(tmp_path)), scheduler=server.address, out=out,
                      scheduler_timeout=WAIT)
        took = time.monotonic() - started
        assert server.accepted
    assert f"scheduler {server.address}: " in str(error.value) and words in str(error.value)
    assert "memory" not in str(error.value)
    assert took < WAIT + 5
    assert contents(out) == before and leftovers(tmp_path) == []


def test_the_command_says_which_scheduler_did_not_answer(tmp_path, earlier):
    path, out, before = earlier
    with Server() as server:
        done = commands.hexapod("sweep", str(other_study(tmp_path)), "--scheduler",
                                server.address, "--out", str(out), cwd=tmp_path,
                                HEXAPOD_SCHEDULER_TIMEOUT=str(WAIT))
    assert done.returncode == 1
    assert done.stderr == (f"hexapod: error: scheduler {server.address}: accepted the "
                           "connection but gave no answer as a Dask scheduler within 0.5 s; "
                           "check the address, or wait longer with --scheduler-timeout "
                           "SECONDS (or HEXAPOD_SCHEDULER_TIMEOUT)\n")
    assert contents(out) == before


@pytest.mark.parametrize("address, words", [
    ("refused", "cannot connect (Connection refused)"),
    ("tcp://host.invalid:8786", "scheduler tcp://host.invalid:8786: cannot connect"),
    ("ucx://127.0.0.1:8786", "needs UCX"),
    ("tls://127.0.0.1:8786", "needs certificates"),
    ("tcp://127.0.0.1", "write tcp://HOST:PORT"),
])
def test_a_scheduler_that_cannot_be_reached_leaves_the_earlier_study(tmp_path, earlier,
                                                                     address, words):
    path, out, before = earlier
    if address == "refused":
        address = f"tcp://127.0.0.1:{free_port()}"
    with pytest.raises(StudyError, match=words.replace("(", r"\(").replace(")", r"\)")):
        run_study(read_study(other_study(tmp_path)), scheduler=address, out=out,
                  scheduler_timeout=WAIT)
    assert contents(out) == before and leftovers(tmp_path) == []


@pytest.mark.parametrize("address, words", [
    ("ucx://127.0.0.1:8786", "the ucx:// protocol needs UCX"),
    ("tls://10.0.0.5:8786", "the tls:// protocol needs certificates"),
    ("tcp://10.0.0.5:123456", "port 123456 is not from 1 to 65535"),
    ("10.0.0.5", "not a scheduler's address"),
])
def test_an_unsupported_scheduler_address_is_a_usage_error(tmp_path, address, words):
    done = commands.hexapod("sweep", str(study_file(tmp_path, SMALL)), "--scheduler", address,
                            cwd=tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert f"argument --scheduler: '{address}': {words}" in done.stderr


def interrupt_after(count: int):
    def progress(state) -> None:
        if state.done - state.reused >= count:
            raise KeyboardInterrupt
    return progress


def test_an_interrupted_study_keeps_the_earlier_one_and_resumes(tmp_path, earlier):
    """Interrupted after two cases: the earlier study is as it was, with the two cases added
    to its cases/, which --resume reuses to a table equal to one run straight through."""
    path, out, before = earlier
    other = other_study(tmp_path)
    with pytest.raises(KeyboardInterrupt):
        run_study(read_study(other), out=out, progress=interrupt_after(2))
    now = contents(out)
    assert {k: v for k, v in now.items() if k in before} == before
    added = [k for k in now if k not in before]
    assert len(added) == 2 and all(k.startswith("cases/") for k in added)
    assert leftovers(tmp_path) == []
    resumed = run_study(read_study(other), out=out, resume=True)
    assert (resumed.computed, resumed.reused) == (3, 2)
    straight = run_study(read_study(other), out=tmp_path / "straight")
    assert resumed.table.csv_text() == straight.table.csv_text()
    assert (out / "study.csv").read_bytes() == (straight.out / "study.csv").read_bytes()
    assert sorted(contents(out)) == sorted(contents(straight.out))  # no case of the earlier


def test_a_first_study_interrupted_keeps_its_cases_for_resume(tmp_path):
    path = study_file(tmp_path, SMALL)
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        run_study(read_study(path), out=out, progress=interrupt_after(1))
    assert sorted(contents(out)) == ["cases/" + next((out / "cases").iterdir()).name,
                                     "study.json"]
    resumed = run_study(read_study(path), out=out, resume=True)
    assert (resumed.computed, resumed.reused) == (2, 1)
    assert (out / "study.csv").is_file()


def test_a_study_that_fails_before_any_case_writes_nothing(tmp_path):
    path = study_file(tmp_path, SMALL)
    with pytest.raises(StudyError, match="Connection refused"):
        run_study(read_study(path), out=tmp_path / "out",
                  scheduler=f"tcp://127.0.0.1:{free_port()}")
    assert not (tmp_path / "out").exists() and leftovers(tmp_path) == []


@pytest.mark.parametrize("moment, number", [("imports", signal.SIGTERM),
                                            ("cases", signal.SIGINT),
                                            ("cases", signal.SIGKILL)])
def test_a_signal_leaves_the_earlier_study_whole(tmp_path, earlier, moment, number):
    """A signal during the command's imports or after its first case (each awaited as the
    run announces it): the conventional status, one line, the earlier study whole; what a
    killed run left beside it is gone after the next run."""
    path, out, before = earlier
    many = other_study(tmp_path, [1.0 + k / 100 for k in range(200)])
    with commands.Running("-m", "hexapod", "sweep", str(many), "--in-process", "--out",
                          str(out), cwd=tmp_path) as child:
        if moment == "imports":
            child.wait_for_handler(number)
        else:
            child.wait_for("cases: 1/200 done")
        child.send_signal(number)
        status, _, err = child.finish()
    now = contents(out)
    assert {k: v for k, v in now.items() if k in before} == before
    assert all(k.startswith("cases/") for k in now if k not in before)
    if number == signal.SIGKILL:
        assert status == -number and leftovers(tmp_path)  # its folder, being written
        run_study(read_study(path), out=out)
    else:
        assert status == 128 + number, err
        assert err.rstrip().endswith(f"hexapod: interrupted ({signal.Signals(number).name})")
        assert "Traceback" not in err
    assert leftovers(tmp_path) == []


# ------------------------------------------------------------------ tampered case files


def _tamper(row: dict, how: str, other: dict):
    if how == "not JSON":
        return "{not json"
    if how == "a list":
        return json.dumps([row])
    if how == "missing key":
        return json.dumps({k: v for k, v in row.items() if k != "metrics"})
    if how == "wrong type":
        return json.dumps(row | {"metrics": {"peak_effort:pivot": "big"}})
    if how == "extra key":
        return json.dumps(row | {"colour": "red"})
    if how == "another metric":
        return json.dumps(row | {"metrics": {"../../x:y": 1.0}, "units": {}})
    return json.dumps(row | {"params": other["params"]})  # another case's parameters


TAMPERED = ["not JSON", "a list", "missing key", "wrong type", "extra key", "other parameters",
            "another metric"]


@pytest.mark.parametrize("how", TAMPERED)
def test_a_tampered_case_file_is_computed_again_on_resume(tmp_path, earlier, how):
    path, out, before = earlier
    files = sorted((out / "cases").iterdir())
    rows = [json.loads(f.read_text()) for f in files]
    files[0].write_text(_tamper(rows[0], how, rows[1]))
    with pytest.warns(UserWarning, match=f"{files[0]}: .*; case {rows[0]['case']} is computed "
                      "again"):
        run = run_study(read_study(path), out=out, resume=True)
    assert (run.computed, run.reused) == (1, 2)
    assert (out / "study.csv").read_bytes() == before["study.csv"]
    fresh = run_study(read_study(path), out=out)  # and without --resume: replaced
    assert fresh.computed == 3


def test_a_case_of_every_status_is_kept_on_resume_and_no_other(earlier):
    """An infeasible case (computed, the ground unable to hold the robot) is a result like an
    ok one: kept by --resume, not computed again; a status no case has is tampering."""
    from hexapod.sweeps.folder import row_problem

    path, out, _ = earlier
    study = read_study(path)
    row = json.loads(sorted((out / "cases").iterdir())[0].read_text())
    (case,) = [c for c in study.cases() if c.key == row["key"]]
    for status in ("ok", "infeasible", "failed"):
        assert row_problem(row | {"status": status}, case) is None
    assert "status must be one of ok, infeasible, failed" in row_problem(
        row | {"status": "slipped"}, case)


def test_the_command_names_a_tampered_case_file_and_finishes(tmp_path, earlier, capsys):
    from hexapod.cli import main

    path, out, before = earlier
    case = sorted((out / "cases").iterdir())[1]
    index = json.loads(case.read_text())["case"]
    case.write_text("[]")
    assert main(["sweep", str(path), "--in-process", "--out", str(out), "--resume"]) == 0
    captured = capsys.readouterr()
    assert "(1 computed, 2 reused, 0 failed)" in captured.out
    assert (f"hexapod: warning: {case}: holds a JSON list, not a case's row (an object); "
            f"case {index} is computed again") in captured.err
    assert (out / "study.csv").read_bytes() == before["study.csv"]


def test_a_case_file_that_is_a_pipe_is_refused_not_read(tmp_path, earlier):
    path, out, _ = earlier
    case = sorted((out / "cases").iterdir())[0]
    case.unlink()
    os.mkfifo(case)
    with pytest.raises(InputFileError, match=rf"cases/{case.name} \(not a regular file\)"):
        run_study(read_study(path), out=out, resume=True)
    assert case.exists()


# ------------------------------------------------------------------ the number of cases


def test_a_study_of_a_billion_cases_is_refused_before_any_is_listed(tmp_path, monkeypatch):
    path = study_file(tmp_path, SMALL + textwrap.dedent("""
        [vary.duty]
        range = [0.5, 0.7]
        steps = 1000000000
    """))
    started = time.monotonic()
    with pytest.raises(HexapodError, match=r"has 3e9 cases \(limit 100,000\).*--max-cases 3e9 "
                       r"\(or HEXAPOD_MAX_CASES\)"):
        read_study(path)
    assert time.monotonic() - started < 1
    assert len(read_study(study_file(tmp_path, SMALL), max_cases=3).cases()) == 3
    with pytest.raises(HexapodError, match="has 3 cases"):
        read_study(study_file(tmp_path, SMALL), max_cases=2)
    monkeypatch.setenv("HEXAPOD_MAX_CASES", "2")
    with pytest.raises(HexapodError, match=r"has 3 cases \(limit 2\)"):
        read_study(study_file(tmp_path, SMALL))
    drawn = Study("drawn", "pendulum", parameters=(Parameter("duty", (), 0.5, 0.7),),
                  samples=10**9, job={"kind": "inverse"})
    with pytest.raises(HexapodError, match="has 1e9 cases"):
        run_study(drawn, max_cases=10**5)
    past_floats = "".join(f"[vary.p{k}]\nrange = [0, 1]\nsteps = {2**62}\n" for k in range(20))
    with pytest.raises(HexapodError, match="has more than 1e300 cases"):
        read_study(study_file(tmp_path, "[study]\nscene = 'pendulum.toml'\n" + past_floats))


def test_the_command_bounds_the_cases(tmp_path):
    path = study_file(tmp_path, SMALL.replace('"small"\n', '"small"\nsamples = 1000000000\n')
                      + '[vary.duty]\nrange = [0.5, 0.7]\n')
    done = commands.in_process("sweep", str(path), "--in-process", cwd=tmp_path)
    assert done.returncode == 1 and done.stderr.count("\n") == 1
    assert f"the study {path} has 3e9 cases (limit 100,000)" in done.stderr
    done = commands.in_process("sweep", str(study_file(tmp_path, SMALL)), "--in-process",
                               "--max-cases", "2", cwd=tmp_path)
    assert done.returncode == 1 and "has 3 cases (limit 2)" in done.stderr
