"""Design sweeps: the study file, its cases, the metrics against closed forms, the table in this
process and on a local Dask cluster (bit for bit), a worker killed mid-study, and resuming."""

from __future__ import annotations

import math
import os
import signal
import textwrap

import numpy as np
import pytest

import hexapod as hx
from hexapod.errors import InputFileError
from hexapod.sweeps import read_study, run_study
from hexapod.sweeps.cases import StudyError, check_study

MASS, LENGTH, RATE, G = 1.3, 0.8, 2.0, 9.81  # kg, m (pivot to centre of mass), rad/s, m/s^2


def driven_pendulum() -> hx.Scene:
    """A planar pendulum turned at a constant rate: the effort is ``m g L sin(theta)``."""
    scene = hx.Scene("spun-pendulum", 2)
    scene.add(hx.scene.PlanarBody("bob", MASS, 0.02, position=[0.0, -LENGTH]))
    scene.add(hx.scene.Revolute("pivot", "ground", "bob", origin=[0.0, 0.0]))
    scene.add(hx.scene.JointDriver("spin", "pivot", hx.scene.Polynomial((0.0, RATE))))
    return scene


def study_file(tmp_path, body: str, name: str = "study.toml"):
    hx.write_scene(driven_pendulum(), tmp_path / "pendulum.toml")
    path = tmp_path / name
    path.write_text(textwrap.dedent(body))
    return path


MASSES = f"""
    [study]
    name = "masses"
    scene = "pendulum.toml"
    [vary."body.bob.mass"]
    values = [1.0, 2.0, 4.0]
    [job]
    samples = 4001
    duration = {2 * math.pi / RATE}
"""


# ------------------------------------------------------------------ the study file


def test_cases_are_the_product_of_lists_and_grids_then_the_draws(tmp_path):
    path = study_file(tmp_path, """
        [study]
        scene = "pendulum.toml"
        samples = 4
        seed = 7
        [vary.a]
        values = ["x", "y"]
        [vary.b]
        range = [1.0, 3.0]
        steps = 3
        [vary.c]
        range = [0.01, 1.0]
        spacing = "log"
    """)
    study = read_study(path)
    cases = study.cases()
    assert len(cases) == 2 * 3 * 4
    assert [c.params["a"] for c in cases[:12]] == ["x"] * 12
    assert [c.params["b"] for c in cases[:12:4]] == [1.0, 2.0, 3.0]  # the last varies fastest
    drawn = [c.params["c"] for c in cases[:4]]
    assert all(0.01 <= x <= 1.0 for x in drawn)
    assert drawn == [c.params["c"] for c in read_study(path).cases()[:4]]  # seeded
    assert drawn == [c.params["c"] for c in cases[4:8]]  # the same draws for each grid point
    assert len({c.key for c in cases}) == len(cases)


@pytest.mark.parametrize("body, key", [
    ("[study]\nscene='pendulum.toml'\n[vary.x]\nrange=[2.0, 1.0]\nsteps=3\n", "vary.x.range"),
    ("[study]\nscene='pendulum.toml'\n[vary.x]\nrange=[0.0, 1.0]\nsteps=1\n", "vary.x.steps"),
    ("[study]\nscene='pendulum.toml'\n[vary.x]\nrange=[0.0, inf]\nsteps=3\n", "vary.x.range"),
    ("[study]\nscene='pendulum.toml'\n[vary.x]\nrange=[0.0, 1.0]\n", "study.samples"),
    ("[study]\nscene='pendulum.toml'\n[vary.x]\nvalues=[1, 1]\n", "vary.x.values"),
    ("[study]\nscene='pendulum.toml'\n[vary.x]\nvalues=[1]\nrange=[0, 1]\n", "vary.x"),
    ("[study]\nscene='pendulum.toml'\ncolour='red'\n", "study.colour"),
    ("[study]\nscene='pendulum.toml'\n[job]\nkind='dance'\n", "job.kind"),
    ("[study]\nscene='pendulum.toml'\n[job]\nsamples=1\n", "job.samples"),
    ("[study]\nscene='pendulum.toml'\n[job]\nmetrics=['beauty']\n", "job.metrics"),
    ("[study]\nscene='pendulum.toml'\n[fixed]\nx=1\n[vary.x]\nvalues=[2]\n", "vary.x"),
    ("[study]\n[vary.x]\nvalues=[2]\n", "study.scene"),
    ("[study]\nscene='pendulum.toml'\n[extra]\n", "extra"),
])
def test_a_bad_study_is_refused_naming_the_file_and_the_key(tmp_path, body, key):
    path = study_file(tmp_path, body)
    with pytest.raises(InputFileError) as error:
        read_study(path)
    assert str(path) in str(error.value) and f"{key}:" in str(error.value)


@pytest.mark.parametrize("parameter, words", [
    ("speed", "unknown parameter 'speed'"),
    ("body.nobody.mass", "no body named 'nobody'"),
    ("body.bob.colour", "unknown key 'colour'"),
    ("weather.wind", "a scene key starts with"),
])
def test_a_parameter_that_names_nothing_is_refused_before_any_work(tmp_path, parameter, words):
    path = study_file(tmp_path, f"""
        [study]
        scene = "pendulum.toml"
        [vary."{parameter}"]
        values = [1.0, 2.0]
    """)
    with pytest.raises(StudyError, match=words):
        check_study(read_study(path))


# ------------------------------------------------------------------ metrics


def test_metrics_of_a_spun_pendulum_match_the_closed_form(tmp_path):
    """Turned at a constant rate, ``tau = m g L sin(theta)``: peak ``m g L``, RMS over a turn
    ``m g L / sqrt 2``, positive work per turn ``2 m g L``; its centre of mass comes back, so no
    cost of transport. The trapezoidal rule on 4001 samples is good to about 1e-7."""
    run = run_study(read_study(study_file(tmp_path, MASSES)))
    table = run.table
    mass = table.data["body.bob.mass"]
    assert list(mass) == [1.0, 2.0, 4.0] and list(table.data["status"]) == ["ok"] * 3
    mgl = mass * G * LENGTH
    np.testing.assert_allclose(table.data["peak_effort:pivot"], mgl, rtol=1e-9)
    np.testing.assert_allclose(table.data["rms_effort:pivot"], mgl / math.sqrt(2), rtol=1e-6)
    np.testing.assert_allclose(table.data["energy"], 2 * mgl, rtol=1e-6)
    assert np.isnan(table.data["cost_of_transport"]).all()
    # the pivot holds m (a - g): largest at the bottom, m (g + w^2 L), sampled there at t = 0
    np.testing.assert_allclose(table.data["peak_force:pivot"], mass * (G + RATE**2 * LENGTH),
                               rtol=1e-12)
    assert table.units["peak_effort:pivot"] == "N m" and table.units["energy"] == "J"
    assert table.units["body.bob.mass"] == "kg"


def test_a_failing_case_is_a_row_with_its_message(tmp_path):
    path = study_file(tmp_path, """
        [study]
        scene = "pendulum.toml"
        [vary."body.bob.mass"]
        values = [1.0, -1.0]
        [job]
        samples = 5
    """)
    run = run_study(read_study(path))
    status, message = run.table.data["status"], run.table.data["message"]
    assert list(status) == ["ok", "failed"]
    assert "mass" in message[1] and message[0] == ""
    assert np.isnan(run.table.data["peak_effort:pivot"][1])


# ------------------------------------------------------------------ on Dask


dask_distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def client():
    """Two worker processes, one thread each, as on the 2-core CI machine."""
    import logging

    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=logging.ERROR)
    with Client(cluster) as dask_client:
        yield dask_client
    cluster.close()


def test_the_table_on_two_workers_equals_the_table_in_process_bit_for_bit(tmp_path, client):
    path = study_file(tmp_path, MASSES.replace("4001", "401") + textwrap.dedent("""
        [vary."scene.gravity.1"]
        values = [-9.81, -1.62, 0.0]
    """))
    # the run in this process writes no folder: its 21 figures took a third of the test
    here = run_study(read_study(path))
    there = run_study(read_study(path), client=client, out=tmp_path / "there")
    assert there.computed == 9
    assert here.table.csv_text() == there.table.csv_text()
    assert here.table.csv_text().encode() == (tmp_path / "there" / "study.csv").read_bytes()
    for name in ("columns.csv", "timings.csv"):
        assert (tmp_path / "there" / name).is_file()
    with np.load(tmp_path / "there" / "study.npz") as saved:  # no pickles needed
        np.testing.assert_array_equal(saved["table"]["energy"], here.table.data["energy"])
        assert list(saved["columns"]) == here.table.columns
    assert list((tmp_path / "there" / "figures").glob("*-map.png"))
    array = hx.sweep(path, client=client, as_frame=False)
    assert array.dtype.metadata["units"]["energy"] == "J"
    np.testing.assert_array_equal(array["energy"], here.table.data["energy"])


def test_a_worker_killed_mid_study_loses_no_case(tmp_path, client):
    path = study_file(tmp_path, """
        [study]
        scene = "pendulum.toml"
        [vary."body.bob.mass"]
        range = [1.0, 2.0]
        steps = 8
        [job]
        samples = 2500
    """)
    killed = []

    def kill_one(state):
        if not killed:
            pids = client.run(os.getpid)
            victim = sorted(pids.values())[0]
            os.kill(victim, signal.SIGKILL)
            killed.append(victim)

    run = run_study(read_study(path), client=client, progress=kill_one)
    assert killed and len(run.table) == 8
    assert list(run.table.data["status"]) == ["ok"] * 8
    client.wait_for_workers(2, timeout=60)


def test_resume_computes_only_what_is_missing(tmp_path):
    # two metric families, not all ten: each of the four runs draws two figures, not 21 (the
    # default families' resume: test_the_command_runs_a_study_and_names_the_largest_effort)
    path = study_file(tmp_path, MASSES.replace("4001", "101")
                      + '    metrics = ["peak_effort", "energy"]\n')
    out = tmp_path / "out"
    first = run_study(read_study(path), out=out)
    cases = sorted((out / "cases").glob("*.json"))
    assert first.computed == 3 and len(cases) == 3
    cases[1].unlink()
    (out / "study.csv").unlink()
    again = run_study(read_study(path), out=out, resume=True)
    assert (again.computed, again.reused) == (1, 2)
    assert again.table.csv_text() == first.table.csv_text()
    changed = run_study(read_study(study_file(tmp_path, MASSES.replace("4001", "102")
                                              + '    metrics = ["peak_effort", "energy"]\n')),
                        out=out, resume=True)
    assert changed.computed == 3  # another job: nothing of the earlier one is reused
    fresh = run_study(read_study(path), out=out)
    assert fresh.computed == 3 and len(list((out / "cases").glob("*.json"))) == 3


def test_an_output_folder_holding_other_files_is_refused(tmp_path):
    path = study_file(tmp_path, MASSES)
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "thesis.tex").write_text("x")
    with pytest.raises(InputFileError, match="did not write"):
        run_study(read_study(path), out=tmp_path / "mine")
    assert (tmp_path / "mine" / "thesis.tex").read_text() == "x"


def test_an_unreachable_scheduler_is_refused_with_one_message(tmp_path):
    path = study_file(tmp_path, MASSES)
    with pytest.raises(StudyError, match="scheduler tcp://127.0.0.1:9: cannot connect"):
        run_study(read_study(path), scheduler="tcp://127.0.0.1:9", out=tmp_path / "o",
                  scheduler_timeout=1)
    assert not (tmp_path / "o").exists()


# ------------------------------------------------------------------ the command


def test_the_command_runs_a_study_and_names_the_largest_effort(tmp_path, capsys):
    from hexapod.cli import main

    path = study_file(tmp_path, MASSES.replace("4001", "201"))
    assert main(["sweep", str(path), "--in-process", "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert "3 cases (3 computed, 0 reused, 0 failed)" in out
    assert f"largest peak effort of the ok cases {4.0 * G * LENGTH:.4g} N m at pivot, case 2" in out
    assert main(["sweep", str(path), "--in-process", "--out", str(tmp_path / "o"),
                 "--resume"]) == 0
    assert "(0 computed, 3 reused, 0 failed)" in capsys.readouterr().out


def test_the_command_refuses_a_bad_study_and_says_how_to_get_dask(tmp_path, capsys,
                                                                  monkeypatch):
    import importlib.util

    from hexapod.cli import main

    path = study_file(tmp_path, "[study]\nscene='pendulum.toml'\n[vary.x]\nrange=[1, 0]\nsteps=2\n")
    assert main(["sweep", str(path), "--in-process"]) == 1
    assert "vary.x.range: low must be below high" in capsys.readouterr().err
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "distributed" else real(name, *a))
    assert main(["sweep", str(study_file(tmp_path, MASSES)), "--workers", "2"]) == 1
    assert "pip install 'hexapod[sweep]'" in capsys.readouterr().err


def test_a_gait_the_ground_cannot_hold_is_an_infeasible_row(tmp_path):
    """The walking robot at 1.2 m/s, duty 0.75, asks the ground to pull its feet: its row is
    'infeasible' (computed, metrics kept), with the count and the first time, never 'ok'."""
    path = tmp_path / "fast.toml"
    path.write_text(textwrap.dedent("""
        [study]
        scene = "hexapod"
        [vary.speed]
        values = [1.2]
        [fixed]
        duty = 0.75
        [job]
        samples = 21
        metrics = ["peak_effort", "slip_samples"]
    """))
    row = run_study(read_study(path)).rows[0]
    assert row["status"] == "infeasible"
    count = int(row["metrics"]["slip_samples"])
    assert 0 < count <= 21
    assert f"at {count} of 21 samples, first at t = " in row["message"]
    assert np.isfinite(row["metrics"]["peak_effort:L2/thc_levation"])


#: The window of the walking robot's cases: three samples over its first 20 ms, where L2, R1 and
#: R3 stand (the others swing), the friction policy's forces differ with mu (by a quarter from
#: 0.5 to 1.0) and from min-wrench's. Samples half a stride apart cost each inverse dynamics two
#: seconds of assembling the pose from the last one's; 20 ms apart, 0.1 s.
WINDOW = 0.02


def test_cases_differing_in_ground_settings_each_get_their_own_numbers(tmp_path):
    """Cases of one robot that differ only in ground-force settings share its model where
    they may (mu: read at run time) and not where they may not (the policy: built into its
    Functions); each case equals its own robot assembled afresh. A frozen model once made every
    case after the first an internal error here."""
    path = tmp_path / "ground.toml"
    path.write_text(textwrap.dedent(f"""
        [study]
        scene = "hexapod"
        [vary."ground.policy"]
        values = ["min-wrench", "friction"]
        [vary."ground.mu"]
        values = [0.5, 1.0]
        [job]
        samples = 3
        duration = {WINDOW}
        metrics = ["peak_ground"]
    """))
    from legs.robot import hexapod_walking

    rows = run_study(read_study(path)).rows
    scene = hexapod_walking()  # each case's robot is assembled afresh from it (1.2 s a build)
    for row in rows:
        assert row["status"] in ("ok", "infeasible"), row["message"]
        scene.ground = hx.scene.GroundForces(policy=row["params"]["ground.policy"],
                                             mu=row["params"]["ground.mu"])
        model = hx.assemble(scene)
        result = hx.inverse_dynamics(model, np.linspace(0.0, WINDOW, 3))
        peak = np.linalg.norm(result.ground_force, axis=-1).max(axis=0)
        np.testing.assert_allclose([row["metrics"][f"peak_ground:{leg}"] for leg in
                                    ("L1", "L2", "L3", "R1", "R2", "R3")], peak, rtol=1e-9)
    by_policy = {row["params"]["ground.policy"]: row["metrics"]["peak_ground:L2"]
                 for row in rows}  # L2: a standing foot in the window
    assert abs(by_policy["min-wrench"] - by_policy["friction"]) > 1e-3 * by_policy["friction"]


def test_builder_arguments_and_scene_keys_reach_the_walking_robot(tmp_path):
    """A case of the built-in walking robot equals the same run made by hand."""
    from legs.robot import hexapod_walking

    path = tmp_path / "walk.toml"
    path.write_text(textwrap.dedent(f"""
        [study]
        scene = "hexapod"
        [fixed]
        "ground.policy" = "min-effort"
        [vary.payload]
        values = [0.5]
        [job]
        samples = 3
        duration = {WINDOW}
        metrics = ["peak_ground", "peak_effort"]
    """))
    row = run_study(read_study(path)).rows[0]
    scene = hexapod_walking(payload=0.5)
    scene.ground = hx.scene.GroundForces(policy="min-effort")
    model = hx.assemble(scene)
    result = hx.inverse_dynamics(model, np.linspace(0.0, WINDOW, 3))
    # min-effort ignores friction: its feet slip, which the row says (computed, infeasible)
    assert not result.feasible
    assert row["status"] == "infeasible" and "first at t = 0 s" in row["message"]
    peak = np.linalg.norm(result.ground_force, axis=-1).max(axis=0)
    # a scene key sends the scene through its TOML form, whose rotations are written as
    # angles: the same robot to the last bits, its legs placed by Newton solves from poses
    # that differ in them (the ground forces agree to some 1e-12)
    np.testing.assert_allclose([row["metrics"][f"peak_ground:{leg}"] for leg in
                                ("L1", "L2", "L3", "R1", "R2", "R3")], peak, rtol=1e-10)
    with pytest.raises(StudyError, match="takes gait, period, speed, duty"):
        check_study(read_study(study_file(tmp_path, "[study]\nscene='hexapod'\n"
                                          "[vary.velocity]\nvalues=[1.0]\n")))
