"""Save and load trained tactile networks as versioned JSON (no pickle: a model file cannot run code).

The file holds the format name and version, the flexdigit version, the target, the input columns, the network
size and packed weights (NETLAB order), the normalisers (E 6.1), the protocol it was trained on and its test
scores. Loading checks every field and names the one that is wrong.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> from flexdigit.tactile.pipeline import ThesisNetwork
>>> x = np.random.default_rng(0).normal(size=(40, 3)); y = x.sum(axis=1)
>>> net = ThesisNetwork(hidden=3, epochs=2).fit(x, y)
>>> path = pathlib.Path(tempfile.mkdtemp()) / "m.json"
>>> _ = save_model(path, net, target="position", inputs=["gauge1_v", "gauge2_v", "gauge3_v"])
>>> bool(np.allclose(load_model(path).network.predict(x), net.predict(x)))
True
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexdigit import __version__
from flexdigit._io import MODEL_LIMIT, atomic_write, read_text
from flexdigit._validation import check_int, check_real
from flexdigit.errors import DataFileError
from flexdigit.tactile.netlab import MLP
from flexdigit.tactile.pipeline import TARGETS, Normaliser, ThesisNetwork

__all__ = ["MODEL_FORMAT", "MODEL_VERSION", "SavedModel", "save_model", "load_model"]

MODEL_FORMAT = "flexdigit-tactile-model"
MODEL_VERSION = 1


@dataclass
class SavedModel:
    """A loaded model: the network and what it was trained for."""

    network: ThesisNetwork
    target: str
    inputs: list[str]
    meta: dict = field(default_factory=dict)


def save_model(
    path: str | Path, network: ThesisNetwork, *, target: str, inputs: list[str], meta=None, force: bool = False
) -> Path:
    """Write a fitted :class:`ThesisNetwork` as JSON; returns the path (atomic; an existing file is refused
    unless ``force``)."""
    net = network.net_
    doc = {
        "format": MODEL_FORMAT,
        "version": MODEL_VERSION,
        "flexdigit_version": __version__,
        "target": target,
        "inputs": list(inputs),
        "hidden": int(net.hidden),
        "n_outputs": int(net.n_outputs_),
        "tol": float(network.tol),
        "weights": net.weights_.tolist(),
        "x_mean": network.x_norm_.mean_.tolist(),
        "x_std": network.x_norm_.std_.tolist(),
        "y_mean": network.y_norm_.mean_.tolist(),
        "y_std": network.y_norm_.std_.tolist(),
        "meta": meta or {},
    }
    path = Path(path)
    with atomic_write(path, "w", force=force) as fh:
        fh.write(json.dumps(doc, indent=1) + "\n")
    return path


def load_model(path: str | Path) -> SavedModel:
    """Read a model written by :func:`save_model`.

    Raises
    ------
    DataFileError
        If the file is not JSON, not a flexdigit model, of a newer version, or a field is missing or inconsistent.
    """
    path = Path(path)
    try:
        doc = json.loads(read_text(path, "a model file", MODEL_LIMIT))
    except json.JSONDecodeError as exc:
        raise DataFileError(f"{path}: not a model file (invalid JSON: {exc})") from None
    except RecursionError:
        raise DataFileError(f"{path}: not a model file (JSON nested too deep)") from None
    if not isinstance(doc, dict) or doc.get("format") != MODEL_FORMAT:
        raise DataFileError(f"{path}: not a {MODEL_FORMAT} file")
    if doc.get("version") != MODEL_VERSION:
        raise DataFileError(
            f"{path}: model format version {doc.get('version')!r}; this flexdigit reads {MODEL_VERSION}"
        )
    for key in ("target", "inputs", "hidden", "n_outputs", "weights", "x_mean", "x_std", "y_mean", "y_std"):
        if key not in doc:
            raise DataFileError(f"{path}: missing field '{key}'")
    if not isinstance(doc["target"], str) or doc["target"] not in TARGETS:
        raise DataFileError(f"{path}: field 'target' is {doc['target']!r}, expected one of {', '.join(TARGETS)}")
    inputs = doc["inputs"]
    if not isinstance(inputs, list) or not inputs or not all(isinstance(c, str) for c in inputs):
        raise DataFileError(f"{path}: field 'inputs' must be a list of column names. Got {inputs!r}")
    nin = len(inputs)
    # an int, not "five" (that reached numpy as a TypeError) nor True; the field names itself in the message
    try:
        hidden = check_int(doc["hidden"], "hidden", "a model file", low=1, high=10_000, error=DataFileError)
        nout = check_int(doc["n_outputs"], "n_outputs", "a model file", low=1, high=1_000, error=DataFileError)
        tol = check_real(doc.get("tol", 1e-7), "tol", "a model file", low=0, low_open=True, error=DataFileError)
    except DataFileError as exc:
        raise DataFileError(f"{path}: {exc}") from None
    if not isinstance(doc.get("meta", {}), dict):
        raise DataFileError(f"{path}: field 'meta' must be an object. Got {doc['meta']!r}")
    arrays = {}
    for key in ("weights", "x_mean", "x_std", "y_mean", "y_std"):
        value = doc[key]
        if not isinstance(value, list) or not all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value
        ):
            raise DataFileError(f"{path}: field '{key}' must be a list of numbers")
        arrays[key] = np.array(value, dtype=float)
    weights, x_mean, x_std = arrays["weights"], arrays["x_mean"], arrays["x_std"]
    y_mean, y_std = arrays["y_mean"], arrays["y_std"]
    expected = nin * hidden + hidden + hidden * nout + nout
    if weights.shape != (expected,):
        raise DataFileError(
            f"{path}: field 'weights' has {weights.size} values; {nin} inputs, {hidden} hidden, {nout} outputs "
            f"need {expected}"
        )
    if x_mean.shape != (nin,) or x_std.shape != (nin,) or y_mean.shape != (nout,) or y_std.shape != (nout,):
        raise DataFileError(f"{path}: normaliser sizes do not match {nin} inputs and {nout} outputs")
    finite = all(np.all(np.isfinite(a)) for a in arrays.values())
    if not (finite and np.all(x_std > 0) and np.all(y_std > 0)):
        raise DataFileError(f"{path}: weights must be finite and normaliser spreads positive")
    mlp = MLP(hidden=hidden, tol=tol)
    mlp.weights_, mlp.n_inputs_, mlp.n_outputs_, mlp.y_ndim_ = weights, nin, nout, 2
    network = ThesisNetwork(hidden=hidden, tol=tol)
    network.net_ = mlp
    network.x_norm_, network.y_norm_ = Normaliser(), Normaliser()
    network.x_norm_.mean_, network.x_norm_.std_ = x_mean, x_std
    network.y_norm_.mean_, network.y_norm_.std_ = y_mean, y_std
    network.y_ndim_ = 1 if nout == 1 else 2
    return SavedModel(network, doc["target"], list(inputs), doc.get("meta", {}))
