"""The batched twin against the scalar twin it vectorises, and its antagonistic cable against closed forms."""

import numpy as np
import pytest

from flexdigit.params import Geometry, Material, RigParams, twin_cells
from flexdigit.twin import Twin
from flexdigit.twin.batched import BatchedChains, BatchedTwin
from flexdigit.twin.calibration import default_calibration
from flexdigit.twin.twin import cable_shortening_m, cached_digit

PSI_ATOL = 1e-9  # rad: the same arithmetic in another order
STATIC_ATOL = 1e-10
ASSEMBLY_RTOL = 1e-14  # BatchedChains.from_rigs against a Chain per rig: the same products, stacked

CAL = default_calibration()
RIGS = [
    (RigParams(), CAL),
    (RigParams(material=Material(youngs_modulus_pa=190e9)), CAL.replace(housing_ei_n_m2=(0.007, 0.003, 0.004))),
    (RigParams(geometry=Geometry(cable_eccentricity_m=5.0e-3)), CAL.replace(cable_stiffness_n_m=2.0e4)),
    (RigParams(), CAL.replace(support_mass_kg=(0.012, 0.006, 0.01), strip_beta_s=1e-3)),
]


def _scalar_run(params, cal, commands, steps, **kw):
    twin = Twin(params, cal, **kw)
    out = []
    for k in range(steps):
        if k in commands:
            twin.command(commands[k])
        twin.advance(twin.dt_s)
        out.append(twin.dynamics.psi.copy())
    return np.array(out)


@pytest.mark.parametrize("orientation", ["vertical", "horizontal"])
def test_steps_like_n_scalar_twins(orientation):
    # a full-range step and back: the servo, the latch, the slack/taut cable and the halved steps all engage
    commands = {0: 43, 40: 8, 55: 30}
    steps = 90
    batch = BatchedTwin([p for p, _ in RIGS], [c for _, c in RIGS], orientation=orientation)
    got = []
    for k in range(steps):
        if k in commands:
            batch.command([commands[k]] * len(RIGS))
        batch.advance(batch.dt_s)
        got.append(batch.psi.copy())
    got = np.array(got)
    for i, (p, c) in enumerate(RIGS):
        ref = _scalar_run(p, c, commands, steps, orientation=orientation)
        np.testing.assert_allclose(got[:, i], ref, atol=PSI_ATOL, rtol=0)
    # some members needed halved steps, alone
    assert batch.substeps.max() > steps
    assert batch.substeps.min() < batch.substeps.max()


def test_statics_and_modes_match_each_chain():
    chains = [cached_digit(p, c, True, "vertical", 3) for p, c in RIGS]
    batch = BatchedChains(chains)
    short = cable_shortening_m(np.array([8, 20, 30, 43]), RigParams())
    psi = batch.solve_static(short)
    for i, ch in enumerate(chains):
        ref = ch.solve_static(cable_shortening_m=[short[i]]).psi_rad[0]
        np.testing.assert_allclose(psi[i], ref, atol=STATIC_ATOL)
    wn, zeta = batch.linear_modes()
    for i, ch in enumerate(chains):
        w, z = ch.linear_modes()
        assert wn[i] == pytest.approx(w[0], rel=1e-10)
        assert zeta[i] == pytest.approx(z[0], rel=1e-8)


def _seeded_rigs(count, seed):
    """Rigs drawn around the thesis rig (seeded): modulus, density, thickness, eccentricity, size, gauge places,
    housing stiffness and mass (none on some), support masses, damping, cable: several layouts in one batch."""
    rng = np.random.default_rng(seed)
    rigs = []
    for _ in range(count):
        size = rng.choice([0.8, 1.0, 1.0, 1.2])
        geo = Geometry(
            section_length_m=0.080 * size,
            digit_length_m=0.270 * size,
            strip_length_m=0.240 * size,
            strip_thickness_m=rng.uniform(0.36e-3, 0.40e-3),
            cable_eccentricity_m=rng.uniform(5e-3, 6.5e-3),
            gauge_positions_m=tuple(size * np.array([0.045, 0.135, 0.225]) + rng.choice([0.0, 1e-3])),
        )
        mat = Material(youngs_modulus_pa=rng.uniform(190e9, 215e9), strip_density_kg_m3=rng.uniform(7700, 8000))
        cal = CAL.replace(
            housing_ei_n_m2=tuple(np.array(CAL.housing_ei_n_m2) * rng.uniform(0.8, 1.2, 3)),
            housing_mass_kg=rng.choice([0.0, rng.uniform(0.005, 0.02)]),
            support_mass_kg=tuple(np.array(CAL.support_mass_kg) * rng.uniform(0.9, 1.1, 3)),
            strip_beta_s=CAL.strip_beta_s * rng.uniform(0.5, 2.0),
            cable_stiffness_n_m=CAL.cable_stiffness_n_m * rng.uniform(0.5, 2.0),
        )
        rigs.append((RigParams(geometry=geo, material=mat), cal))
    return rigs


@pytest.mark.parametrize(
    ("orientation", "housing", "pretension"), [("vertical", True, None), ("horizontal", False, 5.0)]
)
def test_from_rigs_is_the_batch_of_each_rigs_digit(orientation, housing, pretension):
    # stacked assembly against the batch of build_digit chains it replaces: every matrix, the same numbers
    from flexdigit.twin.digit import build_digit

    rigs = _seeded_rigs(40, seed=11)
    kw = {"housing": housing, "orientation": orientation, "cells_per_section": 3}
    pre = None if pretension is None else np.where(np.arange(len(rigs)) % 3 == 0, 0.0, pretension)
    anta = None if pre is None else pre > 0
    ref = BatchedChains([build_digit(p, c, **kw) for p, c in rigs], pre, anta)
    got = BatchedChains.from_rigs([p for p, _ in rigs], [c for _, c in rigs], **kw, pretension_n=pre, antagonist=anta)
    for name in ("k", "c", "a", "ga", "gb", "e", "kc", "to_curvature", "link", "s0", "stiffness", "pre", "antagonist"):
        np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=ASSEMBLY_RTOL, atol=0, err_msg=name)
    assert got.bandwidth == ref.bandwidth
    assert len({float(p.geometry.digit_length_m) for p, _ in rigs}) > 1  # several layouts were stacked
    np.testing.assert_allclose(got.linear_modes()[0], ref.linear_modes()[0], rtol=ASSEMBLY_RTOL)


def test_from_rigs_refuses_rigs_it_cannot_stack():
    with pytest.raises(ValueError, match="one calibration per rig"):
        BatchedChains.from_rigs([RigParams()] * 2, [CAL])
    four = RigParams(geometry=Geometry(section_count=4, digit_length_m=0.36, strip_length_m=0.32))
    with pytest.raises(ValueError, match="rig 1 has 12 springs"):
        BatchedChains.from_rigs(
            [RigParams(), four], [CAL, CAL.replace(housing_ei_n_m2=(0.005,) * 4, support_mass_kg=(0.01,) * 4)]
        )


def test_antagonist_adds_k_e2_at_the_tip_and_bends_both_ways():
    ch = cached_digit(RigParams(), CAL, True, "vertical", 3)
    single, double = BatchedChains([ch], pretension_n=None), BatchedChains([ch], pretension_n=[5.0])
    moment = 1e-4  # N m, small: the linear stiffness

    def compliance(chains, pre_short):
        psi0 = chains.solve_static([pre_short])[0, -1]
        psi1 = chains.solve_static([pre_short], tip_moment_nm=[moment])[0, -1]
        return (psi1 - psi0) / moment

    # the single cable pretensioned by shortening it 5 N worth: taut, like the antagonistic pair at rest
    c1 = compliance(single, 5.0 / ch.cable_stiffness)
    c2 = compliance(double, 0.0)
    # each taut cable adds k_c e^2 to the tip's rotational stiffness (3.3: moment T e, T = k_c (s - e psi))
    assert 1 / c2 - 1 / c1 == pytest.approx(ch.cable_stiffness * ch.eccentricity**2, rel=2e-3)
    # below the equilibrium command the single cable goes slack; the pair bends the digit the other way
    twins = BatchedTwin([RigParams()] * 2, [CAL] * 2, pretension_n=[0.0, 5.0])
    one = BatchedTwin(RigParams(), CAL)
    for t in (one, twins):
        t.command([0] * t.size)
        t.advance(2.0)
    assert abs(one.tip_rotation_deg()[0]) < 0.5
    assert np.all(twins.tip_rotation_deg() < -5.0)


def test_a_described_pair_keeps_its_pretension_like_the_scalar_twin():
    # issue 24: a digit whose [cables] describes the antagonistic pair runs on the batched twin as on the scalar one
    # (each rig's own pretension, no pretension_n argument): both signs of bending, the step through the slack
    # cable, the same numbers to PSI_ATOL
    pair5 = RigParams.from_dict({"cables": {"count": 2, "pretension_n": 5.0}})
    pair2 = RigParams.from_dict({"cables": {"count": 2, "pretension_n": 2.0}})
    rigs = [(pair5, CAL), (pair2, CAL.replace(cable_stiffness_n_m=2.0e4)), (RigParams(), CAL)]
    straight = [p.actuator.equilibrium_command for p, _ in rigs]
    schedule = {0: [c - 20 for c in straight], 60: [c + 20 for c in straight]}
    batch = BatchedTwin([p for p, _ in rigs], [c for _, c in rigs])
    got = []
    for k in range(120):
        if k in schedule:
            batch.command([max(0, c) for c in schedule[k]])
        batch.advance(batch.dt_s)
        got.append(batch.psi.copy())
        if k == 59:
            below = batch.tip_rotation_deg().copy()
    got = np.array(got)
    for i, (p, c) in enumerate(rigs):
        commands = {k: max(0, v[i]) for k, v in schedule.items()}
        # at the batch's resolution, the description's: a scalar twin on a derived calibration runs finer
        scalar = _scalar_run(p, c, commands, 120, cells_per_section=twin_cells(p))
        np.testing.assert_allclose(got[:, i], scalar, atol=PSI_ATOL, rtol=0)
    assert np.all(below[:2] < -5.0)  # the pair bends the digit back below straight (ignored, the digit stays put)
    # detached (cable=False): neither cable of the pair pulls, as the scalar twin's cable=False
    loose = BatchedTwin([pair5], [CAL], cable=False)
    loose.command([0])
    loose.advance(0.5)
    assert abs(loose.tip_rotation_deg()[0]) < 1e-9


def test_bad_inputs_are_named():
    with pytest.raises(ValueError, match="command"):
        BatchedTwin(RigParams()).command([255])
    with pytest.raises(ValueError, match="pretension_n"):
        BatchedTwin([RigParams()] * 2, pretension_n=[1.0, -1.0])
    with pytest.raises(ValueError, match="one clock"):
        from flexdigit.params import Actuator

        BatchedTwin([RigParams(), RigParams(actuator=Actuator(serial_period_s=0.01))])


def test_threads_and_batch_size_do_not_change_a_bit():
    # the kernel steps one rig at a time: blocks on two threads, or the rig in a batch of its own, same bits (no
    # sum runs across rigs, so the thread count is exactly the property; one machine, no stored number)
    rigs = [RigParams(material=Material(youngs_modulus_pa=e)) for e in np.linspace(195e9, 215e9, 256)]
    runs = []
    for threads, batch in ((1, rigs), (2, rigs), (1, rigs[100:101])):
        twins = BatchedTwin(batch)
        twins.threads = threads
        twins.command([30] * len(batch))
        twins.advance(0.4)
        runs.append(twins.psi.copy())
    np.testing.assert_array_equal(runs[1], runs[0])
    np.testing.assert_array_equal(runs[2][0], runs[0][100])


def test_a_diverging_rig_is_named():
    # non-finite angles in one rig: its steps are halved to the limit, then the error names it (no silent NaN)
    twins = BatchedTwin([RigParams()] * 10)
    twins.psi[3, 2] = np.nan
    with pytest.raises(ArithmeticError, match="rig 3"):
        twins.advance(0.04)
