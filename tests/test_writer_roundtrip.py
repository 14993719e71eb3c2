"""Every scene the writer accepts reads back as the same scene; every other one is refused.

Hypothesis draws scenes (bodies of each kind with markers and meshes, joints with ranges or
none, drivers with laws, force elements) with names from any text, hostile characters included,
and numbers from 5e-324 to the largest double, -0.0, infinities and NaN. The writer either
refuses the scene with a HexapodError (and then the scene is invalid, or holds text no UTF-8
file can hold) or writes a file that the reader reads without a problem, and writing what was
read gives the same document again (the rotations, written as roll, pitch and yaw, to
round-off). No model is assembled: it takes a few seconds.
"""

from __future__ import annotations

import math
import string
import tomllib
from collections import Counter
from typing import NamedTuple

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hexapod as hx
from hexapod.errors import HexapodError
from hexapod.scene.reader import scene_from_document
from hexapod.scene.writer import scene_text
from hexapod.spatial import rotation_2d, rotation_from_rpy

ROUND_TRIP = settings(max_examples=100, deadline=None, derandomize=True, database=None,
                      suppress_health_check=[HealthCheck.too_slow])

# characters a TOML writer must escape or refuse, characters that mean something in TOML, and
# characters beyond ASCII (a lone surrogate among them: no UTF-8 file can hold it)
HOSTILE = ("\n\r\t\b\f\x00\x01\x1b\x1f\x7f\"'\\ =#[]{}.,/-_é☃\u2028\u0085\ufeff\u200b\ud800"
           "\U0001f600")
ALLOWED = set(string.ascii_letters + string.digits + "_.-/")

text = st.text(st.characters() | st.sampled_from(HOSTILE), max_size=10)
# one line of text: what a scene name may be, quotes, backslashes and TOML's signs included
LINE = st.characters(exclude_categories=("Cc", "Cs", "Zl", "Zp"))
line = st.text(LINE | st.sampled_from("\"'\\ =#[]{}.,é☃\ufeff\u200b\U0001f600"), min_size=1,
               max_size=10)
valid_name = st.from_regex(r"[A-Za-z0-9_.\-]{1,6}(/[A-Za-z0-9_.\-]{1,4})?", fullmatch=True)
angle = st.floats(-4.0, 4.0)
BOUNDARIES = st.sampled_from(("not-a-knot", "natural", "clamped"))


class Numbers(NamedTuple):
    """The numbers a scene is drawn with: any real, a positive one, a law's value."""

    real: st.SearchStrategy
    positive: st.SearchStrategy
    value: st.SearchStrategy


TINY = (0.0, -0.0, 1e-300, -1e-300, 5e-324, 0.1, -1 / 3, 2.5)
HUGE = (1e16, -1e300, 1e300, 1.7976931348623157e308)
# a clean scene: numbers a scene may hold, the tiny ones and -0.0 included
CLEAN = Numbers(real=st.one_of(st.sampled_from(TINY), st.floats(-1e3, 1e3)),
                positive=st.one_of(st.sampled_from((1e-300, 0.1, 1 / 3)), st.floats(1e-3, 1e3)),
                value=st.one_of(st.sampled_from(TINY), st.floats(-1e3, 1e3)))
# a hostile scene: any double, the largest, infinities and NaN
WIDE = st.one_of(st.sampled_from(TINY + HUGE), st.floats(allow_nan=False, allow_infinity=False))
HOSTILE_NUMBERS = Numbers(
    real=WIDE, positive=st.one_of(st.sampled_from((5e-324, 1e300)), st.floats(1e-300, 1e300)),
    value=st.one_of(WIDE, WIDE, st.sampled_from((math.nan, math.inf, -math.inf))))


def vector(size: int, of):
    return st.lists(of, min_size=size, max_size=size)


@st.composite
def rotation(draw, dimension: int):
    if dimension == 2:
        return rotation_2d(draw(angle))
    return rotation_from_rpy(draw(angle), draw(angle), draw(angle))


@st.composite
def placement(draw, dimension: int, real):
    return hx.spatial.Placement(draw(vector(dimension, real)),
                                draw(st.none() | rotation(dimension)))


@st.composite
def law(draw, numbers: Numbers):
    kind = draw(st.sampled_from(("constant", "polynomial", "harmonic", "spline")))
    real = numbers.real
    if kind == "constant":
        return hx.scene.Constant(draw(numbers.value))
    if kind == "polynomial":
        return hx.scene.Polynomial(draw(st.lists(numbers.value, min_size=1, max_size=4)),
                                   draw(real))
    if kind == "harmonic":
        return hx.scene.Harmonic(draw(real), draw(st.lists(real, max_size=3)),
                                 draw(st.lists(real, max_size=3)), draw(numbers.positive),
                                 draw(real))
    steps = draw(st.lists(st.floats(0.1, 2.0), min_size=4, max_size=6))
    boundary = draw(st.one_of(BOUNDARIES, text) if numbers is HOSTILE_NUMBERS else BOUNDARIES)
    return hx.scene.Spline(tuple(np.cumsum(steps)), draw(vector(len(steps), st.floats(-3, 3))),
                           boundary=boundary)


@st.composite
def body(draw, dimension: int, name, serial: str, numbers: Numbers):
    kind = draw(st.sampled_from(("rigid", "rigid", "particle")))
    real, positive = numbers.real, numbers.positive
    frames = (st.builds(hx.spatial.Placement, vector(dimension, real)) if kind == "particle"
              else placement(dimension, real))  # a particle's markers have no rotation
    common = dict(position=draw(vector(dimension, real)),
                  velocity=draw(vector(dimension, real)),
                  markers=draw(st.dictionaries(name, frames, max_size=2)),
                  mesh=draw(st.just("") | text))
    if kind == "particle":
        return hx.scene.Particle(draw(name) + serial, draw(positive), **common)
    if dimension == 2:
        return hx.scene.PlanarBody(draw(name) + serial, draw(positive), draw(positive),
                                   angle=draw(real), com=draw(vector(2, real)),
                                   angular_velocity=draw(real), **common)
    scale = draw(positive)
    moments = [scale * draw(st.floats(0.6, 1.0)) for _ in range(3)]  # triangle inequality
    return hx.scene.SpatialBody(draw(name) + serial, draw(positive), moments,
                                com=draw(vector(3, real)), rotation=draw(rotation(3)),
                                angular_velocity=draw(vector(3, real)), **common)


def on(draw, owner, where):
    """A reference on a body: one of its markers, ``where`` (a frame or a point), or none."""
    markers = list(getattr(owner, "markers", {}))
    choices = [st.none(), where] + ([st.sampled_from(markers)] if markers else [])
    return draw(st.one_of(*choices))


def joints(draw, dimension: int, bodies, name, serials, real) -> list:
    """A tree: each body hinged (or slid) on the ground or an earlier body."""
    out = []
    for k, child in enumerate(bodies):
        parent = draw(st.sampled_from([None] + bodies[:k]))
        options = dict(parent_frame=on(draw, parent, placement(dimension, real)),
                       child_frame=on(draw, child, placement(dimension, real)))
        particle = any(isinstance(b, hx.scene.Particle) for b in (parent, child))
        if particle:  # it has no orientation: no axis to turn about, none to slide along
            kind = hx.scene.Spherical if dimension == 3 else hx.scene.Revolute
        else:
            kind = draw(st.sampled_from((hx.scene.Revolute, hx.scene.Prismatic)))
        if kind is hx.scene.Prismatic or (kind is hx.scene.Revolute and dimension == 3):
            options["axis"] = draw(vector(dimension, st.floats(0.1, 1)))
        if kind in (hx.scene.Prismatic, hx.scene.Revolute):  # a range, or none
            options["limits"] = draw(st.none() | st.tuples(real, real).map(sorted).filter(
                lambda pair: pair[0] < pair[1]))
        out.append(kind(draw(name) + next(serials), parent.name if parent else "ground",
                        child.name, **options))
    return out


@st.composite
def scenes(draw):
    dimension = draw(st.sampled_from((2, 3)))
    # a clean scene has valid names and numbers in range (tiny ones included); a hostile one
    # names from any text, numbers of any size, infinities and NaN
    hostile = draw(st.booleans())
    name, numbers = ((st.one_of(valid_name, text), HOSTILE_NUMBERS) if hostile
                     else (valid_name, CLEAN))
    real, positive = numbers.real, numbers.positive
    scene = hx.Scene(draw(text if hostile else st.one_of(valid_name, line)), dimension,
                     draw(st.sampled_from(list(hx.scene.LENGTH_UNITS))),
                     gravity=draw(st.none() | vector(dimension, real)),
                     characteristic_length=draw(st.none() | positive),
                     report_forces=draw(st.booleans()))
    serials = (str(k) for k in range(100))  # names made distinct (a duplicate is refused)
    bodies = [draw(body(dimension, name, next(serials), numbers))
              for _ in range(draw(st.integers(1, 3)))]
    scene.add(*bodies)
    tree = joints(draw, dimension, bodies, name, serials, real)
    scene.add(*tree)
    drivable = [j for j in tree if j.drivable]
    if drivable and draw(st.booleans()):
        scene.add(hx.scene.JointDriver(draw(name) + next(serials), drivable[0].name,
                                       draw(law(numbers))))
    if drivable and draw(st.booleans()):
        scene.add(hx.scene.JointEffort(draw(name) + next(serials), drivable[-1].name,
                                       draw(law(numbers))))
    if draw(st.booleans()):
        other = draw(st.sampled_from([None, *bodies[1:]]))
        scene.add(hx.scene.SpringDamper(draw(name) + next(serials), bodies[0].name,
                                        other.name if other else "ground",
                                        point_a=on(draw, bodies[0], vector(dimension, real)),
                                        stiffness=draw(positive), damping=draw(positive),
                                        free_length=draw(st.none() | positive),
                                        force=draw(st.none() | law(numbers))))
    if draw(st.booleans()):
        scene.add(hx.scene.AppliedForce(draw(name) + next(serials), bodies[-1].name,
                                        tuple(draw(law(numbers)) for _ in range(dimension)),
                                        point=draw(st.none() | vector(dimension, real)),
                                        frame=draw(st.sampled_from(("world", "body")))))
    return scene


# ------------------------------------------------------------------ the property

def _rotations(value):
    """Rotation tables as matrices: roll, pitch and yaw are recomputed on each writing."""
    if isinstance(value, dict):
        if set(value) == {"rpy"}:
            return rotation_from_rpy(*value["rpy"]).tolist()
        return {key: _rotations(item) for key, item in value.items()}
    if isinstance(value, list):
        return [_rotations(item) for item in value]
    return value


def _same(first, second, where="document"):
    """Equal documents: the same keys, strings and integers; floats to round-off (a planar
    rotation angle modulo 2 pi)."""
    assert type(first) is type(second), where
    if isinstance(first, dict):
        assert list(first) == list(second), where
        for key in first:
            a, b = first[key], second[key]
            if key == "rotation" and isinstance(a, float):
                a, b = [math.cos(a), math.sin(a)], [math.cos(b), math.sin(b)]
            _same(a, b, f"{where}.{key}")
    elif isinstance(first, list):
        assert len(first) == len(second), where
        for k, (a, b) in enumerate(zip(first, second, strict=True)):
            _same(a, b, f"{where}[{k}]")
    elif isinstance(first, float):
        assert math.isclose(first, second, rel_tol=1e-12, abs_tol=1e-12), \
            f"{where}: {first!r} != {second!r}"
    else:
        assert first == second, f"{where}: {first!r} != {second!r}"


def _bad_name(scene: hx.Scene):
    """The first element or marker name outside the rule, and its first bad character."""
    names = [e.name for e in scene.elements]
    names += [m for b in scene.bodies.values() for m in b.markers]
    for drawn in names:
        outside = [c for c in drawn if c not in ALLOWED]
        if outside:
            return drawn, outside[0]
    return None, None


def _round_trip(scene: hx.Scene) -> str:
    """Write ``scene``; either it is refused for a reason, or it reads back as itself."""
    with np.errstate(all="ignore"):
        problems = scene.problems()
    try:
        written = scene_text(scene)
    except HexapodError as error:
        message = str(error)
        if not problems:  # a valid scene is refused only for text no file can hold
            assert "lone surrogate" in message, message
            return "refused: unwritable text"
        assert str(problems[0]) in message
        drawn, bad = _bad_name(scene)
        if bad is not None:  # the refusal names the character
            assert f"U+{ord(bad):04X}" in message, message
        return "refused: invalid"
    assert not problems, problems
    written = written.encode("utf-8").decode("utf-8")  # as a file holds it
    copy = scene_from_document(tomllib.loads(written), "drawn.toml")  # reads without a problem
    assert copy.name == scene.name
    assert [(e.name, e.kind) for e in copy.elements] == [
        (e.name, e.kind) for e in scene.elements]
    _same(_rotations(tomllib.loads(written)), _rotations(tomllib.loads(scene_text(copy))))
    return "written"


def test_every_written_scene_reads_back_and_every_other_is_refused():
    outcomes = Counter()

    @ROUND_TRIP
    @given(scenes())
    def property_holds(scene):
        outcomes[_round_trip(scene)] += 1

    property_holds()
    # the strategy reaches both sides: scenes written and read back, scenes refused
    assert outcomes["written"] >= 20 and outcomes["refused: invalid"] >= 20, outcomes
