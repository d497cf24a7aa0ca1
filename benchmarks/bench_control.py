"""H-infinity design speed: our Riccati route vs a plain python-control ``hinfsyn`` on the same plant (issue 5)."""

from __future__ import annotations

import warnings

from benchmarks._common import best_of


def _best_ms(fn, repeat: int = 20) -> float:
    """The shortest of ``repeat`` wall times of ``fn()``, ms."""
    return 1e3 * best_of(fn, repeat)


def run() -> list[dict]:
    warnings.simplefilter("ignore")
    from flexdigit.control._threads import single_blas_thread
    from flexdigit.control.generalized import filter_weight, regularise, thesis_generalized_plant
    from flexdigit.control.synthesis import hinf_riccati, hinfsyn_plain
    from flexdigit.control.thesis_designs import THESIS_REGULARISATION, thesis_plant

    eps, margin = THESIS_REGULARISATION[5.0]
    P = regularise(thesis_generalized_plant(thesis_plant(), filter_weight(5.0)), eps)
    ours = _best_ms(lambda: hinf_riccati(P, margin=margin))
    plain = _best_ms(lambda: hinfsyn_plain(P))

    def plain_single():
        with single_blas_thread():
            hinfsyn_plain(P)

    plain_1 = _best_ms(plain_single)
    return [
        {
            "name": "H-inf design, thesis 5 Hz problem (Riccati route, scaled, margin)",
            "value": ours,
            "unit": "ms",
            "goal": "<= 20 ms",
            "note": "gamma bisection from ||P11|| (gtol 1e-4) + central controller, best of 20",
        },
        {
            "name": "plain control.hinfsyn on the same regularised plant",
            "value": plain,
            "unit": "ms",
            "goal": "peer",
            "note": "SLICOT SB10AD gamma search from 1e100, best of 20, default OpenBLAS threads",
        },
        {
            "name": "plain control.hinfsyn, BLAS pinned to one thread",
            "value": plain_1,
            "unit": "ms",
            "goal": "peer",
            "note": "same call inside threadpoolctl's limit(1), as flexdigit runs SLICOT",
        },
    ]
