"""flexdigit's compiled kernels kept per user by their source text (``flexdigit/_numba_cache.py``): a copy of the
package at another path (a fresh clone, another virtual environment) loads a kernel another copy compiled, a kernel
whose text differs compiles its own, and numba's ``__pycache__`` beside the source is left alone.

Each copy runs in a child process (numba keeps what it compiled in the process) with its own user cache folder
(``XDG_CACHE_HOME``), on ``twin/_contact_points._point_load``: one small kernel, compiled in under a second.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import flexdigit

pytestmark = pytest.mark.slow  # three child processes import the twin (~3 s each on an idle machine)

PACKAGE = Path(flexdigit.__file__).parent
KERNEL = Path("twin") / "_contact_points.py"
#: The child: call the kernel once, say what numba's cache did and where it looked.
CHILD = (
    "import json; from flexdigit.twin._contact_points import _point_load as f; f(1e-3, 10.0, 0.0, 1.5, 0.0); "
    "s = f.stats; print(json.dumps({'hits': sum(s.cache_hits.values()), 'misses': sum(s.cache_misses.values()), "
    "'path': s.cache_path}))"
)


def _copy(root: Path) -> Path:
    shutil.copytree(PACKAGE, root / "flexdigit", ignore=shutil.ignore_patterns("__pycache__", "vendor", "static"))
    return root


def _run(src: Path, cache: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env |= {"PYTHONPATH": str(src), "XDG_CACHE_HOME": str(cache)}
    out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, timeout=300, cwd=src)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_a_kernel_compiled_by_one_copy_is_loaded_by_another_at_another_path(tmp_path):
    cache = tmp_path / "cache"
    first = _run(_copy(tmp_path / "a"), cache)
    assert first["misses"] == 1  # compiled
    assert Path(first["path"]).is_relative_to(cache / "flexdigit" / "numba" / "twin")
    again = _run(_copy(tmp_path / "b"), cache)  # another path, its files written later: numba's own would miss
    assert again["hits"] == 1
    assert again["misses"] == 0
    assert again["path"] == first["path"]
    assert not list((tmp_path / "a").rglob("*.nbi"))  # nothing beside the source


def test_a_kernel_whose_text_differs_compiles_its_own(tmp_path):
    cache = tmp_path / "cache"
    first = _run(_copy(tmp_path / "a"), cache)
    edited = _copy(tmp_path / "b")
    kernel = edited / "flexdigit" / KERNEL
    kernel.write_text(kernel.read_text() + "\n# another text, the same functions\n")
    other = _run(edited, cache)
    assert other["misses"] == 1
    assert other["hits"] == 0
    assert other["path"] != first["path"]
