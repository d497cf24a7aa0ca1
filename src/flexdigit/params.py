"""Rig parameters: one source of truth, frozen dataclasses in SI units, the thesis rig as the default.

Sections 2.2-2.5 and 3.1-3.4 of the thesis (tables 3.5, 3.7), transcribed in ``reference/thesis.toml``. Every
field carries its unit in its name; the serial position "command" (0..254) counts as a unit. A few values the
thesis does not give (strip density, bridge excitation, low-pass order) are marked as assumptions in their
docstring; the twin's calibration absorbs them.

Load and save as TOML with :func:`load_params` and :func:`save_params` (``flexdigit params --write rig.toml``
dumps the defaults); every bad value raises :class:`~flexdigit.errors.ParameterError` naming the file, the key,
the value and what was expected.

Examples
--------
>>> p = RigParams()
>>> round(p.geometry.second_moment_m4 * 1e14, 3)   # table 3.7: 5.8532e-14 m^4
5.853
>>> round(p.actuator.rad_per_command, 6)           # E 3.15: 0.8622 deg per command
0.015048
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from dataclasses import dataclass, field
from numbers import Integral, Real
from pathlib import Path
from typing import Any

from flexdigit._io import atomic_write, read_text
from flexdigit._repr import differences, summary
from flexdigit._validation import (
    Array,
    Interval,
    Options,
    Plausible,
    check_array,
    check_int,
    check_real,
    declare,
    validate_fields,
)
from flexdigit.errors import DataFileError, ParameterError

__all__ = [
    "BRIDGE_TYPES",
    "Geometry",
    "Material",
    "Sensors",
    "Actuator",
    "DigitDynamics",
    "Cables",
    "TwinResolution",
    "RigParams",
    "MAX_SECTIONS",
    "MAX_GAUGES",
    "MAX_CELL_LENGTH_M",
    "MIN_CELLS_PER_SECTION",
    "MAX_TWIN_CELLS",
    "cells_no_longer_than",
    "twin_cells",
    "digit_inconsistencies",
    "derived_figures",
    "plausible_ranges",
    "params_template",
    "description_notes",
    "adc_range_notes",
    "builtin_digits",
    "load_params",
    "save_params",
]

BRIDGE_TYPES = ("quarter", "half", "full")
# Plausible ranges (flexdigit._validation.Plausible): generous bounds for a user's own digit, not the thesis rig's
# values; each says why. A value outside its range whose unit slip lands inside it (0.381 "m" for a 0.381 mm strip,
# E = 205 "Pa" for 205 GPa) is refused naming the slip. Lengths share one range so a digit of any sensible size
# (a 5 cm fingertip to a 2 m arm) passes.
#: A digit's or a strip's length.
DIGIT_LENGTH_M = Plausible("m", 0.02, 2.0, "a digit 2 cm to 2 m long: a 1 km strip or a 10 m digit is a unit slip")
#: One frequency of a second-order model (the servo's, the digit's).
_NATURAL_FREQUENCY = Plausible("rad/s", 0.01, 1e4, "a mechanical mode of 0.0016 Hz to 1.6 kHz")


#: A serial position command: the servo board's position byte, 0..254 (255 is its sync byte, 3.4.1).
SERVO_COMMAND = Plausible("", 0, 254, "the servo board's position byte; 255 is its sync byte", integer=True)
#: A gauge channel's voltage as a DAQ card reads it: the thesis's card reads +-5 V; no card reads +-100 V. A
#: channel in mV read as V is 1000 times too large, and named as such.
GAUGE_V = Plausible("V", -100.0, 100.0, "a gauge channel as a DAQ card reads it (the thesis's: +-5 V)")
#: A weight hung on the digit (tactile protocols, the twin's load test): the thesis hung 7.5 to 25 g on its
#: 0.381 mm strip; 2 kg bounds any digit of the sizes Geometry accepts.
LOAD_KG = Plausible("kg", 1e-4, 2.0, "a hung weight of 0.1 g to 2 kg; the thesis hung 7.5 to 25 g")
#: Where a load hangs, measured from the tip: on a digit at most 2 m long (a protocol also checks its own digit).
POSITION_FROM_TIP_M = Plausible("m", 0.0, 2.0, "on a digit at most 2 m long, from its tip")
#: The strip's modulus: a spring backbone carrying bonded gauges, from soft polymers (LDPE, PTFE ~0.2-0.5 GPa;
#: PEEK 3.6 GPa) through nitinol (28-83 GPa), bronzes (~110 GPa) and steels (~200 GPa) to tungsten (411 GPa) and
#: high-modulus carbon fibre (~600 GPa). An elastomer (MPa) carries no foil gauge.
YOUNGS_MODULUS_PA = Plausible("Pa", 1e8, 6e11, "a spring strip: polymers from 0.1 GPa to carbon fibre, 600 GPa")
#: The strip's density: polymers (polyethylene 920, PEEK 1300) through nitinol (6450), steels (7850) and bronzes
#: (8800) to tungsten (19,300) and osmium (22,600); exactly 0 is the weightless strip the beam oracles take.
STRIP_DENSITY_KG_M3 = Plausible(
    "kg/m^3", 800.0, 22_600.0, "polymers (PE 920) to metals (osmium 22,600)", zero="a weightless strip, an idealisation"
)
#: A strain gauge's gauge factor: metal foil ~2 (the thesis's effective 0.8, 6.4) to p-type silicon ~100-200.
GAUGE_FACTOR = Plausible("", 0.5, 250.0, "metal foil ~2 (the thesis's 0.8) to semiconductor gauges ~100-200")
#: An instrumentation amplifier's gain (the thesis's Fylde FE-366-TA: 10,000).
AMPLIFIER_GAIN = Plausible("V/V", 1.0, 1e5, "an instrumentation amplifier: 1 to 100,000 (the thesis's 10,000)")
#: A servo's position pulse (hobby servos: 0.5-2.5 ms; the thesis's 1-2 ms, 3.4.1).
SERVO_PULSE_S = Plausible("s", 1e-4, 5e-3, "a servo pulse of 0.1 to 5 ms (usually 0.5-2.5 ms)")
#: The least part of the digit's rotation (max_rotation_per_section_deg x section_count) the servo's stall torque
#: must bend the strip through: below it the servo cannot bend the strip (RigParams checks it).
STRIP_BEND_FRACTION = 0.1


@declare
@dataclass(frozen=True)
class Geometry:
    """The digit's geometry (2.2, table 3.5, table 3.7).

    Attributes
    ----------
    section_count : int
        Number of sections (2.2): 3.
    section_length_m : float or tuple of float
        Spring-steel strip length per section (2.2.2): 80 mm. One value: every section that long; a list of
        ``section_count`` values: each section its own length, from the base (their sum is ``strip_length_m``).
    strip_thickness_m, strip_width_m : float
        Strip cross-section, 0.015 in x 0.5 in (2.2.2).
    digit_length_m : float
        ``l`` of table 3.7, clamp to tip: 270 mm. Its ``digit_length_m - strip_length_m`` are ``section_count``
        supports of equal length, half a support at the clamp and at the tip (:attr:`section_bounds_m`).
    strip_length_m : float
        Free strip length, 3 x 80 mm = 240 mm; table 3.4's ``y_max`` column fits x ~ 0.241 m, i.e. this.
    cable_eccentricity_m : float
        ``e`` of table 3.7, cable to neutral axis: 5.715 mm.
    gauge_positions_m : tuple of float
        Strain-gauge pairs from the base (table 3.5): 45, 135, 225 mm, midway between supports (2.3.2).
    max_rotation_per_section_deg : float
        30 degrees per section, to keep the spring steel elastic (2.2).
    guide_hole_diameter_m : float
        Cable guide holes, 0.042 in (2.2.1).
    support_lengths_m : tuple of float, optional
        One nylon support length per section, the support that ends it (the last one's centre is the tip; half of
        the first sits at the clamp); left out: ``(digit_length_m - strip_length_m) / section_count`` each (10 mm).
    """

    section_count: int = 3
    section_length_m: float | tuple[float, ...] = 0.080
    strip_thickness_m: float = 0.381e-3
    strip_width_m: float = 12.7e-3
    digit_length_m: float = 0.270
    strip_length_m: float = 0.240
    cable_eccentricity_m: float = 5.715e-3
    gauge_positions_m: tuple[float, ...] = (0.045, 0.135, 0.225)
    max_rotation_per_section_deg: float = 30.0
    guide_hole_diameter_m: float = 1.067e-3
    support_lengths_m: tuple[float, ...] | None = None

    _parameter_constraints = {
        "section_count": [Plausible("", 1, 50, "1 to 50 sectional supports; more is a continuum", integer=True)],
        "section_length_m": [
            Plausible("m", 1e-3, 2.0, "a section 1 mm to the longest digit, 2 m"),
            Array(ndim=1, min_length=1, low=1e-3, high=2.0),  # one per section: each 1 mm to 2 m
        ],
        "strip_thickness_m": [Plausible("m", 2.5e-5, 5e-3, "a strip 0.025 mm (shim stock) to 5 mm (a plate) thick")],
        "strip_width_m": [Plausible("m", 1e-3, 0.2, "a strip 1 mm (a gauge's grid) to 20 cm wide")],
        "digit_length_m": [DIGIT_LENGTH_M],
        "strip_length_m": [DIGIT_LENGTH_M],
        "cable_eccentricity_m": [Plausible("m", 1e-4, 0.1, "a cable 0.1 mm to 10 cm off the neutral axis")],
        "gauge_positions_m": [Array(ndim=1, min_length=1, increasing=True, low=0, low_open=True)],
        "max_rotation_per_section_deg": [Interval(Real, 0, 180, closed="right")],
        "guide_hole_diameter_m": [Plausible("m", 1e-5, 0.02, "a cable guide hole 0.01 to 20 mm across")],
        "support_lengths_m": [Array(ndim=1, min_length=1, low=0.0, high=2.0), None],  # one per section, 0 to 2 m
    }

    def __post_init__(self) -> None:
        owner = type(self).__name__
        positions = self.gauge_positions_m
        if isinstance(positions, tuple | list) and len(set(map(repr, positions))) < len(positions):
            raise ParameterError(
                f"The 'gauge_positions_m' parameter of {owner} puts two gauges at one place: one gauge per position. "
                f"Got {list(positions)!r} instead."
            )
        if not isinstance(self.section_length_m, tuple | list):  # one length: its own message (a unit slip named)
            self._parameter_constraints["section_length_m"][0].check(
                self.section_length_m, "section_length_m", owner, ParameterError
            )
        validate_fields(self)
        if isinstance(self.section_length_m, tuple | list):  # one length per section, from the base
            lengths = check_array(self.section_length_m, "section_length_m", owner, ndim=1, low=1e-3, high=2.0)
            if lengths.size != self.section_count:
                raise ParameterError(
                    f"The 'section_length_m' parameter of {owner} must be one length or {self.section_count} "
                    f"(one per section). Got {lengths.tolist()!r} instead."
                )
            object.__setattr__(self, "section_length_m", tuple(float(x) for x in lengths))
        if self.support_lengths_m is not None:  # one support per section, the one that ends it
            supports = check_array(self.support_lengths_m, "support_lengths_m", owner, ndim=1, low=0.0, high=2.0)
            if supports.size != self.section_count:
                raise ParameterError(
                    f"The 'support_lengths_m' parameter of {owner} must have {self.section_count} values (one per "
                    f"section). Got {supports.tolist()!r} instead."
                )
            object.__setattr__(self, "support_lengths_m", tuple(float(x) for x in supports))
        check_real(self.strip_length_m, "strip_length_m", owner, low=0, low_open=True)
        if self.strip_length_m > self.digit_length_m:  # either key can be the one written wrong: name both
            raise ParameterError(
                f"The 'digit_length_m' parameter of {owner} ({self.digit_length_m:g} m) must be at least "
                f"'strip_length_m' ({self.strip_length_m:g} m): the digit is its strip plus the supports"
            )
        positions = check_array(
            self.gauge_positions_m,
            "gauge_positions_m",
            owner,
            ndim=1,
            min_length=1,
            increasing=True,
            low=0,
            high=self.digit_length_m,
            low_open=True,
            unit="m",
        )
        object.__setattr__(self, "gauge_positions_m", tuple(float(x) for x in positions))

    @property
    def second_moment_m4(self) -> float:
        """Second moment of area of the strip, ``w t^3 / 12`` (table 3.7: 5.8532e-14 m^4)."""
        return self.strip_width_m * self.strip_thickness_m**3 / 12.0

    @property
    def section_pitch_m(self) -> float:
        """Distance between sectional supports along the digit, ``digit_length_m / section_count`` (the mean
        pitch of unequal sections: :attr:`section_bounds_m` gives each one)."""
        return self.digit_length_m / self.section_count

    @property
    def equal_sections(self) -> bool:
        """True if ``section_length_m`` is one length for every section and no ``support_lengths_m`` is given (the
        thesis rig's layout)."""
        return not isinstance(self.section_length_m, tuple) and self.support_lengths_m is None

    @property
    def section_lengths_m(self) -> tuple[float, ...]:
        """Each section's free strip (m), from the base: ``strip_length_m / section_count`` each for one
        ``section_length_m`` (as the twin has always laid them out), else the list given."""
        if not isinstance(self.section_length_m, tuple):
            return (self.strip_length_m / self.section_count,) * self.section_count
        return self.section_length_m

    @property
    def support_length_m(self) -> float:
        """``(digit_length_m - strip_length_m) / section_count`` (m): each support's length (10 mm on the thesis
        rig; half of one at the clamp and half at the tip) unless ``support_lengths_m`` gives them
        (:attr:`supports_m`)."""
        return (self.digit_length_m - self.strip_length_m) / self.section_count

    @property
    def supports_m(self) -> tuple[float, ...]:
        """Each support's length (m), the one that ends section ``k``: ``support_lengths_m`` if given, else
        :attr:`support_length_m` each."""
        if self.support_lengths_m is None:
            return (self.support_length_m,) * self.section_count
        return self.support_lengths_m

    @property
    def section_bounds_m(self) -> tuple[tuple[float, float], ...]:
        """Where each section's free strip starts and ends along the digit (m from the clamp): the one source of the
        layout (twin chain, beam, elastica oracle, shape, gauge checks, design study).

        Sections follow one another from the clamp, each its free strip then a support, half a support at the clamp
        and at the tip (2.2). Equal sections keep the twin's arithmetic, ``k p + h`` to ``(k + 1) p - h`` with
        pitch ``p = digit_length_m / section_count``, so the thesis rig's arrays do not move by a bit.

        Examples
        --------
        >>> [(round(a, 4), round(b, 4)) for a, b in Geometry().section_bounds_m]
        [(0.005, 0.085), (0.095, 0.175), (0.185, 0.265)]
        >>> g = Geometry(section_count=2, section_length_m=(0.1, 0.06), strip_length_m=0.16, digit_length_m=0.18,
        ...              gauge_positions_m=(0.05, 0.14))
        >>> [(round(a, 4), round(b, 4)) for a, b in g.section_bounds_m]
        [(0.005, 0.105), (0.115, 0.175)]
        """
        n = self.section_count
        if self.equal_sections:
            pitch = self.section_pitch_m
            half = 0.5 * (pitch - self.strip_length_m / n)
            return tuple((k * pitch + half, (k + 1) * pitch - half) for k in range(n))
        supports, bounds = self.supports_m, []
        start = 0.5 * supports[0]  # half the first support at the clamp (2.2)
        for length, support in zip(self.section_lengths_m, supports, strict=True):
            bounds.append((start, start + length))
            start += length + support
        return tuple(bounds)

    @property
    def support_centres_m(self) -> tuple[float, ...]:
        """The centres of the ``section_count`` supports that end the sections (m from the clamp; the last is the
        tip): where the support masses sit. Equal sections: ``p, 2 p, ...``, the last never past the tip.

        Examples
        --------
        >>> [round(c, 4) for c in Geometry().support_centres_m]
        [0.09, 0.18, 0.27]
        """
        n, length = self.section_count, self.digit_length_m
        if self.equal_sections:
            pitch = self.section_pitch_m
            return tuple(min(pitch * (k + 1.0), length) for k in range(n))
        ends = [end + 0.5 * support for (_, end), support in zip(self.section_bounds_m, self.supports_m, strict=True)]
        return tuple(min(c, length) for c in ends[:-1]) + (length,)

    @property
    def cross_section_m2(self) -> float:
        """Strip cross-section area, ``w t``."""
        return self.strip_width_m * self.strip_thickness_m


@declare
@dataclass(frozen=True)
class Material:
    """Spring-steel strip material (table 3.7).

    Attributes
    ----------
    youngs_modulus_pa : float
        E = 205 GPa (table 3.7).
    strip_density_kg_m3 : float
        7850 kg/m^3: an assumption (carbon spring steel); the thesis does not give it.
    """

    youngs_modulus_pa: float = 205e9
    strip_density_kg_m3: float = 7850.0

    _parameter_constraints = {
        "youngs_modulus_pa": [YOUNGS_MODULUS_PA],
        "strip_density_kg_m3": [STRIP_DENSITY_KG_M3],
    }

    def __post_init__(self) -> None:
        validate_fields(self)


@declare
@dataclass(frozen=True)
class Sensors:
    """Strain gauges, bridge, amplifier and DAQ card (2.3, 2.5.1, 2.5.2, 6.4).

    Attributes
    ----------
    gauge_resistance_ohm : float
        120 ohm gauges (2.3.2).
    gauge_factor : float
        GF ~ 0.8 (6.4).
    bridge : {"quarter", "half", "full"}
        Half bridge on the rig (E 2.4).
    excitation_v : float
        Bridge supply voltage Vs. An assumption (1 V): the thesis does not give it; the twin's per-channel
        gains are calibrated against E 3.20-3.22 instead.
    amplifier_gain_v_per_v : float
        Fylde FE-366-TA gain, 10,000 (2.5.1).
    amplifier_lowpass_hz : float
        Amplifier low-pass cut-off, 470 Hz (2.5.1).
    amplifier_lowpass_order : int
        Order of that low-pass (Butterworth). An assumption (2); the thesis gives only the cut-off.
    adc_bits : int
        PCI-DAS1602/16: 16 bits (2.5.2).
    adc_range_v : tuple of float
        Input range, +-5 V (2.5.2).
    adc_channels : tuple of int
        Gauge pairs 1..3 on analog inputs 0..2 (table 2.2).
    gauge_bridges : tuple of str, optional
        One bridge per gauge (a chain per gauge); left out: ``bridge`` for every gauge.
    gauge_factors : tuple of float, optional
        One gauge factor per gauge; left out: ``gauge_factor`` for every gauge.
    amplifier_gains_v_per_v : tuple of float, optional
        One amplifier gain per gauge; left out: ``amplifier_gain_v_per_v`` for every gauge.
    """

    gauge_resistance_ohm: float = 120.0
    gauge_factor: float = 0.8
    bridge: str = "half"
    excitation_v: float = 1.0
    amplifier_gain_v_per_v: float = 10_000.0
    amplifier_lowpass_hz: float = 470.0
    amplifier_lowpass_order: int = 2
    adc_bits: int = 16
    adc_range_v: tuple[float, float] = (-5.0, 5.0)
    adc_channels: tuple[int, ...] = (0, 1, 2)
    gauge_bridges: tuple[str, ...] | None = None
    gauge_factors: tuple[float, ...] | None = None
    amplifier_gains_v_per_v: tuple[float, ...] | None = None

    _parameter_constraints = {
        "gauge_factors": [None, Array(ndim=1, min_length=1, low=GAUGE_FACTOR.low, high=GAUGE_FACTOR.high)],
        "amplifier_gains_v_per_v": [
            None,
            Array(ndim=1, min_length=1, low=AMPLIFIER_GAIN.low, high=AMPLIFIER_GAIN.high),
        ],
        "gauge_resistance_ohm": [
            Plausible("ohm", 50.0, 20_000.0, "foil gauges 120-1000 ohm; semiconductor, thin-film up to ~10 kohm")
        ],
        "gauge_factor": [GAUGE_FACTOR],
        "bridge": [Options(BRIDGE_TYPES)],
        "excitation_v": [Plausible("V", 0.1, 30.0, "a bridge supply of 0.1 to 30 V; usually 1-10 V")],
        "amplifier_gain_v_per_v": [AMPLIFIER_GAIN],
        "amplifier_lowpass_hz": [Plausible("Hz", 1.0, 1e5, "an anti-aliasing low-pass of 1 Hz to 100 kHz")],
        "amplifier_lowpass_order": [Plausible("", 1, 8, "a filter of 1 to 8 poles", integer=True)],
        "adc_bits": [Plausible("bits", 8, 24, "a microcontroller's 8-12 bit ADC to a 24-bit DAQ card", integer=True)],
        # a DAQ card's input range: +-100 V is beyond any card (the thesis's is +-5 V)
        "adc_range_v": [Array(shape=(2,), increasing=True, low=-100.0, high=100.0)],
        "adc_channels": [Array(ndim=1, min_length=1, low=0, high=63)],
    }

    def __post_init__(self) -> None:
        validate_fields(self)
        owner = type(self).__name__
        for name in ("gauge_factors", "amplifier_gains_v_per_v"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, tuple(float(v) for v in getattr(self, name)))
        if self.gauge_bridges is not None:
            bridges = self.gauge_bridges
            if isinstance(bridges, str) or not bridges or any(b not in BRIDGE_TYPES for b in bridges):
                raise ParameterError(
                    f"The 'gauge_bridges' parameter of {owner} must be a list of "
                    + ", ".join(repr(b) for b in BRIDGE_TYPES)
                    + f", one per gauge. Got {bridges!r} instead."
                )
            object.__setattr__(self, "gauge_bridges", tuple(bridges))
        rng = check_array(self.adc_range_v, "adc_range_v", owner, shape=(2,), increasing=True)
        object.__setattr__(self, "adc_range_v", (float(rng[0]), float(rng[1])))
        channels = tuple(check_int(c, "adc_channels", owner, low=0, high=63) for c in self.adc_channels)
        if len(channels) == 0 or len(set(channels)) != len(channels):
            raise ParameterError(
                f"The 'adc_channels' parameter of {owner} must be distinct channel numbers. "
                f"Got {list(self.adc_channels)!r} instead."
            )
        object.__setattr__(self, "adc_channels", channels)

    @property
    def per_gauge(self) -> bool:
        """Whether any part of the chain is given gauge by gauge."""
        return any(v is not None for v in (self.gauge_bridges, self.gauge_factors, self.amplifier_gains_v_per_v))

    def chain(self, count: int) -> tuple[tuple[str, ...], tuple[float, ...], tuple[float, ...]]:
        """Each of ``count`` gauges' bridge, gauge factor and amplifier gain (the per-gauge lists, or the scalars).

        Examples
        --------
        >>> Sensors(gauge_bridges=("full", "quarter", "half")).chain(3)[0]
        ('full', 'quarter', 'half')
        >>> Sensors().chain(2)[1]
        (0.8, 0.8)
        """
        return (
            self.gauge_bridges if self.gauge_bridges is not None else (self.bridge,) * count,
            self.gauge_factors if self.gauge_factors is not None else (float(self.gauge_factor),) * count,
            self.amplifier_gains_v_per_v
            if self.amplifier_gains_v_per_v is not None
            else (float(self.amplifier_gain_v_per_v),) * count,
        )

    @property
    def adc_lsb_v(self) -> float:
        """One ADC count in volts: range / 2**bits."""
        return (self.adc_range_v[1] - self.adc_range_v[0]) / 2**self.adc_bits


@declare
@dataclass(frozen=True)
class Actuator:
    """The servo, its driver board, pulley and potentiometer (2.4, 2.5.3, 3.2.4, 3.4.1).

    Attributes
    ----------
    command_min, command_max : int
        Serial position command range, 0..254 (3.4.1); 255 is the board's sync byte and never a position.
    angle_min_deg, angle_max_deg : float
        Servo angle at command_min and command_max: 0 and 219 degrees (3.2.4).
    pulley_radius_m : float
        ``r_M``, the pulley ("inertial disc") radius, 11.5 mm (table 3.7).
    pwm_frequency_hz : float
        Servo pulse frequency, 52 Hz (3.2).
    pulse_width_min_s, pulse_width_max_s : float
        Pulse width at command_min and command_max, 1 and 2 ms (3.4.1).
    serial_period_s : float
        Commands reach the board every 20 ms (5.2): the loop cannot run faster.
    equilibrium_command : int
        The command at which the digit is straight: 8 (table 3.4 note). A file describing a cable pair
        (``[cables] count = 2``) without it puts it mid-range (127), so the digit bends both ways.
    operating_commands : tuple of int
        8..43: 0 to 30 degrees of beam rotation (3.4.1).
    servo_wn_rad_s, servo_zeta : float
        The servo's identified second-order model, 20.53 rad/s and 0.5629 (3.2.4).
    pot_v_at_min_angle_v, pot_v_at_max_angle_v : float
        Potentiometer voltage at 0 and 219 degrees: 0.46688 and 2.4755 V (3.2.4).
    stall_torque_nm : float
        Futaba S-148: 42 oz in = 0.297 N m (2.4).
    gear_ratio : float
        Servo turns per pulley turn, 1 on the thesis rig (the pulley sits on the servo shaft). A reduction ``n``
        divides the command step at the pulley by ``n`` (chapter 8 asks for a finer step): see
        :attr:`pulley_deg_per_command`; the models and the twin draw :attr:`cable_m_per_servo_rad` of cable per
        servo radian (the servo, its potentiometer and its torque limit stay on the servo's side).
    """

    command_min: int = 0
    command_max: int = 254
    angle_min_deg: float = 0.0
    angle_max_deg: float = 219.0
    pulley_radius_m: float = 11.5e-3
    pwm_frequency_hz: float = 52.0
    pulse_width_min_s: float = 1.0e-3
    pulse_width_max_s: float = 2.0e-3
    serial_period_s: float = 0.020
    equilibrium_command: int = 8
    operating_commands: tuple[int, int] = (8, 43)
    servo_wn_rad_s: float = 20.53
    servo_zeta: float = 0.5629
    pot_v_at_min_angle_v: float = 0.46688
    pot_v_at_max_angle_v: float = 2.4755
    stall_torque_nm: float = 0.297
    gear_ratio: float = 1.0

    _parameter_constraints = {
        "gear_ratio": [Plausible("", 1.0, 20.0, "servo turns per pulley turn: 1 (on the shaft) to a 20:1 reduction")],
        "command_min": [SERVO_COMMAND],
        "command_max": [SERVO_COMMAND],
        "angle_min_deg": [Interval(Real, -360, 360)],
        "angle_max_deg": [Interval(Real, -360, 360)],
        "pulley_radius_m": [Plausible("m", 1e-3, 0.1, "a servo pulley 1 mm to 10 cm in radius")],
        "pwm_frequency_hz": [Plausible("Hz", 20.0, 1000.0, "servo pulses: 50 Hz analogue to ~560 Hz digital servos")],
        "pulse_width_min_s": [SERVO_PULSE_S],
        "pulse_width_max_s": [SERVO_PULSE_S],
        "serial_period_s": [Plausible("s", 1e-4, 1.0, "a command every 0.1 ms to 1 s")],
        "equilibrium_command": [SERVO_COMMAND],
        "operating_commands": [Array(shape=(2,), low=0, high=254)],
        "servo_wn_rad_s": [Plausible("rad/s", 1.0, 1000.0, "a position servo's loop: 1 to 1000 rad/s")],
        "servo_zeta": [Plausible("", 0.05, 5.0, "a position servo: 0.05 (ringing) to 5 (sluggish)")],
        "pot_v_at_min_angle_v": [Plausible("V", -100.0, 100.0, "a potentiometer read by a DAQ card")],
        "pot_v_at_max_angle_v": [Plausible("V", -100.0, 100.0, "a potentiometer read by a DAQ card")],
        "stall_torque_nm": [Plausible("N m", 5e-3, 100.0, "a micro servo (0.01 N m) to a large servo (~50 N m)")],
    }

    def __post_init__(self) -> None:
        validate_fields(self)
        owner = type(self).__name__
        # what a declaration cannot say: one field bounded by another
        lo = int(self.command_min)
        hi = check_int(self.command_max, "command_max", owner, low=lo + 1, high=254)
        check_real(self.angle_max_deg, "angle_max_deg", owner, low=self.angle_min_deg, high=360, low_open=True)
        check_real(self.pulse_width_max_s, "pulse_width_max_s", owner, low=self.pulse_width_min_s, low_open=True)
        check_int(self.equilibrium_command, "equilibrium_command", owner, low=lo, high=hi)
        ops = tuple(check_int(c, "operating_commands", owner, low=lo, high=hi) for c in self.operating_commands)
        if len(ops) != 2 or ops[0] >= ops[1]:
            raise ParameterError(
                f"The 'operating_commands' parameter of {owner} must be two increasing commands "
                f"inside [{lo}, {hi}]. Got {list(self.operating_commands)!r} instead."
            )
        object.__setattr__(self, "operating_commands", ops)
        if not ops[0] <= self.equilibrium_command <= ops[1]:  # trial 3: straight at 60 of 8..43 drove command 78
            raise ParameterError(
                f"The 'equilibrium_command' parameter of {owner} (where the digit is straight) must lie within its "
                f"'operating_commands' {list(ops)}. Got {self.equilibrium_command} instead: set operating_commands "
                "around it (a single cable operates above its straight command, a pair either side)."
            )
        check_real(
            self.pot_v_at_max_angle_v, "pot_v_at_max_angle_v", owner, low=self.pot_v_at_min_angle_v, low_open=True
        )

    @property
    def deg_per_command(self) -> float:
        """Servo degrees per command: 219/254 = 0.8622 (E 3.15)."""
        return (self.angle_max_deg - self.angle_min_deg) / (self.command_max - self.command_min)

    @property
    def rad_per_command(self) -> float:
        """Servo radians per command: 0.8622 pi/180 = 0.015048 (E 3.15; printed rounded as 0.0150)."""
        return math.radians(self.deg_per_command)

    @property
    def cable_m_per_servo_rad(self) -> float:
        """Cable drawn in per servo radian, ``r_M / gear_ratio`` (m/rad): E 3.11's ``r_M`` with the gearing."""
        return self.pulley_radius_m / self.gear_ratio

    @property
    def pulley_deg_per_command(self) -> float:
        """The command step at the pulley, ``deg_per_command / gear_ratio`` (0.8622 deg on the thesis rig)."""
        return self.deg_per_command / self.gear_ratio

    @property
    def pot_v_per_command(self) -> float:
        """Potentiometer volts per command: (2.4755 - 0.46688)/254 = 0.0079 V (3.2.4)."""
        return (self.pot_v_at_max_angle_v - self.pot_v_at_min_angle_v) / (self.command_max - self.command_min)


@declare
@dataclass(frozen=True)
class Cables:
    """The tendons that bend the digit (2.1, 2.2.1): the thesis's single cable, or an antagonistic pair.

    The eccentricity is ``Geometry.cable_eccentricity_m`` (table 3.7's ``e``, kept there so older files load).

    Attributes
    ----------
    count : int
        1: the thesis's cable, bending one way; 2: an antagonistic pair bending both ways (2.1 asks for "a two
        cable system to ensure rigidity"; the design study's ``pretension_n > 0``).
    pretension_n : float
        Tension both cables of a pair keep at rest (N); 0 with one cable, positive with a pair (a slack pair
        cannot hold the digit straight).
    guide_friction_ratio : float
        Cable-guide friction, the share of the tension gained or lost across the guides
        (:attr:`flexdigit.twin.calibration.Calibration.cable_friction_ratio`); 0.0548 fitted to the thesis's
        actuated corr2 (7.5).
    """

    count: int = 1
    pretension_n: float = 0.0
    guide_friction_ratio: float = 0.05481279307004473

    _parameter_constraints = {
        "count": [Interval(Integral, 1, 2)],
        "pretension_n": [Plausible("N", 0.0, 100.0, "a tendon's rest tension, at most 100 N")],
        "guide_friction_ratio": [Plausible("", 0.0, 0.5, "the tension's share the guides take: ~0.05, at most 0.5")],
    }

    def __post_init__(self) -> None:
        validate_fields(self)


@declare
@dataclass(frozen=True)
class DigitDynamics:
    """The digit's identified second-order dynamics (3.1.2, tables 3.1 and 3.2).

    Attributes
    ----------
    wn_housing_rad_s, zeta_housing : float
        With the elastomer housing (table 3.2 averages): 13.0995 rad/s, 0.06791.
    wn_bare_rad_s, zeta_bare : float
        Strip and supports alone (table 3.1 averages): 10.16271 rad/s, 0.0025.
    """

    wn_housing_rad_s: float = 13.0995
    zeta_housing: float = 0.06791
    wn_bare_rad_s: float = 10.16271
    zeta_bare: float = 0.0025

    _parameter_constraints = {
        "wn_housing_rad_s": [_NATURAL_FREQUENCY],
        "zeta_housing": [Interval(Real, 0, 10)],
        "wn_bare_rad_s": [_NATURAL_FREQUENCY],
        "zeta_bare": [Interval(Real, 0, 10)],
    }

    def __post_init__(self) -> None:
        validate_fields(self)


#: The longest spring cell (m) of the twin's default resolution: each section's free strip is cut into cells no
#: longer than this. Chosen by the convergence study of ``tests/twin/test_cell_resolution.py`` (docs/digits.md, "The
#: twin's resolution"): on drawn digits 0.15-0.5 m long the gauges' strain and the tip deflection stay within
#: 1 % of the converged twin; the thesis rig's 80 mm sections keep their 3 cells (80 / 27 = 2.96).
MAX_CELL_LENGTH_M = 0.027
#: The fewest cells of a section cut by length (odd, so a gauge midway on a section falls on a spring, as on the
#: thesis rig).
MIN_CELLS_PER_SECTION = 3
#: The most springs a description's ``[twin]`` table may give the whole digit: a 20 ms step of the thesis rig's
#: twin at 243 springs took 12 ms (1.6x real time, 0.22 ms at its 9; 2026-11-27, the shared 2-core machine), so
#: more would fall behind a real-time loop.
MAX_TWIN_CELLS = 243
#: One section's spring count in a ``[twin]`` table: 81 cells cut the thesis rig's 80 mm into 1 mm.
_CELLS = Plausible("", 1, 81, "1 to 81 springs a section (81: 1 mm cells on the thesis rig's 80 mm)", integer=True)


def cells_no_longer_than(geometry: Geometry, max_cell_length_m: float) -> tuple[int, ...]:
    """Cells per section so that none is longer than ``max_cell_length_m``: ``ceil(l_k / h)``, at least
    :data:`MIN_CELLS_PER_SECTION` and odd, for each section's free strip ``l_k`` (``Geometry.section_bounds_m``).

    >>> cells_no_longer_than(Geometry(), MAX_CELL_LENGTH_M), cells_no_longer_than(Geometry(), 0.01)
    ((3, 3, 3), (9, 9, 9))
    """
    out = []
    for start, end in geometry.section_bounds_m:
        n = max(MIN_CELLS_PER_SECTION, math.ceil((end - start) / max_cell_length_m - 1e-9))
        out.append(n + 1 - n % 2)  # odd: the next odd count when even
    return tuple(out)


@declare
@dataclass(frozen=True)
class TwinResolution:
    """The twin's resolution: how finely its chain cuts each section's strip (optional, docs/digits.md).

    Attributes
    ----------
    max_cell_length_m : float, optional
        Cut each section's free strip into cells no longer than this (an odd count, at least 3 a section). Left
        out, with cells_per_section: 27 mm (3 cells a thesis section); the static error falls as the cell's square.
    cells_per_section : int or tuple of int, optional
        Springs per section instead: one count for every section, or one per section from the base. Give this or
        max_cell_length_m, not both; neither: the default resolution.
    """

    max_cell_length_m: float | None = None
    cells_per_section: int | tuple[int, ...] | None = None

    _parameter_constraints = {
        "max_cell_length_m": [
            Plausible("m", 1e-3, 0.5, "cells of 1 mm (243 springs on the thesis rig) to a half-metre section"),
            None,
        ],
        "cells_per_section": [_CELLS, Array(ndim=1, min_length=1, low=_CELLS.low, high=_CELLS.high), None],
    }
    #: Keys that take one value or a list (``RigParams.from_dict`` passes either through).
    _scalar_or_list = ("max_cell_length_m", "cells_per_section")

    def __post_init__(self) -> None:
        validate_fields(self)
        owner = type(self).__name__
        cells = self.cells_per_section
        if cells is not None:
            counts = [cells] if isinstance(cells, Integral | Real) else list(cells)
            for i, n in enumerate(counts):
                if isinstance(n, bool) or not isinstance(n, Integral | Real) or n != int(n):
                    at = "" if isinstance(cells, Integral | Real) else f"[{i}]"
                    raise ParameterError(
                        f"The 'cells_per_section{at}' parameter of {owner} must be a whole number of springs "
                        f"(1 to {_CELLS.high:g}). Got {n!r} instead."
                    )
            whole = tuple(check_int(int(n), "cells_per_section", owner, low=1, high=int(_CELLS.high)) for n in counts)
            object.__setattr__(self, "cells_per_section", whole[0] if isinstance(cells, Integral | Real) else whole)
        if self.max_cell_length_m is not None:
            object.__setattr__(self, "max_cell_length_m", float(self.max_cell_length_m))
            if cells is not None:
                raise ParameterError(
                    f"The 'cells_per_section' parameter of {owner} must be left out when max_cell_length_m is "
                    f"given (one or the other). Got {cells!r} with max_cell_length_m = {self.max_cell_length_m!r}."
                )

    @property
    def is_default(self) -> bool:
        """Whether neither key is given (the twin's default resolution)."""
        return self.max_cell_length_m is None and self.cells_per_section is None

    def cells(self, geometry: Geometry) -> tuple[int, ...]:
        """Springs per section of ``geometry`` at this resolution (the default's: :data:`MAX_CELL_LENGTH_M`).

        Raises
        ------
        ParameterError
            If ``cells_per_section`` is a list of another length than ``geometry.section_count``.
        """
        if self.cells_per_section is None:
            return cells_no_longer_than(geometry, self.max_cell_length_m or MAX_CELL_LENGTH_M)
        if isinstance(self.cells_per_section, int):
            return (self.cells_per_section,) * geometry.section_count
        if len(self.cells_per_section) != geometry.section_count:
            raise ParameterError(
                f"[twin] cells_per_section has {len(self.cells_per_section)} counts for {geometry.section_count} "
                f"sections: one count for all, or one per section. Got {list(self.cells_per_section)!r} instead."
            )
        return self.cells_per_section


@dataclass(frozen=True)
class RigParams:
    """The whole rig: geometry, material, sensors, actuator and identified digit dynamics, and (optional) the
    resolution of its twin (``[twin]``, :class:`TwinResolution`)."""

    geometry: Geometry = field(default_factory=Geometry)
    material: Material = field(default_factory=Material)
    sensors: Sensors = field(default_factory=Sensors)
    actuator: Actuator = field(default_factory=Actuator)
    dynamics: DigitDynamics = field(default_factory=DigitDynamics)
    cables: Cables = field(default_factory=Cables)
    twin: TwinResolution = field(default_factory=TwinResolution)

    def __post_init__(self) -> None:
        g = self.geometry
        if max(g.gauge_positions_m) > g.digit_length_m:
            raise ParameterError(
                f"The 'gauge_positions_m' parameter of Geometry must lie inside (0, {g.digit_length_m:g}]. "
                f"Got {list(g.gauge_positions_m)!r} instead."
            )
        self._check_the_servo_bends_the_strip()

    def _check_the_servo_bends_the_strip(self) -> None:
        """A derived figure no single field shows: the servo must bend the strip through a useful part of its
        rotation. Bending the strip's free length through ``theta`` takes a tip moment ``E I theta / l``, i.e. a
        cable tension ``M / e`` and a servo torque ``M r_M / e`` (E 3.12, E 3.19: ``K2 = E I r_M / (l e)`` is that
        moment per servo radian). The thesis rig needs 0.16 N m of its 0.297 N m stall torque for the full 90 deg;
        a rig whose servo stalls before a tenth of its rotation (a 0.381 "m" strip: K2 = 8.9e7 N m/rad) is a slip
        in the file, not a digit."""
        g, a = self.geometry, self.actuator
        rotation_rad = math.radians(g.max_rotation_per_section_deg * g.section_count)
        moment_nm = self.bending_stiffness_n_m2 * rotation_rad / g.strip_length_m
        torque_nm = moment_nm * a.cable_m_per_servo_rad / g.cable_eccentricity_m
        if torque_nm * STRIP_BEND_FRACTION > a.stall_torque_nm:
            k2 = self.bending_stiffness_n_m2 * a.pulley_radius_m / (g.strip_length_m * g.cable_eccentricity_m)
            raise ParameterError(
                f"The rig parameters describe a strip its servo cannot bend: K2 = E I r_M / (l e) = {k2:.3g} N m/rad "
                f"needs {torque_nm * STRIP_BEND_FRACTION:.3g} N m of servo torque for a tenth of the digit's "
                f"{math.degrees(rotation_rad):g} deg, and the servo stalls at {a.stall_torque_nm:g} N m (check "
                "strip_thickness_m, strip_width_m, youngs_modulus_pa, pulley_radius_m, gear_ratio, "
                "cable_eccentricity_m and their units)"
            )

    @property
    def bending_stiffness_n_m2(self) -> float:
        """EI of the strip alone (N m^2)."""
        return self.material.youngs_modulus_pa * self.geometry.second_moment_m4

    def digit_only(self) -> RigParams:
        """The same description at the twin's default resolution: what names the physical digit. The thesis rig
        with a finer ``[twin]`` is still the rig the packaged calibration was measured on:
        ``params.digit_only() == RigParams()``.

        >>> RigParams(twin=TwinResolution(cells_per_section=9)).digit_only() == RigParams()
        True
        """
        return self if self.twin.is_default else dataclasses.replace(self, twin=TwinResolution())

    def is_thesis_rig(self) -> bool:
        """Whether this describes the thesis rig, whatever its twin's resolution (``[twin]``): the one test for
        "the thesis's own digit" (its packaged calibration, its printed tables), ``digit_only() == RigParams()``.

        >>> RigParams().is_thesis_rig(), RigParams(twin=TwinResolution(cells_per_section=9)).is_thesis_rig()
        (True, True)
        """
        return self.digit_only() == RigParams()

    def replace(self, **sections: Any) -> RigParams:
        """Return a copy with whole sections replaced, e.g. ``p.replace(sensors=Sensors(bridge="full"))``."""
        return dataclasses.replace(self, **sections)

    def to_dict(self) -> dict[str, dict[str, Any]]:
        """Plain nested dict (lists for tuples), as written to TOML; without ``[twin]`` when it is the default (a
        file, a record's metadata and a fingerprint of a description without it stay as they were)."""
        return {
            f.name: {
                k: list(v) if isinstance(v, tuple) else v
                for k, v in dataclasses.asdict(getattr(self, f.name)).items()
                if v is not None  # an optional key left out (TOML has no null)
            }
            for f in dataclasses.fields(self)
            if f.name != "twin" or not self.twin.is_default
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any], source: str = "parameters") -> RigParams:
        """Build from a nested dict (as read from TOML); unknown or mistyped keys raise naming ``source``."""
        if not isinstance(data, dict):
            raise ParameterError(f"{source}: expected a table of sections, got {type(data).__name__}")
        section_types = {f.name: f.default_factory for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - set(section_types))
        if unknown:
            raise ParameterError(
                f"{source}: unknown section {unknown[0]!r}; expected one of "
                + ", ".join(f"[{s}]" for s in section_types)
            )
        sections = {}
        for name, factory in section_types.items():
            values = data.get(name, {})
            if not isinstance(values, dict):
                raise ParameterError(f"{source}: [{name}] must be a table of keys. Got {values!r} instead.")
            allowed = {f.name: f for f in dataclasses.fields(factory)}
            bad = sorted(set(values) - set(allowed))
            if bad:
                raise ParameterError(
                    f"{source}: unknown key {bad[0]!r} in [{name}]; expected one of " + ", ".join(allowed)
                )
            converted = {}
            for key, value in values.items():
                default = getattr(factory(), key)
                if key in getattr(factory, "_scalar_or_list", ()):  # one value or a list: the dataclass checks it
                    value = tuple(value) if isinstance(value, list) else value
                elif isinstance(default, tuple) or default is None:  # None: an optional list, one per gauge
                    if not isinstance(value, list):
                        per = "section" if key == "support_lengths_m" else "gauge"
                        like = f"like {list(default)!r}" if default is not None else f"with one value per {per}"
                        raise ParameterError(f"{source}: [{name}] {key} must be a list {like}. Got {value!r} instead.")
                    value = tuple(value)
                converted[key] = value
            if name == "geometry":
                converted = _derive_lengths(converted)
            if name == "actuator":
                converted = _derive_pair_straight(converted, data.get("cables"))
            try:
                sections[name] = factory(**converted)
            except (ParameterError, TypeError, ValueError) as exc:
                raise ParameterError(f"{source}: [{name}] {exc}") from None
        try:
            return cls(**sections)
        except ParameterError as exc:
            raise ParameterError(f"{source}: {exc}") from None

    def __repr__(self) -> str:
        return summary(self, **(differences(self, RigParams()) or {"thesis_defaults": True}))


#: The description's limits (issue 24): a planar digit of 1-8 sections carrying 1-8 gauges. The dataclasses accept
#: more (the design study probes a grid of gauge positions through one ``Geometry``); a *file* is held to these.
MAX_SECTIONS = 8
MAX_GAUGES = 8
#: How closely lengths must add up (m): a micrometre, far below any workshop tolerance, far above float rounding.
LENGTH_TOLERANCE_M = 1e-6


def _layout_inconsistencies(g: Geometry) -> list[str]:
    """The lengths that do not add up and the gauges off the strip (:func:`digit_inconsistencies`)."""
    lines: list[str] = []
    n = g.section_count
    if not isinstance(g.section_length_m, tuple):
        strip = n * g.section_length_m
        sections = f"section_count x section_length_m = {n} x {g.section_length_m:g}"
        example = n * (g.section_length_m + 0.01)
    else:
        strip = math.fsum(g.section_length_m)
        sections = "the sum of section_length_m " + "[" + ", ".join(f"{x:g}" for x in g.section_length_m) + "]"
        example = strip + n * 0.01
    if abs(strip - g.strip_length_m) > LENGTH_TOLERANCE_M:
        lines.append(
            f"[geometry] strip_length_m = {g.strip_length_m:g} but {sections} = {strip:g} m: the lengths do not add up"
        )
    support = (g.digit_length_m - strip) / n
    given = g.support_lengths_m
    if given is not None:  # half the first at the clamp, the others whole, the last one's centre at the tip
        digit = strip + 0.5 * given[0] + math.fsum(given[:-1]) + 0.5 * given[-1]
        if abs(digit - g.digit_length_m) > LENGTH_TOLERANCE_M:
            lines.append(
                f"[geometry] digit_length_m = {g.digit_length_m:g} but the strip ({strip:g} m) and support_lengths_m "
                f"{list(given)} (half the first, the others whole, half the last) make {digit:g} m: the lengths do "
                "not add up"
            )
    elif support < -LENGTH_TOLERANCE_M:
        lines.append(
            f"[geometry] digit_length_m = {g.digit_length_m:g} is shorter than its {n} sections of "
            f"{_lengths_text(g)} m ({strip:g} m): set it to {strip:g} m plus the supports, e.g. "
            f"{example:g} m with 10 mm supports"
        )
    if given is not None or support >= -LENGTH_TOLERANCE_M:
        halves = [0.5 * max(x, 0.0) for x in g.supports_m]
        # the clamp's half support (as long as half the first), then the one ending each section
        supports = [(0.0, halves[0]), *zip(g.support_centres_m, halves, strict=True)]
        tip_half = halves[-1]
        for i, x in enumerate(g.gauge_positions_m):
            at, half = min(supports, key=lambda centre_half: abs(x - centre_half[0]))  # the nearest support
            if x > g.digit_length_m - tip_half - LENGTH_TOLERANCE_M:
                lines.append(
                    f"[geometry] gauge_positions_m[{i}] = {x:g} m is past the strip, which ends at "
                    f"{g.digit_length_m - tip_half:g} m"
                )
            elif abs(x - at) < half + LENGTH_TOLERANCE_M:
                lines.append(
                    f"[geometry] gauge_positions_m[{i}] = {x:g} m is on the support at {at:g} m "
                    f"({at - half:g} to {at + half:g} m): put it on the strip"
                )
    return lines


def twin_cells(params: RigParams) -> tuple[int, ...]:
    """Springs per section of the twin of ``params``: its ``[twin]`` table's (:class:`TwinResolution`), else the
    default resolution (cells no longer than :data:`MAX_CELL_LENGTH_M`, odd, at least 3). Every builder of the
    digit's chain that is not given explicit cells takes this (:func:`flexdigit.twin.digit.digit_arrays`).

    >>> twin_cells(RigParams()), twin_cells(RigParams(twin=TwinResolution(max_cell_length_m=0.01)))
    ((3, 3, 3), (9, 9, 9))
    """
    return params.twin.cells(params.geometry)


def _twin_inconsistencies(params: RigParams) -> list[str]:
    """A ``[twin]`` table that does not fit the digit: a list of another length, too many springs."""
    t = params.twin
    if t.is_default:
        return []
    try:
        cells = twin_cells(params)
    except ParameterError as exc:
        return [str(exc)]
    if sum(cells) > MAX_TWIN_CELLS:
        key = "cells_per_section" if t.cells_per_section is not None else "max_cell_length_m"
        value = t.cells_per_section if t.cells_per_section is not None else t.max_cell_length_m
        value = list(value) if isinstance(value, tuple) else value
        return [
            f"[twin] {key} = {value!r} makes {sum(cells)} springs ({list(cells)} a section): a twin takes at most "
            f"{MAX_TWIN_CELLS} (a 20 ms step of 243 takes ~12 ms, near real time)"
        ]
    return []


def digit_inconsistencies(params: RigParams) -> list[str]:
    """Every way the description contradicts itself, one line each naming the key; empty if it holds together.

    The rules (the twin's layout, :func:`flexdigit.twin.digit.build_digit`, :attr:`Geometry.section_bounds_m`):
    ``section_count`` sections of ``section_length_m`` (one length, or one per section) of free strip make
    ``strip_length_m``; each section is followed by one support, ``support_lengths_m`` long if given, else
    ``(digit_length_m - strip_length_m) / section_count``, half the first at the clamp and the last one's centre at
    the tip (equal sections: centred at 0, pitch, 2 pitch, ...); a gauge sits on the free strip, never on a
    support or past the strip; one ADC channel per gauge; a cable pair keeps a
    pretension, a single cable none.

    Examples
    --------
    >>> digit_inconsistencies(RigParams())
    []
    >>> four = RigParams(geometry=Geometry(section_count=4))   # 4 x 80 mm with digit_length_m left at 0.27
    >>> digit_inconsistencies(four)[0].split(":")[0]
    '[geometry] strip_length_m = 0.24 but section_count x section_length_m = 4 x 0.08 = 0.32 m'
    """
    g, s, c = params.geometry, params.sensors, params.cables
    lines = []
    n, count = g.section_count, len(g.gauge_positions_m)
    if n > MAX_SECTIONS:
        lines.append(f"[geometry] section_count = {n}: a digit has 1 to {MAX_SECTIONS} sections")
    if count > MAX_GAUGES:
        lines.append(f"[geometry] gauge_positions_m has {count} gauges: a digit carries 1 to {MAX_GAUGES}")
    lines += _layout_inconsistencies(g)
    for i in range(1, count):  # repr-equal places are refused on loading; these are apart by less than the tolerance
        gap = g.gauge_positions_m[i] - g.gauge_positions_m[i - 1]
        if gap < LENGTH_TOLERANCE_M:
            lines.append(
                f"[geometry] gauge_positions_m[{i}] = {g.gauge_positions_m[i]!r} m is {gap * 1e6:.3g} um from "
                f"gauge_positions_m[{i - 1}]: two gauges at one place (positions count to 1 um)"
            )
    if len(s.adc_channels) != count:
        lines.append(
            f"[sensors] adc_channels has {len(s.adc_channels)} channels for {count} gauges: one per gauge, e.g. "
            f"{list(range(count))}"
        )
    for key in ("gauge_bridges", "gauge_factors", "amplifier_gains_v_per_v"):
        values = getattr(s, key)
        if values is not None and len(values) != count:
            lines.append(f"[sensors] {key} has {len(values)} values for {count} gauges: one per gauge")
    if c.count == 2 and c.pretension_n <= 0:
        lines.append("[cables] pretension_n = 0 with count = 2: an antagonistic pair needs a pretension > 0 N")
    if c.count == 1 and c.pretension_n > 0:
        lines.append(f"[cables] pretension_n = {c.pretension_n:g} with count = 1: a single cable has no pretension")
    if not lines:  # the cells are laid out on sections that add up
        lines += _twin_inconsistencies(params)
    return lines


#: The thesis rig's support length (m): 2.2.1's nylon sections, ``(0.27 - 0.24) / 3``; what a description that
#: leaves ``digit_length_m`` out gets.
THESIS_SUPPORT_M = 0.010


def description_notes(params: RigParams) -> list[str]:
    """What a consistent description does that its author may not expect, one line each naming the key (``flexdigit
    params FILE`` prints them; nothing is refused): supports longer or shorter than the thesis's 10 mm, derived from
    a ``digit_length_m`` given with other sections (the template's 0.27 m kept for a 0.20 m strip makes 35 mm
    supports), and a ``[dynamics]`` table that differs from the thesis's, which no twin reads.

    Examples
    --------
    >>> g = Geometry(section_count=2, section_length_m=0.1, strip_length_m=0.2, gauge_positions_m=(0.03, 0.17))
    >>> description_notes(RigParams(geometry=g))[0].split(":")[0]
    "[geometry] digit_length_m = 0.27 (the thesis rig's) makes 2 supports of 35 mm"
    >>> description_notes(RigParams())
    []
    """
    g, notes = params.geometry, []
    support = g.support_length_m
    if g.support_lengths_m is None and abs(support - THESIS_SUPPORT_M) > LENGTH_TOLERANCE_M and support >= 0:
        thesis = " (the thesis rig's)" if g.digit_length_m == Geometry.digit_length_m else ""
        ten = g.strip_length_m + g.section_count * THESIS_SUPPORT_M
        notes.append(
            f"[geometry] digit_length_m = {g.digit_length_m:.6g}{thesis} makes {g.section_count} supports of "
            f"{support * 1e3:.6g} mm: ({g.digit_length_m:.6g} - the {g.strip_length_m:.6g} m strip) / "
            f"{g.section_count} sections; the thesis's are {THESIS_SUPPORT_M * 1e3:g} mm. If that is not your digit, "
            f"leave digit_length_m out ({ten:.6g} m, 10 mm supports) or give support_lengths_m"
        )
    changed = [
        f.name
        for f in dataclasses.fields(DigitDynamics)
        if getattr(params.dynamics, f.name) != getattr(DigitDynamics(), f.name)
    ]
    if changed:
        notes.append(
            f"[dynamics] {', '.join(changed)} {'differs' if len(changed) == 1 else 'differ'} from the thesis rig's, "
            "but no twin reads [dynamics]: a digit's "
            "dynamics come from its geometry, material and calibration; [dynamics] only sets chapter 3's synthetic "
            "identification records"
        )
    notes.extend(adc_range_notes(params))
    return notes


def adc_range_notes(params: RigParams) -> list[str]:
    """A line naming ``[sensors] adc_range_v`` when the range cannot read the gauges' chain at rest: a bridge is
    balanced straight (its amplifier reads 0 V, the twin's ``channel_offset_v`` 0), so a range that starts (or
    ends) at 0 V or excludes it reads every gauge at its rail (a microcontroller's 0..3.3 V ADC needs the chain
    offset to mid-range, or a range around 0 V).

    Examples
    --------
    >>> adc_range_notes(RigParams())
    []
    >>> adc_range_notes(RigParams.from_dict({"sensors": {"adc_range_v": [0.0, 3.3]}}))[0][:52]
    '[sensors] adc_range_v = [0, 3.3] cannot read the gau'
    """
    s = params.sensors
    low, high = s.adc_range_v
    if low + s.adc_lsb_v < 0.0 < high - s.adc_lsb_v:
        return []
    return [
        f"[sensors] adc_range_v = [{low:g}, {high:g}] cannot read the gauges' chain: a balanced bridge reads 0 V "
        f"straight, {'at the range' if low <= 0.0 <= high else 'outside the range'}'s end, so every gauge reads a "
        "rail; give a range around 0 V (e.g. "
        f"[{-(high - low) / 2:g}, {(high - low) / 2:g}]) or offset the amplifier's output to mid-range"
    ]


def _lengths_text(g: Geometry) -> str:
    """``section_length_m`` as a message shows it: ``0.08`` or ``[0.1, 0.06]``."""
    if not isinstance(g.section_length_m, tuple):
        return f"{g.section_length_m:g}"
    return "[" + ", ".join(f"{x:g}" for x in g.section_length_m) + "]"


def derived_figures(params: RigParams) -> dict[str, float | list[float]]:
    """What the description implies (SI units), as ``flexdigit params`` prints it: figures, and where each
    section's free strip starts and ends and each support's centre sits (m from the clamp).

    Examples
    --------
    >>> d = derived_figures(RigParams())
    >>> round(d["support_length_m"], 4), round(d["tip_deg_per_command"], 3)   # 10 mm supports; E 3.15
    (0.01, 1.735)
    """
    g, a = params.geometry, params.actuator
    return {
        "second_moment_m4": g.second_moment_m4,
        "bending_stiffness_n_m2": params.bending_stiffness_n_m2,
        "section_pitch_m": g.section_pitch_m,
        "support_length_m": g.support_length_m,
        "supports_m": list(g.supports_m),
        "section_starts_m": [a for a, _ in g.section_bounds_m],
        "section_ends_m": [b for _, b in g.section_bounds_m],
        "support_centres_m": list(g.support_centres_m),
        "gauge_count": len(g.gauge_positions_m),
        "rad_per_command": a.rad_per_command,
        "deg_per_command": a.deg_per_command,
        "pulley_deg_per_command": a.pulley_deg_per_command,
        # E 3.15: tip rotation = pulley arc / eccentricity
        "tip_deg_per_command": a.pulley_deg_per_command * a.pulley_radius_m / g.cable_eccentricity_m,
        "pot_v_per_command": a.pot_v_per_command,
        "adc_lsb_v": params.sensors.adc_lsb_v,
    } | _cells_figure(params)


def _cells_figure(params: RigParams) -> dict[str, list[int]]:
    """The twin's springs per section (``[twin]``, else the default resolution); none for a ``[twin]`` list that
    does not fit the sections (:func:`digit_inconsistencies` says so)."""
    try:
        return {"twin_cells_per_section": list(twin_cells(params))}
    except ParameterError:
        return {}


def plausible_ranges() -> dict[tuple[str, str], Plausible]:
    """Every key of a description with a plausible range: ``(table, key)`` -> its :class:`Plausible` (unit, bounds
    and the reason), as declared once in the dataclasses' ``_parameter_constraints``; a per-gauge list
    (``gauge_factors``, ``amplifier_gains_v_per_v``) holds each value to its scalar key's range. What ``flexdigit
    params --template`` prints beside each key and docs/digits.md tabulates.

    Examples
    --------
    >>> r = plausible_ranges()[("sensors", "adc_bits")]
    >>> r.low, r.high, r.unit
    (8, 24, 'bits')
    """
    out: dict[tuple[str, str], Plausible] = {}
    for f in dataclasses.fields(RigParams):
        constraints = f.default_factory._parameter_constraints
        for key, declared in constraints.items():
            found = [c for c in declared if isinstance(c, Plausible)]
            if found:
                out[(f.name, key)] = found[0]
    out[("sensors", "gauge_factors")] = GAUGE_FACTOR
    out[("sensors", "amplifier_gains_v_per_v")] = AMPLIFIER_GAIN
    return out


def _range_note(table: str, key: str) -> str:
    """The template's line on a key's plausible range, or ``""``."""
    r = plausible_ranges().get((table, key))
    if r is None:
        return ""
    if (table, key) == ("geometry", "section_count"):  # a file is held to the description's limit
        return f"# Range 1 to {MAX_SECTIONS} in a description (the twin takes up to {r.high:g})."
    unit = f" {r.unit}" if r.unit else ""
    zero = f"; or 0, {r.zero}" if r.zero else ""
    return f"# Range {r.low:g} to {r.high:g}{unit}: {r.why}{zero}."


def _attribute_notes(cls: type) -> dict[str, str]:
    """Each attribute's description from a numpydoc ``Attributes`` section, one line."""
    notes: dict[str, str] = {}
    lines = (cls.__doc__ or "").split("\n")
    names: list[str] = []
    inside = False
    for line in lines:
        text = line.strip()
        if text == "Attributes":
            inside = True
            continue
        if not inside or not text or set(text) == {"-"}:
            continue
        if " : " in text and not line.startswith("        "):
            names = [n.strip() for n in text.split(" : ")[0].split(",")]
            continue
        for name in names:
            notes[name] = (notes.get(name, "") + " " + text).strip()
    return notes


def params_template(params: RigParams | None = None) -> str:
    """An annotated parameter file: every key with its value (the thesis rig by default) and what it means.

    Examples
    --------
    >>> text = params_template()
    >>> RigParams.from_dict(tomllib.loads(text)) == RigParams()
    True
    """
    import tomli_w

    params = params or RigParams()
    out = [
        "# flexdigit: a planar digit described (SI units; 'command' is the servo board's 0..254 position).",
        "# The values are the thesis rig's. Edit them for your digit, then check with: flexdigit params FILE",
        f"# Rules: 1-{MAX_SECTIONS} sections; section_length_m one length for all (strip_length_m = section_count x",
        "# section_length_m) or a list of section_count lengths from the base (strip_length_m = their sum);",
        "# section_count supports of (digit_length_m - strip_length_m) / section_count each end a section (half",
        "# a support at the clamp); `flexdigit params FILE` prints where each section starts and ends;",
        f"# 1-{MAX_GAUGES} gauges on the strip, one adc_channels entry each; a cable pair needs a pretension.",
        "# Each physical key has a plausible range ('# Range ...' above it): a value outside is refused naming it.",
        "# Keys commented out are derived (strip_length_m, digit_length_m: from the sections and 10 mm supports)",
        "# or optional; a key left out keeps the value shown. [dynamics] is the thesis rig's, read by no twin.",
    ]
    derivable = _derivable_lengths(params.geometry)
    thesis_rig = RigParams()
    for f in dataclasses.fields(params):
        section = getattr(params, f.name)
        notes = _attribute_notes(type(section))
        thesis = dataclasses.asdict(getattr(thesis_rig, f.name))
        first = (type(section).__doc__ or "").strip().split("\n")[0]
        out += ["", f"# {first}", f"[{f.name}]"]
        if f.name == "twin":
            out += _twin_template(section, notes)
            continue
        if f.name == "dynamics":
            out += [
                "# No twin reads these (a digit's dynamics come from its geometry, material and calibration): the",
                "# thesis rig's identified values, for chapter 3's synthetic identification records only.",
            ]
        for key, value in dataclasses.asdict(section).items():
            value = list(value) if isinstance(value, tuple) else value
            if key in notes:  # the notes tell the thesis rig's values: said so where this file's differs
                same = value == (list(thesis[key]) if isinstance(thesis[key], tuple) else thesis[key])
                out.append(f"# {notes[key]}" if same else f"# (This digit's differs.) On the thesis rig: {notes[key]}")
            if f.name != "dynamics" and _range_note(f.name, key):  # [dynamics] is read by no twin
                out.append(_range_note(f.name, key))
            if key in derivable:  # what the sections give: written out, a stale copy outlives an edited section
                out.append(f"# Derived when left out ({derivable[key]}); give it only to have it checked.")
                out.append("# " + tomli_w.dumps({key: value}).strip())
                continue
            if value is None and key == "support_lengths_m":  # optional: the thesis's, commented out
                out.append(f"# {key} = " + json.dumps([round(x, 12) for x in params.geometry.supports_m]))
                continue
            if value is None:  # optional: shown as an example, commented out
                keys = ("gauge_bridges", "gauge_factors", "amplifier_gains_v_per_v")
                example = dict(zip(keys, section.chain(len(params.geometry.gauge_positions_m)), strict=True))
                out.append(f"# {key} = " + json.dumps(list(example.get(key, ()))))
                continue
            out.append(tomli_w.dumps({key: value}).strip())
    return "\n".join(out) + "\n"


#: The template's table of the twin's static error (docs/digits.md, "The twin's resolution"): per test digit, the
#: default's error under a tip load (alpha^2 = 1) | the cable (tip 30 deg), and the setting that meets 0.1 %.
#: Measured by ``flexdigit params FILE`` (``flexdigit.twin.resolution``: Richardson on the twin, which matches a
#: solve_bvp elastica; tests/twin/test_twin_resolution.py), 2026-11-27.
_TWIN_ERROR_TABLE = (
    "digit (sections x m)          default cells   error %       max_cell_length_m for 0.1 %",
    "thesis rig (3 x 0.27)         3 a section     0.367 | 0.103   0.014 (7 a section: 0.068 | 0.019)",
    "one section (1 x 0.16)        7               0.521 | 0.164   0.009 (17: 0.088 | 0.028)",
    "two sections (2 x 0.22)       5 a section     0.270 | 0.083   0.0135 (9: 0.083 | 0.025)",
    "short pair (2 x 0.15)         3 a section     0.634 | 0.213   0.009 (9: 0.070 | 0.024)",
    "one long section (1 x 0.404)  15              0.223 | 0.181   0.018 (23: 0.095 | 0.077)",
    "five sections (5 x 0.5)       5 a section     0.081 | 0.021   the default meets it",
)


def _twin_template(section: TwinResolution, notes: dict[str, str]) -> list[str]:
    """The template's ``[twin]`` keys: commented out (the default resolution) unless ``section`` sets one, with
    the static error table."""
    out = [
        "# Left out: cells no longer than 27 mm (3 a thesis section). The chain's static error against the elastica",
        "# falls as the cell's square and each 20 ms step costs more (9 springs a section: 1.6x, 15: 2.8x);",
        "# `flexdigit params FILE` prints this digit's error and the max_cell_length_m that meets 0.1 %:",
        *(f"#   {row}" for row in _TWIN_ERROR_TABLE),
    ]
    examples = {"max_cell_length_m": 0.014, "cells_per_section": 7}
    for key, example in examples.items():
        out.append(f"# {notes[key]}")
        out.append(_range_note("twin", key))
        value = getattr(section, key)
        if value is None:
            out.append(f"# {key} = {example}")
        else:
            out.append(f"{key} = " + json.dumps(list(value) if isinstance(value, tuple) else value))
    return out


def _derivable_lengths(g: Geometry) -> dict[str, str]:
    """``strip_length_m`` and ``digit_length_m`` where the description's sections give them exactly (the template
    leaves them out), each with how it is derived."""
    if g.support_lengths_m is not None:
        return {}
    sections = list(g.section_length_m) if isinstance(g.section_length_m, tuple) else g.section_length_m
    derived = _derive_lengths({"section_count": g.section_count, "section_length_m": sections})
    how = {
        "strip_length_m": "the sum of section_length_m"
        if isinstance(sections, list)
        else "section_count x section_length_m",
        "digit_length_m": "strip_length_m plus section_count supports of 10 mm",
    }
    return {key: text for key, text in how.items() if derived.get(key) == getattr(g, key)}


def _derive_lengths(geometry: dict[str, Any]) -> dict[str, Any]:
    """The lengths a ``[geometry]`` table leaves out, derived from the ones it gives (issue 24): the strip from the
    sections (``section_count x section_length_m``, or the sum of a list of lengths), the digit from the strip and
    the thesis's 10 mm supports.
    A table that gives them all is checked (:func:`digit_inconsistencies`), never changed."""
    count, section = geometry.get("section_count"), geometry.get("section_length_m")
    if count is None and section is None and "support_lengths_m" not in geometry:
        return geometry  # the thesis's sections: its lengths are the defaults
    lengths = isinstance(section, list) and all(isinstance(x, int | float) and not isinstance(x, bool) for x in section)
    if not isinstance(count, int | type(None)) or not (lengths or isinstance(section, int | float | type(None))):
        return geometry  # mistyped: the dataclass names the key
    thesis = Geometry()
    count = (len(section) if lengths else thesis.section_count) if count is None else count
    section = thesis.section_length_m if section is None else section
    out = dict(geometry)
    if "strip_length_m" not in out:
        out["strip_length_m"] = math.fsum(section) if lengths else count * section
    supports = geometry.get("support_lengths_m")
    if "digit_length_m" not in out and isinstance(out["strip_length_m"], int | float):
        if (
            isinstance(supports, list | tuple)
            and supports
            and all(isinstance(x, int | float) and not isinstance(x, bool) for x in supports)
        ):  # half the first at the clamp, the others whole, the last one's centre at the tip
            extra = 0.5 * supports[0] + math.fsum(supports[:-1]) + 0.5 * supports[-1]
            out["digit_length_m"] = out["strip_length_m"] + extra
        else:
            support = (thesis.digit_length_m - thesis.strip_length_m) / thesis.section_count
            out["digit_length_m"] = out["strip_length_m"] + count * support
    return out


#: The thesis rig's operating span above its straight command, commands (8..43, 3.4.1).
_OPERATING_SPAN = 35


def _derive_pair_straight(actuator: dict[str, Any], cables: Any) -> dict[str, Any]:
    """An antagonistic pair (``[cables] count = 2``) bends both ways: where ``[actuator]`` leaves them out, the
    straight (equilibrium) command is the middle of the command range and the operating commands span the thesis's
    35 commands either side of it (the single cable's 8, at the range's foot, leaves nothing below straight).
    Given keys are kept (and checked as ever)."""
    if not isinstance(cables, dict) or cables.get("count") != 2 or "equilibrium_command" in actuator:
        return actuator
    defaults = Actuator()
    low, high = actuator.get("command_min", defaults.command_min), actuator.get("command_max", defaults.command_max)
    if not isinstance(low, int) or not isinstance(high, int) or isinstance(low, bool) or isinstance(high, bool):
        return actuator  # mistyped: the dataclass names the key
    out = dict(actuator)
    straight = (low + high) // 2
    out["equilibrium_command"] = straight
    if "operating_commands" not in out:
        out["operating_commands"] = (max(low, straight - _OPERATING_SPAN), min(high, straight + _OPERATING_SPAN))
    return out


def _builtin_digit_files() -> dict[str, Any]:
    """The example digits packaged in ``flexdigit/reference/digits``: name (the file's stem) -> its resource."""
    from importlib import resources

    folder = resources.files("flexdigit.reference").joinpath("digits")
    return {
        f.name.removesuffix(".toml"): f
        for f in sorted(folder.iterdir(), key=lambda f: f.name)
        if f.name.endswith(".toml")
    }


def builtin_digits() -> dict[str, str]:
    """The example digits a command takes by name (``--params two-sections-four-gauges``) to start from: name ->
    its first comment line (``flexdigit list digits``; ``flexdigit params NAME --write mine.toml`` copies one).

    Examples
    --------
    >>> builtin_digits()["thesis-rig"][:16]
    'The thesis rig: '
    """
    return {
        name: f.read_text(encoding="utf-8").splitlines()[0].lstrip("# ").strip()
        for name, f in _builtin_digit_files().items()
    }


def load_params(path: str | Path, *, check: bool = True) -> RigParams:
    """Read rig parameters from a TOML file, or a built-in example digit by name (:func:`builtin_digits`) when no
    such file exists; missing keys keep the thesis defaults.

    With ``check`` (the default) a description that contradicts itself (:func:`digit_inconsistencies`) is refused
    naming its first inconsistency; ``flexdigit params FILE`` loads without it to list them all.

    Raises
    ------
    ParameterError
        Naming the file, the section and key, the bad value and what was expected.
    FileNotFoundError
        If the file does not exist.
    """
    path = Path(path)
    builtin = _builtin_digit_files().get(str(path)) if not path.exists() else None
    if builtin is not None:
        path = Path(str(builtin))
    text = read_text(path, "a rig parameter TOML")
    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError) as exc:  # RecursionError: nested past the parser
        raise ParameterError(f"{path}: not valid TOML ({exc})") from None
    params = RigParams.from_dict(data, source=str(path))
    problems = digit_inconsistencies(params) if check else []
    if problems:
        more = f" (and {len(problems) - 1} more: flexdigit params {path})" if len(problems) > 1 else ""
        raise ParameterError(f"{path}: {problems[0]}{more}")
    return params


def save_params(params: RigParams, path: str | Path, *, force: bool = False) -> Path:
    """Write ``params`` as TOML (every key, so the file documents the rig); returns the path.

    Written atomically (:mod:`flexdigit._io`); an existing file is kept unless ``force``.

    Raises
    ------
    DataFileError
        If the file cannot be written: its directory does not exist or is not a directory, or the system
        refuses (permissions, a directory in the way); the message names the path and the reason.
    OutputExistsError
        If the file exists and ``force`` is false.
    """
    import tomli_w

    path = Path(path)
    parent = path.parent
    what = f"cannot write the rig parameters to {path}"
    if not parent.exists():
        raise DataFileError(f"{what}: the directory {parent} does not exist (create it first)")
    if not parent.is_dir():
        raise DataFileError(f"{what}: {parent} is not a directory")
    if path.is_dir():
        raise DataFileError(f"{what}: it is a directory; give a file name such as {path / 'rig.toml'}")
    header = "# flexdigit rig parameters (SI units; 'command' is the servo board's 0..254 position).\n"
    try:
        with atomic_write(path, "w", force=force) as fh:
            fh.write(header + tomli_w.dumps(params.to_dict()))
    except FileExistsError:
        raise
    except OSError as exc:
        raise DataFileError(f"{what}: {exc.strerror or exc}") from None
    return path
