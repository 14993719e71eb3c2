"""The import layering of DESIGN section 3: no upward import, no cycle, optional libraries lazy."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import hexapod

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "hexapod"

#: Layer of each module (a package entry covers its sub-modules).
LAYERS = {
    "hexapod.errors": 0, "hexapod.spatial": 0, "hexapod.fastcall": 0, "hexapod.graph": 0,
    "hexapod.fileio": 0,
    "hexapod.scene": 1,
    "hexapod.assembly": 2, "hexapod.model": 2, "hexapod.mechanisms": 2,
    "hexapod.linalg": 3, "hexapod.kinematics": 3, "hexapod.dynamics": 3,
    "hexapod.reactions": 3, "hexapod.inverse": 3, "hexapod.topology": 3,
    "hexapod.recursive": 3, "hexapod.recursive_methods": 3, "hexapod.balance": 3,
    "hexapod.rates": 3,
    "hexapod.integrators": 4, "hexapod.simulate": 4, "hexapod.results": 4,
    "hexapod.diagnostics": 4, "hexapod.extreme": 5,
    "hexapod.studies": 5, "hexapod.references": 5, "hexapod.reports": 5, "hexapod.plotting": 5,
    "hexapod.export": 5, "hexapod.summary": 5, "hexapod.cli": 5, "hexapod.__main__": 5,
    "hexapod": 6,  # the package's __init__ re-exports the public API (this exact module only)
}
LAZY_ONLY = ("matplotlib", "meshio")


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def layer(module: str) -> int:
    candidates = [m for m in LAYERS if module == m or (m != "hexapod" and module.startswith(
        m + "."))]
    assert candidates, f"{module} has no layer in DESIGN: add it to LAYERS"
    return LAYERS[max(candidates, key=len)]


def imports(path: Path) -> list[tuple[str, bool]]:
    """(imported module, at module level) for every import in the file."""
    tree = ast.parse(path.read_text())
    top = {id(node) for node in tree.body}
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(alias.name, id(node) in top) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.append((node.module, id(node) in top))
    return out


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def test_every_module_has_a_layer_and_imports_none_above_it():
    for name, path in modules().items():
        mine = layer(name)
        for target, _ in imports(path):
            if target.split(".")[0] == "legs":
                raise AssertionError(f"{name} imports {target}: the engine never imports legs")
            if target.split(".")[0] != "hexapod" or name == "hexapod":
                continue
            assert layer(target) <= mine, f"{name} (layer {mine}) imports {target} " \
                                          f"(layer {layer(target)})"


def test_no_import_cycle():
    graph = {name: {t for t, _ in imports(path) if t in modules() and t != name}
             for name, path in modules().items()}
    state: dict[str, int] = {}

    def visit(node, stack):
        state[node] = 1
        for nxt in graph[node]:
            if state.get(nxt) == 1:
                raise AssertionError("import cycle: " + " -> ".join(stack + [node, nxt]))
            if nxt not in state:
                visit(nxt, stack + [node])
        state[node] = 2

    for node in graph:
        if node not in state:
            visit(node, [])


def test_optional_libraries_are_imported_lazily():
    for name, path in modules().items():
        for target, at_top in imports(path):
            if target.split(".")[0] in LAZY_ONLY:
                assert not at_top, f"{name} imports {target} at module level"
    code = "import sys, hexapod, hexapod.cli; print(sorted(m for m in %r if m in sys.modules))"
    result = subprocess.run([sys.executable, "-c", code % (LAZY_ONLY,)], capture_output=True,
                            text=True, check=True)
    assert result.stdout.strip() == "[]"


def test_legs_use_only_the_public_api():
    public = set(hexapod.__all__)
    for path in sorted((ROOT / "legs").rglob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith(
                    "hexapod"):
                assert node.module == "hexapod", f"{path.name} imports {node.module}"
                assert {a.name for a in node.names} <= public, path.name
            if isinstance(node, ast.Import):
                for alias in node.names:
                    assert not alias.name.startswith("hexapod."), path.name
