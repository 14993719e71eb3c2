"""The package layout of the README's "Layout" section, enforced: one folder per layer, no upward
import, no cycle, no scene below the model, ``__init__`` files that only re-export, optional
libraries imported lazily, and ``legs/``, ``scripts/`` and the fixture makers (``data/``,
``tests/data/``) on the public API alone.

Each rule is a function from sources to a list of violations, so that the tests below can show
that every rule catches what it forbids (a rule that cannot fail checks nothing).
"""

from __future__ import annotations

import ast
import inspect
import subprocess
import sys
from pathlib import Path

import pytest

import hexapod

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "hexapod"

#: Layer of each top-level module or folder of the package (the README's "Layout" table).
LAYERS = {
    "errors": 0, "spatial": 0, "_support": 0, "_version": 0, "catalog": 0,
    "scene": 1,
    "model": 2,
    "algorithms": 3, "minimal": 3,
    "simulation": 4,
    "output": 5,
    "benchmarks": 6, "sweeps": 6,
    "cli": 7, "__main__": 7,
}
#: The package's own ``__init__`` re-exports the public API: above everything.
TOP = 8
#: Layers that see ``Model`` and ``Data``, never a ``Scene``.
NO_SCENE = ("algorithms", "minimal", "simulation")
LAZY_ONLY = ("matplotlib", "meshio", "dask")


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def layer(module: str) -> int:
    """The layer of ``hexapod.<room>...`` (``hexapod`` itself: TOP)."""
    parts = module.split(".")
    if parts == ["hexapod"]:
        return TOP
    assert parts[1] in LAYERS, f"{module}: hexapod.{parts[1]} has no layer: add it to LAYERS " \
                               "(and to the README's Layout table)"
    return LAYERS[parts[1]]


def imports(source: str) -> list[tuple[str, bool]]:
    """(imported module, at module level) for every absolute import in a source."""
    tree = ast.parse(source)
    top = {id(node) for node in tree.body}
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(alias.name, id(node) in top) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.append((node.module, id(node) in top))
    return out


def package_sources() -> dict[str, str]:
    return {module_name(p): p.read_text() for p in sorted(PACKAGE.rglob("*.py"))}


def packages() -> set[str]:
    return {module_name(p) for p in PACKAGE.rglob("__init__.py")}


# ------------------------------------------------------------------ the rules

def upward_imports(sources: dict[str, str]) -> list[str]:
    """Imports of a higher layer (or of ``legs``, or of a scene below the model)."""
    found = []
    for name, source in sources.items():
        mine = layer(name)
        for target, _ in imports(source):
            root = target.split(".")[0]
            if root == "legs":
                found.append(f"{name} imports {target}: the engine never imports legs")
            if root != "hexapod" or name == "hexapod":
                continue
            if layer(target) > mine:
                found.append(f"{name} (layer {mine}) imports {target} (layer {layer(target)})")
            if name.split(".")[1] in NO_SCENE and target.split(".")[:2] == ["hexapod", "scene"]:
                found.append(f"{name} imports {target}: {name.split('.')[1]}/ sees Model and "
                             "Data, never a Scene")
    return found


def import_cycles(sources: dict[str, str]) -> list[str]:
    """Cycles among the package's modules, by every import (module level or not)."""
    graph = {}
    for name, source in sources.items():
        targets = set()
        for target, _ in imports(source):
            # ``from a.b import c`` may name the module a.b.c
            while target and target not in sources:
                target = target.rpartition(".")[0]
            if target and target != name and not name.startswith(target + "."):
                targets.add(target)
        graph[name] = targets
    state: dict[str, int] = {}
    found = []

    def visit(node, stack):
        state[node] = 1
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                found.append("import cycle: " + " -> ".join(stack + [node, nxt]))
            elif nxt not in state:
                visit(nxt, stack + [node])
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node, [])
    return found


def _is_reexport(node: ast.stmt, package: str) -> bool:
    if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
        return True  # the docstring
    if isinstance(node, ast.ImportFrom):
        return node.level == 0 and (node.module or "").startswith(package.split(".")[0])
    if isinstance(node, ast.Assign):
        names = [t.id for target in node.targets
                 for t in (target.elts if isinstance(target, ast.Tuple) else [target])
                 if isinstance(t, ast.Name)]
        return set(names) <= {"__all__", "__getattr__", "__dir__"}
    return False


def init_logic(sources: dict[str, str], packages: set[str]) -> list[str]:
    """Statements of the ``__init__`` modules of ``packages`` that are not re-exports."""
    found = []
    for name, source in sources.items():
        if name not in packages:
            continue
        for node in ast.parse(source).body:
            if not _is_reexport(node, name):
                found.append(f"{name}/__init__.py line {node.lineno}: not a re-export "
                             f"({type(node).__name__})")
    return found


def private_uses(sources: dict[str, str], public: set[str],
                 namespaces: dict[str, set[str]] | None = None) -> list[str]:
    """Uses of the engine other than ``hexapod.<name in __all__>`` (and ``__version__``), names of
    a public namespace's ``__all__`` (``from hexapod.scene import Revolute``,
    ``hexapod.scene.Revolute``), or the command line's ``from hexapod.cli import main``."""
    namespaces = namespaces or {}
    found = []
    for name, source in sources.items():
        tree = ast.parse(source)
        aliases = {"hexapod"}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.startswith("hexapod."):
                        found.append(f"{name}: import {alias.name}")
                    elif alias.name == "hexapod":
                        aliases.add(alias.asname or "hexapod")
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("hexapod"):
                if node.module == "hexapod.cli" and [a.name for a in node.names] == ["main"]:
                    continue
                space = node.module.partition(".")[2]
                if space in namespaces:
                    found += [f"{name}: hexapod.{space}.{a.name} is not public"
                              for a in node.names if a.name not in namespaces[space]]
                    continue
                if node.module != "hexapod":
                    found.append(f"{name}: from {node.module} import ...")
                    continue
                found += [f"{name}: hexapod.{a.name} is not public" for a in node.names
                          if a.name not in public]
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                    and node.value.id in aliases and node.attr not in public
                    and node.attr != "__version__"):
                found.append(f"{name} line {node.lineno}: hexapod.{node.attr} is not public")
            elif (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Attribute)
                    and isinstance(node.value.value, ast.Name) and node.value.value.id in aliases
                    and node.value.attr in namespaces
                    and node.attr not in namespaces[node.value.attr]):
                found.append(f"{name} line {node.lineno}: hexapod.{node.value.attr}.{node.attr} "
                             "is not public")
    return found


def sources_in(folder: str) -> dict[str, str]:
    return {str(p.relative_to(ROOT)): p.read_text() for p in sorted((ROOT / folder).rglob("*.py"))}


# ------------------------------------------------------------------ the package obeys them

def test_every_module_has_a_layer_and_imports_none_above_it():
    assert upward_imports(package_sources()) == []


def test_no_import_cycle():
    assert import_cycles(package_sources()) == []


def test_no_import_cycle_in_legs():
    legs = {module_name(p): p.read_text() for p in sorted((ROOT / "legs").rglob("*.py"))}
    assert import_cycles(legs) == []


def test_package_init_files_only_reexport():
    assert init_logic(package_sources(), packages()) == []


@pytest.mark.parametrize("folder", ["legs", "scripts", "data", "tests/data"])
def test_legs_and_scripts_use_only_the_public_api(folder):
    namespaces = {name: set(getattr(hexapod, name).__all__) for name in hexapod.__all__
                  if inspect.ismodule(getattr(hexapod, name))}
    assert private_uses(sources_in(folder), set(hexapod.__all__), namespaces) == []


def test_optional_libraries_are_imported_lazily():
    for name, source in package_sources().items():
        for target, at_top in imports(source):
            if target.split(".")[0] in LAZY_ONLY:
                assert not at_top, f"{name} imports {target} at module level"
    code = "import sys, hexapod, hexapod.cli; print(sorted(m for m in %r if m in sys.modules))"
    result = subprocess.run([sys.executable, "-c", code % (LAZY_ONLY,)], capture_output=True,
                            text=True, check=True)
    assert result.stdout.strip() == "[]"


def test_every_public_name_resolves_and_is_documented():
    for name in hexapod.__all__:
        value = getattr(hexapod, name)
        if callable(value) or isinstance(value, type):
            assert (value.__doc__ or "").strip(), f"hexapod.{name} has no docstring"
    assert set(hexapod.__all__) <= set(dir(hexapod))


# ------------------------------------------------------------------ the rules can fail

def test_the_rules_catch_what_they_forbid():
    sources = {
        "hexapod.algorithms.bad": "from hexapod.output.report import report_files\n",
        "hexapod.simulation.peek": "def f():\n    from hexapod.scene.scene import Scene\n",
        "hexapod.model.a": "from hexapod.model.b import x\n",
        "hexapod.model.b": "def g():\n    from hexapod.model.a import y\n",
        "hexapod.output": "x = 1\nfrom hexapod.output.report import report_files\n",
        "hexapod.scene.uses_legs": "import legs\n",
    }
    upward = upward_imports(sources)
    assert any("hexapod.algorithms.bad (layer 3) imports hexapod.output.report" in v
               for v in upward)
    assert any("simulation/ sees Model and Data, never a Scene" in v for v in upward)
    assert any("never imports legs" in v for v in upward)
    assert any("hexapod.model.a -> hexapod.model.b -> hexapod.model.a" in v
               for v in import_cycles(sources))
    assert init_logic(sources, {"hexapod.output"}) == [
        "hexapod.output/__init__.py line 1: not a re-export (Assign)"]
    script = ("import hexapod as hx\nfrom hexapod.algorithms.inverse import tree_plan\n"
              "from hexapod import assemble, _private\nhx.secret(1)\nhx.assemble(2)\n"
              "from hexapod.benchmarks import suite, _jet\n"
              "hx.scene.Revolute(3)\nhx.scene.bodies.inertia_tensor(4)\n")
    found = private_uses({"scripts/x.py": script}, {"assemble", "benchmarks", "scene"},
                         {"benchmarks": {"suite"}, "scene": {"Revolute"}})
    assert found == ["scripts/x.py: from hexapod.algorithms.inverse import ...",
                     "scripts/x.py: hexapod._private is not public",
                     "scripts/x.py: hexapod.benchmarks._jet is not public",
                     "scripts/x.py line 4: hexapod.secret is not public",
                     "scripts/x.py line 8: hexapod.scene.bodies is not public"]
    with pytest.raises(AssertionError, match="has no layer"):
        layer("hexapod.attic.module")
