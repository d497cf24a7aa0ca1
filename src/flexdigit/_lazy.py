"""Package attributes loaded on first use (PEP 562), for packages the command line imports to build its parser.

A leaf module: imports nothing of flexdigit.
"""

from __future__ import annotations

import importlib


def lazy_exports(package: str, names: dict[str, str]):
    """``(__getattr__, __all__)`` for ``package``: each public name of ``names`` (name -> its submodule) is imported
    from its submodule when first looked up, so importing the package itself loads none of them."""

    def __getattr__(name: str):
        if name in names:
            return getattr(importlib.import_module(names[name]), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__, list(names)
