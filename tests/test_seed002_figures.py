"""Figs. 6-10 of Richard, Anderson and Andrews (``scripts/papers/seed002_figures.py``): the engine
against the closed-loop pendulum's Lagrange equation, the vector network's matrices, and the files
``make`` writes.

The reference is built here from the paper's numbers (Section 5, in dm), apart from the script
and from the scene file, so a wrong number in either, or a wrong engine, fails the test.
"""

from __future__ import annotations

import numpy as np
import pytest
from script_loader import load_script

from hexapod.benchmarks import ClosedLoopPendulum


@pytest.fixture(scope="module")
def script():
    return load_script("scripts/papers/seed002_figures.py")


@pytest.fixture(scope="module")
def three_seconds(script):
    return script.run(3.0)


def paper_lagrange(t_end: float):
    """Richard, Anderson and Andrews, Section 5 (dm, kg, s; y down): m1 = 2 kg from (0, 0) at
    (4, 4), m2 = 1 kg from (7, 0) at (12, 5), at rest, g = 98.1 dm/s^2."""
    return ClosedLoopPendulum(m1=2.0, m2=1.0, anchor1=(0.0, 0.0), anchor2=(7.0, 0.0),
                              p1=(4.0, 4.0), p2=(12.0, 5.0), g=98.1).solve(t_end, rtol=1e-13,
                                                                          atol=1e-13)


def test_engine_matches_the_lagrange_equation(three_seconds):
    """Over 3 s (about two periods) the engine's particles stay within 1e-6 dm of the Lagrange
    solution at every saved state (measured: about 1e-10 dm), the motion is the paper's (x1
    swings from 4 dm to about -4.4 dm, x2 from 12 to about 3.2 dm), and the lengths of the
    three links are those the paper's reading gives."""
    data = three_seconds
    t, engine = data["t"], data["engine"]
    assert t[0] == 0.0 and t[-1] == pytest.approx(3.0) and np.diff(t).max() <= 0.005 + 1e-12
    p1, p2, _ = paper_lagrange(3.0)(t)
    reference = np.stack([p1, p2], axis=1)
    difference = np.abs(engine - reference).max()
    assert difference < 1e-6, difference
    assert data["difference"] == pytest.approx(difference, rel=1e-6, abs=1e-15)
    # the figures' reference is the paper's
    assert np.abs(data["lagrange"] - reference).max() < 1e-9
    assert np.abs(engine[0] - [[4.0, 4.0], [12.0, 5.0]]).max() < 1e-9
    assert -4.6 < engine[:, 0, 0].min() < -4.2 and 3.0 < engine[:, 1, 0].min() < 3.4
    lengths = [np.linalg.norm(engine[:, 0], axis=1),
               np.linalg.norm(engine[:, 1] - [7.0, 0.0], axis=1),
               np.linalg.norm(engine[:, 1] - engine[:, 0], axis=1)]
    for length, expected in zip(lengths, (5.657, 7.071, 8.062), strict=True):
        assert np.abs(length - expected).max() < 1e-3


def test_the_comparison_sees_a_wrong_motion(three_seconds):
    """The criterion is not blind: the same pendulum with g off by 1e-6 relative, or released
    1e-6 dm away, leaves the engine more than 1e-6 dm from it within 3 s."""
    data = three_seconds
    t, engine = data["t"], data["engine"]
    for change in ({"g": 98.1 * (1 + 1e-6)}, {"p1": (4.0, 4.0 + 1e-6)}):
        fields = {"m1": 2.0, "m2": 1.0, "anchor1": (0.0, 0.0), "anchor2": (7.0, 0.0),
                  "p1": (4.0, 4.0), "p2": (12.0, 5.0), "g": 98.1, **change}
        p1, p2, _ = ClosedLoopPendulum(**fields).solve(3.0, rtol=1e-13, atol=1e-13)(t)
        assert np.abs(engine - np.stack([p1, p2], axis=1)).max() > 1e-6, change


def test_cutset_and_circuit_matrices_are_orthogonal(script):
    net = script.network()
    K, S, C = net.incidence, net.cutset, net.circuit
    assert K.shape == (5, 9) and S.shape == (4, 9) and C.shape == (5, 9)
    assert np.all(S @ C.T == 0)
    assert np.all(K @ C.T == 0)  # each circuit is a closed walk
    assert np.array_equal(S[:, :4], np.eye(4)) and np.array_equal(C[:, 4:], np.eye(5))
    assert np.array_equal(net.A, -net.B.T)
    tree = sorted(e.kind for e in net.edges if e.tree)
    assert tree == ["inertial", "inertial", "specified-point", "specified-point"]
    # the script's check stops on matrices that are not orthogonal
    broken = C.copy()
    broken[0, 0] = -broken[0, 0]
    with pytest.raises(RuntimeError, match="not orthogonal"):
        script.check_orthogonal(S, broken, net.branches)


def test_make_writes_what_it_lists(script, tmp_path):
    entries = script.make(tmp_path, duration=0.5)
    files = [e["file"] for e in entries]
    assert sorted(files) == sorted(p.name for p in tmp_path.iterdir())
    reproduces = " ".join(e["reproduces"] for e in entries)
    for figure in ("Fig. 6", "Fig. 7", "Fig. 8", "Fig. 9", "Fig. 10"):
        assert figure + " " in reproduces + " "
    for entry in entries:
        assert set(entry) == {"file", "reproduces", "parameters", "caption"}
        assert entry["caption"] and entry["parameters"]
        path = tmp_path / entry["file"]
        if path.suffix == ".png":
            assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 10_000
    # the mapping of the paper's captions: Fig. 7 y1, Fig. 8 x1, Fig. 9 y2, Fig. 10 x2
    quantity = {e["reproduces"].split(" (")[0]: e["parameters"].get("quantity")
                for e in entries}
    assert [quantity[f"Fig. {k}"] for k in (7, 8, 9, 10)] == ["y1 (dm)", "x1 (dm)", "y2 (dm)",
                                                               "x2 (dm)"]
    text = (tmp_path / script.MATRICES_FILE).read_text()
    for heading in ("Incidence matrix", "Cutset matrix", "Circuit matrix", "cutset x circuit"):
        assert heading in text
    assert "| e5 | e6 | e7 | e8 | e9 |" in text
