"""The thesis's figures, as printed (``thesis.toml``), and a loader that names what is missing.

Examples
--------
>>> thesis_value("hinf.tzw_peak_db")
2.2645
>>> thesis_value("geometry.strain_gauge_positions_from_base_m")
[0.045, 0.135, 0.225]
"""

from __future__ import annotations

import tomllib
from functools import lru_cache
from importlib import resources
from typing import Any

__all__ = ["thesis", "thesis_value", "thesis_complex"]


@lru_cache(maxsize=1)
def thesis() -> dict[str, Any]:
    """All figures of ``thesis.toml`` as a nested dict (cached; do not mutate)."""
    with resources.files(__package__).joinpath("thesis.toml").open("rb") as fh:
        return tomllib.load(fh)


def thesis_value(key: str) -> Any:
    """The printed figure at a dotted ``key`` such as ``"plant.g_den"``; ``KeyError`` names the missing part."""
    node: Any = thesis()
    walked = []
    for part in key.split("."):
        walked.append(part)
        if not isinstance(node, dict) or part not in node:
            raise KeyError(f"no thesis figure '{'.'.join(walked)}' in reference/thesis.toml")
        node = node[part]
    return node


def thesis_complex(key: str) -> list[complex]:
    """A list of complex numbers stored as strings (``"-11.5550+16.9700j"``)."""
    return [complex(v.replace(" ", "")) for v in thesis_value(key)]
