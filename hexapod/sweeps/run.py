"""Running a study: in this process, or as tasks of ``dask.distributed`` (a local cluster of
worker processes, or a cluster already running), each case's row kept on disk as it arrives so
that an interrupted study resumes where it stopped.

The output folder (:mod:`hexapod.sweeps.folder`) holds ``study.json`` (what was run),
``cases/`` (one JSON file per finished case, named by the case's key), ``study.csv``,
``columns.csv``, ``study.npz``, ``timings.csv``, ``units.json`` and ``figures/``; the study is
written beside it and swapped in whole at the end, so that an earlier study there stays whole
until the new one is complete.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hexapod._support.limits import check_cases
from hexapod.sweeps.cases import check_study, run_case
from hexapod.sweeps.cluster import StudyClient, worker_count
from hexapod.sweeps.folder import StudyFolder
from hexapod.sweeps.spec import Study, read_study, study_from_document
from hexapod.sweeps.table import SweepTable, timings_csv_text

if TYPE_CHECKING:
    import numpy as np


@dataclass
class Progress:
    """Where a study stands, as given to a ``progress`` callback."""

    total: int
    done: int = 0  # finished, failed included, reused included
    failed: int = 0
    infeasible: int = 0  # computed, but the ground cannot hold the robot
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
          as_frame: bool | None = None, max_cases: int | None = None,
          scheduler_timeout: float | None = None) -> np.ndarray | Any:
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
        Without a client: the address of a running Dask scheduler to send the cases to,
        ``tcp://HOST:PORT``.
    out : path, optional
        Keep the cases and write the table and figures in this folder. The study is written
        beside it and swapped in when complete: an earlier study there stays whole until then,
        and a folder holding anything a study did not write is refused.
    resume : bool
        Reuse the cases already in ``out`` (same parameters, scene, job and code version).
    progress : callable, optional
        Called with a :class:`Progress` as cases finish.
    as_frame : bool, optional
        Return a pandas DataFrame (default: when pandas is installed) rather than a structured
        array; both carry the units (``attrs["units"]``, ``dtype.metadata["units"]``).
    max_cases : int, optional
        The most cases the study may have (default: ``HEXAPOD_MAX_CASES``, else 100,000).
    scheduler_timeout : float, optional
        Seconds ``scheduler`` has to answer and to have a worker (default:
        ``HEXAPOD_SCHEDULER_TIMEOUT``, else 10).

    Returns
    -------
    numpy structured array or pandas.DataFrame
        One row per case: its parameters, status and metrics.

    Raises
    ------
    InputFileError
        The study cannot be read or cannot run (an unknown parameter, a scene key that leads
        nowhere, no Dask for a cluster, a scheduler that does not answer), or ``out`` holds
        something else.
    HexapodError
        The study has more cases than ``max_cases``.
    """
    study = spec if isinstance(spec, Study) else (
        study_from_document(spec, max_cases=max_cases) if isinstance(spec, dict)
        else read_study(spec, max_cases))
    run = run_study(study, client=client, workers=workers, scheduler=scheduler, out=out,
                    resume=resume, progress=progress, max_cases=max_cases,
                    scheduler_timeout=scheduler_timeout)
    if as_frame is None:
        import importlib.util

        as_frame = importlib.util.find_spec("pandas") is not None
    return run.table.frame() if as_frame else run.table.records()


def run_study(study: Study, *, client=None, workers: int | None = None,
              scheduler: str | None = None, out: str | Path | None = None,
              resume: bool = False, progress: Callable[[Progress], None] | None = None,
              announce: Callable[[str], None] | None = None, max_cases: int | None = None,
              scheduler_timeout: float | None = None) -> SweepRun:
    """Run ``study`` (see :func:`sweep`); ``announce`` receives one-line notices (the
    cluster's dashboard)."""
    check_cases(study.count(), f"the study {study.source or study.name}", max_cases)
    check_study(study)
    cases = study.cases()
    cluster = StudyClient(client, workers, scheduler, announce, scheduler_timeout)
    folder = StudyFolder(Path(out), _description(study, len(cases))) if out is not None \
        else None
    try:
        kept = folder.reuse(cases, _families(study)) if folder is not None and resume else {}
        todo = [c for c in cases if c.key not in kept]
        state = Progress(len(cases), done=len(kept), reused=len(kept),
                         started=time.perf_counter())
        rows = list(kept.values())
        rows += [_failed(c) if row is None else row for c, row in
                 _execute(study, todo, cluster, folder, state, progress)]
        wall = time.perf_counter() - state.started
        table = SweepTable.from_rows([p.name for p in study.parameters], rows)
        if folder is not None:
            folder.finish(*_outputs(study, table, rows))
    except BaseException:
        if folder is not None:
            folder.abandon()
        raise
    return SweepRun(study, table, sorted(rows, key=lambda r: r["case"]), len(todo), len(kept),
                    wall, folder.folder if folder is not None else None)


def _failed(case, message: str = "lost: no result came back") -> dict:
    return {"case": case.index, "key": case.key, "params": case.params, "status": "failed",
            "message": message, "metrics": {}, "units": {}, "cpu_s": 0.0, "wall_s": 0.0,
            "worker": ""}


def _execute(study, todo, cluster: StudyClient, folder, state, progress):
    """Yield ``(case, row)`` as cases finish, storing each row in ``folder``."""

    def finished(case, row):
        if folder is not None:
            folder.write_case(row)
        state.done += 1
        state.failed += row["status"] not in ("ok", "infeasible")
        state.infeasible += row["status"] == "infeasible"
        if progress is not None:
            progress(state)

    if cluster.given is None and cluster.workers is None and cluster.scheduler is None:
        for case in todo:
            state.running = 1
            row = run_case(study, case)
            state.running = 0
            finished(case, row)
            yield case, row
        return
    if not todo:
        return
    with cluster as dask_client:
        from distributed import as_completed

        futures = {dask_client.submit(run_case, study, case, pure=False,
                                      key=f"case-{case.index}-{case.key}"): case
                   for case in todo}
        state.running = min(len(futures), worker_count(dask_client))
        for future in as_completed(futures):
            case = futures.pop(future)
            try:
                row = future.result()
            except Exception as error:  # a worker that died running it, again and again
                row = _failed(case, f"{type(error).__name__}: {error}")
            state.running = min(len(futures), worker_count(dask_client))
            finished(case, row)
            yield case, row


def _families(study: Study) -> set[str]:
    """The metric families the study's job keeps."""
    from hexapod.sweeps.metrics import FAMILIES

    return set(study.job.get("metrics") or FAMILIES[study.job.get("kind", "inverse")])


def _description(study: Study, cases: int) -> dict:
    return {"name": study.name, "description": study.description, "source": study.source,
            **study.identity(), "parameters": [p.name for p in study.parameters],
            "cases": cases, "seed": study.seed, "samples": study.samples}


def _outputs(study: Study, table: SweepTable, rows: list[dict]) -> tuple[dict, dict]:
    """The table's files and the figures (name -> content)."""
    from hexapod.output.figures import png_bytes
    from hexapod.output.sweep_figures import sweep_figures

    files = {"study.csv": table.csv_text(), "columns.csv": table.columns_csv_text(),
             "study.npz": table.npz_bytes(), "timings.csv": timings_csv_text(rows),
             "units.json": table.units_json()}
    status = table.data["status"]
    figures = {name: png_bytes(figure) for name, figure in
               sweep_figures(table.parameters(), table.metrics(), table.units, status,
                             study.name)}
    return files, figures
