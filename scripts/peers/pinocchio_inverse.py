"""The `hexapod inverse` CSV computed by Pinocchio, for comparison (not a test; needs the
optional `compare` extra: `pip install ".[compare]"`).

Pinocchio's RNEA gives ``tau`` and ``data.f[i]``, the spatial force the parent transmits to the
child through joint ``i``, in the joint's local frame (the URDF child link frame), about its
origin: the report convention of this project. Fixed joints are merged into frames by
Pinocchio, so only joints with a degree of freedom are written.

    python3 scripts/peers/pinocchio_inverse.py MODEL.urdf MOTION.csv OUT.csv
"""

from __future__ import annotations

import argparse
import csv
import sys
import time

import numpy as np


def pinocchio_table(urdf: str, motion: str) -> tuple[list[str], np.ndarray, float]:
    """Header, rows and the seconds spent in the sample loop (RNEA plus reading data.f)."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(urdf)
    data = model.createData()
    with open(motion, newline="") as stream:
        rows = list(csv.reader(stream))
    header, values = rows[0], np.array(rows[1:], dtype=float)
    column = {name: k for k, name in enumerate(header)}
    joints = list(model.names)[1:]
    n = values.shape[0]
    q, v, a = np.zeros((n, model.nq)), np.zeros((n, model.nv)), np.zeros((n, model.nv))
    for j, name in enumerate(joints, start=1):
        iq, iv = model.idx_qs[j], model.idx_vs[j]
        angle = values[:, column[name]]
        if model.nqs[j] == 2:  # a continuous joint: q holds (cos, sin) of the angle
            q[:, iq], q[:, iq + 1] = np.cos(angle), np.sin(angle)
        else:
            q[:, iq] = angle
        v[:, iv] = values[:, column[f"qd:{name}"]]
        a[:, iv] = values[:, column[f"qdd:{name}"]]
    out_header = ["t"]
    for name in joints:
        out_header += [f"tau:{name}"] + [f"{c}:{name}" for c in ("Fx", "Fy", "Fz", "Tx", "Ty",
                                                                  "Tz")]
    out = np.zeros((n, len(out_header)))
    out[:, 0] = values[:, column["t"]]
    start = time.perf_counter()
    for k in range(n):
        tau = pin.rnea(model, data, q[k], v[k], a[k])
        for j in range(1, model.njoints):
            base = 1 + 7 * (j - 1)
            out[k, base] = tau[model.idx_vs[j]]
            out[k, base + 1:base + 4] = data.f[j].linear
            out[k, base + 4:base + 7] = data.f[j].angular
    return out_header, out, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("urdf")
    parser.add_argument("motion")
    parser.add_argument("out")
    args = parser.parse_args()
    try:
        header, table, _ = pinocchio_table(args.urdf, args.motion)
    except ImportError:
        sys.exit("pinocchio is not installed: pip install '.[compare]'")
    with open(args.out, "w") as stream:
        stream.write(",".join(header) + "\n")
        for row in table:
            stream.write(",".join(format(x, ".17g") for x in row) + "\n")


if __name__ == "__main__":
    main()
