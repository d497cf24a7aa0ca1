"""Contact in the twin against solutions it was not written from.

- The elastica boundary-value problem of the whole digit (rigid supports, support masses, the cable, the body's
  foundation with its edges and inclusions as free boundaries), solved by ``scipy.integrate.solve_bvp`` in
  ``tests/oracles.py``: tip position and contact force within :data:`BVP_RTOL` (1 %, issue 13) at the twin's
  default resolution (3 cells per section).
- A beam on an elastic foundation (Hetenyi 1946): the small-deflection tip load of a uniform cantilever resting on
  a Winkler foundation, from the general solution of ``EI y'''' + k y = 0`` (a 4 x 4 linear solve for its
  constants): :data:`FOUNDATION_RTOL`.
- Point forces and a line load in small deflection: the bending moment at every spring is the statics of a
  cantilever, ``sum P (a - x) + q (end - x)^2 / 2`` (exact for the chain at its springs): :data:`MOMENT_RTOL`.
- Dynamics: a uniform strip oscillating in its first mode against a body that touches it along its whole length
  (gap 0) is a bilinear oscillator; the foundation adds ``k / mu`` to the mode's ``w^2`` without changing its shape,
  so the period is ``pi / w1 + pi / sqrt(w1^2 + k / mu)`` with ``w1`` Euler-Bernoulli's: :data:`PERIOD_RTOL`.
"""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.params import RigParams
from flexdigit.twin import Twin
from flexdigit.twin.calibration import default_calibration
from flexdigit.twin.contact import Inclusion, PointForce, Pressure, Tissue, solve_contact
from flexdigit.twin.digit import Chain, DynamicState
from flexdigit.twin.twin import cable_shortening_m, cached_digit

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from oracles import digit_contact_bvp, thesis_digit_segments  # noqa: E402

pytestmark = pytest.mark.blas  # run again under other OpenBLAS kernels by `make test` (docs/guide/reliability.md)

BVP_RTOL = 0.01
FOUNDATION_RTOL = 0.01
MOMENT_RTOL = 1e-6
PERIOD_RTOL = 0.01
#: "Exact" for the pressure quadrature: within 1e-12 of the largest moment, each spring's moment. Rounding in the
#: solve and the differencing of the joint angles leaves at most 406 eps (9e-14) of it under the Haswell, SkylakeX,
#: Nehalem and Prescott kernels; a rule that put the load of the cell the load ends in at the cell's middle would
#: be off by 1.4e-2 of it.
QUADRATURE_TOL = 1e-12
#: The compiled contact quadrature against the numpy one, on each array's scale: the same operations in the same
#: order, equal to the bit on this machine under all four BLAS kernels; but numba compiles for the CPU it runs on
#: and numpy's sin/cos and sums have SIMD paths of their own, so another CPU may differ by an ulp per operation,
#: carried through at most 24 links' sums: 64 eps.
CONTACT_KERNEL_TOL = 64 * np.finfo(float).eps
#: The compiled generalised forces, Jacobians and resultant against their numpy references, on each array's scale:
#: the same products in the same order for the forces and Jacobians (equal to the bit here), but the resultant's
#: sums run in order where np.sum sums pairwise, and another CPU's sin/cos may differ by an ulp: an ulp per point of
#: up to ~200 (the links in contact x the body's pieces x Gauss points), 1e-13 (450 eps); a lever, a sign or a
#: cosine wrong would be off by its whole term, ~1e-2 of the scale.
GENERALIZED_KERNEL_TOL = 1e-13

PARAMS = RigParams()
CAL = default_calibration()
L_STRIP, EI_STRIP = 0.24, 205e9 * 12.7e-3 * 0.381e-3**3 / 12
MU = 7850.0 * 12.7e-3 * 0.381e-3


def _oracle(tissue: Tissue, command: int, **extra):
    segments, supports = thesis_digit_segments(PARAMS, CAL)
    body = {
        "start": tissue.start_m,
        "end": tissue.end_m,
        "gap": tissue.gap_m,
        "modulus": tissue.modulus_n_m2,
        "exponent": tissue.exponent,
        "side": tissue.sign,
        "inclusions": [(i.centre_m, i.width_m, i.ratio) for i in tissue.inclusions],
    }
    return digit_contact_bvp(
        segments,
        strip_mass_per_m=PARAMS.material.strip_density_kg_m3 * PARAMS.geometry.cross_section_m2,
        point_masses=dict(zip(supports, CAL.support_mass_kg, strict=True)),
        gravity_ab=(-9.80665, 0.0),  # the twin's default mounting: vertical, tip up
        eccentricity_m=PARAMS.geometry.cable_eccentricity_m,
        cable_stiffness_n_m=CAL.cable_stiffness_n_m,
        cable_shortening_m=float(cable_shortening_m(command, PARAMS)),
        tissue=body,
        **extra,
    )


CASES = {
    # a stiff body beside the tip, the cable pressing the digit into it (the palpation set-up)
    "tip, linear": (Tissue(0.24, 0.30, 0.02, 5000.0), 20, {}),
    # Hertzian exponent, contact over the middle section, past a rigid support
    "middle, Hunt-Crossley n = 1.5": (Tissue(0.10, 0.20, 0.01, 20000.0, exponent=1.5), 25, {}),
    # a 3x inclusion inside the contact: its edges are free boundaries of the BVP
    "inclusion in the contact": (Tissue(0.15, 0.30, 0.04, 2000.0, inclusions=(Inclusion(0.255, 0.01, 3.0),)), 30, {}),
}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_contact_statics_match_the_elastica_bvp(name):
    tissue, command, _ = CASES[name]
    ref = _oracle(tissue, command)
    assert ref.converged, ref.message
    chain = cached_digit(PARAMS, CAL, True, "vertical", 3)
    sol = solve_contact(chain, tissue=tissue, cable_shortening_m=[float(cable_shortening_m(command, PARAMS))])
    assert sol.converged
    assert ref.contact_force_n < -0.05  # a real contact, pushing the digit back (N)
    assert np.linalg.norm(sol.tip_m[0] - ref.tip) / np.linalg.norm(ref.tip) < BVP_RTOL
    assert sol.contact_force_n[0] == pytest.approx(ref.contact_force_n, rel=BVP_RTOL)
    assert sol.static.tension_n[0] == pytest.approx(ref.tension_n, rel=BVP_RTOL)
    assert sol.contact_centroid_m[0] == pytest.approx(ref.contact_centroid_m, abs=1e-3)


@pytest.mark.slow
def test_point_forces_and_a_line_load_match_the_bvp():
    loads = [PointForce(0.12, -0.05), PointForce(0.26, -0.08), Pressure(0.19, 0.25, 0.06)]
    tissue = Tissue(0.24, 0.30, 0.03, 5000.0)
    ref = _oracle(tissue, 22, point_forces_b={0.12: -0.05, 0.26: -0.08}, pressures_b=[(0.19, 0.25, 0.06)])
    assert ref.converged, ref.message
    chain = cached_digit(PARAMS, CAL, True, "vertical", 3)
    sol = solve_contact(chain, tissue=tissue, loads=loads, cable_shortening_m=[float(cable_shortening_m(22, PARAMS))])
    assert np.linalg.norm(sol.tip_m[0] - ref.tip) / np.linalg.norm(ref.tip) < BVP_RTOL
    assert sol.contact_force_n[0] == pytest.approx(ref.contact_force_n, rel=BVP_RTOL)


def test_contact_converges_with_resolution():
    tissue, command, _ = CASES["tip, linear"]
    short = [float(cable_shortening_m(command, PARAMS))]
    forces = [
        solve_contact(
            cached_digit(PARAMS, CAL, True, "vertical", c), tissue=tissue, cable_shortening_m=short
        ).contact_force_n[0]
        for c in (3, 9, 27)
    ]
    # the 27-cell chain stands in for the limit: the error falls roughly as h^2 (3x finer: ~9x smaller)
    assert abs(forces[0] - forces[2]) > 4 * abs(forces[1] - forces[2])


def hetenyi_tip_deflection(p_n, length, ei, k):
    """Small-deflection tip deflection of a cantilever resting on a Winkler foundation ``k`` (N/m^2) under a tip
    load ``p_n``: ``y = e^{bx}(A cos bx + B sin bx) + e^{-bx}(C cos bx + D sin bx)``, ``b = (k / 4 EI)^(1/4)``;
    clamped at 0 (y = y' = 0), free at L (EI y'' = 0, EI y''' = -P)."""
    b = (k / (4 * ei)) ** 0.25

    def basis(x):  # y, y', y'', y''' of the four solutions at x
        rows = []
        for sgn, trig in ((1, 0), (1, 1), (-1, 0), (-1, 1)):
            z = complex(sgn * b, b)  # e^{(sgn b + i b) x}: real part cos, imaginary part sin
            rows.append([(z**d * np.exp(z * x)).imag if trig else (z**d * np.exp(z * x)).real for d in range(4)])
        return np.array(rows).T

    m0, ml = basis(0.0), basis(length)
    system = np.array([m0[0], m0[1], ml[2], ml[3]])
    coef = np.linalg.solve(system, [0.0, 0.0, 0.0, -p_n / ei])
    return float(ml[0] @ coef)


def test_beam_on_elastic_foundation_matches_hetenyi():
    k = 2000.0  # N/m^2: beta L = 1.6, the deflection stays on one side (the unilateral body never lets go)
    chain = Chain.uniform(L_STRIP, EI_STRIP, 48)
    p = 1e-4
    sol = solve_contact(
        chain, tissue=Tissue(-0.01, 0.3, 0.0, k, side="opposite"), load_s_m=[[L_STRIP]], load_force_ab_n=[[[0, -p]]]
    )
    exact = hetenyi_tip_deflection(p, L_STRIP, EI_STRIP, k)
    assert exact > 0
    assert -sol.tip_m[0, 1] == pytest.approx(exact, rel=FOUNDATION_RTOL)
    bare = p * L_STRIP**3 / (3 * EI_STRIP)
    assert exact < 0.8 * bare  # the foundation carries a real share of the load


def line_load_moment(x, lo, hi, total):
    """Moment at ``x`` of ``total`` N spread evenly on ``[lo, hi]``: ``q/2 ((hi - x)^2 - (max(x, lo) - x)^2)``."""
    q = total / (hi - lo)
    inside = np.clip(x, lo, hi)
    return np.where(x < hi, 0.5 * q * ((hi - x) ** 2 - (inside - x) ** 2), 0.0)


def test_point_forces_and_a_line_load_give_the_cantilever_moments():
    chain = Chain.uniform(L_STRIP, EI_STRIP, 24)
    loads = [PointForce(0.08, 2e-6), PointForce(0.2, -1e-6), Pressure(0.1, 0.22, 3e-6)]
    sol = solve_contact(chain, loads=loads)
    x = chain.joint_s_m
    curvature = np.diff(sol.static.psi_rad[0], prepend=0.0) / chain.cell_length_m
    moment = 2e-6 * np.clip(0.08 - x, 0, None) - 1e-6 * np.clip(0.2 - x, 0, None)
    moment += line_load_moment(x, 0.1, 0.22, 3e-6)
    np.testing.assert_allclose(curvature * EI_STRIP, moment, rtol=MOMENT_RTOL, atol=1e-12)


def test_pressure_quadrature_is_exact_for_the_moment_past_a_spring():
    # a line load ending between two springs: the 2-point rule per piece still gives the exact statics
    chain = Chain.uniform(L_STRIP, EI_STRIP, 6)
    total = 1e-6
    sol = solve_contact(chain, loads=[Pressure(0.05, 0.17, total)])
    moment = line_load_moment(chain.joint_s_m, 0.05, 0.17, total)
    curvature = np.diff(sol.static.psi_rad[0], prepend=0) / chain.cell_length_m
    # Exact up to rounding, so compared on the scale of the largest moment (the root's): past the load's end the
    # moment is 0.0 and the chain gives a rounding residue whose sign and size follow the BLAS kernel (-3.2e-23 on
    # SkylakeX, 0.0 on Haswell), which no relative tolerance admits.
    np.testing.assert_allclose(curvature * EI_STRIP, moment, rtol=0, atol=QUADRATURE_TOL * np.abs(moment).max())


def test_unilateral_contact_oscillates_as_a_bilinear_oscillator():
    n = 16
    chain = Chain.uniform(L_STRIP, EI_STRIP, n, mass_per_length_kg_m=MU)
    w1 = 1.8751040687**2 * math.sqrt(EI_STRIP / (MU * L_STRIP**4))  # Euler-Bernoulli, clamped-free
    k = 3.0 * MU * w1**2  # in contact the mode runs at 2 w1: the period is 3/4 of the free one
    w_chain = chain.linear_modes()[0][0]
    assert w_chain == pytest.approx(w1, rel=0.01)
    # start in the chain's own first mode, moving into the body (its surface at the straight strip: gap 0)
    import scipy.linalg

    m = chain.a_mass
    vals, vecs = scipy.linalg.eigh(chain.k_psi, m)
    mode = vecs[:, 0] / np.max(np.abs(vecs[:, 0])) * 1e-3
    state = DynamicState(chain, psi=np.zeros(n), omega=mode * w_chain)
    from flexdigit.twin.contact import TissueContact

    state.contact = TissueContact(chain, Tissue(-0.01, 0.3, 0.0, k))
    h, t, tip, times = 5e-4, 0.0, [], []
    for _ in range(int(1.2 / h)):
        state.step(h, -np.inf, -np.inf)
        t += h
        tip.append(chain.tip(state.psi)[1])
        times.append(t)
    tip, times = np.array(tip), np.array(times)
    # upward zero crossings of the tip (leaving the body into free flight) are one period apart
    up = np.flatnonzero((tip[:-1] < 0) & (tip[1:] >= 0))
    crossings = times[up] - tip[up] * h / (tip[up + 1] - tip[up])
    period = float(np.mean(np.diff(crossings)))
    exact = math.pi / w_chain + math.pi / math.sqrt(w_chain**2 + k / MU)
    assert period == pytest.approx(exact, rel=PERIOD_RTOL)
    assert period < 0.8 * 2 * math.pi / w_chain  # the body shortens the period


def test_the_twin_settles_on_the_static_contact():
    tissue = Tissue(0.24, 0.30, 0.02, 5000.0, damping_s_m=0.5)
    twin = Twin(seed=0)
    twin.set_tissue(tissue)
    twin.command(20)
    twin.advance(8.0)
    force, centroid, _ = twin.contact_state()
    static = solve_contact(twin.chain, tissue=tissue, cable_shortening_m=[float(cable_shortening_m(20, PARAMS))])
    assert force == pytest.approx(static.contact_force_n[0], rel=0.01)
    assert centroid == pytest.approx(static.contact_centroid_m[0], abs=5e-4)
    np.testing.assert_allclose(twin.tip_position_m(), static.tip_m[0], atol=2e-4)


def test_press_and_pressure_on_the_twin_move_the_gauges_as_the_statics_say():
    twin = Twin(seed=0, command=20)
    twin.press(-0.05, 0.25)
    twin.apply_pressure(-0.04, 0.15, 0.2)
    twin.advance(10.0)
    static = solve_contact(
        twin.chain,
        loads=[PointForce(0.25, -0.05), Pressure(0.15, 0.2, -0.04)],
        cable_shortening_m=[float(cable_shortening_m(20, PARAMS))],
    )
    np.testing.assert_allclose(twin.tip_position_m(), static.tip_m[0], atol=1e-4)
    twin.clear_presses()
    assert twin.presses == []


def test_set_tissue_settle_starts_at_rest_in_contact():
    twin = Twin(seed=0, command=25)
    twin.set_tissue(Tissue(0.24, 0.30, 0.02, 5000.0), settle=True)
    force0, _, _ = twin.contact_state()
    twin.advance(1.0)
    assert force0 < -0.1
    assert twin.contact_state()[0] == pytest.approx(force0, rel=1e-3)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: Tissue(0.2, 0.1, 0.0, 1.0), "'end_m' parameter of Tissue"),
        (lambda: Tissue(0.1, 0.2, 0.0, -5.0), "'modulus_n_m2'"),
        (lambda: Tissue(0.1, 0.2, float("nan"), 5.0), "'gap_m'"),
        (lambda: Tissue(0.1, 0.2, 0.0, 5.0, exponent=0.5), "'exponent'"),
        (lambda: Tissue(0.1, 0.2, 0.0, 5.0, side="left"), "'side'"),
        (lambda: Tissue(0.1, 0.3, 0, 5, inclusions=(Inclusion(0.2, 0.04, 3), Inclusion(0.21, 0.02, 2))), "overlap"),
        (lambda: Inclusion(0.2, 0.0, 3.0), "'width_m'"),
        (lambda: Twin().press(0.1, 0.3), "'position_m' parameter of Twin.press"),
        (lambda: Twin().press(float("inf"), 0.2), "'force_n' parameter of Twin.press"),
        (lambda: Twin().apply_pressure(0.1, 0.2, 0.1), "'end_m' parameter of Twin.apply_pressure"),
        (lambda: Twin().set_tissue("soft"), "'tissue' parameter of Twin.set_tissue"),
    ],
)
def test_bad_contact_inputs_are_named(make, message):
    with pytest.raises(ParameterError, match=message):
        make()


def test_compiled_contact_quadrature_is_the_numpy_quadrature_to_rounding():
    # TissueContact.points runs a compiled kernel; the numpy quadrature it replaced is the reference: seeded random
    # bodies (either side, gaps from pressing-in to clear, inclusions), mountings, resolutions and batches of
    # shapes, rates with damping: every array within CONTACT_KERNEL_TOL of its scale (equal to the bit here)
    rng = np.random.default_rng(13)
    for trial in range(120):
        chain, contact = _random_contact(rng, trial)
        psi = rng.normal(0.0, 0.15, (int(rng.integers(1, 25)), chain.n)) * rng.uniform(0.0, 2.0)
        omega = rng.normal(0.0, 1.0, psi.shape)
        for got, want in zip(contact.points(psi, omega), contact._points_numpy(psi, omega), strict=True):
            scale = np.abs(want).max(initial=0.0)
            np.testing.assert_allclose(got, want, rtol=CONTACT_KERNEL_TOL, atol=CONTACT_KERNEL_TOL * scale)


def test_compiled_contact_forces_are_the_numpy_forces_to_rounding():
    # TissueContact.generalized and .resultant run compiled kernels (the dynamics ask them every step, each reading
    # asks the resultant); the numpy code they replaced is the reference: seeded random bodies (either side, gaps,
    # inclusions, Hunt-Crossley exponents 1 and 1.5, with and without damping), mountings, resolutions, batches of
    # shapes with and without rates: every array within GENERALIZED_KERNEL_TOL of its scale, the NaNs where they are
    rng = np.random.default_rng(29)
    for trial in range(90):
        chain, contact = _random_contact(rng, trial, exponent=(1.0, 1.5)[trial % 5 == 0])
        psi = rng.normal(0.0, 0.15, (int(rng.integers(1, 25)), chain.n)) * rng.uniform(0.0, 2.0)
        omega = (None, rng.normal(0.0, 1.0, psi.shape))[trial % 3 != 1]
        gen, res = contact.generalized(psi, omega), contact.resultant(psi, omega)
        gen_ref, res_ref = contact._generalized_numpy(psi, omega), contact._resultant_numpy(psi, omega)
        assert (gen[2] is None) == (gen_ref[2] is None), f"trial {trial}: dQ/domega given without damping"
        names = ("Q", "dQ/dpsi", "dQ/domega", "force", "centroid", "first", "last", "beyond")
        got = [*gen, res[0], res[1], *res[2], res[3]]
        want = [*gen_ref, res_ref[0], res_ref[1], *res_ref[2], res_ref[3]]
        for name, a, b in zip(names, got, want, strict=True):
            if b is None:
                continue
            scale = np.nanmax(np.abs(b), initial=0.0)
            np.testing.assert_allclose(a, b, rtol=0, atol=GENERALIZED_KERNEL_TOL * scale, err_msg=f"{trial}: {name}")


def _random_contact(rng, trial: int, **tissue_options):
    """A seeded random body beside the digit (either side, a gap from pressing-in to clear, an inclusion on three
    trials of four, damping on odd trials), on a mounting and resolution set by ``trial``: ``(chain, contact)``."""
    from flexdigit.twin.contact import TissueContact

    chain = cached_digit(PARAMS, CAL, True, ("vertical", "horizontal")[trial % 2], (3, 2, 4)[trial % 3])
    start = float(rng.uniform(0.0, 0.2))
    end = start + float(rng.uniform(0.01, 0.3))
    inclusions = (Inclusion(float(rng.uniform(start, end)), 0.02, float(rng.uniform(0.3, 5.0))),) if trial % 4 else ()
    tissue = Tissue(
        start,
        end,
        float(rng.uniform(-0.002, 0.02)),
        float(rng.uniform(1e3, 1e5)),
        inclusions=inclusions,
        damping_s_m=0.5 * (trial % 2),
        side=("cable", "opposite")[trial % 3 == 0],
        **tissue_options,
    )
    return chain, TissueContact(chain, tissue)
