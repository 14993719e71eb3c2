"""Write the Pinocchio fixtures of the tests: URDF, motion and expected CSV (needs `pin`).

Each fixture in ``tests/data/pinocchio-fixtures/<name>/`` is a URDF written here directly (random
trees and chains: revolute, continuous, prismatic and fixed joints, joint origins and inertials
with random ``xyz`` and ``rpy``, unnormalised axes, full inertia tensors, a massless link on a
fixed joint), a motion with exact derivatives, and ``expected.csv``: Pinocchio's ``tau`` and
``data.f`` in the `hexapod inverse` format. The tests compare `hexapod inverse` with them
(CI has no Pinocchio). Re-run after changing the generator:

    pip install ".[compare]" && python3 tests/data/make_pinocchio_fixtures.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
OUT = Path(__file__).resolve().parent / "pinocchio-fixtures"  # beside this file

sys.path.insert(0, str(ROOT / "scripts" / "peers"))
from pinocchio_inverse import pinocchio_table  # noqa: E402


def _f(values) -> str:
    return " ".join(repr(float(x)) for x in np.atleast_1d(values))


def _rotation(rng) -> np.ndarray:
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    angle = rng.uniform(0, np.pi)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def random_urdf(seed: int, links: int, chain: bool, massless: bool = False) -> tuple[str, list]:
    """URDF text and the movable joints (name, type)."""
    rng = np.random.default_rng(seed)
    lines = ['<?xml version="1.0"?>', f'<robot name="random-{seed}">', '  <link name="base"/>']
    movable = []
    for k in range(links):
        parent = "base" if k == 0 else (f"l{k - 1}" if chain else f"l{rng.integers(0, k)}")
        name = f"l{k}"
        moments = np.sort(rng.uniform(0.01, 0.1, 3))
        moments[2] = min(moments[2], moments[0] + moments[1])
        R = _rotation(rng)
        J = R @ np.diag(moments) @ R.T  # a full tensor with products of inertia
        weightless = massless and k == links - 1
        lines.append(f'  <link name="{name}">')
        if not weightless:
            lines += ["    <inertial>",
                      f'      <origin xyz="{_f(rng.normal(size=3) * 0.1)}" '
                      f'rpy="{_f(rng.uniform(-1, 1, 3))}"/>',
                      f'      <mass value="{_f(rng.uniform(0.3, 2.0))}"/>',
                      f'      <inertia ixx="{_f(J[0, 0])}" ixy="{_f(J[0, 1])}" '
                      f'ixz="{_f(J[0, 2])}" iyy="{_f(J[1, 1])}" iyz="{_f(J[1, 2])}" '
                      f'izz="{_f(J[2, 2])}"/>',
                      "    </inertial>"]
        lines.append("  </link>")
        kind = "fixed" if weightless or (k > 1 and rng.uniform() < 0.15) else str(
            rng.choice(["revolute", "continuous", "prismatic"], p=[0.5, 0.2, 0.3]))
        lines += [f'  <joint name="j{k}" type="{kind}">', f'    <parent link="{parent}"/>',
                  f'    <child link="{name}"/>',
                  f'    <origin xyz="{_f(rng.normal(size=3) * 0.2)}" '
                  f'rpy="{_f(rng.uniform(-1.5, 1.5, 3))}"/>']
        if kind != "fixed":
            lines.append(f'    <axis xyz="{_f(rng.normal(size=3) * rng.uniform(0.5, 2))}"/>')
            lines.append('    <limit lower="-10" upper="10" effort="100" velocity="10"/>')
            lines.append('    <dynamics damping="0.5" friction="0.1"/>')  # ignored by both
            movable.append(f"j{k}")
        lines.append("  </joint>")
    lines.append("</robot>")
    return "\n".join(lines) + "\n", movable


def motion_csv(seed: int, joints: list, samples: int = 40) -> str:
    rng = np.random.default_rng(1000 + seed)
    t = np.linspace(0.0, 1.0, samples)
    columns, header = [t], ["t"]
    q, qd, qdd = [], [], []
    for _name in joints:
        a, w, phase, c = rng.uniform(0.3, 1.2), rng.uniform(2, 9), rng.uniform(0, 6), \
            rng.normal() * 0.3
        q.append(c + a * np.sin(w * t + phase))
        qd.append(a * w * np.cos(w * t + phase))
        qdd.append(-a * w * w * np.sin(w * t + phase))
    header += joints + [f"qd:{n}" for n in joints] + [f"qdd:{n}" for n in joints]
    columns += q + qd + qdd
    rows = np.column_stack(columns)
    return ",".join(header) + "\n" + "\n".join(",".join(format(x, ".17g") for x in row)
                                                for row in rows) + "\n"


FIXTURES = {"chain-3": (11, 3, True, False), "chain-6": (12, 6, True, False),
            "tree-7": (13, 7, False, False), "tree-9-massless": (14, 9, False, True)}


def main() -> None:
    for name, (seed, links, chain, massless) in FIXTURES.items():
        folder = OUT / name
        folder.mkdir(parents=True, exist_ok=True)
        urdf, joints = random_urdf(seed, links, chain, massless)
        (folder / "model.urdf").write_text(urdf)
        (folder / "motion.csv").write_text(motion_csv(seed, joints))
        header, table, _ = pinocchio_table(str(folder / "model.urdf"),
                                           str(folder / "motion.csv"))
        (folder / "expected.csv").write_text(
            ",".join(header) + "\n"
            + "\n".join(",".join(format(x, ".17g") for x in row) for row in table) + "\n")
        print(f"wrote {folder.relative_to(ROOT)}: {len(joints)} moving joints")


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT / "scripts"))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    main()
