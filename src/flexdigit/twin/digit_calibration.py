"""A default calibration for a digit nobody has measured, scaled from the thesis rig's fitted one by the physics.

The packaged calibration (:func:`flexdigit.twin.calibration.packaged_calibration`) is fitted to the thesis rig's
records (tables 3.1, 3.2, 3.6, E 3.20-3.22, 7.5). A digit described by another parameter file (other sections,
gauges, strip, cable) has no records yet; :func:`calibration_for` gives its twin the values the thesis rig's would
become under that digit's description, each by the law below. ``0`` subscripts are the thesis rig's
(:class:`~flexdigit.params.RigParams` defaults) and its packaged calibration, or another reference rig and its
calibration (``calibration_for(params, reference, reference_params)``: the design study scales its baseline's).

- ``support_mass_kg``: a nylon support is a block as long as the support (``l_s``, 10 mm), as wide as the strip
  (``w``) and about as tall as the cable guides either side of the strip (``2 e``): its mass scales with that
  volume, ``m = m0 (l_s / l_s0) (w / w0) (e / e0)``, one value per support, each by its own length
  (``Geometry.supports_m``: ``support_lengths_m`` if the description gives them).
- ``housing_ei_n_m2``: the elastomer housing encloses strip and cable guides, a section ``w`` wide and ``~2 e``
  tall, so its bending stiffness scales as ``w (2 e)^3``: ``EI_h = EI_h0 (w / w0) (e / e0)^3``. The base section
  keeps the thesis's base value (stiffened by the clamp, 3.4.1: gauge 1 barely bends), the others the thesis's
  uniform value (the mean of its sections 2..n). ``EI`` is a property of the cross-section, not of the length:
  each section's rotational stiffness in the twin's chain is ``EI / l_k`` over its own free length ``l_k``
  (``Geometry.section_bounds_m``), so sections of unequal lengths scale with their own length there.
- ``strip_beta_s``, ``housing_beta_s``: stiffness-proportional damping ``c = beta k``, scaled so that the digit's
  first mode keeps the thesis rig's damping ratio: ``beta = beta0 wn1_0 / wn1`` (below, "The damping law").
- ``cable_stiffness_n_m``: ``k = E_c A_c / l_c`` with the cable's run ``l_c`` along the digit: ``k = k0 L0 / L``.
- ``housing_mass_kg``: the housing's volume ``~ w (2 e) L``: ``m_h = m_h0 (w / w0)(e / e0)(L / L0)`` (0 on the
  thesis rig: its mass is folded into its fitted stiffness).
- ``channel_gain``: the per-channel factor on ``amplifier_gain x excitation`` that the gauge-volt lines fixed; the
  bridge, gauge factor and amplifier of a new digit are in its sensor chain already, so the factor is the
  thesis's at the same relative position along the digit (``x / L``, interpolated linearly between the thesis's
  three gauges, held beyond them).
- ``channel_offset_v``: a bridge's imbalance, not a property of its place: the thesis's offset for a gauge at a
  thesis gauge's relative position, else 0 (a balanced bridge, the unbiased guess).
- ``noise_white_v``, ``noise_drift_v_per_sqrt_s``: the amplifier's input-referred noise, amplified: scaled by
  ``amplifier_gain / amplifier_gain0`` (each gauge's own amplifier); ``pot_noise_v`` kept (the same servo
  potentiometer and card).
- ``cable_friction_ratio``: the description's ``[cables] guide_friction_ratio`` (default: the thesis's fit).

The damping law
---------------
The thesis fits ``beta`` to the zetas of its release tests (tables 3.1, 3.2), so a ``beta`` is only known at the
thesis rig's frequencies. Stiffness-proportional damping dissipates per cycle ``pi beta w`` times the energy
stored: its loss factor ``eta = beta w`` grows with frequency. The internal damping of metals (spring steel,
bronzes, titanium) and of filled elastomers is not viscous but close to hysteretic: the energy lost per cycle is
a fraction of the energy stored that hardly depends on the frequency (Lazan, *Damping of Materials and Members in
Structural Mechanics*, 1968; Nashif, Jones and Henderson, *Vibration Damping*, 1985, ch. 2-3; Adhikari, *Damping
Models for Structural Vibration*, 2000, ch. 1: a frequency-independent loss factor is the usual model of
structural damping, and a viscous model is matched to it at the frequency of the mode that matters). What
carries over from one digit to another of the same materials is then the loss factor ``eta``, i.e. the modal
damping ratio ``zeta = eta / 2``, not the relaxation time ``beta``: keeping ``beta`` makes a long, soft digit
(first mode 5 rad/s) three times less damped than the thesis rig (15 rad/s) and a short one three times more,
which no material does. So ``beta`` is matched at the digit's first bending mode:
``beta = beta0 wn1_0 / wn1``, the same factor for strip and housing (each material keeps its loss factor
``eta = beta0 wn1_0``; the digit's first-mode ``zeta`` is the thesis rig's, up to how its strain energy splits
between strip and housing). ``wn1`` is the first mode of the chain's linear modal analysis
(:meth:`flexdigit.twin.digit.Chain.linear_modes`) of the housed digit, straight, without its cable and without
gravity (a property of the structure, not of how it is mounted: a long digit that would buckle tip up still has
one), at the twin's 3 cells per section; ``wn1_0`` the same of the thesis rig with the reference calibration.
On the thesis rig the factor is exactly 1 (the same chain both times). A user's calibration file, fitted to the
digit's own records (``flexdigit calibrate``), replaces all of this (:func:`twin_calibration`, the one default
of every twin built without a calibration).

On the thesis rig every ratio is 1 and every relative position a thesis gauge's, so the packaged calibration comes
back (``tests/twin/test_digit_calibration.py`` holds the table, within 5 % per value as issue 24 asks; in fact to
rounding).

Examples
--------
>>> from flexdigit.params import RigParams
>>> from flexdigit.twin.calibration import packaged_calibration
>>> calibration_for(RigParams()).housing_ei_n_m2 == packaged_calibration().housing_ei_n_m2
True
>>> calibration_for(RigParams()).strip_beta_s == packaged_calibration().strip_beta_s   # factor exactly 1
True
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from flexdigit.errors import ParameterError
from flexdigit.params import RigParams
from flexdigit.twin.calibration import (
    Calibration,
    default_calibration,
    default_calibration_source,
    load_calibration,
    packaged_calibration,
)

__all__ = [
    "calibration_for",
    "is_derived",
    "decay_time_constant_s",
    "first_mode_rad_s",
    "twin_calibration",
]

#: Cells per section of the chain whose first mode sets the damping factor: 3, the thesis rig's own resolution
#: (:func:`flexdigit.twin.default_cells` gives it 3), so the factor is exactly 1 there. Longer sections get finer
#: twins (27 mm cells) but keep the law's 3-cell first mode: the factor is a scaling estimate, and the step figures
#: of the test digits were measured with it (tests/twin/test_digit_calibration.py).
MODAL_CELLS_PER_SECTION = 3

#: A gauge "at a thesis gauge's place" when their relative positions agree this closely (x / L, dimensionless).
_SAME_PLACE = 1e-9


def calibration_for(
    params: RigParams, reference: Calibration | None = None, reference_params: RigParams | None = None
) -> Calibration:
    """The default calibration of the digit ``params`` describes, scaled from ``reference`` (the packaged thesis
    calibration by default) by the laws of the module docstring.

    Parameters
    ----------
    params : RigParams
        The digit (any section and gauge count).
    reference : Calibration, optional
        The calibration to scale from: the packaged thesis fit by default.
    reference_params : RigParams, optional
        The rig ``reference`` belongs to (its ``0`` subscripts in the laws): the thesis rig by default. A design
        study scales its baseline's calibration (any digit's, fitted or derived) to each design this way.

    Returns
    -------
    Calibration
        One value per section/support of ``params`` and per gauge.

    Raises
    ------
    ParameterError
        If ``reference`` does not have one value per section and gauge of ``reference_params``.
    """
    ref = reference if reference is not None else packaged_calibration()
    base = reference_params if reference_params is not None else RigParams()
    if not _describes(ref, base):
        raise ParameterError(
            f"The 'reference' parameter of calibration_for must have one value per section and gauge of its rig "
            f"({base.geometry.section_count} sections, {len(base.geometry.gauge_positions_m)} gauges). Got "
            f"{len(ref.support_mass_kg)} support masses and {len(ref.channel_gain)} channel gains instead."
        )
    scaled = _scaled_statics(params, ref, base)
    damping = first_mode_rad_s(base, ref) / first_mode_rad_s(params, scaled)  # wn1_0 / wn1: the damping law
    return scaled.replace(strip_beta_s=ref.strip_beta_s * damping, housing_beta_s=ref.housing_beta_s * damping)


@lru_cache(maxsize=64)
def first_mode_rad_s(params: RigParams, calibration: Calibration) -> float:
    """The first bending mode (rad/s) of the housed digit, straight, its cable slack, without gravity (the chain's
    linear modal analysis at :data:`MODAL_CELLS_PER_SECTION` cells a section): the frequency the damping law
    matches the materials' loss factors at (module docstring).

    Examples
    --------
    >>> round(first_mode_rad_s(RigParams(), packaged_calibration()), 2)
    14.97
    """
    wn, _ = _weightless_chain(params, calibration).linear_modes()
    return float(wn[0])


def decay_time_constant_s(params: RigParams, calibration: Calibration) -> float:
    """The time constant (s) of the digit's slowest-decaying vibration, ``1 / min(zeta wn)`` over the modes of its
    housed chain straight with its cable(s) taut (how a sweep or a loop holds it), without gravity: ``zeta wn`` is
    about ``c / 2m``, which gravity's stiffness hardly moves (a 0.44 m phosphor-bronze pair: 5.3 s tip up, 5.4 s
    hung). What a wait for the digit to come to rest scales with.

    Examples
    --------
    >>> round(decay_time_constant_s(RigParams(), packaged_calibration()), 2)
    0.44
    """
    wn, zeta = _weightless_chain(params, calibration).linear_modes(cable_taut=params.cables.count)
    return float(1.0 / np.min(zeta * wn))


def _weightless_chain(params: RigParams, calibration: Calibration):
    """The housed digit's chain at :data:`MODAL_CELLS_PER_SECTION` cells a section, without gravity."""
    from flexdigit.twin.digit import Chain, digit_arrays

    arrays = digit_arrays(params, calibration, housing=True, cells_per_section=MODAL_CELLS_PER_SECTION)
    arrays["gravity_ab_m_s2"] = np.zeros(2)
    return Chain(**arrays)


def _scaled_statics(params: RigParams, ref: Calibration, thesis: RigParams) -> Calibration:
    # ``thesis``: the reference rig (the thesis rig unless calibration_for was given another)
    """Every law of the module docstring but the damping's (``ref``'s ``beta`` kept)."""
    g, g0 = params.geometry, thesis.geometry
    n = g.section_count
    width = g.strip_width_m / g0.strip_width_m
    ecc = g.cable_eccentricity_m / g0.cable_eccentricity_m
    length = g.digit_length_m / g0.digit_length_m
    support0 = g0.support_length_m if g0.support_lengths_m is None else float(np.mean(g0.supports_m))
    support_mass = tuple(float(np.mean(ref.support_mass_kg)) * (s / support0) * width * ecc for s in g.supports_m)
    housing = np.asarray(ref.housing_ei_n_m2, dtype=float) * width * ecc**3
    uniform = float(np.mean(housing[1:])) if housing.size > 1 else float(housing[0])
    housing_ei = (float(housing[0]),) + (uniform,) * (n - 1)

    rel0 = np.asarray(g0.gauge_positions_m) / g0.digit_length_m
    rel = np.asarray(g.gauge_positions_m) / g.digit_length_m
    gain = tuple(float(v) for v in np.interp(rel, rel0, ref.channel_gain))
    offsets = []
    for x in rel:
        same = np.flatnonzero(np.abs(rel0 - x) < _SAME_PLACE)
        offsets.append(float(ref.channel_offset_v[same[0]]) if same.size else 0.0)
    count = rel.size
    gain0 = float(np.mean(thesis.sensors.chain(rel0.size)[2]))  # the reference's amplifier (the thesis's 10,000)
    amplify = np.asarray(params.sensors.chain(count)[2]) / gain0  # per gauge
    white = tuple(float(v) for v in float(np.mean(ref.noise_white_v)) * amplify)
    drift = tuple(float(v) for v in float(np.mean(ref.noise_drift_v_per_sqrt_s)) * amplify)
    return ref.replace(
        support_mass_kg=support_mass,
        housing_ei_n_m2=housing_ei,
        cable_stiffness_n_m=ref.cable_stiffness_n_m / length,
        housing_mass_kg=ref.housing_mass_kg * width * ecc * length,
        channel_gain=gain,
        channel_offset_v=tuple(offsets),
        noise_white_v=white,
        noise_drift_v_per_sqrt_s=drift,
        cable_friction_ratio=params.cables.guide_friction_ratio,
    )


def twin_calibration(params: RigParams | None = None, path=None) -> Calibration:
    """The calibration a twin of ``params`` runs with when none is passed: the one default of the library and the
    CLI alike (:class:`~flexdigit.twin.twin.Twin`, ``open_rig("sim", params)``, every command's ``--params``).

    In order: the file ``path`` if given; the calibration a :func:`~flexdigit.twin.calibration.use_calibration`
    block made the default, if it has one value per section and per gauge of ``params`` (``reproduce
    --calibration``); the packaged thesis fit for the thesis rig (``params`` None or equal to ``RigParams()`` but for
    its ``[twin]`` resolution);
    else :func:`calibration_for` (the thesis's scaled to that digit). Any other digit, even one of 3 sections and
    3 gauges like the thesis rig's, is not the rig the packaged fit was measured on: its twin gets the scaled one.

    Examples
    --------
    >>> from flexdigit.params import Geometry, RigParams
    >>> from flexdigit.twin.calibration import default_calibration
    >>> twin_calibration(RigParams()) == default_calibration()
    True
    >>> thick = RigParams(geometry=Geometry(strip_thickness_m=0.5e-3))   # 3 sections and 3 gauges, another strip
    >>> twin_calibration(thick) == calibration_for(thick) != default_calibration()
    True
    """
    if path is not None:
        return load_calibration(path)
    params = RigParams() if params is None else params
    if default_calibration_source() != "packaged" and _describes(default_calibration(), params):
        return default_calibration()
    if params.is_thesis_rig():  # the thesis rig, whatever its twin's resolution ([twin])
        return packaged_calibration()
    return _calibration_for_cached(params.digit_only())  # the laws read the digit, not its twin's resolution


def is_derived(params: RigParams, calibration: Calibration) -> bool:
    """Whether ``calibration`` is the default :func:`calibration_for` derives for the digit of ``params`` (a digit
    nobody measured, not the thesis rig): a twin on it gets a resolution fine enough for its statics
    (:func:`flexdigit.twin.resolution.twin_default_cells`); a fitted calibration keeps the cells it was fitted at.

    >>> is_derived(RigParams(), packaged_calibration())
    False
    """
    digit = params.digit_only()
    return digit != RigParams() and calibration == _calibration_for_cached(digit)


def _describes(calibration: Calibration, params: RigParams) -> bool:
    """Whether ``calibration`` has one value per section (support masses) and per gauge (channel gains) of
    ``params``."""
    return len(calibration.support_mass_kg) == params.geometry.section_count and len(calibration.channel_gain) == len(
        params.geometry.gauge_positions_m
    )


@lru_cache(maxsize=64)
def _calibration_for_cached(params: RigParams) -> Calibration:
    """:func:`calibration_for` from the packaged calibration, cached (twins of one digit are built many times)."""
    return calibration_for(params)
