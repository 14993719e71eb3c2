"""The light catalogue of integrators and problems the command line reads (its help loads neither
CasADi nor SciPy) agrees with what the classes and the studies declare."""

from __future__ import annotations

import inspect
from pathlib import Path

import hexapod
from hexapod import catalog
from hexapod.benchmarks import work_precision
from hexapod.simulation import methods, registry
from hexapod.simulation.integrators import Integrator
from hexapod.simulation.registry import INTEGRATORS

SCENES = Path(__file__).resolve().parent.parent / "data" / "scenes"


def test_the_catalogue_is_the_registry():
    assert list(methods.METHODS) == list(INTEGRATORS)
    for name, cls in INTEGRATORS.items():
        declared = methods.Method(cls.order, cls.index, cls.adaptive, cls.stabilisation)
        assert methods.METHODS[name] == declared, name


def test_the_registry_table_is_the_catalogue():
    """The table of registry.py's docstring: a row per method, in order, with METHODS' order,
    index and step control."""
    lines = registry.__doc__.splitlines()
    borders = [i for i, line in enumerate(lines) if line.startswith("=====")]
    rows = [line.split() for line in lines[borders[1] + 1:borders[-1]] if line.startswith("``")]
    assert [row[0].strip("`") for row in rows] == list(methods.METHODS)
    for row in rows:
        method = methods.METHODS[row[0].strip("`")]
        step = "adaptive" if method.adaptive else "fixed"
        assert (int(row[1]), int(row[2]), row[3]) == (method.order, method.index, step), row


def test_the_summaries_say_what_the_classes_declare():
    summary = methods.METHODS["rk4-baumgarte"].summary()
    assert summary == ("order 4, index 1, fixed step, Baumgarte (alpha = beta), Euler parameters "
                       "renormalised")
    for name, cls in INTEGRATORS.items():
        step = "adaptive" if cls.adaptive else "fixed step"
        assert methods.METHODS[name].summary() == \
            f"order {cls.order}, index {cls.index}, {step}, {cls.stabilisation}"


def test_defaults_are_written_once():
    for name in ("DEFAULT_METHOD", "DEFAULT_RTOL", "DEFAULT_ATOL"):
        assert getattr(registry, name) is getattr(methods, name)
    assert methods.DEFAULT_METHOD in INTEGRATORS
    assert work_precision.PROBLEMS is catalog.PROBLEMS
    for parameter in ("rtol", "atol"):
        default = inspect.signature(Integrator.__init__).parameters[parameter].default
        assert default is getattr(methods, f"DEFAULT_{parameter.upper()}")


def test_the_command_line_defaults_are_the_constants():
    from hexapod.cli.app import build_parser

    args = build_parser().parse_args(["simulate"])
    # the method, tolerances left unset, so that simulate() applies the defaults (the method:
    # the scene's, a contact scheme for unilateral contacts; a fixed-step method warns only
    # about tolerances the user gave)
    assert (args.method, args.rtol, args.atol) == (None, None, None)
    pendulum = hexapod.assemble(hexapod.load_scene(SCENES / "pendulum.toml"))
    assert registry.default_method(pendulum) == methods.DEFAULT_METHOD
    assert build_parser().parse_args(["bench"]).problems == list(catalog.PROBLEMS)
