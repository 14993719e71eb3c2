"""Running a study: in this process, or as tasks of ``dask.distributed`` (a local cluster of
worker processes, or a cluster already running), each case's row kept on disk as it arrives so
that an interrupted study resumes where it stopped.

The output folder holds ``study.json`` (what was run), ``cases/`` (one JSON file per finished
case, named by the case's key), and when the study ends ``study.csv``, ``columns.csv``,
``study.npz``, ``timings.csv``, ``units.json`` and ``figures/``; every file is written atomically.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hexapod._support.files import write_atomically
from hexapod.errors import InputFileError
from hexapod.sweeps.cases import StudyError, check_study, run_case
from hexapod.sweeps.spec import Study, read_study, study_from_document
from hexapod.sweeps.table import SweepTable, timings_csv_text

if TYPE_CHECKING:
    import numpy as np

#: The files a study writes in its output folder (anything else there is not ours).
OUTPUT_FILES = ("study.json", "study.csv", "columns.csv", "study.npz", "timings.csv",
                "units.json")
OUTPUT_FOLDERS = ("cases", "figures")
#: Seconds to wait for a scheduler named by address.
CONNECT_TIMEOUT = 10


@dataclass
class Progress:
    """Where a study stands, as given to a ``progress`` callback."""

    total: int
    done: int = 0  # finished, failed included, reused included
    failed: int = 0
    running: int = 0
    reused: int = 0
    started: float = 0.0

    def eta(self) -> float | None:
        """Seconds left at the pace of the cases computed so far (None before the first)."""
        computed = self.done - self.reused
        if computed <= 0:
            return None
        return (time.perf_counter() - self.started) / computed * (self.total - self.done)


@dataclass
class SweepRun:
    """A finished study: its table, its rows, and how many cases were computed or reused."""

    study: Study
    table: SweepTable
    rows: list[dict]
    computed: int
    reused: int
    wall_s: float
    out: Path | None = None


def load_study(spec) -> Study:
    """A :class:`Study` from a study file's path, a parsed document (dict) or a Study."""
    if isinstance(spec, Study):
        return spec
    if isinstance(spec, dict):
        return study_from_document(spec)
    return read_study(spec)


def sweep(spec: str | Path | dict | Study, client: Any = None, *, workers: int | None = None,
          scheduler: str | None = None, out: str | Path | None = None, resume: bool = False,
          progress: Callable[[Progress], None] | None = None,
          as_frame: bool | None = None) -> np.ndarray | Any:
    """Run a design study and return its table.

    Parameters
    ----------
    spec : path, dict or Study
        The study (``docs/sweeps.md``).
    client : dask.distributed.Client, optional
        Run the cases as tasks of this client's cluster.
    workers : int, optional
        Without a client: run on a local cluster of this many worker processes (``None``: in
        this process, without Dask).
    scheduler : str, optional
        Without a client: the address of a running Dask scheduler to send the cases to.
    out : path, optional
        Keep the cases and write the table and figures in this folder.
    resume : bool
        Reuse the cases already in ``out`` (same parameters, scene, job and code version).
    progress : callable, optional
        Called with a :class:`Progress` as cases finish.
    as_frame : bool, optional
        Return a pandas DataFrame (default: when pandas is installed) rather than a structured
        array; both carry the units (``attrs["units"]``, ``dtype.metadata["units"]``).

    Returns
    -------
    numpy structured array or pandas.DataFrame
        One row per case: its parameters, status and metrics.

    Raises
    ------
    InputFileError
        The study cannot be read or cannot run (an unknown parameter, a scene key that leads
        nowhere, no Dask for a cluster), or ``out`` holds something else.
    """
    run = run_study(load_study(spec), client=client, workers=workers, scheduler=scheduler,
                    out=out, resume=resume, progress=progress)
    if as_frame is None:
        import importlib.util

        as_frame = importlib.util.find_spec("pandas") is not None
    return run.table.frame() if as_frame else run.table.records()


def run_study(study: Study, *, client=None, workers: int | None = None,
              scheduler: str | None = None, out: str | Path | None = None,
              resume: bool = False, progress: Callable[[Progress], None] | None = None,
              announce: Callable[[str], None] | None = None) -> SweepRun:
    """Run ``study`` (see :func:`sweep`); ``announce`` receives one-line notices (the
    cluster's dashboard)."""
    check_study(study)
    cases = study.cases()
    folder = _prepare(Path(out), study, resume, len(cases)) if out is not None else None
    kept = _kept_rows(folder, cases) if folder is not None and resume else {}
    todo = [c for c in cases if c.key not in kept]
    state = Progress(len(cases), done=len(kept), reused=len(kept), started=time.perf_counter())
    rows = list(kept.values())
    rows += [_failed(c) if row is None else row for c, row in
             _execute(study, todo, client, workers, scheduler, folder, state, progress,
                      announce)]
    wall = time.perf_counter() - state.started
    parameters = [p.name for p in study.parameters]
    table = SweepTable.from_rows(parameters, rows)
    if folder is not None:
        _write_outputs(folder, study, table, rows)
    return SweepRun(study, table, sorted(rows, key=lambda r: r["case"]), len(todo), len(kept),
                    wall, folder)


def _failed(case, message: str = "lost: no result came back") -> dict:
    return {"case": case.index, "key": case.key, "params": case.params, "status": "failed",
            "message": message, "metrics": {}, "units": {}, "cpu_s": 0.0, "wall_s": 0.0,
            "worker": ""}


def _execute(study, todo, client, workers, scheduler, folder, state, progress, announce):
    """Yield ``(case, row)`` as cases finish, storing each row in ``folder``."""

    def finished(case, row):
        if folder is not None:
            write_atomically(folder / "cases" / f"{case.key}.json", json.dumps(row))
        state.done += 1
        state.failed += row["status"] != "ok"
        if progress is not None:
            progress(state)

    if client is None and workers is None and scheduler is None:
        for case in todo:
            state.running = 1
            row = run_case(study, case)
            state.running = 0
            finished(case, row)
            yield case, row
        return
    with _client(client, workers, scheduler, announce) as dask_client:
        from distributed import as_completed

        futures = {dask_client.submit(run_case, study, case, pure=False,
                                      key=f"case-{case.index}-{case.key}"): case
                   for case in todo}
        state.running = min(len(futures), _worker_count(dask_client))
        for future in as_completed(futures):
            case = futures.pop(future)
            try:
                row = future.result()
            except Exception as error:  # a worker that died running it, again and again
                row = _failed(case, f"{type(error).__name__}: {error}")
            state.running = min(len(futures), _worker_count(dask_client))
            finished(case, row)
            yield case, row


def _worker_count(client) -> int:
    try:
        return max(1, len(client.scheduler_info()["workers"]))
    except Exception:
        return 1


class _client:
    """A Dask client for the study: the one given (left open), or one made here on a local
    cluster or a scheduler's address (closed at the end)."""

    def __init__(self, client, workers, scheduler, announce):
        self.given, self.workers, self.scheduler, self.announce = (client, workers, scheduler,
                                                                   announce)
        self.made = []

    def __enter__(self):
        if self.given is not None:
            return self.given
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise StudyError("running a study on Dask needs dask.distributed: "
                             "pip install 'hexapod[sweep]' (or run it in this process)") \
                from None
        import logging

        if self.scheduler is not None:
            try:
                client = Client(self.scheduler, timeout=CONNECT_TIMEOUT)
            except (OSError, TimeoutError, ValueError) as error:
                raise StudyError(f"scheduler {self.scheduler}: cannot connect "
                                 f"({type(error).__name__}: {error})") from None
            self.made.append(client)
        else:
            cluster = LocalCluster(n_workers=self.workers, threads_per_worker=1,
                                   processes=True, dashboard_address=":0",
                                   silence_logs=logging.ERROR,
                                   env={"OPENBLAS_NUM_THREADS": "1"})
            client = Client(cluster)
            self.made += [client, cluster]
        if self.announce is not None:
            self.announce(f"Dask dashboard: {client.dashboard_link}")
        return client

    def __exit__(self, *exc):
        for thing in self.made:
            try:
                thing.close()
            except Exception:
                pass
        return False


# ------------------------------------------------------------------ the output folder


def _prepare(folder: Path, study: Study, resume: bool, cases: int) -> Path:
    """Make ``folder`` ready: create it, or clear an earlier study's files (unless resuming);
    refuse a folder that holds anything else."""
    if folder.exists() or folder.is_symlink():
        if not folder.is_dir() or folder.is_symlink():
            raise InputFileError(f"{folder}: exists and is not a directory; choose another "
                                 "output folder")
        foreign = sorted(p.name for p in folder.iterdir()
                         if p.name not in OUTPUT_FILES + OUTPUT_FOLDERS)
        if foreign:
            shown = ", ".join(foreign[:3]) + (", ..." if len(foreign) > 3 else "")
            raise InputFileError(f"{folder}: holds files a study did not write ({shown}); "
                                 "choose another output folder")
        if not resume:
            _clear(folder)
    for sub in ("", *OUTPUT_FOLDERS):
        try:
            (folder / sub).mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise InputFileError(f"{folder / sub}: cannot make the folder ({error})") from None
    write_atomically(folder / "study.json", json.dumps(_description(study, cases), indent=1) + "\n")
    return folder


def _clear(folder: Path) -> None:
    for name in OUTPUT_FILES:
        (folder / name).unlink(missing_ok=True)
    for sub, pattern in (("cases", "*.json"), ("figures", "*.png")):
        for path in (folder / sub).glob(pattern):
            path.unlink()


def _description(study: Study, cases: int) -> dict:
    return {"name": study.name, "description": study.description, "source": study.source,
            **study.identity(), "parameters": [p.name for p in study.parameters],
            "cases": cases, "seed": study.seed, "samples": study.samples}


def _kept_rows(folder: Path, cases) -> dict[str, dict]:
    """The rows of ``cases`` already in ``folder/cases`` (by key; unreadable files ignored)."""
    kept = {}
    for case in cases:
        path = folder / "cases" / f"{case.key}.json"
        try:
            row = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if isinstance(row, dict) and row.get("key") == case.key:
            row["case"] = case.index
            kept[case.key] = row
    return kept


def _write_outputs(folder: Path, study: Study, table: SweepTable, rows: list[dict]) -> None:
    write_atomically(folder / "study.csv", table.csv_text())
    write_atomically(folder / "columns.csv", table.columns_csv_text())
    write_atomically(folder / "study.npz", table.npz_bytes())
    write_atomically(folder / "timings.csv", timings_csv_text(rows))
    write_atomically(folder / "units.json", table.units_json())
    from hexapod.output.figures import png_bytes
    from hexapod.output.sweep_figures import sweep_figures

    status = table.data["status"]
    for name, figure in sweep_figures(table.parameters(), table.metrics(), table.units, status,
                                      study.name):
        write_atomically(folder / "figures" / name, png_bytes(figure))

