"""Shared hypothesis strategies for the loader fuzz tests (issue 16): one place every loader's tests draw from.

A loader is fuzzed from a valid file (made here, independently of the loader: seeded numbers, known structure)
by two families of edits, so that most generated inputs are *almost* valid, where loaders go wrong:

- :func:`mutated_bytes`: the file's bytes truncated, a slice deleted or duplicated, bytes flipped or inserted,
  lines shuffled, or replaced by random binary;
- :func:`edited_document`: one value of the parsed document (a TOML table, a JSON object, a metadata dict)
  replaced by a random value of another type or range (:data:`json_values`, :data:`toml_values`), a key removed
  or an unknown key added.

:func:`assert_loader_contract` states the property: the loader returns, or raises one of the project's errors
(:class:`flexdigit.errors.FlexdigitError`) whose message is one line naming the file; never another exception
(a traceback for a user) and never a hang. To fuzz a new loader (dataset import, MCAP, tissue TOML, study
specs): make a valid file in a module-scoped fixture, then ``@given(mutated_bytes(valid))`` and/or
``@given(edited_document(doc, toml_values))``, write the example to a path and call the contract. The example
counts come from the hypothesis profile (tests/conftest.py: 200 in ``make test``, 10,000 in ``make fuzz``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import strategies as st

from flexdigit.errors import FlexdigitError

__all__ = [
    "json_scalars",
    "json_values",
    "toml_values",
    "mutated_bytes",
    "edited_document",
    "assert_loader_contract",
    "loop_samples",
]

#: Numbers a file may hold that loaders must cope with: huge, tiny, negative zero, NaN, infinities, big integers.
numbers = st.one_of(
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, -0.0, 1e300, -1e300, 1e-300, 2**63, -(2**63) - 1, 255, 254, 256, -1]),
)
text = st.text(max_size=12)
json_scalars = st.one_of(st.none(), st.booleans(), numbers, text)
#: Any JSON value, nested a little.
json_values = st.recursive(
    json_scalars,
    lambda children: st.lists(children, max_size=4) | st.dictionaries(text, children, max_size=4),
    max_leaves=8,
)
#: Any TOML value (no null; integers within 64 bits; tables and arrays nested a little).
toml_values = st.recursive(
    st.one_of(
        st.booleans(),
        st.integers(min_value=-(2**63), max_value=2**63 - 1),
        st.floats(allow_nan=True, allow_infinity=True),
        text,
    ),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(text, children, max_size=3),
    max_leaves=6,
)


def loop_samples(seed: int, n: int = 8) -> list[dict]:
    """``n`` samples of a 20 ms loop as its log and recordings hold them (seeded numbers: a valid seed file)."""
    rng = np.random.default_rng(seed)
    return [
        {
            "k": k,
            "t": 0.02 * k,
            "setpoint": 30.0,
            "gauges_v": [float(v) for v in rng.normal(0, 0.2, 3)],
            "pot_v": None,
            "y": float(rng.normal(30, 1)),
            "command": int(rng.integers(0, 255)),
        }
        for k in range(n)
    ]


@st.composite
def mutated_bytes(draw, valid: bytes) -> bytes:
    """``valid`` with one to three random edits (module docstring)."""
    data = bytearray(valid)
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["truncate", "delete", "duplicate", "flip", "insert", "lines", "binary"]))
        n = len(data)
        if kind == "binary":
            data = bytearray(draw(st.binary(max_size=200)))
            continue
        if n == 0:
            data += draw(st.binary(min_size=1, max_size=20))
            continue
        i = draw(st.integers(0, n - 1))
        j = draw(st.integers(i, min(n, i + 64)))
        if kind == "truncate":
            del data[i:]
        elif kind == "delete":
            del data[i:j]
        elif kind == "duplicate":
            data[j:j] = data[i:j]
        elif kind == "flip":
            data[i] = draw(st.integers(0, 255))
        elif kind == "insert":
            noise = st.one_of(st.binary(min_size=1, max_size=8), st.sampled_from([b",", b"\n", b'"', b"\x00"]))
            data[i:i] = draw(noise)
        else:  # two lines swapped (a row out of order, a header below its data)
            lines = bytes(data).split(b"\n")
            a = draw(st.integers(0, len(lines) - 1))
            b = draw(st.integers(0, len(lines) - 1))
            lines[a], lines[b] = lines[b], lines[a]
            data = bytearray(b"\n".join(lines))
    return bytes(data)


def _paths(doc, prefix=()):
    """Every (path, value) of a nested dict/list document."""
    yield prefix, doc
    if isinstance(doc, dict):
        for key, value in doc.items():
            yield from _paths(value, (*prefix, key))
    elif isinstance(doc, list):
        for k, value in enumerate(doc):
            yield from _paths(value, (*prefix, k))


@st.composite
def edited_document(draw, valid: dict, values=json_values) -> dict:
    """A deep copy of ``valid`` with one value replaced by a draw from ``values``, a key removed, or a key added."""
    import copy

    doc = copy.deepcopy(valid)
    paths = [p for p, _ in _paths(doc) if p]
    path = draw(st.sampled_from(paths))
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    last = path[-1]
    action = draw(st.sampled_from(["replace", "replace", "replace", "remove", "add"]))
    if action == "replace":
        parent[last] = draw(values)
    elif action == "remove":
        del parent[last]
    elif isinstance(parent, dict):
        parent[draw(text.filter(lambda k: k not in parent))] = draw(values)
    else:
        parent.append(draw(values))
    return doc


def assert_loader_contract(load, path: Path, *, names_file: bool = True):
    """Call ``load(path)``; it returns, or raises a one-line flexdigit error naming ``path`` (module docstring)."""
    try:
        return load(path)
    except FlexdigitError as exc:
        message = str(exc)
        assert message, f"not a one-line message: {message!r}"
        assert "\n" not in message, f"not a one-line message: {message!r}"
        if names_file:
            assert path.name in message, f"the message does not name the file: {message!r}"
        assert "Traceback" not in message
        return exc
