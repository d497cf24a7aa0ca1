"""Global sensitivity of the metrics to the uncertain parameters: Morris screening, then Sobol indices (SALib).

The thesis's first item of future work (chapter 8): "a sensitivity and stability analysis should be conducted into
the effects of all system parameters". Given a spec (:mod:`flexdigit.studies.spec`), :func:`run_sensitivity`

1. screens with Morris's elementary effects (``SALib.sample.morris``, ``SALib.analyze.morris``: ``mu_star`` with
   its bootstrap interval, ``sigma``), trajectories on 4 levels of each parameter's quantiles 0.5 %..99.5 % (an
   unbounded normal has no 0 and 100 % quantile);
2. estimates Sobol's first-order and total indices (S1, ST; S2 on request) with Saltelli's design
   (``SALib.sample.sobol``, scrambled Sobol points mapped through each distribution's inverse CDF) and
   ``SALib.analyze.sobol``, with bootstrap confidence intervals; a second-order design's S1, ST and S2 average
   SALib's estimates over both halves of the design (A with AB_i, and B with BA_i: :func:`averaged_sobol_indices`,
   Saltelli 2002), a lower variance for no extra evaluation;
3. checks convergence: the design at 2N contains the design at N (the Sobol sequence extends), so the indices are
   computed at both from one set of evaluations; a metric converged when no S1 or ST moves by more than
   ``convergence_tol`` (default 0.05) between N and 2N. An unconverged metric is flagged and named, and the
   study says to double N.

Indices are not computed for a metric that failed or was not finite on some rows (an unstable loop has no settling
time): the rows and their parameters are reported instead of indices built on the rest. A metric that does not
vary over the study has no indices either (it is reported constant).

Outputs (:func:`write_outputs`, through :mod:`flexdigit._io`): ``indices.parquet`` (tidy: ``metric, method, index,
parameter, parameter_2, n_base, value, conf``), ``evaluations.parquet`` (one row per evaluation: the design it
belongs to, the parameter values, the metrics, the error), ``summary.json`` and figures (``figures/``: Sobol bars
with intervals per metric, the total-index map, S2 heat maps).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexdigit._io import atomic_path, atomic_write, check_output
from flexdigit._json import to_jsonable
from flexdigit._repr import fields_summary
from flexdigit._validation import check_int, check_real
from flexdigit.errors import ParameterError
from flexdigit.studies import figures
from flexdigit.studies.execution import run_study, warn
from flexdigit.studies.metrics import SENSITIVITY_METRICS, UNDEFINED, MetricContext, metric_of
from flexdigit.studies.spec import StudySpec, load_spec

__all__ = [
    "SensitivitySettings",
    "SensitivityResult",
    "averaged_sobol_indices",
    "run_sensitivity",
    "sobol_indices",
    "write_outputs",
]

#: Morris levels are placed on these quantiles of each distribution (0 and 1 are infinite for a normal).
MORRIS_QUANTILES = (0.005, 0.995)

#: What :func:`sobol_indices` computes, by whether the design is second-order (``summary.json``'s ``sobol_estimator``).
SOBOL_ESTIMATORS = {
    False: "SALib.analyze.sobol: S1 Saltelli et al. 2010, ST Jansen, on A, AB_i, B",
    True: "mean of SALib's S1, ST, S2 on (A, AB_i, B) and on (B, BA_i, A): Saltelli 2002 (averaged_sobol_indices)",
}


@dataclass(frozen=True)
class SensitivitySettings:
    """The ``[sensitivity]`` table of a spec (defaults in brackets).

    morris_trajectories [10], morris_levels [4], sobol_n [128] (base samples; the study evaluates the design at
    2N for the convergence check), second_order [false], bootstrap [200] resamples, confidence [0.95],
    convergence_tol [0.05], chunk_size [8] rows per task, bayes_samples [500].
    """

    morris_trajectories: int = 10
    morris_levels: int = 4
    sobol_n: int = 128
    second_order: bool = False
    bootstrap: int = 200
    confidence: float = 0.95
    convergence_tol: float = 0.05
    chunk_size: int = 8
    bayes_samples: int = 500

    @classmethod
    def from_spec(cls, spec: StudySpec, **overrides) -> SensitivitySettings:
        table = dict(spec.settings.get("sensitivity", {}))
        table.update({k: v for k, v in overrides.items() if v is not None})
        allowed = cls.__dataclass_fields__
        bad = sorted(set(table) - set(allowed))
        if bad:
            raise ParameterError(
                f"{spec.source}: unknown key {bad[0]!r} in [sensitivity]; expected one of " + ", ".join(allowed)
            )
        where = f"{spec.source}: [sensitivity]"
        try:
            out = cls(
                morris_trajectories=check_int(
                    table.get("morris_trajectories", 10), "morris_trajectories", where, low=0
                ),
                morris_levels=check_int(table.get("morris_levels", 4), "morris_levels", where, low=2, high=100),
                sobol_n=check_int(table.get("sobol_n", 128), "sobol_n", where, low=4, high=2**20),
                second_order=table.get("second_order", False),
                bootstrap=check_int(table.get("bootstrap", 200), "bootstrap", where, low=10, high=100_000),
                confidence=check_real(
                    table.get("confidence", 0.95), "confidence", where, low=0.5, high=1, high_open=True
                ),
                convergence_tol=check_real(
                    table.get("convergence_tol", 0.05), "convergence_tol", where, low=0, low_open=True
                ),
                chunk_size=check_int(table.get("chunk_size", 8), "chunk_size", where, low=1, high=100_000),
                bayes_samples=check_int(table.get("bayes_samples", 500), "bayes_samples", where, low=10, high=10**6),
            )
        except ParameterError as exc:
            raise ParameterError(str(exc).replace(f"of {where}", f"in {where}")) from None
        if not isinstance(out.second_order, bool):
            raise ParameterError(f"{where} second_order must be true or false. Got {out.second_order!r} instead.")
        if out.sobol_n & (out.sobol_n - 1):
            raise ParameterError(
                f"{where} sobol_n must be a power of 2 (Sobol points balance at powers of 2). "
                f"Got {out.sobol_n} instead."
            )
        return out


@dataclass
class SensitivityResult:
    """What :func:`run_sensitivity` found (see the module docstring)."""

    spec: StudySpec
    settings: SensitivitySettings
    metrics: tuple[str, ...]
    values: np.ndarray
    design: np.ndarray
    outputs: dict[str, np.ndarray]
    errors: list[str | None]
    morris: dict[str, dict] = field(default_factory=dict)
    sobol: dict[str, dict[int, dict]] = field(default_factory=dict)
    convergence: dict[str, dict] = field(default_factory=dict)
    refused: dict[str, str] = field(default_factory=dict)

    @property
    def failed_rows(self) -> list[int]:
        return [i for i, e in enumerate(self.errors) if e]

    def table(self) -> list[dict]:
        """The tidy table of indices (one row per metric, method, index, parameter (pair) and N)."""
        names = self.spec.names
        rows = []
        for metric, res in self.morris.items():
            for j, name in enumerate(names):
                for index in ("mu_star", "sigma", "mu"):
                    conf = res["mu_star_conf"][j] if index == "mu_star" else math.nan
                    rows.append(
                        _row(
                            metric, "morris", index, name, None, self.settings.morris_trajectories, res[index][j], conf
                        )
                    )
        for metric, by_n in self.sobol.items():
            for n, res in by_n.items():
                for j, name in enumerate(names):
                    for index in ("S1", "ST"):
                        rows.append(_row(metric, "sobol", index, name, None, n, res[index][j], res[f"{index}_conf"][j]))
                if "S2" in res:
                    for j in range(len(names)):
                        for k in range(j + 1, len(names)):
                            rows.append(
                                _row(
                                    metric, "sobol", "S2", names[j], names[k], n, res["S2"][j, k], res["S2_conf"][j, k]
                                )
                            )
        return rows

    def summary(self) -> dict:
        """Everything a user (or ``--json``) needs, as plain values."""
        names = self.spec.names
        out = {
            "study": self.spec.name,
            "spec": self.spec.source,
            "fingerprint": self.spec.fingerprint(),
            "parameters": [
                {"name": p.name, "distribution": p.describe(), "source": p.source} for p in self.spec.parameters
            ],
            "evaluations": int(self.values.shape[0]),
            "sobol_n": [self.settings.sobol_n, 2 * self.settings.sobol_n],
            "sobol_estimator": SOBOL_ESTIMATORS[self.settings.second_order],
            "failed_rows": [
                {
                    "row": i,
                    "design": str(self.design[i]),
                    "error": self.errors[i],
                    "parameters": dict(zip(names, self.values[i].tolist(), strict=True)),
                }
                for i in self.failed_rows
            ],
            "refused": self.refused,
            "metrics": {},
        }
        for metric in self.metrics:
            about = metric_of(metric, MetricContext(user_metrics=self.spec.user_metrics))
            entry: dict = {"unit": about.unit, "description": about.description}
            if metric in self.morris:
                res = self.morris[metric]
                entry["morris"] = {
                    n: {"mu_star": res["mu_star"][j], "mu_star_conf": res["mu_star_conf"][j], "sigma": res["sigma"][j]}
                    for j, n in enumerate(names)
                }
            if metric in self.sobol:
                res = self.sobol[metric][2 * self.settings.sobol_n]
                entry["sobol"] = {
                    n: {
                        "S1": res["S1"][j],
                        "S1_conf": res["S1_conf"][j],
                        "ST": res["ST"][j],
                        "ST_conf": res["ST_conf"][j],
                    }
                    for j, n in enumerate(names)
                }
                entry["ranking"] = [names[j] for j in np.argsort(-np.asarray(res["ST"]))]
            if metric in self.convergence:
                entry["convergence"] = self.convergence[metric]
            ok = self.outputs[metric][np.isfinite(self.outputs[metric])]
            entry["range"] = [float(ok.min()), float(ok.max())] if ok.size else None
            out["metrics"][metric] = entry
        return out

    __repr__ = fields_summary


def _row(metric, method, index, parameter, parameter_2, n, value, conf) -> dict:
    return {
        "metric": metric,
        "method": method,
        "index": index,
        "parameter": parameter,
        "parameter_2": parameter_2,
        "n_base": int(n),
        "value": float(value),
        "conf": float(conf),
    }


def _salib_seed(seed: int, stream: int) -> int:
    # SALib's analyzers test ``if seed:`` and fall back to the global generator for 0: never hand them a 0
    return int(np.random.SeedSequence([seed, stream]).generate_state(1)[0]) | 1


def _problem(spec: StudySpec) -> dict:
    d = len(spec.parameters)
    return {"num_vars": d, "names": spec.names, "bounds": [[0.0, 1.0]] * d}


def sensitivity_design(spec: StudySpec, settings: SensitivitySettings) -> tuple[np.ndarray, np.ndarray]:
    """Unit-cube samples of the whole study and the design each row belongs to (``morris`` or ``sobol``)."""
    from SALib.sample import morris as morris_sample
    from SALib.sample import sobol as sobol_sample

    problem = _problem(spec)
    parts, labels = [], []
    if settings.morris_trajectories:
        u = morris_sample.sample(
            problem, settings.morris_trajectories, num_levels=settings.morris_levels, seed=_salib_seed(spec.seed, 1)
        )
        lo, hi = MORRIS_QUANTILES
        parts.append(lo + (hi - lo) * u)
        labels += ["morris"] * u.shape[0]
    u = sobol_sample.sample(
        problem, 2 * settings.sobol_n, calc_second_order=settings.second_order, seed=_salib_seed(spec.seed, 2)
    )
    parts.append(u)
    labels += ["sobol"] * u.shape[0]
    return np.vstack(parts), np.array(labels)


def sobol_indices(spec_or_names, outputs, second_order: bool, bootstrap: int, confidence: float, seed: int) -> dict:
    """Sobol indices of one metric's outputs (Saltelli order, ``SALib.sample.sobol``), as arrays; bootstrap seeded.

    A first-order design (rows A, AB_i, B) is ``SALib.analyze.sobol``: S1 by Saltelli et al. (2010), ST by Jansen.
    A second-order design also holds the rows BA_i (B with column i from A), and with them every index has a second
    estimate, the same estimator with A and B exchanged (Saltelli 2002, "Making best use of model evaluations to
    compute sensitivity indices", Comput. Phys. Commun. 145, 280-297): S1, ST and S2 are the mean of the two
    (:func:`averaged_sobol_indices`), a lower variance for no extra evaluation.
    """
    from SALib.analyze import sobol as sobol_analyze

    names = spec_or_names.names if hasattr(spec_or_names, "names") else list(spec_or_names)
    if second_order:
        return averaged_sobol_indices(names, outputs, bootstrap, confidence, seed)
    problem = {"num_vars": len(names), "names": names, "bounds": [[0.0, 1.0]] * len(names)}
    res = sobol_analyze.analyze(
        problem,
        np.asarray(outputs, dtype=float),
        calc_second_order=False,
        num_resamples=bootstrap,
        conf_level=confidence,
        seed=_salib_seed(seed, 3),
    )
    return {k: np.asarray(res[k], dtype=float) for k in ("S1", "S1_conf", "ST", "ST_conf")}


def averaged_sobol_indices(names, outputs, bootstrap: int, confidence: float, seed: int) -> dict:
    """S1, ST and S2 of a second-order Saltelli design from both of its halves, with bootstrap intervals.

    ``SALib.analyze.sobol`` estimates S1 (Saltelli et al. 2010) and ST (Jansen) from the rows A, AB_i and B alone,
    and S2 (Saltelli 2002) from BA_j and AB_k. Exchanging A and B gives the same estimators on B, BA_i and A
    (BA_i is B with column i from A): a second estimate of each index from the other half of the evaluations
    (Saltelli 2002, "Making best use of model evaluations to compute sensitivity indices", Comput. Phys. Commun.
    145, 280-297; Saltelli et al. 2010, Comput. Phys. Commun. 181, 259-270). Each index here is the mean of its
    two estimates: SALib's estimate on the design, and SALib's on the design with A and B exchanged
    (``tests/studies/test_sensitivity_averaged.py`` checks it against both, with the same resamples).

    The two halves share A and B, so they are correlated: the mean has (1 + rho) / 2 of one half's variance
    (rho their correlation, halves of equal variance), no gain where rho = 1 (the total index of an input that
    enters the output additively is the same from both halves), half the variance where rho = 0 and less where
    the halves err in opposite directions (rho < 0: the S1 of the Ishigami function's x3, whose true S1 is 0).
    The bootstrap draws its resamples of the N base rows as SALib does (the same generator and seed) and evaluates
    both halves on each resample, so an interval is that of the mean.
    ``names``: the parameters, in column order; ``outputs``: the model outputs in SALib's order, N (2D + 2) values.
    Returns arrays ``S1, S1_conf, ST, ST_conf`` (D) and ``S2, S2_conf`` (D x D, upper triangle; NaN elsewhere).
    """
    from scipy.stats import norm

    y = np.asarray(outputs, dtype=float)
    d = len(names)
    if y.ndim != 1 or y.size == 0 or y.size % (2 * d + 2):
        raise ParameterError(
            f"averaged_sobol_indices needs the outputs of a second-order Saltelli design: N (2D + 2) = N x "
            f"{2 * d + 2} values for D = {d} parameters. Got shape {y.shape} instead."
        )
    n = y.size // (2 * d + 2)
    rows = ((y - y.mean()) / y.std()).reshape(n, 2 * d + 2)  # SALib normalises the outputs so, and orders rows so
    # SALib's resamples of the base rows: np.random.default_rng(seed).integers(N, size=(N, resamples))
    r = np.random.default_rng(_salib_seed(seed, 3)).integers(n, size=(n, bootstrap))
    point = _both_halves(rows[:, None, :], d)
    boot = _both_halves(rows[r], d)
    z = norm.ppf(0.5 + confidence / 2)
    upper = np.triu(np.ones((d, d), dtype=bool), 1)
    out = {}
    for key in ("S1", "ST", "S2"):
        out[key] = point[key][0]
        out[f"{key}_conf"] = z * boot[key].std(axis=0, ddof=1)
    for key in ("S2", "S2_conf"):
        out[key] = np.where(upper, out[key], np.nan)
    return out


def _both_halves(rows: np.ndarray, d: int) -> dict[str, np.ndarray]:
    """The mean of SALib's S1, ST and S2 estimators (``SALib.analyze.sobol.first_order``, ``total_order``,
    ``second_order``) on (A, AB, B) and on (B, BA, A), for rows of shape (N, resamples, 2D + 2); arrays with the
    resamples first."""
    a, ab, ba, b = rows[..., 0], rows[..., 1 : d + 1], rows[..., d + 1 : 2 * d + 1], rows[..., 2 * d + 1]
    var = np.var(np.concatenate([a, b]), axis=0)[:, None]  # SALib's: the variance of A and B together
    # first_order(A, AB, B) = mean(B (AB - A)) / var, and exchanged; total_order(A, AB, B) = mean((A - AB)^2) / 2 var
    s1 = np.mean(b[..., None] * (ab - a[..., None]) + a[..., None] * (ba - b[..., None]), axis=0) / (2 * var)
    st = np.mean((a[..., None] - ab) ** 2 + (b[..., None] - ba) ** 2, axis=0) / (4 * var)
    # closed second-order index of (j, k): BA_j and AB_k share x_j (from A) and x_k (from B); AB_j and BA_k alike
    n = rows.shape[0]
    closed = (np.einsum("nrj,nrk->rjk", ba, ab) + np.einsum("nrj,nrk->rjk", ab, ba)) / (2 * n)
    closed = (closed - np.mean(a * b, axis=0)[:, None, None]) / var[..., None]
    s2 = closed - s1[:, :, None] - s1[:, None, :]
    return {"S1": s1, "ST": st, "S2": s2}


def run_sensitivity(
    spec: StudySpec,
    out_dir: str | Path,
    *,
    settings: SensitivitySettings | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    force: bool = False,
    progress: bool = True,
    rerun: str | None = None,
) -> SensitivityResult:
    """Run (or resume) a sensitivity study; its journal lives in ``out_dir`` (see :mod:`flexdigit.studies.execution`).

    ``rerun`` is what the "NOT converged" warning tells the user to do, in the caller's own terms (a command and a
    flag that exist: ``flexdigit reproduce`` has no ``--n``); by default ``flexdigit study sensitivity`` with
    ``--n`` at 4N. Returns the result; :func:`write_outputs` writes its files.
    """
    if not spec.parameters:  # SALib would fail on an empty problem (an IndexError, an internal error)
        raise ParameterError(
            f"study {spec.name!r} declares no uncertain parameters ([parameters.SECTION.FIELD] with a distribution): "
            "a sensitivity study needs at least one (a design spec's grid is run with `flexdigit study design`)"
        )
    settings = settings or SensitivitySettings.from_spec(spec)
    metrics = spec.study_metrics(SENSITIVITY_METRICS)
    u, design = sensitivity_design(spec, settings)
    values = spec.values_from_unit(u)
    context = MetricContext(
        baseline=spec.baseline,
        seed=spec.seed,
        bayes_samples=settings.bayes_samples,
        user_metrics=spec.user_metrics,
    )
    out_dir = Path(out_dir)
    header = {
        "kind": "sensitivity",
        "study": spec.name,
        "fingerprint": _fingerprint(spec, settings, metrics),
        "rows": int(values.shape[0]),
    }
    outputs, errors = run_study(
        spec.parameter_set,
        values,
        metrics,
        context,
        out_dir,
        header,
        seed=spec.seed,
        chunk_size=settings.chunk_size,
        workers=workers,
        scheduler=scheduler,
        force=force,
        progress=progress,
        label=f"sensitivity {spec.name}",
    )
    result = SensitivityResult(spec, settings, tuple(metrics), values, design, outputs, errors)
    _analyse(result, u, rerun or f"rerun `flexdigit study sensitivity` with --n {4 * settings.sobol_n}")
    return result


def _undefined(metric: str, value: float) -> str:
    """Why ``metric`` has no value on a row that ran: the metric's own words (:data:`metrics.UNDEFINED`) for a NaN,
    else the value itself (an infinity from a user's metric)."""
    if math.isnan(value) and metric in UNDEFINED:
        return f"{metric} undefined: {UNDEFINED[metric]}"
    return f"{metric} = {value}"


def _fingerprint(spec, settings, metrics) -> str:
    import hashlib
    import json

    text = json.dumps([spec.fingerprint(), settings.__dict__, list(metrics)], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _analyse(result: SensitivityResult, u: np.ndarray, rerun: str) -> None:
    from SALib.analyze import morris as morris_analyze

    spec, settings = result.spec, result.settings
    problem = _problem(spec)
    names = spec.names
    for metric in result.metrics:
        y = result.outputs[metric]
        bad = np.flatnonzero(~np.isfinite(y))
        if bad.size:
            i = int(bad[0])
            why = result.errors[i] or _undefined(metric, y[i])
            params = ", ".join(f"{n}={v:.6g}" for n, v in zip(names, result.values[i], strict=True))
            result.refused[metric] = (
                f"not finite on {bad.size} of {y.size} rows (e.g. row {i}: {why}; {params}): "
                "no indices from a subset of the design"
            )
            warn(f"{metric}: {result.refused[metric]}")
            continue
        if np.ptp(y) <= 1e-12 * max(1.0, float(np.max(np.abs(y)))):
            result.refused[metric] = f"constant over the study ({y[0]:.6g}): no parameter moves it"
            continue
        morris = result.design == "morris"
        if morris.any():
            res = morris_analyze.analyze(
                problem,
                u[morris],
                y[morris],
                num_resamples=settings.bootstrap,
                conf_level=settings.confidence,
                num_levels=settings.morris_levels,
                seed=_salib_seed(spec.seed, 4),
            )
            result.morris[metric] = {
                k: np.asarray(res[k], dtype=float) for k in ("mu_star", "mu_star_conf", "sigma", "mu")
            }
        ys = y[result.design == "sobol"]
        d = len(names)
        per_base = 2 * d + 2 if settings.second_order else d + 2
        by_n = {}
        for n in (settings.sobol_n, 2 * settings.sobol_n):
            by_n[n] = sobol_indices(
                names, ys[: n * per_base], settings.second_order, settings.bootstrap, settings.confidence, spec.seed
            )
        result.sobol[metric] = by_n
        a, b = by_n[settings.sobol_n], by_n[2 * settings.sobol_n]
        change = float(max(np.max(np.abs(a["S1"] - b["S1"])), np.max(np.abs(a["ST"] - b["ST"]))))
        converged = change <= settings.convergence_tol
        result.convergence[metric] = {
            "converged": converged,
            "max_change": change,
            "tolerance": settings.convergence_tol,
            "n": [settings.sobol_n, 2 * settings.sobol_n],
        }
        if not converged:
            warn(
                f"{metric}: Sobol indices NOT converged: they moved by {change:.3f} > {settings.convergence_tol} "
                f"between N = {settings.sobol_n} and {2 * settings.sobol_n}; {rerun}"
            )


def write_outputs(result: SensitivityResult, out_dir: str | Path, *, force: bool = False) -> dict[str, Path]:
    """Write ``indices.parquet``, ``evaluations.parquet``, ``summary.json`` and the figures; return their paths."""
    import json

    import pyarrow as pa
    import pyarrow.parquet as pq

    out_dir = Path(out_dir)
    paths = {
        "indices": out_dir / "indices.parquet",
        "evaluations": out_dir / "evaluations.parquet",
        "summary": out_dir / "summary.json",
    }
    for path in paths.values():
        check_output(path, force=force)
    meta = {
        b"flexdigit_study": json.dumps(
            {"study": result.spec.name, "fingerprint": result.spec.fingerprint(), "settings": result.settings.__dict__}
        ).encode()
    }
    table = result.table()
    columns = ["metric", "method", "index", "parameter", "parameter_2", "n_base", "value", "conf"]
    indices = pa.table({c: [r[c] for r in table] for c in columns}).replace_schema_metadata(meta)
    with atomic_path(paths["indices"], force=force) as tmp:
        pq.write_table(indices, tmp)
    evals = {"row": np.arange(result.values.shape[0]), "design": result.design.astype(str)}
    for j, name in enumerate(result.spec.names):
        evals[name] = result.values[:, j]
    for metric in result.metrics:
        evals[metric] = result.outputs[metric]
    evals["error"] = [e or "" for e in result.errors]
    with atomic_path(paths["evaluations"], force=force) as tmp:
        pq.write_table(pa.table(evals).replace_schema_metadata(meta), tmp)
    summary = result.summary()
    summary["figures"] = [str(p) for p in figures.sensitivity_figures(result, out_dir / "figures", force=force)]
    with atomic_write(paths["summary"], "w", force=force) as fh:
        json.dump(to_jsonable(summary), fh, indent=2)
    return paths


#: The metrics the batched twin computes for a whole task at once: the report's study runs on these.
TWIN_METRICS = (
    "release_wn_rad_s",
    "release_zeta",
    "actuated_wn_rad_s",
    "rotation_gain_deg_per_command",
    "tip_stiffness_nm_per_rad",
)


def twin_sensitivity(
    sobol_n: int = 64, *, seed: int = 0, spec: StudySpec | None = None, rerun: str | None = None
) -> SensitivityResult:
    """The shipped tolerances' Sobol indices for the twin's metrics (:data:`TWIN_METRICS`), in this process.

    What ``flexdigit reproduce`` shows (no Dask cluster start-up inside the report): every evaluation is one pass
    of the batched twin, so 2N (d + 2) rows cost a few seconds. The control and tactile metrics need a controller
    design or a Monte Carlo per row: ``flexdigit study sensitivity thesis-tolerances`` computes them on Dask.
    ``rerun``: the hint of the "NOT converged" warning (:func:`run_sensitivity`), in the caller's terms.
    """
    import dataclasses
    import tempfile

    spec = spec or load_spec("thesis-tolerances")
    spec = dataclasses.replace(spec, metrics=TWIN_METRICS, seed=seed)
    settings = SensitivitySettings(morris_trajectories=4, sobol_n=sobol_n, chunk_size=10**6, bootstrap=200)
    with tempfile.TemporaryDirectory() as tmp:
        return run_sensitivity(spec, tmp, settings=settings, workers=0, progress=False, rerun=rerun)
