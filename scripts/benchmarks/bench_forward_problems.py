"""The problems of ``scripts/benchmarks/bench_forward.py`` and their reference motions: the
scenes, the centres of mass in the state, quintic Hermite interpolation, and the cached tight
reference against which every run's error is measured."""

from __future__ import annotations

import hashlib
import io
import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from bench_inverse import chain_scene  # the same chains in every benchmark
from measure import log

import hexapod as hx
from hexapod import get_integrator
from legs import front_leg_scene

REFERENCE_RTOL = 1e-12
REFERENCE_MAX_STEP = 2.5e-3  # s, the reference's largest step (for the interpolation)


# ------------------------------------------------------------------ problems

def four_bar_scene() -> hx.Scene:
    """The four-bar of ``data/scenes/four_bar_3d.toml`` (crank 0.1 m, coupler 0.5 m, rocker
    0.4 m, ground 0.4 m, slender bars) in the plane, free (1 DOF), with the crank turned to lie
    along +x: the scene file's pose (crank and rocker vertical) is an equilibrium."""
    scene = hx.Scene("four-bar", dimension=2, gravity=[0.0, -9.81])
    A, B, C, D = (np.array(p) for p in ([0.0, 0.0], [0.1, 0.0], [0.4, 0.4], [0.4, 0.0]))
    for name, mass, (P, R) in (("crank", 0.3, (A, B)), ("coupler", 1.0, (B, C)),
                               ("rocker", 0.8, (D, C))):
        length = float(np.linalg.norm(R - P))
        scene.add(hx.scene.PlanarBody(name, mass, mass * length**2 / 12, position=(P + R) / 2,
                                      angle=float(np.arctan2(*(R - P)[::-1]))))
    scene.add(hx.scene.Revolute("A", "ground", "crank", origin=A))
    scene.add(hx.scene.Revolute("B", "crank", "coupler", origin=B))
    scene.add(hx.scene.Revolute("C", "coupler", "rocker", origin=C))
    scene.add(hx.scene.Revolute("D", "ground", "rocker", origin=D))  # closes the loop
    return scene


@dataclass
class Problem:
    key: str
    title: str
    build: Callable[[], hx.Scene]
    t_end: float
    chain: int | None = None  # bodies, for the serial chains

    def spec(self) -> dict:
        return {"key": self.key, "title": self.title, "t_end": self.t_end, "chain": self.chain}


def problems(sizes: list[int]) -> list[Problem]:
    out = [Problem("front-leg", "front leg, falling", lambda: front_leg_scene(gait=False), 0.5),
           Problem("four-bar", "four-bar (planar), falling", four_bar_scene, 2.0)]
    for n in sizes:
        out.append(Problem(f"chain-{n}", f"chain of {n}, hanging", lambda n=n: chain_scene(n),
                           0.5, chain=n))
    return out


# ------------------------------------------------------------------ positions and errors

def position_indices(model: hx.Model) -> np.ndarray:
    """Indices in ``q`` (and, the same, in ``v``) of every body's centre of mass, (bodies, d)."""
    d = model.dimension
    return (np.array([[b.q.start + k for k in range(d)] for b in model.bodies]),
            np.array([[b.v.start + k for k in range(d)] for b in model.bodies]))


def hermite5(s: np.ndarray, h: np.ndarray, y0, y1, d0, d1, a0, a1) -> np.ndarray:
    """Quintic Hermite interpolation on [0, 1] (``s``) of an interval of length ``h``, from the
    values, first and second derivatives at both ends (error O(h^6))."""
    s2, s3 = s * s, s * s * s
    s4, s5 = s3 * s, s3 * s2
    H0 = 1 - 10 * s3 + 15 * s4 - 6 * s5
    H1 = s - 6 * s3 + 8 * s4 - 3 * s5
    H2 = 0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5
    H3 = 0.5 * s3 - s4 + 0.5 * s5
    H4 = -4 * s3 + 7 * s4 - 3 * s5
    H5 = 10 * s3 - 15 * s4 + 6 * s5
    shape = (-1,) + (1,) * (y0.ndim - 1)
    H0, H1, H2, H3, H4, H5, h = (x.reshape(shape) for x in (H0, H1, H2, H3, H4, H5, h))
    return (H0 * y0 + H5 * y1 + h * (H1 * d0 + H4 * d1) + h * h * (H2 * a0 + H3 * a1))


@dataclass
class Reference:
    """The reference motion of the centres of mass: ``r, rd, rdd`` (N, bodies, d) at ``t``."""

    t: np.ndarray
    r: np.ndarray
    rd: np.ndarray
    rdd: np.ndarray
    meta: dict = field(default_factory=dict)

    @property
    def scale(self) -> float:
        return float(np.linalg.norm(self.r, axis=-1).max())

    def at(self, times: np.ndarray, every: int = 1) -> np.ndarray:
        t, r, rd, rdd = (x[::every] for x in (self.t, self.r, self.rd, self.rdd))
        times = np.clip(np.asarray(times, dtype=float), t[0], t[-1])
        k = np.clip(np.searchsorted(t, times, side="right") - 1, 0, t.size - 2)
        h = t[k + 1] - t[k]
        s = (times - t[k]) / h
        return hermite5(s, h, r[k], r[k + 1], rd[k], rd[k + 1], rdd[k], rdd[k + 1])

    def error(self, times: np.ndarray, positions: np.ndarray) -> float:
        """The relative error ``e`` of the protocol."""
        gap = np.linalg.norm(positions - self.at(times), axis=-1)
        return float(gap.max() / self.scale)

    def interpolation_check(self) -> float:
        """The error of interpolating from every other sample at the samples left out,
        relative to the scale (at twice the reference's spacing: pessimistic)."""
        if self.t.size < 5:
            return float("nan")
        last = self.t.size - 1 - (self.t.size - 1) % 2  # keep the last point of the coarse set
        coarse = Reference(self.t[:last + 1], self.r[:last + 1], self.rd[:last + 1],
                           self.rdd[:last + 1])
        odd = np.arange(1, last, 2)
        gap = np.linalg.norm(self.r[odd] - coarse.at(self.t[odd], every=2), axis=-1)
        return float(gap.max() / self.scale)

    def npz_bytes(self) -> bytes:
        buffer = io.BytesIO()
        np.savez_compressed(buffer, t=self.t, r=self.r, rd=self.rd, rdd=self.rdd,
                            meta=np.array(json.dumps(self.meta)))
        return buffer.getvalue()


def write_bytes_atomically(path: Path, content: bytes) -> None:
    """:func:`hexapod.output.write_atomically`, making the folder first."""
    path.parent.mkdir(parents=True, exist_ok=True)
    hx.output.write_atomically(path, content)


def model_fingerprint(model: hx.Model) -> str:
    """A hash of what fixes the motion: initial state, masses, inertias, joint frames."""
    digest = hashlib.sha256()
    for array in [model.q0, model.v0, model.gravity]:
        digest.update(np.ascontiguousarray(array, dtype=float).tobytes())
    for b in model.bodies:
        digest.update(np.array([b.mass, *np.ravel(b.inertia)], dtype=float).tobytes())
    for j in model.joints:
        digest.update(j.kind.encode())
        for frame in (j.parent_frame, j.child_frame):
            digest.update(frame.position.tobytes() + np.ravel(frame.rotation).tobytes())
    return digest.hexdigest()[:16]


def reference(problem: Problem, model: hx.Model, method: str, folder: Path) -> Reference:
    """The cached reference of ``problem``, or a new one (written to ``folder`` at once)."""
    meta = {"problem": problem.spec(), "method": method, "rtol": REFERENCE_RTOL,
            "atol": REFERENCE_RTOL, "max_step": REFERENCE_MAX_STEP,
            "hexapod": hx.__version__, "model": model_fingerprint(model)}
    path = folder / f"{problem.key}.npz"
    if path.is_file():
        try:
            with np.load(path) as saved:
                cached = Reference(saved["t"], saved["r"], saved["rd"], saved["rdd"],
                                   json.loads(str(saved["meta"])))
        except (OSError, ValueError, KeyError) as error:
            log(f"  {path}: unreadable ({error}), computed again")
        else:
            if {k: cached.meta.get(k) for k in meta} == meta:
                log(f"  reference from {path}")
                return cached
            log(f"  {path}: made with other settings, computed again")
    log(f"  reference: {method} at rtol = {REFERENCE_RTOL:g} ...")
    q_index, v_index = position_indices(model)
    cls = get_integrator(method)
    cpu = time.process_time()
    integrator = cls(model, 0.0, problem.t_end, rtol=REFERENCE_RTOL, atol=REFERENCE_RTOL,
                     max_step=REFERENCE_MAX_STEP)
    samples = [(integrator.t, integrator.q[q_index], integrator.v[v_index],
                integrator.v_dot[v_index])]
    while integrator.status == "running":
        integrator.step()
        samples.append((integrator.t, integrator.q[q_index], integrator.v[v_index],
                        integrator.v_dot[v_index]))
    if integrator.status != "finished":
        raise RuntimeError(f"{problem.key}: the reference failed: {integrator.message}")
    t, r, rd, rdd = (np.array(x) for x in zip(*samples, strict=True))
    meta.update(steps=integrator.counters.steps, cpu_s=time.process_time() - cpu)
    result = Reference(t, r, rd, rdd, meta)
    write_bytes_atomically(path, result.npz_bytes())
    log(f"  reference: {integrator.counters.steps} steps, {meta['cpu_s']:.1f} s, saved to {path}")
    return result
