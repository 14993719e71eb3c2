"""A study's output folder, written beside and swapped in whole: an earlier study there stays
as it was until the new one is complete, and nothing the study did not write is ever touched.

The folder holds ``study.json`` (what was run, and the figures it drew), ``cases/`` (one file
per finished case, named by the case's key), ``study.csv``, ``columns.csv``, ``study.npz``,
``timings.csv``, ``units.json`` and ``figures/``. A run:

1. checks the folder before any work (:func:`foreign_files`): it may hold only those files, as
   regular files and folders (a link, a folder named ``study.csv``, a file of the user's is
   named and the run refused; nothing is deleted, no link followed);
2. writes the new study in a temporary folder beside it (:class:`StudyFolder`): each case's
   row as it finishes, and with ``--resume`` the earlier cases it reuses, each read back and
   checked (:func:`row_problem`; one that fails is computed again, with a warning);
3. at the end, swaps the complete folder in at once; the earlier study is then removed.

A run that fails or is interrupted leaves the earlier study as it was, and adds the cases it
finished to its ``cases/`` (none there replaced), so that ``--resume`` reuses them; when there
was no earlier study, the folder then holds ``study.json`` and ``cases/`` alone.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import stat
import warnings
from pathlib import Path

from hexapod._support.files import (
    recover_directory,
    staging_directory,
    swap_directory,
    write_atomically,
)
from hexapod.errors import InputFileError

#: The files a study writes in its output folder, and its folders.
OUTPUT_FILES = ("study.json", "study.csv", "columns.csv", "study.npz", "timings.csv",
                "units.json")
OUTPUT_FOLDERS = ("cases", "figures")
#: A case's file: its key (spec.Study.case_key) and ``.json``.
CASE_FILE = re.compile(r"[0-9a-f]{20}\.json")
#: The largest case file read back (a row is a few kilobytes).
MAX_CASE_BYTES = 2**20
#: A case's statuses (hexapod.sweeps.cases.run_case).
STATUSES = ("ok", "infeasible", "failed")
#: A case's row: its keys and the types of their values.
ROW_TYPES = {"case": int, "key": str, "params": dict, "status": str, "message": str,
             "metrics": dict, "units": dict, "cpu_s": float, "wall_s": float, "worker": str}
#: A leftover of a write killed mid-way (files.write_atomically's temporary name).
_LEFTOVER = re.compile(r"\.(?P<name>.+)\.[0-9]+\.[^/]*\.tmp")


def _leftover_of(name: str, ours) -> bool:
    match = _LEFTOVER.fullmatch(name)
    return bool(match) and ours(match["name"])


def _entries(folder: Path) -> list[os.DirEntry]:
    try:
        with os.scandir(folder) as entries:
            return list(entries)
    except OSError as error:
        raise InputFileError(f"{folder}: cannot read the folder ({error.strerror})") from None


def _kind(entry: os.DirEntry) -> str:
    if entry.is_symlink():
        return "a symbolic link"
    if entry.is_dir(follow_symlinks=False):
        return "a folder"
    return "a file" if entry.is_file(follow_symlinks=False) else "not a regular file"


def _figure_names(folder: Path) -> set[str] | None:
    """The figures the earlier study's ``study.json`` says it drew (None: it does not say)."""
    path = folder / "study.json"
    try:
        if not stat.S_ISREG(os.lstat(path).st_mode) or path.stat().st_size > MAX_CASE_BYTES:
            return None
        figures = json.loads(path.read_text(encoding="utf-8")).get("figures")
    except (OSError, ValueError, AttributeError, RecursionError):
        return None
    if isinstance(figures, list) and all(isinstance(f, str) for f in figures):
        return set(figures)
    return None


def foreign_files(folder: Path) -> list[str]:
    """What in ``folder`` a study did not write, each name with its kind when that is what is
    wrong (``cases (a symbolic link)``, ``study.csv (a folder)``, ``figures/mine.png``)."""
    foreign = []

    def judge(entries, ours, prefix: str = "", folders=()):
        for entry in entries:
            kind, name = _kind(entry), prefix + entry.name
            if kind == ("a folder" if entry.name in folders else "a file") and (
                    entry.name in folders or ours(entry.name)
                    or _leftover_of(entry.name, ours)):
                continue
            known = ours(entry.name) or entry.name in folders
            foreign.append(f"{name} ({kind})" if known else name)

    judge(_entries(folder), lambda n: n in OUTPUT_FILES, folders=OUTPUT_FOLDERS)
    if (folder / "cases").is_dir() and not (folder / "cases").is_symlink():
        judge(_entries(folder / "cases"), CASE_FILE.fullmatch, "cases/")
    if (folder / "figures").is_dir() and not (folder / "figures").is_symlink():
        drawn = _figure_names(folder)
        judge(_entries(folder / "figures"),
              (lambda n: n.endswith(".png")) if drawn is None else drawn.__contains__,
              "figures/")
    return sorted(foreign)


def check_folder(folder: Path) -> None:
    """Refuse, before any work, an output folder that is not a folder or holds anything a study
    did not write; a folder left half-swapped by a run that was killed is put right first.

    Raises
    ------
    InputFileError
        Naming the folder and up to three of the files; nothing is touched.
    """
    recover_directory(folder)
    if not (folder.exists() or folder.is_symlink()):
        return
    if folder.is_symlink() or not folder.is_dir():
        raise InputFileError(f"{folder}: exists and is not a directory; choose another "
                             "output folder")
    foreign = foreign_files(folder)
    if foreign:
        shown = ", ".join(foreign[:3]) + (f", and {len(foreign) - 3} more"
                                          if len(foreign) > 3 else "")
        raise InputFileError(f"{folder}: holds files a study did not write ({shown}); nothing "
                             "there is deleted or followed: move them, or choose another "
                             "output folder")


def row_problem(row, case, families=None) -> str | None:
    """What is wrong with ``row`` as the result of ``case`` (None: nothing): its keys, the
    types of their values, its key and parameters, and its metrics' families (one of
    ``families`` when given)."""
    if not isinstance(row, dict):
        return f"holds a JSON {type(row).__name__}, not a case's row (an object)"
    missing = [k for k in ROW_TYPES if k not in row]
    extra = [str(k) for k in row if k not in ROW_TYPES]
    if missing or extra:
        return "; ".join(([f"lacks the key(s) {', '.join(missing)}"] if missing else [])
                         + ([f"has unknown key(s) {', '.join(extra[:5])}"] if extra else []))
    for key, kind in ROW_TYPES.items():
        value = row[key]
        number = kind is float and isinstance(value, int | float)
        if isinstance(value, bool) or not (isinstance(value, kind) or number):
            return f"{key} must be {kind.__name__}, got {type(value).__name__}"
    if row["status"] not in STATUSES:
        return f"status must be one of {', '.join(STATUSES)}, got {row['status']!r}"
    for key, kind in (("metrics", (int, float)), ("units", (str,))):
        bad = [k for k, v in row[key].items() if isinstance(v, bool) or not isinstance(v, kind)]
        if bad:
            return f"{key}.{bad[0]} must be {'a number' if key == 'metrics' else 'a string'}"
    strange = [m for m in row["metrics"] if families is not None
               and m.partition(":")[0] not in families] + [u for u in row["units"]
                                                           if u not in row["metrics"]]
    if strange:
        return f"{strange[0]!r} is not a metric of the study's job"
    if not all(math.isfinite(v) and v >= 0 for v in (row["cpu_s"], row["wall_s"])):
        return "cpu_s and wall_s must be finite seconds, at least 0"
    if row["key"] != case.key:
        return f"its key {row['key']!r} is not the file's name"
    if json.dumps(row["params"], sort_keys=True) != json.dumps(case.params, sort_keys=True):
        return (f"its parameters {json.dumps(row['params'], sort_keys=True)[:200]} are not "
                f"those of case {case.index} of the study")
    return None


def _read_case(path: Path, case, families) -> tuple[dict | None, str]:
    """The row in ``path`` and its text, or (None, what is wrong)."""
    try:
        size = os.lstat(path).st_size
        if size > MAX_CASE_BYTES:
            return None, f"{size} bytes, more than a case's row ({MAX_CASE_BYTES} at most)"
        text = path.read_text(encoding="utf-8")
        row = json.loads(text)
    except (OSError, UnicodeDecodeError) as error:
        return None, f"cannot be read ({error})"
    except (ValueError, RecursionError) as error:
        return None, f"not JSON ({str(error).split(':')[0]})"
    problem = row_problem(row, case, families)
    return (None, problem) if problem else (row, text)


class StudyFolder:
    """The new study, written in a folder beside ``folder`` (see the module's docstring);
    ``description`` is ``study.json``'s content."""

    def __init__(self, folder: Path, description: dict):
        self.folder = Path(folder)
        check_folder(self.folder)
        self.description = description
        self.staging = staging_directory(self.folder)
        try:
            for sub in OUTPUT_FOLDERS:
                (self.staging / sub).mkdir()
            self._write_description()
        except BaseException:
            shutil.rmtree(self.staging, ignore_errors=True)
            raise

    def _write_description(self) -> None:
        write_atomically(self.staging / "study.json",
                         json.dumps(self.description, indent=1) + "\n")

    def reuse(self, cases, families=None) -> dict[str, dict]:
        """The rows of ``cases`` finished in the earlier study (by key), each checked (its
        metrics of ``families``, when given) and kept in the new one; a file that fails the
        check is named in a warning and its case is computed again."""
        kept = {}
        earlier = self.folder / "cases"
        if not earlier.is_dir():
            return kept
        for case in cases:
            path = earlier / f"{case.key}.json"
            if not path.exists():
                continue
            row, text = _read_case(path, case, families)
            if row is None:
                warnings.warn(f"{path}: {text}; case {case.index} is computed again",
                              stacklevel=2)
                continue
            row["case"] = case.index
            self._keep(path, text)
            kept[case.key] = row
        return kept

    def _keep(self, path: Path, text: str) -> None:
        target = self.staging / "cases" / path.name
        try:
            os.link(path, target)  # the same bytes, without copying them
        except OSError:
            write_atomically(target, text)

    def write_case(self, row: dict) -> None:
        """Keep a finished case's row."""
        write_atomically(self.staging / "cases" / f"{row['key']}.json", json.dumps(row))

    def finish(self, files: dict[str, bytes | str], figures: dict[str, bytes]) -> Path:
        """Write the table's ``files`` and the ``figures`` (name -> content), then swap the
        complete study in, if the folder still holds nothing but an earlier study."""
        from hexapod._support.signals import deferred

        for name, content in files.items():
            write_atomically(self.staging / name, content)
        for name, content in figures.items():
            write_atomically(self.staging / "figures" / name, content)
        self.description["figures"] = sorted(figures)
        self._write_description()
        with deferred():  # the swap and the removal of the earlier study, as one step
            check_folder(self.folder)  # what came there during the run is not removed
            swap_directory(self.staging, self.folder)
        return self.folder

    def abandon(self) -> None:
        """After a failure or an interruption: the earlier study left as it was, with the cases
        finished here added to its ``cases/`` (none there replaced); without an earlier study,
        this folder holding its description and cases; nothing when no case finished."""
        from hexapod._support.signals import deferred

        with deferred():
            try:
                finished = [e.name for e in _entries(self.staging / "cases")
                            if CASE_FILE.fullmatch(e.name)]
                if finished and not (self.folder.exists() or self.folder.is_symlink()):
                    swap_directory(self.staging, self.folder)
                elif finished:
                    self._add_cases(finished)
            except (OSError, InputFileError):
                pass  # the cases are lost, nothing else
            finally:
                shutil.rmtree(self.staging, ignore_errors=True)

    def _add_cases(self, names: list[str]) -> None:
        target = self.folder / "cases"
        if not target.exists() and not target.is_symlink():
            target.mkdir()
        if target.is_symlink() or not target.is_dir():
            return
        for name in names:
            try:
                os.link(self.staging / "cases" / name, target / name)  # never replaces
            except FileExistsError:
                continue
            except OSError:
                if not (target / name).exists():
                    os.replace(self.staging / "cases" / name, target / name)
