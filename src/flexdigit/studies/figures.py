"""Figures of the studies: Sobol indices with their intervals, the total-index map, S2 heat maps, Pareto fronts.

Each function draws from a result object and saves through :mod:`flexdigit._io` (atomic, no clobber without
``force``); the report calls the ``*_figure`` builders and saves them itself, and ``flexdigit study ... --plot``
saves the study's main one (:func:`sensitivity_figure`; a design study's Pareto front, titled by
:func:`with_subject`). Figures are made without pyplot (:func:`flexdigit._plot.new_figure`: no global state,
nothing to close).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flexdigit._io import atomic_path
from flexdigit._plot import new_figure

__all__ = [
    "sobol_bars_figure",
    "total_index_map_figure",
    "s2_figure",
    "pareto_figure",
    "sample_size_text",
    "convergence_note",
    "sensitivity_bars",
    "sensitivity_total_map",
    "sensitivity_figures",
    "sensitivity_figure",
    "study_subject",
    "with_subject",
]


def _save(fig, path: Path, force: bool) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path, force=force) as tmp:
        fig.savefig(tmp, dpi=110, bbox_inches="tight", format="png")
    return path


def sobol_bars_figure(names, res: dict, title: str):
    """S1 and ST per parameter as bars with their bootstrap confidence intervals."""
    d = len(names)
    x = np.arange(d)
    fig, ax = new_figure(figsize=(max(6.0, 0.45 * d + 2), 3.6))
    ax.bar(x - 0.2, res["S1"], 0.4, yerr=res["S1_conf"], capsize=2, label="S1 (first order)")
    ax.bar(x + 0.2, res["ST"], 0.4, yerr=res["ST_conf"], capsize=2, label="ST (total)")
    ax.set_xticks(x, [n.replace("calibration.", "cal.") for n in names], rotation=60, ha="right", fontsize=7)
    ax.set_ylabel("Sobol index")
    ax.set_title(title, fontsize=9)
    ax.axhline(0, color="k", lw=0.5)
    ax.legend(fontsize=7)
    return fig


def total_index_map_figure(names, metrics, st: np.ndarray, title: str):
    """Total indices, metrics (rows) x parameters (columns)."""
    fig, ax = new_figure(figsize=(max(6.0, 0.45 * len(names) + 3), 0.45 * len(metrics) + 2))
    im = ax.imshow(np.clip(st, 0, 1), vmin=0, vmax=1, cmap="viridis", aspect="auto")
    ax.set_xticks(
        range(len(names)), [n.replace("calibration.", "cal.") for n in names], rotation=60, ha="right", fontsize=7
    )
    ax.set_yticks(range(len(metrics)), metrics, fontsize=7)
    for i in range(st.shape[0]):
        for j in range(st.shape[1]):
            if np.isfinite(st[i, j]) and st[i, j] >= 0.05:
                ax.text(
                    j, i, f"{st[i, j]:.2f}", ha="center", va="center", fontsize=6, color="w" if st[i, j] < 0.6 else "k"
                )
    fig.colorbar(im, ax=ax, label="total Sobol index ST")
    ax.set_title(title, fontsize=9)
    return fig


def s2_figure(names, s2: np.ndarray, title: str):
    """Second-order indices as a heat map (upper triangle)."""
    d = len(names)
    grid = np.full((d, d), np.nan)
    iu = np.triu_indices(d, 1)
    grid[iu] = s2[iu]
    fig, ax = new_figure(figsize=(0.4 * d + 3, 0.4 * d + 2.5))
    im = ax.imshow(grid, cmap="magma", aspect="equal")
    labels = [n.replace("calibration.", "cal.") for n in names]
    ax.set_xticks(range(d), labels, rotation=60, ha="right", fontsize=6)
    ax.set_yticks(range(d), labels, fontsize=6)
    fig.colorbar(im, ax=ax, label="S2")
    ax.set_title(title, fontsize=9)
    return fig


def pareto_figure(x, y, front, marks: dict, xlabel: str, ylabel: str, title: str):
    """Candidates (grey), their Pareto front (line) and marked designs (``marks``: label -> (x, y))."""
    fig, ax = new_figure(figsize=(6.2, 4.2))
    ax.scatter(x, y, s=8, c="0.75", label="candidates")
    order = np.argsort(x[front])
    ax.plot(x[front][order], y[front][order], "-o", ms=4, color="C0", label="Pareto front")
    for k, (label, (mx, my)) in enumerate(marks.items()):
        ax.scatter([mx], [my], s=70, marker="*^sDv"[k % 5], color=f"C{k + 1}", zorder=5, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    return fig


def sample_size_text(settings) -> str:
    """The N a figure's indices come from, tied to the N asked for (``--n 8``): the study evaluates 2N base samples
    and compares the indices at N and 2N, so the figures show 2N and say so.

    >>> from flexdigit.studies.sensitivity import SensitivitySettings
    >>> sample_size_text(SensitivitySettings(sobol_n=8))
    'N = 16 (2 x 8: indices at 8 and 16 compared)'
    """
    n = settings.sobol_n
    return f"N = {2 * n} (2 x {n}: indices at {n} and {2 * n} compared)"


def convergence_note(conv: dict | None) -> str:
    """``"NOT converged: ..."`` for a metric whose indices moved past the tolerance (on the figure, not only the
    terminal), ``""`` when converged."""
    if not conv or conv.get("converged", True):
        return ""
    small, big = conv["n"]
    return f"NOT converged: moved {conv['max_change']:.3f} > {conv['tolerance']} between N = {small} and {big}"


def sensitivity_bars(result, metric: str, title: str):
    """:func:`sobol_bars_figure` of one metric at 2N, its title carrying the N used and any "NOT converged"."""
    note = convergence_note(result.convergence.get(metric))
    res = result.sobol[metric][2 * result.settings.sobol_n]
    return sobol_bars_figure(result.spec.names, res, title + (f"\n{note}" if note else ""))


def sensitivity_total_map(result, title: str):
    """:func:`total_index_map_figure` at 2N; an unconverged metric's row says so, and the title counts them."""
    big = 2 * result.settings.sobol_n
    metrics = list(result.sobol)
    st = np.array([result.sobol[m][big]["ST"] for m in metrics])
    labels = [m + (" (NOT converged)" if convergence_note(result.convergence.get(m)) else "") for m in metrics]
    off = sum(label.endswith("(NOT converged)") for label in labels)
    tail = f"\n{off} of {len(metrics)} metrics NOT converged" if off else ""
    return total_index_map_figure(result.spec.names, labels, st, title + tail)


def sensitivity_figures(result, fig_dir: Path, *, force: bool = False) -> list[Path]:
    """Every figure of a sensitivity result, saved under ``fig_dir``."""
    names = result.spec.names
    big = 2 * result.settings.sobol_n
    size = sample_size_text(result.settings)
    paths = []
    for metric, by_n in result.sobol.items():
        res = by_n[big]
        fig = sensitivity_bars(result, metric, f"{metric}: Sobol indices, {size}, {result.settings.confidence:.0%} CI")
        paths.append(_save(fig, fig_dir / f"sobol_{metric}.png", force))
        if "S2" in res:
            paths.append(
                _save(
                    s2_figure(names, res["S2"], f"{metric}: second-order indices"), fig_dir / f"s2_{metric}.png", force
                )
            )
    if result.sobol:
        fig = sensitivity_total_map(result, f"{result.spec.name}: total Sobol indices, {size}")
        paths.append(_save(fig, fig_dir / "sobol_total_map.png", force))
    return paths


def study_subject(spec) -> str:
    """What a study's baseline is, for a title: ``robot rao2021``, ``the thesis rig`` or ``the digit of SPEC``."""
    robot = getattr(spec.baseline, "robot", None)
    if robot is not None:
        return f"robot {robot.name}"
    if spec.baseline.params.is_thesis_rig():
        return "the thesis rig"
    return f"the digit of {Path(spec.source).name}"


def with_subject(fig, spec):
    """``fig`` with a suptitle naming the study and its baseline (:func:`study_subject`)."""
    fig.suptitle(f"study {spec.name} on {study_subject(spec)}", fontsize=9)
    return fig


def sensitivity_figure(result):
    """The main figure of a sensitivity study (``flexdigit study sensitivity ... --plot``): one metric's S1 and ST
    with their intervals (:func:`sensitivity_bars`), or for several metrics the map of their total indices
    (:func:`sensitivity_total_map`), at 2N, titled with the study and its baseline."""
    size = sample_size_text(result.settings)
    metrics = list(result.sobol)
    if len(metrics) == 1:
        conf = f"{result.settings.confidence:.0%} CI"
        fig = sensitivity_bars(result, metrics[0], f"{metrics[0]}: Sobol indices, {size}, {conf}")
    else:
        fig = sensitivity_total_map(result, f"total Sobol indices, {size}")
    return with_subject(fig, result.spec)
