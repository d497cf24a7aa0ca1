"""Plausible values in a digit's description (issue 24: "bad descriptions refused in one line"): every physical key
has a range with its reason (:func:`flexdigit.params.plausible_ranges`); a value just outside is refused in one
line naming the file, the key, the value and the range, and what real digits have (nitinol, PEEK and bronze strips,
semiconductor gauges, 8- to 24-bit ADCs, a 20:1 gear) loads."""

from __future__ import annotations

import pytest
import tomli_w

from digits import DIGITS, random_digit, write_digit
from flexdigit.errors import ParameterError
from flexdigit.params import builtin_digits, load_params, params_template, plausible_ranges

RANGES = plausible_ranges()
#: How far outside a bound the known-answer values sit (relative): far above float rounding, a value a typo makes.
OUTSIDE = 1e-3

#: The bounds the issue names, known answers: (table, key) -> (low, high).
NAMED = {
    ("material", "strip_density_kg_m3"): (800.0, 22_600.0),  # polymers (PE 920) to osmium
    ("material", "youngs_modulus_pa"): (1e8, 6e11),  # LDPE/PTFE to high-modulus carbon fibre
    ("sensors", "gauge_factor"): (0.5, 250.0),  # foil ~2 (the thesis's 0.8) to semiconductor ~100-200
    ("sensors", "adc_bits"): (8, 24),
    ("actuator", "gear_ratio"): (1.0, 20.0),
    ("sensors", "amplifier_gain_v_per_v"): (1.0, 1e5),
    ("sensors", "excitation_v"): (0.1, 30.0),
    ("sensors", "gauge_resistance_ohm"): (50.0, 20_000.0),
    ("actuator", "stall_torque_nm"): (5e-3, 100.0),
    ("actuator", "pwm_frequency_hz"): (20.0, 1000.0),
    ("actuator", "servo_wn_rad_s"): (1.0, 1000.0),
    ("actuator", "servo_zeta"): (0.05, 5.0),
}
#: The per-gauge lists, each value held to its scalar key's range.
PER_GAUGE = {"gauge_factors": "gauge_factor", "amplifier_gains_v_per_v": "amplifier_gain_v_per_v"}


def _outside(r, side: str):
    """A value just outside the range ``r`` on ``side``."""
    if r.type.__name__ == "Integral":
        return r.low - 1 if side == "low" else r.high + 1
    bound = r.low if side == "low" else r.high
    step = -OUTSIDE if side == "low" else OUTSIDE
    return bound + step * abs(bound) if bound != 0 else step


@pytest.mark.parametrize(("key", "bounds"), list(NAMED.items()), ids=lambda v: "-".join(map(str, v)))
def test_the_named_bounds(key, bounds):
    r = RANGES[key]
    assert (r.low, r.high) == bounds
    assert r.why  # the reason, in one phrase


@pytest.mark.parametrize("side", ["low", "high"])
@pytest.mark.parametrize("key", sorted(RANGES), ids="-".join)
def test_a_value_just_outside_is_refused_in_one_line(key, side, tmp_path):
    table, name = key
    r = RANGES[key]
    value = _outside(r, side)
    if name in PER_GAUGE:
        document = {"sensors": {name: [RANGES[("sensors", PER_GAUGE[name])].valid_value(), value, 1.0]}}
    else:
        document = {table: {name: value}}
    path = write_digit("thesis", tmp_path, **document)
    with pytest.raises(ParameterError) as info:
        load_params(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(str(path))
    assert f"'{name}'" in message
    if name not in PER_GAUGE:
        assert r.describe() in message  # the expected range and its reason
        assert repr(value) in message or str(value) in message


@pytest.mark.parametrize(
    "document",
    [
        {"material": {"youngs_modulus_pa": 75e9, "strip_density_kg_m3": 6450.0}},  # nitinol (austenite)
        {"material": {"youngs_modulus_pa": 28e9, "strip_density_kg_m3": 6450.0}},  # nitinol (martensite)
        {"material": {"youngs_modulus_pa": 3.6e9, "strip_density_kg_m3": 1300.0}},  # PEEK
        {"material": {"youngs_modulus_pa": 110e9, "strip_density_kg_m3": 8800.0}},  # phosphor bronze
        {"material": {"youngs_modulus_pa": 0.2e9, "strip_density_kg_m3": 920.0}},  # polyethylene
        {"sensors": {"gauge_factor": 150.0, "gauge_resistance_ohm": 1000.0}},  # a p-type silicon gauge
        {"sensors": {"gauge_factors": [2.0, 120.0, 0.8]}},  # foil, semiconductor and the thesis's
        {"sensors": {"adc_bits": 8}},
        {"sensors": {"adc_bits": 24, "excitation_v": 10.0, "gauge_resistance_ohm": 350.0}},
        {"actuator": {"gear_ratio": 20.0}},
        {"geometry": {"strip_thickness_m": 0.05e-3}},  # 0.05 mm shim stock
    ],
    ids=["nitinol-A", "nitinol-M", "peek", "bronze", "pe", "silicon", "mixed-gauges", "8-bit", "24-bit", "gear-20",
         "shim"],
)  # fmt: skip
def test_what_real_digits_have_loads(document, tmp_path):
    params = load_params(write_digit("thesis", tmp_path, **document))
    for table, values in document.items():
        for key, value in values.items():
            got = getattr(getattr(params, table), key)
            assert (list(got) if isinstance(got, tuple) else got) == value


def test_the_weightless_strip_is_zero_not_a_tiny_density(tmp_path):
    """0 kg/m^3 is the beam oracles' idealisation (named as such); 1e-30 kg/m^3 is no material."""
    assert load_params(write_digit("thesis", tmp_path, material={"strip_density_kg_m3": 0.0})).material
    path = write_digit("thesis", tmp_path, material={"strip_density_kg_m3": 1e-30})
    with pytest.raises(ParameterError, match=r"'strip_density_kg_m3' .* inside \[800, 22600\] kg/m\^3 .* 1e-30"):
        load_params(path)


def test_every_example_and_test_digit_still_loads(tmp_path):
    for name in builtin_digits():
        load_params(name)
    for name in DIGITS:
        load_params(write_digit(name, tmp_path))
    for seed in range(61):
        path = tmp_path / f"random-{seed}.toml"
        path.write_text(tomli_w.dumps(random_digit(seed)))
        load_params(path)


def test_the_template_states_each_range():
    text = params_template()
    for (table, key), r in RANGES.items():
        if table == "dynamics" or key == "section_count":
            continue
        assert f"# Range {r.low:g} to {r.high:g}" in text, key
    assert "# Range 1 to 8 in a description" in text
