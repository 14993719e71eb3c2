"""Expression laws: values, exact derivatives, shapes and pickling; scene files that hold them
(read, assembled, written back); and the errors of malformed expressions."""

from __future__ import annotations

import math
import pickle

import casadi as ca
import numpy as np
import pytest
from scene_documents import write_scene

import hexapod
from hexapod.model.assemble import assemble
from hexapod.scene.expression import DEEPEST, LONGEST, ExpressionError, parse
from hexapod.scene.laws import LAW_TYPES, Expression, Scaled
from hexapod.scene.reader import read_scene
from hexapod.scene.writer import scene_text
from hexapod.scene.writer import write_scene as write_scene_file

TIMES = np.linspace(0.0123, 1.9877, 41)
ROAD = {"r": 0.1, "w": 10.0}


def road(t):
    """The car-axis road law asin(r sin(w t)) and its derivatives, in closed form."""
    r, w = ROAD["r"], ROAD["w"]
    s, sd, sdd = r * np.sin(w * t), r * w * np.cos(w * t), -r * w * w * np.sin(w * t)
    root = np.sqrt(1 - s * s)
    return np.arcsin(s), sd / root, sdd / root + sd * sd * s / root**3


#: expression, constants, the same in NumPy, and the times near which it has a kink
CASES = [
    ("asin(r*sin(w*t))", ROAD, lambda t: np.arcsin(0.1 * np.sin(10 * t)), ()),
    ("-t^2", {}, lambda t: -(t**2), ()),
    ("2^3^2", {}, lambda t: np.full_like(t, 512.0), ()),
    ("t**3 - 2*t**2 + t/4 - -t + +1", {}, lambda t: t**3 - 2 * t**2 + t / 4 + t + 1, ()),
    ("exp(-t/tau) * cos(2*pi*f*t)", {"tau": 0.5, "f": 1.5},
     lambda t: np.exp(-t / 0.5) * np.cos(2 * np.pi * 1.5 * t), ()),
    ("sqrt(1 + t^2) * log(2 + t)", {}, lambda t: np.sqrt(1 + t**2) * np.log(2 + t), ()),
    ("atan2(sin(t), cos(t) + 2)", {}, lambda t: np.arctan2(np.sin(t), np.cos(t) + 2), ()),
    ("min(t, 1) + max(t^2, 0.5)", {}, lambda t: np.minimum(t, 1) + np.maximum(t**2, 0.5),
     (1.0, math.sqrt(0.5))),
    ("abs(t - 1)^3", {}, lambda t: np.abs(t - 1) ** 3, (1.0,)),
    ("if_else(t < 1 && t > 0.5 || t >= 1.5, sinh(t), cosh(t))", {},
     lambda t: np.where(((t < 1) & (t > 0.5)) | (t >= 1.5), np.sinh(t), np.cosh(t)),
     (0.5, 1.0, 1.5)),
    ("if_else(!(t < 1), 1 - t, tanh(3*(t - 1)))", {},
     lambda t: np.where(t >= 1, 1 - t, np.tanh(3 * (t - 1))), (1.0,)),
    ("atan(t) - acos(t/4) + tan(t/3) + sin(cos(exp(t/2)))", {},
     lambda t: np.arctan(t) - np.arccos(t / 4) + np.tan(t / 3) + np.sin(np.cos(np.exp(t / 2))),
     ()),
    ("2^-t * e^t / pi + 1e-3*t + 2.5E+1 + .5", {},
     lambda t: 2.0**-t * np.e**t / np.pi + 1e-3 * t + 25.0 + 0.5, ()),
    ("(1 + t)^-0.5 * a_1", {"a_1": 3.0}, lambda t: 3.0 * (1 + t) ** -0.5, ()),
]
IDS = [case[0] for case in CASES]


def smooth_times(kinks) -> np.ndarray:
    """TIMES away from the kinks, where differences straddling them mean nothing."""
    if not kinks:
        return TIMES
    return TIMES[np.min(np.abs(TIMES[:, None] - np.array(kinks)), axis=1) > 0.01]


@pytest.mark.parametrize("expression, constants, reference, kinks", CASES, ids=IDS)
def test_values_match_numpy(expression, constants, reference, kinks):
    f = Expression(expression, constants).evaluate(TIMES)[0]
    np.testing.assert_allclose(f, reference(TIMES), rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("expression, constants, reference, kinks", CASES, ids=IDS)
def test_derivatives_match_finite_differences(expression, constants, reference, kinks):
    law = Expression(expression, constants)
    t = smooth_times(kinks)
    f, fd, fdd = law.evaluate(t)
    # f' against the central difference of f with h = 1e-4: truncation h^2/6 |f'''| (at most
    # 2e-7 here, |f'''| < 1e2) and round-off eps |f| / h (2e-12 |f|), so 1e-6 of the scale.
    h = 1e-4
    fd_num = (law(t + h) - law(t - h)) / (2 * h)
    assert np.max(np.abs(fd - fd_num)) <= 1e-6 * max(1.0, np.max(np.abs(fd)), np.max(np.abs(f)))
    # f'' against the second difference of f with h = 1e-3: truncation h^2/12 |f''''| (at most
    # 1e-4 here, |f''''| < 1e3) and round-off 4 eps |f| / h^2 (1e-9 |f|), so 1e-4 of the scale.
    h = 1e-3
    fdd_num = (law(t + h) - 2 * f + law(t - h)) / h**2
    assert np.max(np.abs(fdd - fdd_num)) <= 1e-4 * max(1.0, np.max(np.abs(fdd)),
                                                      np.max(np.abs(f)))


def test_derivatives_are_exact():
    for got, exact in zip(Expression("asin(r*sin(w*t))", ROAD).evaluate(TIMES), road(TIMES),
                          strict=True):
        np.testing.assert_allclose(got, exact, rtol=1e-13, atol=1e-13)
    f, fd, fdd = Expression("3*t^4 - t").evaluate(TIMES)
    np.testing.assert_allclose(fd, 12 * TIMES**3 - 1, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(fdd, 36 * TIMES**2, rtol=1e-14)
    # if_else differentiates the branch it takes; the NaN of the other does not leak
    f, fd, fdd = Expression("if_else(t > 0, sqrt(t), 0)").evaluate(np.array([-1.0, 4.0]))
    np.testing.assert_array_equal(f, [0.0, 2.0])
    np.testing.assert_array_equal(fd, [0.0, 0.25])
    np.testing.assert_array_equal(fdd, [0.0, -1 / 32])


def test_precedence():
    def value(text):
        return float(Expression(text).evaluate(3.0)[0])

    assert value("2^3^2") == 512.0
    assert value("2**3**2") == 512.0
    assert value("-t^2") == -9.0
    assert value("(-t)^2") == 9.0
    assert value("2^-1*4") == 2.0  # (2^-1)*4, as in Python
    assert value("1 - 2 - 3") == -4.0
    assert value("12 / 2 / 3") == 2.0
    assert value("1 + 2 * 3") == 7.0
    assert value("if_else(t > 2 && t < 4 || t == 0, 1, 2)") == 1.0
    assert value("if_else(!(t > 2) || t != 3, 1, 2)") == 2.0


def test_shapes():
    law = Expression("asin(r*sin(w*t))", ROAD)
    for t in (0.3, np.float64(0.3), np.array(0.3)):
        out = law.evaluate(t)
        assert all(isinstance(x, np.ndarray) and x.shape == () for x in out)
        np.testing.assert_allclose([float(x) for x in out], [float(x) for x in road(0.3)],
                                   rtol=1e-14)
    for shape in ((7,), (3, 4), (2, 1, 3), (0,)):
        t = np.linspace(0, 1, math.prod(shape)).reshape(shape)
        out = law.evaluate(t)
        assert [x.shape for x in out] == [shape] * 3
        for got, exact in zip(out, road(t), strict=True):
            np.testing.assert_allclose(got, exact, rtol=1e-13, atol=1e-15)
    # a constant expression is an array shaped like t too
    assert [x.shape for x in Expression("pi").evaluate(np.zeros((2, 2)))] == [(2, 2)] * 3


def test_symbolic_forms_are_the_law():
    law = Expression("asin(r*sin(w*t))", ROAD)
    for kind in (ca.SX, ca.MX):
        t = kind.sym("t")
        function = ca.Function("f", [t], list(law.symbolic(t)))
        got = [float(x) for x in function(0.7)]
        np.testing.assert_allclose(got, [float(x) for x in road(0.7)], rtol=1e-14)
    got = [float(x) for x in Scaled(law, -2.0).symbolic(ca.SX(0.7))]
    np.testing.assert_allclose(got, [-2 * float(x) for x in road(0.7)], rtol=1e-14)


def test_the_law_is_a_value():
    law = Expression("asin(r*sin(w*t))", {"w": 10, "r": 0.1}, period=2 * math.pi / 10)
    assert LAW_TYPES["expression"] is Expression and law.kind == "expression"
    assert law.constants == (("r", 0.1), ("w", 10.0))  # sorted pairs: hashable, comparable
    assert law == Expression("asin(r*sin(w*t))", (("w", 10.0), ("r", 0.1)), 2 * math.pi / 10)
    law.evaluate(0.1)  # compiled: the cached function takes no part in comparisons
    assert hash(law) == hash(Expression("asin(r*sin(w*t))", ROAD, 2 * math.pi / 10))
    assert "_function" not in repr(law)
    assert law.cycle_time() == 2 * math.pi / 10
    assert Expression("t").cycle_time() is None
    scaled = law.scaled(1e-3)
    assert isinstance(scaled, Expression) and scaled.cycle_time() == law.cycle_time()
    np.testing.assert_allclose(scaled.evaluate(TIMES), 1e-3 * np.array(road(TIMES)),
                               rtol=1e-13)


def test_pickle_round_trip():
    law = Expression("asin(r*sin(w*t)) + if_else(t < 1, t^3, 3*t - 2)", ROAD, period=1.0)
    before = law.evaluate(TIMES)  # compiled: the function is not pickled, but built again
    copy = pickle.loads(pickle.dumps(law))
    assert copy == law
    for got, expected in zip(copy.evaluate(TIMES), before, strict=True):
        np.testing.assert_array_equal(got, expected)
    fresh = pickle.loads(pickle.dumps(Expression("t^2")))
    assert float(fresh.evaluate(3.0)[0]) == 9.0


def test_problems_of_the_law_itself():
    def problems(*args, **kwargs):
        return Expression(*args, **kwargs).problems()

    assert problems("asin(r*sin(w*t))", ROAD) == []
    assert problems("asin(2)") == []  # NaN is the user's: found when evaluated, not here
    assert problems("w*t", {"w": math.nan}) == ["constants: 'w' is not finite: nan"]
    assert "beyond the 1e15" in problems("w*t", {"w": 1e16})[0]
    assert "taken by a function" in problems("t", {"sin": 1.0})[0]
    assert "taken by the time" in problems("1", {"t": 1.0})[0]
    assert "not a name" in problems("t", {"2w": 1.0})[0]
    assert "given twice" in problems("w*t", (("w", 1.0), ("w", 2.0)))[0]
    assert "at most 1000" in problems("t", {f"c{k}": 1.0 for k in range(1001)})[0]
    assert problems("t", period=0.0) == ["period must be positive and finite, got 0.0"]
    assert problems("sinn(t)")[0].startswith("expression: at character 1: unknown function")
    with pytest.raises(ValueError, match="expression law is invalid"):
        Expression("t +").evaluate(0.0)


# ------------------------------------------------------------------ scene files

SCENE = """
[scene]
name = "road"
dimension = 2
length_unit = "mm"

[[body]]
name = "axle"
mass = 1.0
inertia = 83300.0
com = [500.0, 0.0]

[[body]]
name = "block"
mass = 2.0
inertia = 10.0
position = [0.0, -100.0]

[[joint]]
name = "hinge"
type = "revolute"
parent = "ground"
child = "axle"

[[driver]]
name = "road"
joint = "hinge"
law = {LAW}

[[driver]]
name = "slide"
body = "block"
coordinate = "x"
law = { type = "expression", expression = "5*t^2 +\\n c", constants = { c = 1 } }

[[force]]
name = "damper"
type = "effort"
joint = "hinge"
law = { type = "expression", expression = "if_else(t < 1, -0.2*t, -0.2)" }
"""
ROAD_LAW = ('{ type = "expression", expression = "asin(r*sin(w*t))", '
            'constants = { r = 0.1, w = 10 }, period = 0.6283185307179586 }')


def scene_file(tmp_path, law: str, name: str = "road"):
    return write_scene(tmp_path, name, SCENE.replace("{LAW}", law))


def test_a_scene_with_expression_laws_assembles_and_reads_back(tmp_path):
    scene = read_scene(scene_file(tmp_path, ROAD_LAW))
    law = scene.elements[3].law
    assert law == Expression("asin(r*sin(w*t))", ROAD, period=0.6283185307179586)
    model = assemble(scene)
    assert model.cycle_time() == pytest.approx(0.6283185307179586)
    t = np.array([0.0, 0.1, 0.37])
    w, wd, wdd = model.law_values(t)
    for got, exact in zip((w[0], wd[0], wdd[0]), road(t), strict=True):  # an angle: unscaled
        np.testing.assert_allclose(got, exact, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(w[1], 1e-3 * (5 * t**2 + 1), rtol=1e-13)  # mm to m
    np.testing.assert_allclose(wdd[1], 1e-2, rtol=1e-13)
    data = model.create_data()
    q = hexapod.assemble_positions(model, data, 0.37)
    assert q[2] == pytest.approx(float(road(0.37)[0]), abs=1e-10)  # the rod's angle
    # written back, the file reads as the same scene
    path = write_scene_file(scene, tmp_path / "written.toml")
    again = read_scene(path)
    assert [e.law for e in again.elements[3:]] == [e.law for e in scene.elements[3:]]
    assert scene_text(again) == scene_text(scene)


def test_a_scaled_expression_law_is_written_as_an_expression(tmp_path):
    scene = read_scene(scene_file(tmp_path, ROAD_LAW))
    scene.elements[3].law = Scaled(scene.elements[3].law, 0.5)
    again = read_scene(write_scene_file(scene, tmp_path / "scaled.toml"))
    law = again.elements[3].law
    assert isinstance(law, Expression) and law.expression == "0.5*(asin(r*sin(w*t)))"
    np.testing.assert_allclose(law.evaluate(TIMES), 0.5 * np.array(road(TIMES)), rtol=1e-13)


def test_an_invalid_expression_law_is_not_written(tmp_path):
    scene = read_scene(scene_file(tmp_path, ROAD_LAW))
    scene.elements[3].law = Expression("asin(r*sin(w*t)", ROAD)
    with pytest.raises(hexapod.ModelError, match="expression: at character 16"):
        scene_text(scene)


#: malformed expressions: the text, the character named and a fragment of the message
MALFORMED = [
    ("", 1, "the expression is empty"),
    ("   ", 1, "the expression is empty"),
    ("sin(", 5, "but the expression ends"),
    ("t +", 4, "but the expression ends"),
    ("sinn(t)", 1, "unknown function 'sinn' (known: sin, cos,"),
    ("t $ 2", 3, "unexpected '$'"),
    ("1e999", 1, "not finite"),
    ("2*w*t", 3, "unknown name 'w' (not t, pi, e or a constant)"),
    ("atan2(t)", 1, "'atan2' takes 2 arguments, got 1"),
    ("sin(t, 1)", 1, "'sin' takes 1 argument, got 2"),
    ("t < 1", 3, "comparison '<' outside if_else"),
    ("if_else(t, 1, 2)", 1, "must be a condition"),
    ("0 < t < 1", 7, "cannot be chained"),
    ("t" + "+t" * (LONGEST // 2), LONGEST + 1, "longer than 10,000 characters"),
    ("(" * 200 + "t" + ")" * 200, DEEPEST + 1, "nested more than 100 levels deep"),
    ("-" * 200 + "t", DEEPEST + 1, "nested more than 100 levels deep"),
    ("2^" * 200 + "t", 2 * DEEPEST + 2, "nested more than 100 levels deep"),
    ("(t + 1))", 8, "unbalanced ')'"),
    ("sin(2*(t + 1)", 14, "expected ',' or ')' to close the '(' at character 4"),
    ("2t", 1, "malformed number '2t'"),
    ("t = 1", 3, "unexpected '='"),
    ("sin", 1, "needs its arguments in parentheses"),
    ("1e20*t", 1, "beyond the 1e15"),
]


@pytest.mark.parametrize("text, position, fragment", MALFORMED,
                         ids=[repr(m[0][:20]) for m in MALFORMED])
def test_a_malformed_expression_is_one_clear_error(tmp_path, text, position, fragment):
    with pytest.raises(ExpressionError) as info:
        parse(text, largest=1e15)  # as the law parses it
    assert info.value.position == position and fragment in str(info.value), str(info.value)
    # read from a file: one problem, naming the file, the key and the character
    law = '{ type = "expression", expression = ' + scene_text_string(text) + " }"
    path = scene_file(tmp_path, law)
    with pytest.raises(hexapod.ModelError) as info:
        read_scene(path)
    (problem,) = info.value.problems
    assert problem.where == f"{path}, driver[0].law"
    assert problem.message.startswith(f"expression: at character {position}: ")
    assert fragment in problem.message
    assert str(path) in str(info.value)


def scene_text_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


@pytest.mark.parametrize("law, key, fragment", [
    ('{ type = "expression" }', "driver[0].law", "an expression law needs expression"),
    ('{ type = "expression", expression = 1.0 }', "driver[0].law", "expression must be a string"),
    ('{ type = "expression", expression = "t", constants = [1] }', "driver[0].law",
     "constants must be a table of names and numbers"),
    ('{ type = "expression", expression = "w*t", constants = { w = "ten" } }', "driver[0].law",
     "constants.w must be a number"),
    ('{ type = "expression", expression = "w*t", constants = { w = nan } }', "driver[0].law",
     "constants: 'w' is not finite"),
    ('{ type = "expression", expression = "t", constants = { sin = 1 } }', "driver[0].law",
     "constants: constant name 'sin' is taken by a function"),
    ('{ type = "expression", expression = "t", period = -1 }', "driver[0].law",
     "period must be positive"),
    ('{ type = "expression", expression = "t", frequency = 1 }', "driver[0].law",
     "unknown key(s) frequency for an expression law (expected expression, constants, period)"),
])
def test_bad_keys_of_an_expression_law(tmp_path, law, key, fragment):
    path = scene_file(tmp_path, law)
    with pytest.raises(hexapod.ModelError) as info:
        read_scene(path)
    (problem,) = info.value.problems
    assert problem.where == f"{path}, {key}" and fragment in problem.message, problem


def test_long_expressions_are_translated_without_recursion():
    text = "+".join(["t"] * (LONGEST // 2))  # a left-leaning tree 5000 deep
    assert float(Expression(text).evaluate(2.0)[0]) == 2.0 * (LONGEST // 2)
    text = "-(" * 50 + "t" + ")" * 50  # 100 levels: the deepest allowed
    assert float(Expression(text).evaluate(2.0)[0]) == 2.0
