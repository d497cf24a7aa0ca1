"""flexdigit's compiled kernels kept per user, keyed by their source text, not by where the source lies.

numba's own cache (``cache=True``) sits in ``__pycache__`` beside the source: a fresh clone, a new virtual
environment or another checkout of the same flexdigit compiles every kernel again (~40 s of CPU for those the
documentation's gallery runs, more for the whole suite). Here each kernel module's machine code is kept under the
user's cache folder (``$XDG_CACHE_HOME/flexdigit/numba``, else ``~/.cache/flexdigit/numba``) in a folder named for
the module and the SHA-256 of its text, so any copy of the same text loads it. numba still checks what it checks in
``__pycache__``: the source's content hash, numba's version, the argument types and the CPU.

The kernel modules import nothing of flexdigit's into their compiled code (each is self-contained: numpy, math and
numba only), so a module's own text is all its machine code depends on. ``NUMBA_CACHE_DIR``, when set, still wins;
where the user's cache folder cannot be written, numba's ``__pycache__`` is used as before.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from numba.core import caching

__all__ = ["cache_root", "install"]

PACKAGE = Path(__file__).resolve().parent


def cache_root() -> Path:
    """The folder the kernels' machine code is kept in (``$XDG_CACHE_HOME/flexdigit/numba`` or ``~/.cache/...``)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "flexdigit" / "numba"


def _inside_package(py_file: str) -> Path | None:
    try:
        return Path(py_file).resolve().relative_to(PACKAGE)
    except (OSError, ValueError):
        return None


_LOCATOR_BASES = (getattr(caching, "_SourceFileBackedLocatorMixin", None), getattr(caching, "_CacheLocator", None))

if None not in _LOCATOR_BASES:

    class SourceTextLocator(*_LOCATOR_BASES):
        """numba's cache locator for a flexdigit kernel: ``cache_root() / <package folder> / <module>-<sha256>``."""

        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            inside = _inside_package(py_file)
            digest = hashlib.sha256(Path(py_file).read_bytes()).hexdigest()[:20]
            self._cache_path = str(cache_root().joinpath(*inside.parent.parts, f"{inside.stem}-{digest}"))

        def get_cache_path(self):
            return self._cache_path

        @classmethod
        def from_function(cls, py_func, py_file):
            if _inside_package(py_file) is None:
                return None  # not flexdigit's: numba's own locators
            return super().from_function(py_func, py_file)  # None where the folder cannot be written

else:  # a numba without these bases: its own cache only
    SourceTextLocator = None


def install() -> bool:
    """Put :class:`SourceTextLocator` after ``NUMBA_CACHE_DIR``'s locator and before ``__pycache__``'s, once; a
    kernel module calls it before its first ``numba.njit(cache=True)``. False where this numba has no such list."""
    classes = getattr(getattr(caching, "CacheImpl", None), "_locator_classes", None)
    if SourceTextLocator is None or not isinstance(classes, list):
        return False
    if SourceTextLocator not in classes:
        classes.insert(1 if classes and classes[0] is getattr(caching, "UserProvidedCacheLocator", None) else 0,
                       SourceTextLocator)  # fmt: skip
    return True
