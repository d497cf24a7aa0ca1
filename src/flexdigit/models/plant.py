"""The plant G(s): servo command -> deflection at a strain gauge, assembled from the component models (thesis 3.5).

Two variants, both built from components (nothing about G is typed in):

``"printed"``
    ``G(s) = K2 K3 MT_rad(s) E'(s)`` as the thesis computed it, which reproduces
    ``48.7 / (s^4 + 23.65 s^3 + 537.3 s^2 + 2616 s + 4.354e4)`` m per command at gauge 1 (K1 excluded):
    K2 = E I r_M/(l e) (:mod:`.cable`), K3 = a/s from the printed fits (:mod:`.conversion`, in m/V),
    ``MT_rad(s) = MT(s) x 109.1344 pi/180`` (:mod:`.servo`) and a digit factor
    ``E'(s) = wn^2/(s^2 + 2 zeta wn s + wn^2)`` with wn = 10.16 rad/s of table 3.1 (the bare strip) and the
    damping coefficient ``2 zeta wn = 0.543`` 1/s (zeta = 0.0267) of the digit factor
    ``103.3/(s^2 + 0.543 s + 103.3)`` that the ``[plant]`` note of ``reference/thesis.toml`` identifies
    (:data:`PRINTED_DIGIT_DAMPING_1_PER_S`). The text says E(s) of 3.1.2 (with housing,
    171.61/(s^2 + 1.782 s + 171.61)) is used; it is not what the printed G contains. The damping only sets the
    real part of the slow poles (and the s^3..s^1 coefficients): the numerator 48.7, the s^0 coefficient and the
    poles' imaginary parts follow from the other components whatever it is.

``"consistent"``
    The same chain with units that hold: command -> servo angle (``MT(s)`` with unit DC gain x 0.015048 rad per
    command) -> cable shortening ``r_M theta`` -> tip moment (``E I / (l e)``, i.e. K2 overall) -> the digit's
    dynamics E(s) with housing (unit DC gain) -> curvature ``M / E I`` -> the chosen ``output``:

    ================== ============================================ ==========================
    output             gain from curvature kappa                     unit
    ================== ============================================ ==========================
    curvature_1_per_m  1                                            1/m
    tip_rotation_rad   l (slope at the tip; = r_M theta / e)        rad
    tip_deflection_m   l^2 / 2 (E 3.14)                             m
    deflection_sgN_m   x_N^2 / 2 (E 3.15, gauge N of table 3.5)     m
    strain_sgN         t / 2 (surface strain)                       1
    gauge_v_sgN        t/2 x GF/2 x Vs x amplifier gain (E 2.4)     V
    ================== ============================================ ==========================

    ``gains="measured"`` rescales the deflection and gauge-voltage outputs to the measured per-command figures
    (the printed fits of table 3.6 and E 3.20-3.22): 0.0565, 0.9047, 2.7705 mm and 0.0086, 0.0119, 0.0088 V per
    command at gauges 1-3.

What "30 degrees of beam rotation" means in commands: by the cable model the tip turns
``r_M x 0.015048 / e = 0.0303 rad = 1.735 deg`` per command, so 30 deg is 17.3 commands (from command 8 to 25.3).
The thesis says 8..43 in 3.4.1 (that is 30 deg of *servo* rotation) and "approximately fifteen steps" in 3.6.
With ``output="tip_rotation_rad"`` a 30 deg (0.5236 rad) reference needs 17.3 commands at DC, well inside
0..254. See :func:`explain_discrepancies` for every printed-vs-consistent difference.

Examples
--------
>>> g = build_plant("printed")
>>> [round(float(c), 2) for c in g.tf.num[0][0]]
[48.71]
>>> [round(float(c), 1) for c in g.tf.den[0][0]]
[1.0, 23.7, 537.3, 2616.0, 43530.8]
>>> c = build_plant("consistent", output="tip_rotation_rad")
>>> round(float(c.dc_gain), 5)                  # rad of tip rotation per command
0.03028
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from flexdigit._repr import summary
from flexdigit._validation import check_choice, check_real
from flexdigit.errors import ParameterError
from flexdigit.models import bridge, cable, conversion, second_order, servo
from flexdigit.models.polytf import PolyTF, ctrb, obsv
from flexdigit.params import RigParams

__all__ = [
    "VARIANTS",
    "PRINTED_DIGIT_DAMPING_1_PER_S",
    "GAIN_SOURCES",
    "output_choices",
    "Plant",
    "companion_ss",
    "printed_digit_zeta",
    "build_plant",
    "closed_loop_printed_k1",
    "commands_for_tip_rotation",
    "explain_discrepancies",
    "tip_rotation_command_range",
]

if TYPE_CHECKING:
    import control

VARIANTS = ("printed", "consistent")
#: ``2 zeta wn`` (1/s) of the digit factor inside the printed G(s), ``103.3/(s^2 + 0.543 s + 103.3)``, as identified
#: in the ``[plant]`` note of ``reference/thesis.toml`` (from the shared reference): the thesis prints neither it nor
#: its zeta ~ 0.027, which is in no table (tables 3.1/3.2 give 0.0025 and 0.068).
PRINTED_DIGIT_DAMPING_1_PER_S = 0.543
GAIN_SOURCES = ("cable", "measured")
_GAUGE_OUTPUT = re.compile(r"^(deflection_sg|strain_sg|gauge_v_sg)(\d+)(_m)?$")


def output_choices(params: RigParams | None = None) -> tuple[str, ...]:
    """Every ``output=`` name :func:`build_plant` accepts for the consistent variant (gauges from ``params``)."""
    n = len((params or RigParams()).geometry.gauge_positions_m)
    kinds = (("deflection_sg", "_m"), ("strain_sg", ""), ("gauge_v_sg", ""))
    per_gauge = [f"{kind}{k}{suffix}" for kind, suffix in kinds for k in range(1, n + 1)]
    return ("curvature_1_per_m", "tip_rotation_rad", "tip_deflection_m", "gauge_v", *per_gauge)


@dataclass(frozen=True)
class Plant:
    """A plant model: its transfer function and state space, what goes in and out, and the factors it is made of.

    The plant is held as numpy polynomials and matrices; :attr:`tf`, :attr:`ss` and :attr:`components` convert
    them to python-control objects on first use (``import control`` costs 2 s, which ``flexdigit model`` does not
    need to pay for its poles, ranks and DC gain).

    Attributes
    ----------
    variant : {"printed", "consistent"}
    output : str
        What the output is (``"deflection_sg1_m"``, ``"tip_rotation_rad"``, ...).
    poly : PolyTF
        Command -> output, monic denominator.
    abcd : tuple of ndarray
        ``(A, B, C, D)``, a realisation of ``poly``: the companion form of 3.5 for ``printed``; for
        ``consistent`` the servo and the digit in series, states the servo's output (commands' worth) and its rate,
        the tip moment (N m) and its rate.
    input_unit, output_unit : str
        ``"command"`` and e.g. ``"m"``.
    factors : dict
        The factors, name -> float gain or :class:`PolyTF`, in the order they are multiplied.
    notes : tuple of str
        How this variant was put together.
    """

    variant: str
    output: str
    poly: PolyTF
    abcd: tuple
    input_unit: str
    output_unit: str
    factors: dict = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    @cached_property
    def tf(self) -> control.TransferFunction:
        """Command -> output as a ``control.TransferFunction``."""
        return self.poly.to_control()

    @cached_property
    def ss(self) -> control.StateSpace:
        """:attr:`abcd` as a ``control.StateSpace``."""
        import control

        return control.ss(*self.abcd)

    @cached_property
    def components(self) -> dict:
        """:attr:`factors` with each :class:`PolyTF` as a ``control.TransferFunction`` (floats as they are)."""
        return {k: v.to_control() if isinstance(v, PolyTF) else v for k, v in self.factors.items()}

    @property
    def order(self) -> int:
        """Number of states of :attr:`abcd` (4 in the thesis)."""
        return int(np.shape(self.abcd[0])[0])

    @property
    def poles(self) -> np.ndarray:
        """Poles (rad/s), sorted by real part then imaginary part."""
        return _sorted(self.poly.poles())

    @property
    def zeros(self) -> np.ndarray:
        """Finite transmission zeros (rad/s); empty for this plant."""
        return _sorted(self.poly.zeros())

    @property
    def dc_gain(self) -> float:
        """G(0), output unit per command."""
        return self.poly.dcgain()

    @property
    def controllability_rank(self) -> int:
        """Rank of the controllability matrix of :attr:`abcd` (4 in the thesis)."""
        a, b = self.abcd[0], self.abcd[1]
        return int(np.linalg.matrix_rank(_scaled(ctrb(a, b))))

    @property
    def observability_rank(self) -> int:
        """Rank of the observability matrix of :attr:`abcd` (4 in the thesis)."""
        a, c = self.abcd[0], self.abcd[2]
        return int(np.linalg.matrix_rank(_scaled(obsv(a, c).T)))

    @property
    def is_stable(self) -> bool:
        """All poles in the open left half plane."""
        return bool(np.all(self.poles.real < 0))

    @property
    def is_minimum_phase(self) -> bool:
        """Stable with no zeros in the closed right half plane (3.5: no transmission zeros, so minimum phase)."""
        return self.is_stable and bool(np.all(self.zeros.real < 0))

    def per_command(self, command_steps=1.0):
        """Static output for a number of command steps away from the equilibrium command (output unit)."""
        out = self.dc_gain * np.asarray(command_steps, dtype=float)
        return out if out.ndim else float(out)

    def closed_loop_poly(self, k1: float) -> PolyTF:
        """Unity-feedback closed loop with gain ``k1`` in the forward path, ``k1 G / (1 + k1 G)``, as a PolyTF."""
        k = check_real(k1, "k1", "Plant.closed_loop")
        return (k * self.poly).feedback()

    def closed_loop(self, k1: float) -> control.TransferFunction:
        """Unity-feedback closed loop with gain ``k1`` in the forward path: ``k1 G / (1 + k1 G)`` (table 4.1).

        The printed closed loop (86.2 / (... + 4.362e4)) needs ``k1 = 1.7699`` command per output unit, a tenth
        of E 3.16's 17.6991 command per mm (and 17,699 command per m would be the unit-correct figure).
        """
        return self.closed_loop_poly(k1).to_control()

    def summary(self) -> dict:
        """Poles, zeros, DC gain, ranks and phase, as plain values (for ``--json`` and the report)."""
        g = self.poly.normalised()
        return {
            "variant": self.variant,
            "output": self.output,
            "input_unit": self.input_unit,
            "output_unit": self.output_unit,
            "num": g.num.tolist(),
            "den": g.den.tolist(),
            "poles": self.poles,
            "zeros": self.zeros,
            "dc_gain": self.dc_gain,
            "controllability_rank": self.controllability_rank,
            "observability_rank": self.observability_rank,
            "order": self.order,
            "stable": self.is_stable,
            "minimum_phase": self.is_minimum_phase,
        }

    def __repr__(self) -> str:
        return summary(
            self,
            variant=self.variant,
            output=self.output,
            order=self.order,
            dc_gain=(self.dc_gain, f"{self.output_unit}/{self.input_unit}"),
            poles=(self.poles, "rad/s"),
        )


def _sorted(values) -> np.ndarray:
    v = np.asarray(values, dtype=complex)
    return v[np.lexsort((v.imag, v.real))] if v.size else v


def _scaled(matrix: np.ndarray) -> np.ndarray:
    """Columns scaled to unit norm, so a rank test is not fooled by the 1e4..1e11 spread of the companion form."""
    norms = np.linalg.norm(matrix, axis=0)
    norms[norms == 0] = 1.0
    return matrix / norms


def companion_ss(tf: control.TransferFunction) -> control.StateSpace:
    """MATLAB's ``tf2ss`` form for a strictly proper SISO TF with a constant numerator, as printed in 3.5.

    ``A = [[-a1, -a2, ..., -an], [1, 0, ...], ...]``, ``B = e1``, ``C = [0 ... 0 b0]``.
    """
    import control

    return control.ss(*_companion(PolyTF.from_control(tf)))


def _companion(g: PolyTF) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The matrices of :func:`companion_ss` for a PolyTF."""
    g = g.normalised()
    num, den = g.num, g.den
    n = den.size - 1
    if n < 1 or num.size > n:
        raise ParameterError(f"companion_ss needs a strictly proper transfer function. Got order {n}.")
    a = np.zeros((n, n))
    a[0, :] = -den[1:]
    a[1:, :-1] = np.eye(n - 1)
    b = np.zeros((n, 1))
    b[0, 0] = 1.0
    c = np.zeros((1, n))
    c[0, n - num.size :] = num
    return a, b, c, np.zeros((1, 1))


def _second_order_series(first: PolyTF, first_gain: float, second: PolyTF, second_gain: float) -> tuple:
    """``second_gain second(s) x first_gain first(s)`` for two ``b0/(s^2 + a1 s + a0)`` factors, states
    ``[y1, y1', y2, y2']`` (each factor's output before its gain, and its rate)."""
    blocks = []
    for g in (first.normalised(), second.normalised()):
        if g.den.size != 3 or g.num.size != 1:
            raise ParameterError(f"_second_order_series needs b0/(s^2 + a1 s + a0) factors. Got {g!r}.")
        blocks.append((np.array([[0.0, 1.0], [-g.den[2], -g.den[1]]]), np.array([[0.0], [g.num[0]]])))
    (a1, b1), (a2, b2) = blocks
    c1 = np.array([[first_gain, 0.0]])
    a = np.block([[a1, np.zeros((2, 2))], [b2 @ c1, a2]])
    b = np.vstack([b1, np.zeros((2, 1))])
    c = np.array([[0.0, 0.0, second_gain, 0.0]])
    return a, b, c, np.zeros((1, 1))


def printed_digit_zeta(
    params: RigParams | None = None, damping_1_per_s: float = PRINTED_DIGIT_DAMPING_1_PER_S
) -> float:
    """The digit damping ratio inside the printed G(s): ``zeta = (2 zeta wn) / (2 wn)``, about 0.0267.

    ``damping_1_per_s`` is the ``0.543`` 1/s of the identified digit factor ``103.3/(s^2 + 0.543 s + 103.3)``
    (:data:`PRINTED_DIGIT_DAMPING_1_PER_S`), ``wn`` table 3.1's 10.16271 rad/s (``params.dynamics.wn_bare_rad_s``).
    It is not read from the printed poles, so that their real part -0.2715 is a check, not an input. (The
    identification formula ``2 zeta wn = 8 / Ts`` would put Ts at 14.7 s.)

    Examples
    --------
    >>> round(printed_digit_zeta(), 5)
    0.02672
    """
    wn = (params or RigParams()).dynamics.wn_bare_rad_s
    damping = check_real(damping_1_per_s, "damping_1_per_s", "printed_digit_zeta", low=0)
    return damping / (2.0 * wn)


def _gauge_index(output: str, params: RigParams) -> tuple[str, int] | None:
    m = _GAUGE_OUTPUT.match(output)
    if m is None:
        return None
    kind, k = m.group(1), int(m.group(2))
    if not 1 <= k <= len(params.geometry.gauge_positions_m):
        return None
    return kind, k - 1


def build_plant(
    variant: str = "printed",
    params: RigParams | None = None,
    *,
    output: str = "deflection_sg1_m",
    gains: str = "cable",
    printed_digit_damping_1_per_s: float = PRINTED_DIGIT_DAMPING_1_PER_S,
) -> Plant:
    """Assemble the plant G(s) of 3.5 from the component models.

    Parameters
    ----------
    variant : {"printed", "consistent"}
        ``"printed"`` reproduces the thesis's G(s) (m per command at a gauge, K1 excluded) from its components
        with the thesis's own unit slips; ``"consistent"`` is the unit-correct chain (see the module docstring).
    params : RigParams, optional
        Rig parameters (thesis defaults).
    output : str
        ``"deflection_sg1_m"`` (default; ``sg2``, ``sg3`` likewise) for both variants; the consistent variant
        also offers ``"tip_rotation_rad"``, ``"tip_deflection_m"``, ``"curvature_1_per_m"``, ``"strain_sgN"``,
        ``"gauge_v_sgN"`` (``"gauge_v"`` = gauge 1). See :func:`output_choices`.
    gains : {"cable", "measured"}
        Consistent variant only: DC gains from the cable model (default) or scaled to the measured per-command
        figures (printed fits of table 3.6, E 3.20-3.22; deflection and gauge-voltage outputs only).
    printed_digit_damping_1_per_s : float
        Printed variant only: ``2 zeta wn`` (1/s) of its digit factor (default 0.543, see
        :data:`PRINTED_DIGIT_DAMPING_1_PER_S`).

    Returns
    -------
    Plant

    Raises
    ------
    ParameterError
        For an unknown variant, output or gain source, or an output the variant cannot give.
    """
    params = params or RigParams()
    check_choice(variant, "variant", VARIANTS, "build_plant")
    check_choice(gains, "gains", GAIN_SOURCES, "build_plant")
    if output == "gauge_v":
        output = "gauge_v_sg1"
    if variant == "printed":
        return _printed(params, output, gains, printed_digit_damping_1_per_s)
    return _consistent(params, output, gains)


def _printed(params: RigParams, output: str, gains: str, damping_1_per_s: float) -> Plant:
    gauge = _gauge_index(output, params)
    if gauge is None or gauge[0] != "deflection_sg" or not output.endswith("_m"):
        raise ParameterError(
            "The 'output' parameter of build_plant('printed') must be a gauge deflection such as "
            f"'deflection_sg1_m' (the printed G is m per command). Got {output!r} instead."
        )
    if gains != "cable":
        raise ParameterError(
            f"The 'gains' parameter of build_plant('printed') must be 'cable' (as printed). Got {gains!r} instead."
        )
    k = gauge[1]
    k3 = conversion.k3_printed_mm_per_v()
    if k >= len(k3):
        raise ParameterError(f"The printed K3 exists for gauges 1..{len(k3)} only. Got {output!r} instead.")
    k2 = cable.k2_nm_per_rad(params)
    k3_m_per_v = k3[k] * 1e-3  # mm -> m, as 3.5 does
    mt_rad = servo.servo_poly(params, form="printed")
    e_printed = second_order.digit_poly(params.dynamics.wn_bare_rad_s, printed_digit_zeta(params, damping_1_per_s))
    tf = (k2 * k3_m_per_v * mt_rad * e_printed).normalised()
    components = {
        "K2_nm_per_rad": k2,
        "K3_m_per_v": k3_m_per_v,
        "MT_rad_per_command_printed": mt_rad,
        "E_digit_printed": e_printed,
    }
    notes = (
        f"G = K2 K3 MT(s) x 109.1344 pi/180 x E'(s), E' from table 3.1's wn with 2 zeta wn = {damping_1_per_s:g} 1/s "
        "(the digit factor the [plant] note of reference/thesis.toml identifies).",
        "Units as printed: MT has unit DC gain, so 'rad per command' is 126.6x too large; E' is 1 V per N m.",
    )
    return Plant("printed", output, tf, _companion(tf), "command", "m", components, notes)


def _consistent(params: RigParams, output: str, gains: str) -> Plant:
    choices = output_choices(params)
    if output not in choices:
        raise ParameterError(
            "The 'output' parameter of build_plant('consistent') must be one of "
            + ", ".join(repr(c) for c in choices)
            + f". Got {output!r} instead."
        )
    g, a, s = params.geometry, params.actuator, params.sensors
    ei = params.bending_stiffness_n_m2
    mt = servo.servo_unit_poly(params)
    e_digit = second_order.digit_poly_from_params(params, housing=True)
    rad_per_command = a.rad_per_command
    moment_per_shortening = ei / (g.digit_length_m * g.cable_eccentricity_m)  # E 3.12 with 1/rho = dl/(l e)
    gauge = _gauge_index(output, params)
    if output == "curvature_1_per_m":
        out_gain, unit = 1.0, "1/m"
    elif output == "tip_rotation_rad":
        out_gain, unit = g.digit_length_m, "rad"
    elif output == "tip_deflection_m":
        out_gain, unit = g.digit_length_m**2 / 2.0, "m"  # E 3.14
    else:
        kind, k = gauge
        x = g.gauge_positions_m[k]
        if kind == "deflection_sg":
            out_gain, unit = x**2 / 2.0, "m"  # E 3.13/3.15 at the gauge
        elif kind == "strain_sg":
            out_gain, unit = g.strip_thickness_m / 2.0, "1"
        else:
            out_gain, unit = g.strip_thickness_m / 2.0 * bridge.bridge_gain_v_per_strain(s), "V"  # E 2.4
    components = {
        "MT_unit": mt,
        "rad_per_command": rad_per_command,
        "pulley_radius_m": a.pulley_radius_m,
        "moment_per_shortening_n": moment_per_shortening,
        "E_digit_housing": e_digit,
        "curvature_per_moment_1_per_nm2": 1.0 / ei,
        f"{output}_per_curvature": out_gain,
    }
    static = rad_per_command * a.cable_m_per_servo_rad * moment_per_shortening / ei * out_gain
    notes = [
        "command -> MT(s) (unit DC gain) x rad/command -> r_M -> E I/(l e) -> E(s) housing -> 1/(E I) -> output.",
        f"K2 = {a.cable_m_per_servo_rad * moment_per_shortening:.6g} N m/rad (E 3.19).",
    ]
    if gains == "measured":
        measured = _measured_per_command(output, params)
        if measured is None:
            raise ParameterError(
                "The 'gains' parameter of build_plant('consistent') can be 'measured' only for a gauge deflection "
                f"or gauge voltage output (the thesis measured nothing else). Got output {output!r}."
            )
        components["measured_over_cable"] = measured / static
        notes.append(f"DC gain scaled to the measured {measured:.6g} {unit} per command (table 3.6, E 3.20-3.22).")
        static = measured
    tf = (static * mt * e_digit).normalised()
    k2 = rad_per_command * a.cable_m_per_servo_rad * moment_per_shortening  # N m of tip moment per command
    abcd = _second_order_series(mt, k2, e_digit, static / k2)
    return Plant("consistent", output, tf, abcd, "command", unit, components, tuple(notes))


def _measured_per_command(output: str, params: RigParams) -> float | None:
    gauge = _gauge_index(output, params)
    if gauge is None or gauge[0] == "strain_sg":
        return None
    kind, k = gauge
    if kind == "deflection_sg":
        fits = conversion.printed_deflection_fits()
        return fits[k].slope * 1e-3 if k < len(fits) else None
    fits = conversion.printed_voltage_fits()
    return fits[k].slope if k < len(fits) else None


def closed_loop_printed_k1() -> float:
    """The K1 the printed closed loop of table 4.1 uses: E 3.16's 17.6991 command/mm divided by 10 (1.7699)."""
    return conversion.k1_printed_command_per_mm()[0] / 10.0


def commands_for_tip_rotation(rotation_deg: float, params: RigParams | None = None) -> float:
    """Command steps from equilibrium for a tip ("beam") rotation in degrees, by the cable model (1.735 deg each).

    Examples
    --------
    >>> round(commands_for_tip_rotation(30.0), 2)
    17.29
    """
    return float(cable.commands_for_tip_rotation(rotation_deg, params))


def explain_discrepancies(params: RigParams | None = None) -> list[str]:
    """The numbered, written explanation of each difference between the printed plant and the consistent one.

    Every figure in the text is computed here from the component models, so the explanation stays true if the
    parameters change.
    """
    p = params or RigParams()
    a, g = p.actuator, p.geometry
    printed = build_plant("printed", p)
    consistent = build_plant("consistent", p)
    measured = build_plant("consistent", p, gains="measured")
    pot_v_per_cmd = a.pot_v_per_command
    pot_printed = servo.PotentiometerMap.printed()
    pot_params = servo.PotentiometerMap.from_params(p)
    k2 = cable.k2_nm_per_rad(p)
    k2_printed_i = cable.k2_nm_per_rad(p, second_moment_m4=5.85e-14)
    ei = p.bending_stiffness_n_m2
    v_per_nm_cable = g.strip_thickness_m / 2.0 / ei * bridge.bridge_gain_v_per_strain(p.sensors)
    v_per_nm_measured = conversion.printed_voltage_fits()[0].slope / (k2 * a.rad_per_command)
    zeta_p = printed_digit_zeta(p)
    k1 = conversion.k1_printed_command_per_mm()[0]
    rot = cable.tip_rotation_per_command_deg(p)
    e_den = printed.factors["E_digit_printed"].den
    items = [
        "Digit factor. 3.5 says G = K1 K2 K3 MT(s) E(s) with E(s) = 171.61/(s^2 + 1.782 s + 171.61) (housing, "
        f"table 3.2), but the printed G contains {e_den[2]:.4g}/(s^2 + {e_den[1]:.3g} s + {e_den[2]:.4g}): wn = "
        f"{p.dynamics.wn_bare_rad_s:.5g} rad/s of table 3.1 (bare strip) with zeta = {zeta_p:.4f}, a damping "
        f"found in no table (2 zeta wn = {e_den[1]:.3g} 1/s, slow poles' real part {-e_den[1] / 2:.4f} as printed). "
        "The consistent plant uses E(s) with housing.",
        "Servo units. MT(s) = 421.5/(s^2 + 23.11 s + 421.5) has unit DC gain, yet 3.2.4 multiplies it by "
        "109.1344 deg/V x pi/180 = 1.905 rad/V and calls 802.854/(...) 'rad per serial command'. The potentiometer "
        f"moves {pot_v_per_cmd:.5f} V per command, so the servo turns {a.rad_per_command:.6f} rad per command "
        f"(E 3.15), {math.radians(pot_printed.slope_deg_per_v) / a.rad_per_command:.1f} times less than the printed "
        "factor. The consistent plant "
        "uses MT(s) x rad_per_command.",
        f"K2. E I r_M/(l e) from table 3.7 is {k2:.6f} N m/rad; the printed 0.089377 is reproduced "
        f"({k2_printed_i:.6f}) with I rounded to 5.85e-14 m^4 before multiplying. Difference "
        f"{100 * abs(k2 / 0.089377 - 1):.3f} %, kept in both variants.",
        "Digit gain. E(s) is printed as V per N m with unit DC gain, i.e. 1 V per N m. By the bridge chain "
        f"(E 2.4, GF 0.8, Vs = {p.sensors.excitation_v:g} V assumed, gain 10,000) the gauge gives "
        f"{v_per_nm_cable:.3g} V per N m of tip moment; the measured E 3.20 slope over K2 x rad_per_command gives "
        f"{v_per_nm_measured:.3g} V per N m. The consistent plant goes moment -> curvature M/(E I) -> output "
        "instead of through a volt it never defines.",
        "K3 units. K3 is mm per volt (E 3.23); 3.5 first writes G with 6.757e13 'mm/m' and then 48.7 m per "
        "command, and the state space has C = [0 0 0 6.7571e10] with A(1,4) = -43535: 48.7 x 1000 is neither "
        "6.757e13 nor 6.7571e10, so the three printed gains are not mutually consistent; only 48.7 follows from "
        "the components (K2 x K3[m/V] x 802.854 x 103.3).",
        f"DC gain. The printed G(0) = {printed.dc_gain * 1e3:.4g} mm per command at gauge 1; the cable model "
        f"(table 3.4) gives {consistent.dc_gain * 1e3:.4g} mm and the measurements (table 3.6 fit) "
        f"{measured.dc_gain * 1e3:.4g} mm per command: the printed plant is "
        f"{printed.dc_gain / consistent.dc_gain:.1f}x the theory and {printed.dc_gain / measured.dc_gain:.1f}x "
        "the measurement.",
        f"K1. E 3.16 gives K1 = {k1:.4f} command per mm at gauge 1; the printed closed loop of table 4.1 "
        f"(86.2/(... + 4.362e4)) uses {k1 / 10:.4f}, a tenth of it. With G in m per command the unit-correct K1 "
        f"would be {k1 * 1e3:.0f} command per m.",
        f"Potentiometer. The line 109.1344 V - 51.162 passes through 0 deg at {pot_printed.voltage_v(0.0):.4f} V, "
        f"not the printed {a.pot_v_at_min_angle_v} V (a transposed digit); the two printed end points give "
        f"{pot_params.slope_deg_per_v:.4f} deg/V. The printed plant uses the printed line.",
        f"Beam rotation in commands. The cable model turns the tip {rot:.3f} deg per command (r_M x "
        f"{a.rad_per_command:.6f} / e), so 30 deg of tip rotation is {30.0 / rot:.1f} commands. 3.4.1 says "
        "commands 8..43 are 0-30 deg of beam rotation (35 commands = 30.2 deg of servo rotation), 3.6 says "
        "'approximately fifteen discrete steps or 12.93 degrees of motor rotation'.",
    ]
    return [f"{i}. {text}" for i, text in enumerate(items, start=1)]


def tip_rotation_command_range(max_rotation_deg: float = 30.0, params: RigParams | None = None) -> tuple[int, int]:
    """Commands from equilibrium to ``max_rotation_deg`` of tip rotation (cable model), rounded up.

    Examples
    --------
    >>> tip_rotation_command_range(30.0)
    (8, 26)
    """
    p = params or RigParams()
    steps = math.ceil(commands_for_tip_rotation(max_rotation_deg, p))
    return p.actuator.equilibrium_command, p.actuator.equilibrium_command + steps
