"""Large and hostile inputs: how long each command takes on them, and how much memory.

Each input is generated in a temporary folder (removed at the end), and each command runs as
``python3 -m hexapod ...`` in a fresh child process, stopped after ``--timeout`` seconds. Its
wall time and peak resident memory (the child's own ``ru_maxrss``, from ``os.wait4``) are
printed in a Markdown table with its exit status and the first line it wrote on stderr.

Cases:

* ``chain-1000``: ``hexapod info`` and ``hexapod dynamics`` of a serial chain of 1000 spatial
  bodies (revolute joints with random axes, as in ``bench_inverse.py``), a TOML scene;
* ``urdf-2000``, ``urdf-20000``: ``hexapod info`` of a URDF chain of 2000 and 20,000 links
  (the second is above the default model-size limit);
* ``free-100000``: ``hexapod info`` of 100,000 free bodies (no joint), as refused by the
  default model-size limit and with the limit raised (``HEXAPOD_MAX_BODIES``);
* ``motion-100000``: ``hexapod inverse`` of a 3-link URDF with a motion of 100,000 columns (all
  but three naming no joint), and the same with a duplicated column;
* ``mesh-257M``: ``hexapod export`` of a scene whose body names a mesh file of 257 MiB (a sparse
  file: nothing written but its size), above the 256 MiB limit; ``mesh-stl-header``: a binary
  STL of 584 bytes whose header declares a billion triangles; ``mesh-corrupt``: a VTU file of
  garbage (meshio exits on it);
* ``npz-crafted``: ``hexapod export`` of a ``results.npz`` of a few kilobytes whose ``q``
  declares 10^6 x 10^6 numbers (8 TB).

    python3 scripts/benchmarks/large_inputs.py [--timeout 300] [--only chain-1000 npz-crafted ...]
"""

from __future__ import annotations

import argparse
import io
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from measure import start

ROOT = Path(__file__).resolve().parents[2]
INERTIA = 'ixx="0.001" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"'


# ------------------------------------------------------------------ inputs

def chain_toml(n: int, seed: int = 0) -> str:
    """A chain of ``n`` spatial bodies of 1 kg, 0.1 m apart along x, revolute joints with random
    axes hanging from the ground (the chains of ``bench_inverse.py``)."""
    rng = np.random.default_rng(seed)
    lines = ["[scene]", f'name = "chain-{n}"', "dimension = 3", 'length_unit = "m"', ""]
    for k in range(n):
        axis = ", ".join(repr(float(x)) for x in rng.normal(size=3))
        parent = "ground" if k == 0 else f"l{k - 1}"
        lines += ["[[body]]", f'name = "l{k}"', "mass = 1.0", "inertia = [0.001, 0.01, 0.01]",
                  "com = [0.05, 0.0, 0.0]", f"position = [{0.1 * k!r}, 0.0, 0.0]", "",
                  "[[joint]]", f'name = "j{k}"', 'type = "revolute"', f'parent = "{parent}"',
                  f'child = "l{k}"', f"origin = [{0.1 * k!r}, 0.0, 0.0]", f"axis = [{axis}]", ""]
    return "\n".join(lines)


def free_toml(n: int) -> str:
    lines = ["[scene]", f'name = "free-{n}"', "dimension = 3", 'length_unit = "m"', ""]
    for k in range(n):
        lines += ["[[body]]", f'name = "b{k}"', "mass = 1.0", "inertia = [0.001, 0.01, 0.01]",
                  f"position = [{0.1 * k!r}, 0.0, 0.0]", ""]
    return "\n".join(lines)


def chain_urdf(n: int) -> str:
    """A URDF chain of ``n`` links of 1 kg, 0.1 m apart, axes alternately along z and y."""
    lines = ['<?xml version="1.0"?>', f'<robot name="chain-{n}">', '  <link name="base"/>']
    lines += [f'  <link name="l{k}"><inertial><origin xyz="0.05 0 0"/><mass value="1"/>'
              f"<inertia {INERTIA}/></inertial></link>" for k in range(n)]
    for k in range(n):
        parent = "base" if k == 0 else f"l{k - 1}"
        axis = "0 1 0" if k % 2 else "0 0 1"
        lines.append(f'  <joint name="j{k}" type="revolute"><parent link="{parent}"/>'
                     f'<child link="l{k}"/><origin xyz="{0.1 if k else 0.0} 0 0"/>'
                     f'<axis xyz="{axis}"/></joint>')
    return "\n".join(lines + ["</robot>", ""])


def wide_motion(columns: int, duplicate: bool = False) -> str:
    """Samples of ``j0 .. j<columns - 1>`` (the 3-link URDF has j0, j1, j2) at 5 times."""
    names = [f"j{k}" for k in range(columns)]
    if duplicate:
        names[-1] = "j1"
    rows = [",".join([f"{0.1 * i:g}"] + ["0"] * columns) for i in range(5)]
    return "\n".join([",".join(["t", *names]), *rows, ""])


def crafted_npz(path: Path) -> None:
    """A results.npz whose ``q`` declares 10^6 x 10^6 numbers and holds a kilobyte."""
    from numpy.lib import format as npy

    def member(shape, dtype="<f8", data=None) -> bytes:
        stream = io.BytesIO()
        npy.write_array_header_1_0(stream, {"descr": dtype, "fortran_order": False,
                                            "shape": shape})
        size = int(np.prod(shape)) * np.dtype(dtype).itemsize
        return stream.getvalue() + (bytes(size) if data is None else data)

    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("t.npy", member((3,)))
        archive.writestr("q.npy", member((10**6, 10**6), data=bytes(1024)))
        archive.writestr("v.npy", member((3, 6)))
        archive.writestr("lam.npy", member((3, 5)))
        archive.writestr("coordinates.npy", member((7,), "<U8"))


def mesh_scene(folder: Path, mesh: str) -> Path:
    """The pendulum of data/scenes with a mesh file named for its rod."""
    text = (ROOT / "data" / "scenes" / "pendulum.toml").read_text()
    path = folder / f"pendulum-{Path(mesh).stem}.toml"
    path.write_text(text.replace('name = "rod"\n', f'name = "rod"\nmesh = "{mesh}"\n'))
    return path


# ------------------------------------------------------------------ cases

@dataclass
class Case:
    name: str
    args: list[str]
    env: dict = field(default_factory=dict)


def prepare(folder: Path, only: set[str]) -> list[Case]:
    """Write the inputs of the cases asked for into ``folder``; the cases, in order."""
    cases = []

    def wanted(name: str) -> bool:
        return not only or name in only

    if wanted("chain-1000"):
        (folder / "chain-1000.toml").write_text(chain_toml(1000))
        cases += [Case("chain-1000", ["info", "chain-1000.toml"]),
                  Case("chain-1000", ["dynamics", "chain-1000.toml"])]
    for n in (2000, 20_000):
        if wanted(f"urdf-{n}"):
            (folder / f"chain-{n}.urdf").write_text(chain_urdf(n))
            cases.append(Case(f"urdf-{n}", ["info", f"chain-{n}.urdf"]))
    if wanted("free-100000"):
        (folder / "free-100000.toml").write_text(free_toml(100_000))
        cases += [Case("free-100000", ["info", "free-100000.toml"]),
                  Case("free-100000", ["info", "free-100000.toml"],
                       {"HEXAPOD_MAX_BODIES": "100000"})]
    if wanted("motion-100000"):
        (folder / "chain-3.urdf").write_text(chain_urdf(3))
        (folder / "wide.csv").write_text(wide_motion(100_000))
        (folder / "wide-twice.csv").write_text(wide_motion(100_000, duplicate=True))
        cases += [Case("motion-100000", ["inverse", "chain-3.urdf", "--motion", name,
                                         "--out", "out.csv"])
                  for name in ("wide.csv", "wide-twice.csv")]
    meshes = {"mesh-257M": "big.stl", "mesh-stl-header": "liar.stl", "mesh-corrupt": "bad.vtu"}
    if any(wanted(name) for name in meshes):
        with open(folder / "big.stl", "wb") as stream:  # sparse: only its size is written
            stream.truncate(257 * 1024**2)
        (folder / "liar.stl").write_bytes(bytes(80) + (10**9).to_bytes(4, "little")
                                          + bytes(500))
        (folder / "bad.vtu").write_text("<VTKFile>garbage")
        plain = mesh_scene(folder, "none.stl")  # the results to export, once
        subprocess.run([sys.executable, "-m", "hexapod", "simulate", plain.name, "--t-end",
                        "0.01", "--out", "run"], cwd=folder, check=True, capture_output=True)
        for name, mesh in meshes.items():
            if wanted(name):
                scene = mesh_scene(folder, mesh).name
                cases.append(Case(name, ["export", "run", "--scene", scene, "--vtk",
                                         f"vtk-{name}"]))
    if wanted("npz-crafted"):
        (folder / "crafted").mkdir()
        crafted_npz(folder / "crafted" / "results.npz")
        cases.append(Case("npz-crafted", ["export", "crafted", "--scene",
                                          str(ROOT / "data" / "scenes" / "pendulum.toml"),
                                          "--vtk", "vtk-crafted"]))
    return cases


def measure(case: Case, folder: Path, timeout: float) -> dict:
    """Run one case in a fresh child: exit status, first stderr line, wall s, peak MB."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", **case.env}
    env.pop("HEXAPOD_DEBUG", None)
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        child = subprocess.Popen([sys.executable, "-m", "hexapod", *case.args], cwd=folder,
                                 env=env, stdout=out, stderr=err, start_new_session=True)
        stopped = threading.Event()

        def stop() -> None:
            stopped.set()
            os.killpg(child.pid, signal.SIGKILL)

        timer = threading.Timer(timeout, stop)
        timer.start()
        try:
            _, status, usage = os.wait4(child.pid, 0)  # this child's own resource usage
        finally:
            timer.cancel()
        wall = time.perf_counter() - start
        child.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        lines = err.read().decode(errors="replace").splitlines()
    first = next((line for line in lines if line.strip()), "")
    return {"status": f"timeout ({timeout:g} s)" if stopped.is_set() else child.returncode,
            "stderr": first if len(first) <= 150 else first[:147] + "...", "wall": wall,
            "peak": usage.ru_maxrss / 1024}  # KiB on Linux


def command_text(case: Case) -> str:
    env = " ".join(f"{k}={v}" for k, v in case.env.items())
    args = " ".join(Path(a).name if os.sep in a else a for a in case.args)
    return f"{env + ' ' if env else ''}hexapod {args}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--timeout", type=float, default=300.0,
                        help="seconds a command may run (default 300)")
    parser.add_argument("--only", nargs="+", default=[], metavar="CASE",
                        help="run only these cases (chain-1000, urdf-2000, urdf-20000, "
                        "free-100000, motion-100000, mesh-257M, mesh-stl-header, mesh-corrupt, "
                        "npz-crafted)")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory(prefix="hexapod-large-") as scratch:
        folder = Path(scratch)
        for case in prepare(folder, set(args.only)):
            print(f"{case.name}: {command_text(case)} ...", file=sys.stderr, flush=True)
            result = measure(case, folder, args.timeout)
            rows.append((case, result))
    print("| case | command | exit | first line on stderr | wall s | peak MB |")
    print("| --- | --- | --- | --- | ---: | ---: |")
    for case, r in rows:
        said = r["stderr"].replace("|", "\\|")
        print(f"| {case.name} | `{command_text(case)}` | {r['status']} | {said} | "
              f"{r['wall']:.1f} | {r['peak']:.0f} |")
    return 0


if __name__ == "__main__":
    start("large_inputs")
    sys.exit(main())
