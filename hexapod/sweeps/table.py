"""The result of a study: one row per case, one column per parameter and metric.

Columns, in order: ``case``, the varied parameters (the study's order), ``status`` (``ok``,
``infeasible``: computed but the ground cannot give the feet's forces, ``failed``),
``message``, then the metrics by family (:data:`hexapod.sweeps.metrics.FAMILIES`) and element
(first appearance). The table is a function of the cases' results alone, sorted by
case: it does not depend on the number of workers or the order in which cases finished. What a
run cost (CPU and wall seconds, the worker) is kept beside it (``timings.csv``), since it
differs from run to run.

Units: ``columns.csv`` and ``study.npz`` give each column's unit as the study knows it (empty
for text and pure numbers); ``units.json`` (:meth:`SweepTable.units_json`) states them for
every file of the study as every command's sidecar does (``docs/outputs.md``): ``1`` for a pure
number, null for text.
"""

from __future__ import annotations

import csv
import io
import math

import numpy as np

from hexapod._support.signals import deferred
from hexapod.simulation.results import Columns, units_json
from hexapod.sweeps.metrics import FAMILIES
from hexapod.sweeps.spec import parameter_unit

#: Columns that are not results: the case and its outcome.
CASE_COLUMNS = ("case", "status", "message")
#: ``timings.csv``: what each case cost, column -> (unit, meaning).
TIMINGS_COLUMNS: Columns = {"case": (None, "the case's number"),
                            "cpu_s": ("s", "CPU time of the case"),
                            "wall_s": ("s", "wall-clock time of the case"),
                            "worker": (None, "the worker that ran it")}
#: ``columns.csv``: the columns of ``study.csv`` described (as text).
COLUMNS_CSV_COLUMNS: Columns = {"column": (None, "a column of study.csv"),
                                "kind": (None, "case, parameter, status or metric"),
                                "unit": (None, "its unit (empty: text or a pure number)")}
_MEANINGS = {"case": "the case's number",
             "status": "ok, infeasible (the ground cannot give the feet's forces) or failed",
             "message": "why the case failed or is infeasible (empty when ok)"}


class SweepTable:
    """A study's table: ``columns`` in order, ``data`` (column -> 1-D array), ``units`` and
    ``kinds`` (column -> ``case``, ``parameter``, ``status``, ``metric``)."""

    def __init__(self, columns: list[str], data: dict, units: dict, kinds: dict):
        self.columns = columns
        self.data = data
        self.units = units
        self.kinds = kinds

    def __len__(self) -> int:
        return len(self.data["case"]) if self.columns else 0

    @classmethod
    def from_rows(cls, parameters: list[str], rows: list[dict]) -> SweepTable:
        """The table of case rows (as :func:`hexapod.sweeps.cases.run_case` returns them)."""
        rows = sorted(rows, key=lambda r: r["case"])
        metric_columns: dict[str, str] = {}
        for row in rows:
            for column, unit in row.get("units", {}).items():
                metric_columns.setdefault(column, unit)
            for column in row.get("metrics", {}):
                metric_columns.setdefault(column, "")
        order = {f: k for kind in FAMILIES.values() for k, f in enumerate(kind)}
        metrics = sorted(metric_columns, key=lambda c: order.get(c.partition(":")[0], 99))
        data = {"case": np.array([r["case"] for r in rows], dtype=int)}
        for name in parameters:
            data[name] = _column([r["params"].get(name) for r in rows])
        data["status"] = _column([r["status"] for r in rows], text=True)
        data["message"] = _column([r["message"] for r in rows], text=True)
        for column in metrics:
            data[column] = np.array([r["metrics"].get(column, math.nan) for r in rows],
                                    dtype=float)
        columns = ["case", *parameters, "status", "message", *metrics]
        kinds = {c: ("parameter" if c in parameters else "metric" if c in metric_columns
                     else "case") for c in columns}
        kinds["status"] = kinds["message"] = "status"
        units = {c: parameter_unit(c) if c in parameters else metric_columns.get(c, "")
                 for c in columns}
        return cls(columns, data, units, kinds)

    def parameters(self) -> dict[str, np.ndarray]:
        return {c: self.data[c] for c in self.columns if self.kinds[c] == "parameter"}

    def metrics(self) -> dict[str, np.ndarray]:
        return {c: self.data[c] for c in self.columns if self.kinds[c] == "metric"}

    def records(self) -> np.ndarray:
        """The table as a structured array; its dtype's metadata holds the units."""
        dtype = np.dtype([(c, self.data[c].dtype) for c in self.columns],
                         metadata={"units": dict(self.units)})
        out = np.empty(len(self), dtype=dtype)
        for c in self.columns:
            out[c] = self.data[c]
        return out

    def frame(self):
        """The table as a pandas DataFrame (``attrs["units"]``); pandas must be installed."""
        import pandas

        frame = pandas.DataFrame({c: self.data[c] for c in self.columns})
        frame.attrs["units"] = dict(self.units)
        return frame

    # ---------------------------------------------------------------- files

    def csv_text(self) -> str:
        """``study.csv``: a header of column names, one line per case; numbers written to
        round-trip exactly."""
        stream = io.StringIO()
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(self.columns)
        for k in range(len(self)):
            writer.writerow([_cell(self.data[c][k]) for c in self.columns])
        return stream.getvalue()

    def columns_csv_text(self) -> str:
        """``columns.csv``: each column's name, kind and unit."""
        stream = io.StringIO()
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(["column", "kind", "unit"])
        for c in self.columns:
            writer.writerow([c, self.kinds[c], self.units[c]])
        return stream.getvalue()

    def column_units(self) -> Columns:
        """The columns of ``study.csv`` in order, each with its unit (``1`` a pure number, None
        text) and meaning."""
        out: Columns = {}
        for c in self.columns:
            kind, unit = self.kinds[c], self.units[c]
            if kind == "metric":
                out[c] = (unit or "1", f"metric {c.partition(':')[0]}")
            elif kind == "parameter":
                text = self.data[c].dtype.kind == "U"
                # a builder argument the study has no unit for is a factor or a fraction
                # (docs/sweeps.md); a scene key's unit is the scene's, not known here ("")
                out[c] = (None if text else unit or ("" if "." in c else "1"),
                          "varied parameter")
            else:
                out[c] = (None, _MEANINGS.get(c, c))  # a label or text
        return out

    def units_json(self) -> str:
        """``units.json``: every column of ``study.csv``, ``timings.csv`` and ``columns.csv``
        with its unit and meaning."""
        return units_json({"study.csv": self.column_units(), "timings.csv": TIMINGS_COLUMNS,
                           "columns.csv": COLUMNS_CSV_COLUMNS})

    def npz_bytes(self) -> bytes:
        """``study.npz``: ``table`` (the structured array), ``units`` and ``kinds`` (one per
        column, in order); loads without pickles."""
        stream = io.BytesIO()
        records = self.records()
        with deferred():  # a signal inside ZipFile's constructor makes its finaliser print
            np.savez(stream, table=np.asarray(records, dtype=np.dtype(records.dtype.descr)),
                     columns=np.array(self.columns),
                     units=np.array([self.units[c] for c in self.columns]),
                     kinds=np.array([self.kinds[c] for c in self.columns]))
        return stream.getvalue()


def _column(values: list, text: bool = False) -> np.ndarray:
    if not text and values and all(isinstance(v, int | float) and not isinstance(v, bool)
                                   for v in values):
        return np.array(values, dtype=float)
    return np.array(["" if v is None else _text(v) for v in values], dtype=str)


def _text(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def _cell(value) -> str:
    if isinstance(value, np.floating | float):
        return repr(float(value))
    if isinstance(value, np.integer | int):
        return str(int(value))
    return str(value)


def timings_csv_text(rows: list[dict]) -> str:
    """``timings.csv``: each case's CPU and wall seconds and its worker (columns as
    :data:`TIMINGS_COLUMNS`), by case."""
    lines = [",".join(TIMINGS_COLUMNS)] + [
        f"{r['case']},{r.get('cpu_s', 0.0)!r},{r.get('wall_s', 0.0)!r},{r.get('worker', '')}"
        for r in sorted(rows, key=lambda r: r["case"])]
    return "\n".join(lines) + "\n"
