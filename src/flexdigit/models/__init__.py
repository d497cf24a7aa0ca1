"""Component models of the rig (thesis chapter 3): bridge/amplifier/ADC, beam, digit, motor, servo, cable,
conversion coefficients, and the plant G(s) assembled from them.

>>> from flexdigit.models import build_plant
>>> plant = build_plant()        # G(s) of E 3.32 from the thesis rig's parameters

Every public name below is imported from its module on first use, so ``import flexdigit.models`` is cheap.
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "Cantilever": "flexdigit.models.beam",
        "elastica_tip_deflection": "flexdigit.models.beam",
        "gauge_voltage_v": "flexdigit.models.bridge",
        "strain_from_voltage": "flexdigit.models.bridge",
        "bridge_gain_v_per_strain": "flexdigit.models.bridge",
        "strain_to_volts_tf": "flexdigit.models.bridge",
        "adc_counts": "flexdigit.models.bridge",
        "counts_to_volts": "flexdigit.models.bridge",
        "adc_quantise": "flexdigit.models.bridge",
        "gauge_noise_scale": "flexdigit.models.bridge",
        "cable_shortening_m": "flexdigit.models.cable",
        "tip_rotation_rad": "flexdigit.models.cable",
        "tip_rotation_per_command_deg": "flexdigit.models.cable",
        "tip_deflection_m": "flexdigit.models.cable",
        "LinearFit": "flexdigit.models.conversion",
        "linear_fit": "flexdigit.models.conversion",
        "k1_command_per_mm": "flexdigit.models.conversion",
        "k3_mm_per_v": "flexdigit.models.conversion",
        "percent_error": "flexdigit.models.conversion",
        "DCMotor": "flexdigit.models.motor",
        "motor_angle_tf": "flexdigit.models.motor",
        "Plant": "flexdigit.models.plant",
        "build_plant": "flexdigit.models.plant",
        "PolyTF": "flexdigit.models.polytf",
        "zeta_from_overshoot": "flexdigit.models.second_order",
        "overshoot_from_zeta": "flexdigit.models.second_order",
        "wn_from_settling_time": "flexdigit.models.second_order",
        "natural_frequency_from_damped": "flexdigit.models.second_order",
        "digit_tf": "flexdigit.models.second_order",
        "digit_tf_from_params": "flexdigit.models.second_order",
        "PotentiometerMap": "flexdigit.models.servo",
        "servo_tf": "flexdigit.models.servo",
        "command_to_angle_rad": "flexdigit.models.servo",
        "angle_to_command": "flexdigit.models.servo",
        "Chapter3Study": "flexdigit.models.chapter3_tables",
        "chapter3_study": "flexdigit.models.chapter3_tables",
    },
)
