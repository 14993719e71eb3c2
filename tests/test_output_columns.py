"""Outputs that describe themselves (docs/outputs.md): every CSV a command writes names its
columns by one scheme, and a units sidecar names exactly its columns, each with a known unit."""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import re
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod.cli import main

ROOT = Path(__file__).resolve().parents[1]
CHAIN = ROOT / "tests" / "data" / "pinocchio-fixtures" / "chain-3"
#: a time series: ``t``, then ``quantity:element`` (element: a scene name, '/'-joined parts)
SERIES = re.compile(r"^(t|[A-Za-z][A-Za-z0-9_]*:[A-Za-z0-9_./-]+)$")
#: a record (one row per run or case): a field, or ``family:element``
RECORD = re.compile(r"^[A-Za-z][A-Za-z0-9_]*(:[A-Za-z0-9_./-]+)?$")
UNITS = {"s", "m", "rad", "kg", "N", "N m", "J", "m/s", "rad/s", "m/s^2", "rad/s^2", "N/m",
         "1/s", "A", "W", "kg m^2", "1", None}


def read_table(path: Path) -> tuple[list[str], list[list[str]]]:
    text = path.read_text(encoding="ascii")  # everything ASCII
    header, *rows = list(csv.reader(io.StringIO(text)))
    return header, rows


def check_described(folder: Path, units_file: Path, scheme: re.Pattern) -> dict:
    """Every CSV of ``folder`` is in the sidecar with exactly its columns in order, named by
    ``scheme``, each unit known; a column with a unit holds numbers. Returns the sidecar."""
    units = json.loads(units_file.read_text(encoding="ascii"))
    assert sorted(units) == sorted(p.name for p in folder.glob("*.csv"))
    for name, columns in units.items():
        header, rows = read_table(folder / name)
        assert header == list(columns), name
        for column, described in columns.items():
            assert scheme.match(column), f"{name}: {column!r} breaks the naming scheme"
            assert set(described) == {"unit", "quantity"} and described["quantity"]
            assert described["unit"] in UNITS, f"{name}: {column}: {described['unit']!r}"
            if described["unit"] is not None:
                k = header.index(column)
                np.array([row[k] for row in rows], dtype=float)  # numbers, nan allowed
    return units


def elements(model) -> set[str]:
    """What an element of a column may be: a joint, a foot, a row, a body's component."""
    return ({j.name for j in model.joints} | {r.name for r in model.rows}
            | {c.name.removesuffix("/ground") for c in model.contacts}
            | set(model.coordinate_names) | set(model.velocity_names))


@pytest.fixture
def no_figures(monkeypatch):
    """The report without drawing (its figures are tested elsewhere): the CSVs stay real."""
    import hexapod.output.report as report

    monkeypatch.setattr(report, "render_figures",
                        lambda builders, workers=1: dict.fromkeys(builders, b""))


@pytest.mark.parametrize("scene, tables", [
    ("front-leg", ["inverse.csv"]),
    ("hexapod", ["ground.csv", "inverse.csv", "margins.csv", "trunk.csv", "motors.csv"]),
])
def test_a_report_describes_every_csv_it_writes(tmp_path, capsys, no_figures, scene, tables):
    out = tmp_path / "report"
    motors = ["--actuators", str(ROOT / "data" / "actuators" / "hexapod.toml")] \
        if "motors.csv" in tables else []
    assert main(["report", scene, "--samples", "2", "--out", str(out), *motors]) == 0
    units = check_described(out, out / "units.json", SERIES)
    assert sorted(units) == sorted(tables)
    model = hx.assemble(hx.load_scene(scene))
    known = elements(model)
    for name in ("inverse.csv", "ground.csv"):
        for column in list(units.get(name, {}))[1:]:
            assert column.partition(":")[2] in known, column
    if scene == "hexapod":
        trunk = units["trunk.csv"]
        assert trunk["q:trunk.x"]["unit"] == "m" and trunk["angle:trunk.yaw"]["unit"] == "rad"
        assert trunk["v:trunk.wz"]["unit"] == "rad/s" and "world" in trunk["v:trunk.wz"]["quantity"]
        assert units["ground.csv"]["status:L1"]["unit"] is None
        assert units["ground.csv"]["ratio:R3"]["unit"] == "1"
        assert units["inverse.csv"]["GRz:L1"]["unit"] == "N"
        assert units["margins.csv"]["margin:static"]["unit"] == "m"
        assert units["motors.csv"]["P_el:L1/ctr"]["unit"] == "W"
        assert units["motors.csv"]["I:L1/ctr"]["unit"] == "A"


def test_simulate_describes_its_csv_and_its_npz(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["simulate", "front-leg", "--t-end", "0.002", "--forces", "--out", str(out)]) == 0
    units = check_described(out, out / "units.json", SERIES)["results.csv"]
    model = hx.assemble(hx.load_scene("front-leg"))
    known = elements(model)
    assert all(c.partition(":")[2] in known for c in list(units)[1:])
    body = model.bodies[0].name
    assert units[f"v:{body}.wx_body"]["unit"] == "rad/s"
    assert units[f"vdot:{body}.vz"]["unit"] == "m/s^2"
    assert units[f"q:{body}.e0"]["unit"] == "1"
    kinds = {r.name: r.kind for r in model.rows}
    for row, kind in kinds.items():
        assert units[f"lambda:{row}"]["unit"] == {"length": "N", "angle": "N m"}[kind]
    assert units[f"tau:{model.joints[0].name}"]["unit"] == "N m"
    with np.load(out / "results.npz") as saved:
        for names, key, prefix in (("coordinates", "coordinate_units", "q"),
                                   ("velocities", "velocity_units", "v"),
                                   ("velocities", "acceleration_units", "vdot"),
                                   ("rows", "row_units", "lambda")):
            assert [units[f"{prefix}:{n}"]["unit"] for n in saved[names]] == list(saved[key])
        assert list(saved["effort_units"]) == ["N m"] * len(model.joints)


def test_a_planar_scene_names_its_angle_and_prismatic_efforts():
    """The units follow the element: a planar body's angle in rad, its rate in rad/s, a
    prismatic joint's effort in N, a revolute's in N m."""
    from hexapod.simulation.results import state_columns, wrench_columns

    scene = hx.Scene("slider", dimension=2)
    scene.add(hx.scene.PlanarBody("cart", mass=1.0, inertia=0.1))
    scene.add(hx.scene.PlanarBody("arm", mass=1.0, inertia=0.1, position=[0.5, 0.0]))
    scene.add(hx.scene.Prismatic("rail", "ground", "cart", origin=[0.0, 0.0], axis=[1.0, 0.0]))
    scene.add(hx.scene.Revolute("hinge", "cart", "arm", origin=[0.0, 0.0]))
    model = hx.assemble(scene)
    states, wrenches = state_columns(model), wrench_columns(model, "world")
    assert states["q:cart.angle"][0] == "rad" and states["v:arm.w"][0] == "rad/s"
    assert states["vdot:arm.w"][0] == "rad/s^2"
    assert wrenches["tau:rail"][0] == "N" and wrenches["tau:hinge"][0] == "N m"
    assert "world axes" in wrenches["Fx:hinge"][1]


def test_inverse_writes_its_units_beside_the_csv(tmp_path, capsys):
    out = tmp_path / "X.csv"
    assert main(["inverse", str(CHAIN / "model.urdf"), "--motion", str(CHAIN / "motion.csv"),
                 "--out", str(out), "--frame", "world"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["X.csv", "X.units.json"]
    units = check_described(tmp_path, tmp_path / "X.units.json", SERIES)["X.csv"]
    assert units["tau:j0"] == {"unit": "N m", "quantity": "effort about the joint's axis, "
                               "parent on child"}
    assert "world axes" in units["Fx:j0"]["quantity"]


def test_an_inverse_csv_that_fails_takes_its_sidecar_with_it(tmp_path, capsys, monkeypatch):
    import hexapod.output.inverse_csv as inverse_csv

    real = inverse_csv.write_atomically

    def failing(path, content):
        if str(path).endswith(".csv"):
            raise KeyboardInterrupt
        return real(path, content)

    monkeypatch.setattr(inverse_csv, "write_atomically", failing)
    code = main(["inverse", str(CHAIN / "model.urdf"), "--motion", str(CHAIN / "motion.csv"),
                 "--out", str(tmp_path / "X.csv")])
    assert code == 130 and list(tmp_path.iterdir()) == []


def test_the_record_tables_describe_every_field():
    """runs.csv of check and bench and stability.csv: a unit for every field the rows hold
    (a field added to a run without a unit fails here, not after an hour of checking)."""
    from hexapod.benchmarks.check import RUN_COLUMNS, CaseRun
    from hexapod.benchmarks.stable_steps import STABILITY_COLUMNS, StabilityRow
    from hexapod.benchmarks.work_precision import RUN_COLUMNS as BENCH_COLUMNS
    from hexapod.benchmarks.work_precision import Run, runs_csv_text

    fields = [f.name for f in dataclasses.fields(CaseRun) if f.name != "result"]
    assert list(RUN_COLUMNS) == fields
    assert list(STABILITY_COLUMNS) == list(StabilityRow(1e3, "rk4", 1e-3, 1e-3, "b").as_dict())
    assert list(BENCH_COLUMNS) == [f.name for f in dataclasses.fields(Run)]
    run = Run("andrews", "rk4", "h=0.001", "finished", 0.5, 10, 40, 1e-6, 1e-12, 1e-9, None)
    header, rows = read_table_text(runs_csv_text([run]))
    assert header == list(BENCH_COLUMNS) and rows[0][10] == ""
    for table in (RUN_COLUMNS, STABILITY_COLUMNS, BENCH_COLUMNS):
        for column, (unit, what) in table.items():
            assert RECORD.match(column) and unit in UNITS and what


def test_a_study_describes_its_tables():
    from hexapod.sweeps.table import SweepTable, timings_csv_text

    rows = [{"case": k, "params": {"duty": 0.5 + k / 10, "gait": "tripod",
                                   "joint.L1/ctr.stiffness": 2.0, "period": 0.5},
             "status": "ok", "message": "",
             "metrics": {"peak_effort:L1/ctr": 1.0, "slip_samples": 0.0, "energy": 2.0},
             "units": {"peak_effort:L1/ctr": "N m", "slip_samples": "", "energy": "J"}}
            for k in range(2)]
    table = SweepTable.from_rows(["duty", "gait", "joint.L1/ctr.stiffness", "period"], rows)
    units = json.loads(table.units_json())
    assert list(units) == ["study.csv", "timings.csv", "columns.csv"]
    assert list(units["study.csv"]) == read_table_text(table.csv_text())[0]
    assert list(units["timings.csv"]) == read_table_text(timings_csv_text(rows))[0]
    assert list(units["columns.csv"]) == read_table_text(table.columns_csv_text())[0]
    study = {c: d["unit"] for c, d in units["study.csv"].items()}
    assert study == {"case": None, "duty": "1", "gait": None, "joint.L1/ctr.stiffness": "",
                     "period": "s", "status": None, "message": None,
                     "peak_effort:L1/ctr": "N m", "slip_samples": "1", "energy": "J"}


def test_the_sensitivity_table_describes_its_columns(tmp_path, capsys):
    out = tmp_path / "sensitivity"
    assert main(["sensitivity", "front-leg", "--parameters", "body.femur.mass", "--samples",
                 "5", "--metrics", "peak_effort", "--no-figures", "--out", str(out)]) == 0
    units = check_described(out, out / "units.json", RECORD)
    assert list(units) == ["sensitivities.csv"]


def test_an_optimisation_describes_its_tables(tmp_path, capsys):
    from tests.test_optimize import study

    out = tmp_path / "optimum"
    assert main(["optimize", str(study(tmp_path)), "--no-figures", "--out", str(out)]) == 0
    units = check_described(out, out / "units.json", RECORD_OR_SERIES)
    assert list(units)[:2] == ["optimization.csv", "optimum.csv"]


#: the optimisation's folder holds its records and its optimum's report (time series)
RECORD_OR_SERIES = re.compile(f"{RECORD.pattern}|{SERIES.pattern}")


def read_table_text(text: str) -> tuple[list[str], list[list[str]]]:
    header, *rows = list(csv.reader(io.StringIO(text)))
    return header, rows
