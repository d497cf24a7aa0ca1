"""Package attributes loaded on first use (PEP 562): a domain's public names without importing its modules.

A leaf module: imports nothing of flexdigit. Each domain's ``__init__`` lists its public names and the submodule
each lives in::

    __getattr__, __all__ = lazy_exports(__name__, {"Twin": "flexdigit.twin.twin", ...})

so ``from flexdigit.twin import Twin`` works, ``dir(flexdigit.twin)`` (and a shell's tab completion) lists
``Twin``, and ``import flexdigit.twin`` alone loads none of the submodules (``flexdigit --help`` stays fast).
"""

from __future__ import annotations

import importlib
import sys


def lazy_exports(package: str, names: dict[str, str]):
    """``(__getattr__, __all__)`` for ``package``: each public name of ``names`` (name -> its module) is imported
    from its module when first looked up, so importing the package itself loads none of them. A name whose module
    is ``package.name`` is that submodule itself (``{"twin": "flexdigit.twin"}`` in ``flexdigit``).

    Also gives the package a ``__dir__`` listing the public names beside what it already holds (PEP 562), so
    ``dir()`` and tab completion show them before their first use.
    """
    module = sys.modules[package]

    def __getattr__(name: str):
        if name in names:
            if names[name] == f"{package}.{name}":
                return importlib.import_module(names[name])
            return getattr(importlib.import_module(names[name]), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(set(vars(module)) | set(names))

    module.__dir__ = __dir__
    return __getattr__, list(names)
