"""Cost of one forward-dynamics solve at a state against the number of bodies (not a test).

Protocol: for serial chains of N spatial bodies joined by revolute joints (random axes, the
chains of ``bench_inverse.py`` and ``bench_forward.py``), the model is built once (assembly and
first solve reported apart, wall time), one solve is run as warm-up, then the median CPU time
(``time.process_time``, one BLAS thread: a shared machine's load does not count) of REPEATS
solves is taken. The solve is ``hexapod.forward_dynamics``: the exact, rank-deciding one (the
sparse path of ``hexapod.algorithms.saddle`` above 1e5 entries of ``Phi_v``). The growth
exponent is the slope of log(time) against log(N) fitted over the chain lengths, and the slopes
between consecutive lengths are printed too. The front leg and the six-legged robot are timed
the same way.

    python3 scripts/benchmarks/bench_state_solve.py [--sizes 10 30 100] [--repeats 7]
"""

from __future__ import annotations

import argparse
import time

from measure import growth_exponent, local_slopes, median_time, one_blas_thread, start

one_blas_thread()  # before NumPy loads: process_time counts every thread

import numpy as np  # noqa: E402
from bench_inverse import chain_scene  # noqa: E402  (the same chains in both benchmarks)

import hexapod as hx  # noqa: E402
from legs import front_leg_scene  # noqa: E402


def hexapod_robot() -> hx.Scene:
    scene = hx.Scene("six-legs")
    scene.add(hx.scene.SpatialBody("trunk", 18.4, [0.218, 1.055, 1.226]))
    scene.add(hx.scene.Fixed("stand", "ground", "trunk"))
    for k, side in enumerate(("L1", "R1", "L2", "R2", "L3", "R3")):
        left = side.startswith("L")
        placement = hx.spatial.Placement(
            [0.24 - 0.12 * (k // 2), 0.08 if left else -0.08, -0.04],
            np.diag([1.0, 1.0, 1.0]) if left else np.diag([1.0, -1.0, -1.0]))
        scene.attach(front_leg_scene(phase=0.0 if side in ("L1", "R2", "L3") else np.pi),
                     side, base="trunk", placement=placement)
    return scene


def measure(scene: hx.Scene, repeats: int, t: float = 0.1) -> dict:
    begun = time.perf_counter()
    model = hx.assemble(scene)
    built = time.perf_counter()
    data = model.create_data()
    q = hx.assemble_positions(model, data, t)
    v = hx.solve_velocities(model, data, t, q)
    hx.forward_dynamics(model, data, t, q, v)  # warm-up: builds the CasADi Functions
    warm = time.perf_counter()
    solve = median_time(lambda _: hx.forward_dynamics(model, data, t, q, v), repeats)
    return {"bodies": len(model.bodies), "n_v": model.n_v, "n_c": model.n_c,
            "assemble_s": built - begun, "first_solve_s": warm - built, "solve_ms": 1e3 * solve}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 30, 100])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    rows = [("front leg", measure(front_leg_scene(), args.repeats)),
            ("six legs on a trunk", measure(hexapod_robot(), args.repeats))]
    chains = [(f"chain of {n}", measure(chain_scene(n), args.repeats)) for n in args.sizes]
    print(f"{'scene':<22}{'bodies':>7}{'n_v':>6}{'n_c':>6}{'assemble s':>12}"
          f"{'1st solve s':>12}{'solve ms':>10}")  # solve: CPU, the others wall
    for name, r in rows + chains:
        print(f"{name:<22}{r['bodies']:>7}{r['n_v']:>6}{r['n_c']:>6}{r['assemble_s']:>12.3f}"
              f"{r['first_solve_s']:>12.3f}{r['solve_ms']:>10.2f}")
    if len(chains) >= 2:
        bodies = [r["bodies"] for _, r in chains]
        cost = [r["solve_ms"] for _, r in chains]
        print(f"growth exponent of the solve over the chains: {growth_exponent(bodies, cost):.2f}")
        print("slopes between consecutive lengths: " + ", ".join(
            f"{a}-{b}: {slope:.2f}" for a, b, slope in local_slopes(bodies, cost)))


if __name__ == "__main__":
    start("bench_state_solve")
    main()
