"""A point contact on rao2021 located from its gauges, over a seeded set of contacts: the first-order estimate
(``locate_contact`` without tensions) and the one refined through the twin (``sense_contact``), against the twin's
truth (issue 26's follow-up: a 50 mN push along y at 300 mm was 25 % off).

The set (seed 0): 60 contacts at nodes from the second gauge station (75 mm) to the tip, directions uniform on
the sphere, magnitudes log-uniform 10-200 mN, tensions 0, (2,0,0,0,1,0) or (4,0,0,0,2,0) N, read without noise
and with a microstrain of it. Rows: the force error (% of the force) median / 95th percentile / largest, the
place error, the share within two of the estimate's own sigmas, and the time per refined estimate.

Run: ``python -m benchmarks bench_tdcrfix``.
"""

from __future__ import annotations

import time

import numpy as np

TENSIONS_N = ([0.0] * 6, [2.0, 0, 0, 0, 1.0, 0], [4.0, 0, 0, 0, 2.0, 0])


def contact_set(count: int = 60, seed: int = 0) -> list[tuple[list[float], float, np.ndarray]]:
    """``(tensions, s_m, force_n)`` per contact: places on the twin's nodes beyond 75 mm, directions uniform on
    the sphere, magnitudes log-uniform in 10-200 mN."""
    from flexdigit.tdcr import ROBOTS, pressed_shape

    nodes = pressed_shape(ROBOTS["rao2021"], TENSIONS_N[0]).s_m
    nodes = nodes[nodes > 0.076]
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        direction = rng.normal(size=3)
        magnitude = np.exp(rng.uniform(np.log(0.01), np.log(0.2)))
        tensions = TENSIONS_N[rng.integers(len(TENSIONS_N))]
        out.append((tensions, float(rng.choice(nodes)), magnitude * direction / np.linalg.norm(direction)))
    return out


def survey(count: int = 60, seed: int = 0, noise_std: float = 0.0) -> dict:
    """The errors of both estimates over :func:`contact_set`; contacts the twin cannot hold are counted apart."""
    from flexdigit.errors import ParameterError
    from flexdigit.tdcr import ROBOTS, locate_contact, sense_contact

    robot = ROBOTS["rao2021"]
    first, refined, place_first, place_refined, within, seconds, failed = [], [], [], [], [], [], 0
    sure = []
    for k, (tensions, s_m, force) in enumerate(contact_set(count, seed)):
        start = time.perf_counter()
        try:
            found = sense_contact(robot, tensions, contact_s_m=s_m, contact_force_n=force, noise_std=noise_std, seed=k)
        except ParameterError:
            failed += 1
            continue
        seconds.append(time.perf_counter() - start)
        est = found.estimate
        seen = force if est.unseen_direction is None else force - (force @ est.unseen_direction) * est.unseen_direction
        magnitude = np.linalg.norm(force)
        refined.append(np.linalg.norm(est.force_n - seen) / magnitude)
        place_refined.append(abs(est.s_m - s_m))
        within.append(bool(np.all(np.abs(est.force_n - seen) <= 2 * est.force_std_n + 1e-12)))
        sure.append(bool(np.linalg.norm(est.force_std_n) <= 0.2 * magnitude))  # not said "uncertain" by the CLI
        plain = locate_contact(robot, found.layout, found.strains, found.free)
        seen = (
            force
            if plain.unseen_direction is None
            else force - (force @ plain.unseen_direction) * plain.unseen_direction
        )
        first.append(np.linalg.norm(plain.force_n - seen) / magnitude)
        place_first.append(abs(plain.s_m - s_m))
    return {
        "first": np.array(first),
        "refined": np.array(refined),
        "place_first_m": np.array(place_first),
        "place_refined_m": np.array(place_refined),
        "within_2_sigma": np.array(within),
        "sure": np.array(sure),
        "seconds": np.array(seconds),
        "failed": failed,
    }


def _spread(errors) -> str:
    median, high = 100 * np.median(errors), 100 * np.percentile(errors, 95)
    return f"median {median:.3g} %, 95th {high:.3g} %, max {100 * errors.max():.3g} %"


def run() -> list[dict]:
    """Both estimates' force errors, without noise and with a microstrain (``python -m benchmarks bench_tdcrfix``)."""
    from threadpoolctl import threadpool_limits

    rows = []
    with threadpool_limits(1):
        for noise in (0.0, 1e-6):
            got = survey(noise_std=noise)
            label = "no noise" if noise == 0 else "1 microstrain noise"
            n = got["refined"].size
            rows += [
                {
                    "name": f"tdcr contact, first order: force error ({label})",
                    "value": 100 * float(np.median(got["first"])),
                    "unit": "% median",
                    "goal": "",
                    "note": f"{_spread(got['first'])}; place error max {1e3 * got['place_first_m'].max():.1f} mm; "
                    f"{n} contacts, 10-200 mN, seed 0",
                },
                {
                    "name": f"tdcr contact, refined through the twin: force error ({label})",
                    "value": 100 * float(np.median(got["refined"])),
                    "unit": "% median",
                    "goal": "",
                    "note": f"{_spread(got['refined'])}; place error max {1e3 * got['place_refined_m'].max():.2f} mm; "
                    f"{int(got['within_2_sigma'].sum())}/{n} within 2 sigma per component; "
                    f"the {int(got['sure'].sum())} not said uncertain: {_spread(got['refined'][got['sure']])}; "
                    f"{got['failed']} the twin could not hold; {1e3 * np.median(got['seconds']):.0f} ms median each",
                },
            ]
    return rows


if __name__ == "__main__":
    for row in run():
        print(row)
