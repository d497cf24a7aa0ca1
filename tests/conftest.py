"""Shared test set-up: a non-interactive matplotlib backend, and the hypothesis profiles.

Hypothesis profiles (issue 16): ``flexdigit`` (the default, ``make test``) runs 200 examples per property,
derandomized (the same examples every run: a seeded test suite); ``fuzz`` (``make fuzz``, or
``HYPOTHESIS_PROFILE=fuzz``) runs 10,000, from the seed ``make fuzz`` passes (``FUZZ_SEED``, default 0).
"""

import os
from pathlib import Path

import matplotlib
import pytest
from hypothesis import HealthCheck, settings

matplotlib.use("Agg")

#: Examples per property in ``make test`` and in ``make fuzz`` (quoted in docs/guide/reliability.md).
EXAMPLES = {"flexdigit": 200, "fuzz": 10_000}
_COMMON = dict(
    deadline=None,  # a shared 2-core machine: timing is not a property
    database=None,  # nothing written beside the tests; failures print their example
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much],
)
settings.register_profile("flexdigit", max_examples=EXAMPLES["flexdigit"], derandomize=True, **_COMMON)
settings.register_profile("fuzz", max_examples=EXAMPLES["fuzz"], **_COMMON)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "flexdigit"))


def pytest_report_header(config):
    """The OpenBLAS kernel the numbers are computed with (``make test`` runs the ``blas`` tests under several)."""
    import numpy  # noqa: F401  (loads numpy's OpenBLAS, which threadpoolctl reports)
    from threadpoolctl import threadpool_info

    kernels = sorted({str(i.get("architecture")) for i in threadpool_info() if i.get("internal_api") == "openblas"})
    asked = os.environ.get("OPENBLAS_CORETYPE", "unset")
    return f"openblas kernel: {', '.join(kernels) or 'none'} (OPENBLAS_CORETYPE={asked})"


#: The documentation site's build (tests/test_docs.py: Sphinx and the gallery's examples, a minute or more); first.
FIRST = "test_docs.py"
#: The longest files (path under tests/) and their seconds in a full run on two workers (the run's own list of its
#: 30 longest files, a fresh clone of 0d15c45 on an idle machine, `make test`'s pytest 11 min 56 s, flexdigit's
#: numba kernels already in the user's cache; tdcr/test_chain_kernel at its figure with a cold cache, c0c3f27):
#: first, longest first, so that neither worker is left running one of them alone at the end.
LONGEST_S = {
    "tactile/test_digit_data_path.py": 76,
    "cli/test_campaign_digits.py": 69,
    "report/test_digit_reports.py": 67,
    "cli/test_digit_control.py": 51,
    "studies/test_execution.py": 48,
    "live/test_page.py": 47,
    "firmware/test_board.py": 45,
    "tactile/test_bayes_drift.py": 42,
    "test_io_commands.py": 34,
    "tdcr/test_chain_kernel.py": 31,
    "cli/test_palpate_pairs.py": 30,
    "twin/test_twin_resolution.py": 29,
    "tactile/test_refined_network.py": 27,
    "firmware/test_eight_gauges.py": 26,
    "cli/test_stop_signals.py": 25,
    "live/test_server.py": 24,
    "firmware/test_digit_images.py": 23,
    "live/test_resources.py": 22,
    "studies/test_resources.py": 21,
    "rig/test_rotation_perturbed.py": 21,
    "rig/backends/test_stream_third_party.py": 21,
    "studies/test_cluster.py": 21,
}
_TESTS = Path(__file__).resolve().parent


def pytest_configure(config):
    """Keep the files in the order :func:`pytest_collection_modifyitems` gives them. pytest-xdist (3.8) hands
    ``--dist loadfile``'s files out by their number of tests, most first, unless told not to: the site's build (one
    test) and the files of one or two slow tests went last, one worker finishing them alone while the other idled.
    """
    if hasattr(config.option, "loadscopereorder"):  # xdist installed; harmless without -n
        config.option.loadscopereorder = False


def pytest_collection_modifyitems(session, config, items):
    """Run the longest files first: the site's build, then the files of :data:`LONGEST_S` longest first, then every
    other file with a ``slow`` test, then the rest (each group in its collected order). ``make test`` runs two
    pytest-xdist workers that take whole files (``--dist loadfile``): started first, the long files overlap the
    short ones instead of one left running alone at the end (longest-processing-time-first scheduling). The order
    is the same in every worker, as xdist requires."""
    slow = {item.path for item in items if item.get_closest_marker("slow")}

    def measured_s(path: Path) -> float:
        try:
            return LONGEST_S.get(path.relative_to(_TESTS).as_posix(), 0)
        except ValueError:  # a doctest of src/flexdigit
            return 0

    items.sort(key=lambda item: (item.path.name != FIRST, -measured_s(item.path), item.path not in slow))


#: Seconds each test file took (set-up, call and tear-down of its tests, as the workers report them to the
#: controller); printed at the end of the run, the longest first, for :data:`LONGEST_S`.
_FILE_SECONDS: dict[str, float] = {}
#: How many files the summary lists.
FILES_SHOWN = 30


def pytest_runtest_logreport(report):
    path = report.nodeid.split("::", 1)[0]
    _FILE_SECONDS[path] = _FILE_SECONDS.get(path, 0.0) + report.duration


def pytest_terminal_summary(terminalreporter):
    """The longest test files of this run (seconds, summed over their tests): where the suite's time goes."""
    if not _FILE_SECONDS:
        return
    terminalreporter.section(f"the {FILES_SHOWN} longest files (s, their tests summed)")
    longest = sorted(_FILE_SECONDS.items(), key=lambda item: -item[1])[:FILES_SHOWN]
    for path, seconds in longest:
        terminalreporter.write_line(f"{seconds:8.1f}  {path}")


def _work_started(*args, **kwargs):
    raise RuntimeError("the work started")


@pytest.fixture
def work_must_not_start(monkeypatch):
    """``work_must_not_start(obj, "name", ...)``: those attributes raise "the work started" when called, so a test
    can check that a refusal came before the work (the twin stepping, a chapter building), not after it."""

    def patch(*targets):
        for obj, name in zip(targets[::2], targets[1::2], strict=True):
            monkeypatch.setattr(obj, name, _work_started)

    return patch


@pytest.fixture
def drawn(monkeypatch):
    """The figures :func:`flexdigit._plot.save_plot` saved, in order (the ``--plot`` tests read their lines)."""
    import flexdigit._plot

    figures = []
    save = flexdigit._plot.save_plot

    def keep(fig, path, command="", *, force=False):
        figures.append(fig)
        return save(fig, path, command, force=force)

    monkeypatch.setattr(flexdigit._plot, "save_plot", keep)
    return figures
