"""The public face: ``hexapod.__all__`` holds the pipeline and what users call, every name of
every public ``__all__`` resolves, and every public name of ``hexapod`` and of the namespaces
``hexapod.scene``, ``hexapod.output``, ``hexapod.simulation`` and ``hexapod.spatial`` is
documented (numpydoc ``Parameters`` and ``Returns`` sections naming what it takes and gives)
and typed.

The rules are functions from an object to its problems, so that the last test can show that
each catches what it forbids.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import re
import types

import pytest

import hexapod

#: The namespaces whose names carry the full numpydoc sections.
DOCUMENTED = ("scene", "output", "simulation", "spatial")
#: The most names ``hexapod.__all__`` may hold.
LARGEST_TOP = 60
SECTION = re.compile(r"^(\w[\w ]*)\n-{3,}\n", flags=re.M)


def namespaces() -> dict[str, types.ModuleType]:
    """``hexapod`` and the public namespaces it lists."""
    out = {"hexapod": hexapod}
    for name in hexapod.__all__:
        value = getattr(hexapod, name)
        if inspect.ismodule(value):
            out[f"hexapod.{name}"] = value
    return out


def public_objects() -> dict[str, object]:
    """The documented public names (each object once, by its first public name), modules
    left out."""
    out: dict[str, object] = {}
    seen: set[int] = set()
    spaces = {"hexapod": hexapod} | {f"hexapod.{n}": importlib.import_module(f"hexapod.{n}")
                                      for n in DOCUMENTED}
    for space, module in spaces.items():
        for name in module.__all__:
            value = getattr(module, name)
            if inspect.ismodule(value) or id(value) in seen:
                continue
            seen.add(id(value))
            out[f"{space}.{name}"] = value
    return out


def sections(doc: str) -> dict[str, str]:
    """The numpydoc sections of a docstring by title (the text before the first: ``""``)."""
    doc = inspect.cleandoc(doc)
    out = {}
    parts = SECTION.split(doc)
    out[""] = parts[0]
    for title, body in zip(parts[1::2], parts[2::2], strict=True):
        out[title.strip()] = body
    return out


def named(section: str) -> set[str]:
    """The names a Parameters or Attributes section documents: the entries at its left
    margin, ``name : type``, ``a, b : type`` or a bare ``name``."""
    out = set()
    for line in section.splitlines():
        match = re.match(r"(\*{0,2}\w+(?:\s*,\s*\*{0,2}\w+)*)\s*(?::|$)", line)
        if match:
            out |= {word.strip().lstrip("*") for word in match.group(1).split(",")}
    return out


def _signature(value) -> inspect.Signature | None:
    try:
        return inspect.signature(value)
    except (TypeError, ValueError):  # a class with the built-in __init__ (an exception)
        return None


def _returns_nothing(annotation) -> bool:
    return annotation is None or annotation == "None"


def problems(name: str, value) -> list[str]:
    """What the public ``value`` lacks: a docstring with a summary line; a ``Parameters``
    (classes: or ``Attributes``) section naming every parameter; for a function a ``Returns``
    (or ``Yields``) section unless it returns None, and annotations on every parameter and on
    the return."""
    if not callable(value):
        return []
    doc = inspect.getdoc(value) or ""
    if not doc.strip() or not doc.splitlines()[0].strip():
        return [f"{name}: no summary line"]
    found = sections(doc)
    signature = _signature(value)
    if signature is None:
        return []
    is_class = isinstance(value, type)
    parameters = [p for p in signature.parameters.values() if p.name not in ("self", "cls")]
    out = []
    if parameters:
        titles = ("Parameters", "Attributes") if is_class else ("Parameters",)
        documented = set().union(*(named(found[t]) for t in titles if t in found))
        if not any(t in found for t in titles):
            out.append(f"{name}: no {' or '.join(titles)} section")
        else:
            out += [f"{name}: parameter {p.name!r} is not documented" for p in parameters
                    if p.name not in documented]
    out += [f"{name}: parameter {p.name!r} has no type hint" for p in parameters
            if p.annotation is inspect.Parameter.empty]
    if not is_class:
        if signature.return_annotation is inspect.Signature.empty:
            out.append(f"{name}: no return type hint")
        elif not _returns_nothing(signature.return_annotation) and not (
                {"Returns", "Yields"} & set(found)):
            out.append(f"{name}: no Returns section")
    return out


# ------------------------------------------------------------------ the public face obeys them

def test_the_top_level_holds_the_pipeline_and_no_more():
    top = set(hexapod.__all__)
    assert len(top) <= LARGEST_TOP, f"hexapod.__all__ has {len(top)} names"
    assert {"Scene", "assemble", "Model", "Data", "forward_dynamics", "inverse_dynamics",
            "simulate", "scene", "output", "spatial", "simulation"} <= top
    # scene elements, report plumbing, frames and defaults live in their namespaces
    for space, names in {"scene": ["Revolute", "Harmonic", "GROUND", "Motion", "urdf_text"],
                         "output": ["png_bytes", "write_atomically", "inverse_table"],
                         "spatial": ["Placement", "rotation_about_axis"],
                         "simulation": ["DEFAULT_METHOD", "DEFAULT_RTOL", "DEFAULT_ATOL"]
                         }.items():
        assert not top & set(names)
        assert set(names) <= set(getattr(hexapod, space).__all__)


def test_every_name_of_every_public_all_resolves():
    for space, module in namespaces().items():
        for name in module.__all__:
            assert getattr(module, name) is not None, f"{space}.{name}"
        assert set(module.__all__) <= set(dir(module)), space
    assert hexapod.scene.Scene is hexapod.Scene
    assert inspect.ismodule(hexapod.scene) and hexapod.scene.__name__ == "hexapod.scene"


@pytest.mark.parametrize("name", sorted(public_objects()))
def test_every_public_name_is_documented_and_typed(name):
    assert problems(name, public_objects()[name]) == []


# ------------------------------------------------------------------ the rules can fail

def test_the_rules_catch_what_they_forbid():
    def bare(a, b: int = 1):
        return a

    def half(a: float, b: float) -> float:
        """Half a sum.

        Parameters
        ----------
        a : float
        """
        return (a + b) / 2

    def quiet(a: int) -> None:
        """Nothing back.

        Parameters
        ----------
        a : int
            Ignored.
        """

    @dataclasses.dataclass
    class Point:
        """A point.

        Attributes
        ----------
        x, y : float
            Coordinates, m.
        """

        x: float
        y: float
        z: float = 0.0

    assert problems("bare", bare) == ["bare: no summary line"]
    bare.__doc__ = "Something."
    assert problems("bare", bare) == ["bare: no Parameters section",
                                      "bare: parameter 'a' has no type hint",
                                      "bare: no return type hint"]
    assert problems("half", half) == ["half: parameter 'b' is not documented",
                                      "half: no Returns section"]
    assert problems("quiet", quiet) == []
    assert problems("Point", Point) == ["Point: parameter 'z' is not documented"]
    assert named("a, *args : int\n    Text.\nb\n    More: text.\n") == {"a", "args", "b"}
