"""Lazy re-exports for package ``__init__`` files (PEP 562).

``import hexapod`` then costs nothing until a name is used, so that ``hexapod --help`` loads
neither CasADi nor SciPy; ``from hexapod import assemble`` and ``hexapod.assemble`` work as with
eager imports, and ``dir(hexapod)`` lists the public API.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable


def attach(package: str, exports: dict[str, list[str]]
           ) -> tuple[Callable[[str], object], Callable[[], list[str]], list[str]]:
    """``__getattr__``, ``__dir__`` and ``__all__`` for a package that re-exports, for each
    module in ``exports``, the names listed with it.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : dict
        ``{module: [name, ...]}``; a name equal to the module's last component re-exports the
        sub-package itself.
    """
    where = {name: module for module, names in exports.items() for name in names}

    def __getattr__(name: str):
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        loaded = importlib.import_module(module)
        # the package itself, even when it holds a module of the same name (hexapod.scene.scene)
        value = loaded if module.rpartition(".")[2] == name else getattr(loaded, name)
        globals_of_package = importlib.import_module(package).__dict__
        globals_of_package[name] = value  # found directly from now on
        return value

    def __dir__() -> list[str]:
        return sorted(where)

    return __getattr__, __dir__, sorted(where)
