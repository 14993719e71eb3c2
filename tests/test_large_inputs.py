"""Large and hostile inputs: read in linear time and bounded memory, refused before the work when
they cannot be read, and the sparse diagnostics of large models equal to the dense ones."""

from __future__ import annotations

import io
import sys
import time
import tracemalloc
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod._support.fastcall import FastFunction, ScatteredFunction
from hexapod.algorithms import linalg, sparse_qr
from hexapod.benchmarks.redundant import bricard
from hexapod.errors import InputFileError, ModelError
from hexapod.output.describe import describe_model
from hexapod.output.recording import read_recording
from hexapod.output.vtk import scene_meshes
from hexapod.scene.motion import MotionWarning, apply_motion, read_motion
from hexapod.scene.reader import read_scene
from hexapod.scene.urdf import read_urdf

from mechanisms import four_bar, random_tree

ROOT = Path(__file__).resolve().parent
CHAIN_3 = ROOT / "data" / "pinocchio-fixtures" / "chain-3" / "model.urdf"


# ------------------------------------------------------------------ motion files

def test_wide_motion_header_is_checked_in_linear_time_and_names_the_duplicates(tmp_path):
    """20,000 columns (the check was quadratic: seconds here, minutes at 100,000)."""
    names = [f"j{k}" for k in range(20_000)]
    names[7000], names[12000] = "j5", "j9"  # j5 twice, j9 twice
    path = tmp_path / "wide.csv"
    path.write_text(",".join(["t", *names]) + "\n0," + ",".join(["0"] * 20_000) + "\n1,"
                    + ",".join(["1"] * 20_000) + "\n")
    start = time.perf_counter()
    with pytest.raises(ModelError) as error:
        read_motion(path)
    assert time.perf_counter() - start < 1.0
    message = str(error.value)
    assert str(path) in message and "'j5' appears twice" in message \
        and "'j9' appears twice" in message and "2 problems" in message


def test_estimated_derivatives_are_one_warning_naming_every_joint(tmp_path):
    t = np.linspace(0.0, 1.0, 50)
    path = tmp_path / "motion.csv"
    np.savetxt(path, np.column_stack([t, np.sin(t), t, np.cos(t), np.cos(t)]), delimiter=",",
               header="t,j0,j1,j2,qd:j2", comments="")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        apply_motion(read_urdf(CHAIN_3), read_motion(path))
    said = [str(w.message) for w in caught if issubclass(w.category, MotionWarning)]
    assert len(said) == 1, said
    assert said[0].startswith(f"{path}: velocities and accelerations of 2 joints estimated")
    assert "j0, j1;" in said[0] and "accelerations of 1 joint" in said[0] \
        and "(columns qdd: absent): j2" in said[0] and "qd:<joint> and qdd:<joint>" in said[0]


def test_a_file_of_many_wrong_columns_lists_some_and_counts_the_rest(tmp_path):
    path = tmp_path / "wide.csv"
    names = [f"knee{k}" for k in range(5000)]
    path.write_text(",".join(["t", *names]) + "\n" + "\n".join(
        f"{i}," + ",".join(["0"] * len(names)) for i in range(4)) + "\n")
    with pytest.raises(ModelError) as error:
        apply_motion(read_urdf(CHAIN_3), read_motion(path))
    lines = str(error.value).splitlines()
    assert len(lines) < 30 and "is not a joint of the model" in lines[1]
    assert lines[-1].endswith("and 4980 more problems of the same file")


# ------------------------------------------------------------------ simulation results

def _npy(shape, dtype=np.float64, data: bytes | None = None) -> bytes:
    """A .npy member: a header declaring ``shape`` followed by ``data`` (default: all of it)."""
    from numpy.lib import format as npy

    stream = io.BytesIO()
    npy.write_array_header_1_0(stream, {"descr": npy.dtype_to_descr(np.dtype(dtype)),
                                        "fortran_order": False, "shape": shape})
    size = int(np.prod(shape)) * np.dtype(dtype).itemsize
    return stream.getvalue() + (bytes(size) if data is None else data)


def test_results_declaring_huge_arrays_are_refused_from_their_headers(tmp_path):
    """A file of kilobytes whose header declares 1e12 numbers (8 TB): refused naming the file and
    the array, without reading or allocating them."""
    (tmp_path / "run").mkdir()
    path = tmp_path / "run" / "results.npz"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("t.npy", _npy((3,)))
        archive.writestr("q.npy", _npy((10**6, 10**6), data=bytes(1000)))
        for key in ("v", "lam"):
            archive.writestr(f"{key}.npy", _npy((3, 2)))
        archive.writestr("coordinates.npy", _npy((2,), "<U4"))
    tracemalloc.start()
    try:
        with pytest.raises(InputFileError) as error:
            read_recording(tmp_path / "run")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 20e6
    message = str(error.value)
    assert str(path) in message and "array 'q'" in message and "(1000000, 1000000)" in message


def test_results_with_a_wrong_shape_are_refused_before_their_data_is_read(tmp_path):
    (tmp_path / "run").mkdir()
    with zipfile.ZipFile(tmp_path / "run" / "results.npz", "w") as archive:
        archive.writestr("t.npy", _npy((3,)))
        for key in ("q", "v"):
            archive.writestr(f"{key}.npy", _npy((3, 2)))
        archive.writestr("lam.npy", _npy((4, 2)))
        archive.writestr("coordinates.npy", _npy((2,), "<U4"))
    with pytest.raises(InputFileError, match=r"array 'lam' has shape \(4, 2\)"):
        read_recording(tmp_path / "run")


# ------------------------------------------------------------------ meshes

def _scene_with_mesh(tmp_path: Path, mesh: str) -> hx.Scene:
    text = (ROOT.parent / "data" / "scenes" / "pendulum.toml").read_text()
    (tmp_path / "scene.toml").write_text(text.replace(
        'name = "rod"\n', f'name = "rod"\nmesh = "{mesh}"\n'))
    return read_scene(tmp_path / "scene.toml")


def test_a_mesh_above_the_limit_is_refused_naming_the_scene_the_body_and_the_file(
        tmp_path, monkeypatch):
    with open(tmp_path / "big.stl", "wb") as stream:  # sparse: nothing written but its size
        stream.truncate(2 * 1024**2 + 1)
    scene = _scene_with_mesh(tmp_path, "big.stl")
    monkeypatch.setenv("HEXAPOD_MAX_MESH_BYTES", "2M")
    with pytest.raises(InputFileError) as error:
        scene_meshes(scene)
    message = str(error.value)
    assert str(tmp_path / "scene.toml") in message and "body 'rod'" in message
    assert "big.stl: 2097153 bytes, above the limit of 2097152 bytes for a body's mesh" \
        in message
    with pytest.raises(InputFileError, match="big.stl: 2 MiB, above the limit of 1 MiB"):
        scene_meshes(scene, limit=1024**2)


def test_a_binary_stl_declaring_more_triangles_than_it_holds_is_refused(tmp_path):
    (tmp_path / "liar.stl").write_bytes(bytes(80) + (10**9).to_bytes(4, "little") + bytes(500))
    with pytest.raises(InputFileError, match="declares 1000000000 triangles"):
        scene_meshes(_scene_with_mesh(tmp_path, "liar.stl"))


def test_meshio_exiting_becomes_a_clean_error(tmp_path, monkeypatch, capsys):
    import meshio

    def read(path, *args, **kwargs):
        print(f"Error: Couldn't read file {path} as vtu")
        sys.exit(1)

    monkeypatch.setattr(meshio, "read", read)
    (tmp_path / "part.vtu").write_text("not a mesh")
    with pytest.raises(InputFileError) as error:
        scene_meshes(_scene_with_mesh(tmp_path, "part.vtu"))
    assert "body 'rod'" in str(error.value) and "cannot read the mesh (Error: Couldn't read" \
        in str(error.value)
    assert capsys.readouterr().out == ""


# ------------------------------------------------------------------ large models

def test_sparse_outputs_are_the_dense_ones():
    model = hx.assemble(random_tree(5, 12, chain=True))
    rng = np.random.default_rng(0)
    for name in ("Phi_v", "dynamics_terms"):
        function = getattr(model, name)
        args = [rng.normal(size=function.numel_in(i)) for i in range(function.n_in())]
        for dense, scattered in zip(FastFunction(function)(*args),
                                    ScatteredFunction(function)(*args), strict=True):
            assert dense.shape == scattered.shape and np.array_equal(dense, scattered)


SCENES = {"chain of 50": lambda: random_tree(7, 50, chain=True, driven=False),
          "driven tree of 40": lambda: random_tree(8, 40),
          "four-bar in 3-D": lambda: four_bar(3, 0.7),
          "Bricard": lambda: bricard().scene}


@pytest.mark.parametrize("name", SCENES)
def test_sparse_diagnostics_equal_the_dense_ones(name, monkeypatch):
    """Rank, redundant rows, degrees of freedom, condition number: the sparse QR and ARPACK of
    large models against the dense QR and SVD, forced on models small enough for both."""
    model = hx.assemble(SCENES[name]())
    dense = describe_model(model)
    monkeypatch.setattr(sparse_qr, "SPARSE_ABOVE", 0)
    monkeypatch.setattr(sparse_qr, "SPARSE_DENSITY", 2.0)
    calls = []
    factor = sparse_qr.sparse_split
    monkeypatch.setattr(linalg, "sparse_split", lambda *a, **k: calls.append(1) or factor(*a,
                                                                                        **k))
    sparse = describe_model(model)
    assert calls  # the sparse path was taken
    assert sparse["mobility"] == dense["mobility"]
    if name in ("four-bar in 3-D", "Bricard"):
        assert dense["mobility"]["redundant_rows"]
    for key in ("condition_number", "sigma_min"):
        assert sparse["initial_pose"][key] == pytest.approx(dense["initial_pose"][key],
                                                            rel=1e-8)
    assert sparse["initial_pose"]["max_abs_phi"] < 1e-12
