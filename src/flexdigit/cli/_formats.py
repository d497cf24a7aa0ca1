"""The files flexdigit reads, described for ``--help``: what each holds, with a short example that loads.

Each command's epilog shows the formats it takes (tests/cli/test_help.py loads every example here with the
library's own reader, so an example cannot drift from what the reader accepts). Units are SI unless a key names
another; unknown keys are refused naming the file and the key.
"""

from __future__ import annotations

#: A format: (title, what it holds, an example file).
FORMATS: dict[str, tuple[str, str, str]] = {
    "params": (
        "rig parameters (TOML, --params)",
        "Any of the tables and keys 'flexdigit params' prints; what is left out keeps the thesis rig's value, "
        "except strip_length_m and digit_length_m: derived from the sections a file gives (and 10 mm supports). "
        "[dynamics] is the thesis rig's identified values: no twin reads it.",
        """\
[geometry]
digit_length_m = 0.27
gauge_positions_m = [0.045, 0.135, 0.225]
[sensors]
adc_bits = 12
""",
    ),
    "calibration": (
        "twin calibration (TOML, --calibration; written by 'flexdigit calibrate')",
        "Every key of [calibration], one value per digit section or gauge channel where a list; [fit] says how "
        "it was made.",
        """\
[calibration]
support_mass_kg = [0.0084, 0.0084, 0.0084]
housing_ei_n_m2 = [0.0057, 0.0039, 0.0039]
strip_beta_s = 0.00033
housing_beta_s = 0.025
cable_stiffness_n_m = 56743.0
housing_mass_kg = 0.0
channel_gain = [0.088, 0.122, 0.103]
channel_offset_v = [-0.121, 0.597, 0.035]
noise_white_v = [0.002, 0.002, 0.002]
noise_drift_v_per_sqrt_s = [0.0002, 0.0002, 0.0002]
pot_noise_v = 0.005
cable_friction_ratio = 0.055
[fit]
source = "fitted by hand"
""",
    ),
    "protocol": (
        "load protocol (TOML, 'flexdigit collect FILE'; built-ins: 'flexdigit list protocols')",
        "Weights hung at positions, optionally at actuation commands, each read 'repetitions' times.",
        """\
name = "my-protocol"
description = "two weights at three positions, cable detached"
orientation = "horizontal"
loads_g = [10.0, 20.0]
positions_from_tip_cm = [0, 5, 10]
actuation_commands = []        # e.g. [0, 20, 40]; empty: actuation disabled
repetitions = 5
no_load_repetitions = 5
settle_s = 15.0
""",
    ),
    "dataset": (
        "tactile readings from another rig (CSV, 'flexdigit dataset import FILE')",
        "One reading a row, a header naming the columns; the flags map them to gauges, load and position, with "
        "their units ('flexdigit dataset import readings.csv --gauges sg1,sg2,sg3 --load mass_g --load-unit g "
        "--position pos_mm --position-unit mm --out d.parquet' for the file below).",
        """\
sg1,sg2,sg3,mass_g,pos_mm
0.101,0.652,0.043,0,0
0.142,0.701,0.061,25,30
0.118,0.677,0.052,25,120
""",
    ),
    "tissue": (
        "tissue (TOML, 'flexdigit palpate --tissue FILE'; built-ins: 'flexdigit list tissues')",
        "Where the tissue lies beside the digit; on the twin also its gap and modulus (palpation estimates them).",
        """\
[tissue]
name = "my-block"
side = "cable"            # or "opposite"
start_mm = 150.0          # along the digit from its base
end_mm = 350.0
gap_mm = 30.0             # twin only: surface to the straight digit's axis
modulus_n_m2 = 1000.0     # twin only: N/m per metre of digit pressed in
""",
    ),
    "palpation": (
        "palpation protocol (TOML, 'flexdigit palpate --protocol FILE'; built-ins: 'flexdigit list protocols')",
        "A [sweep] of commands (or [scan] offsets, or [force] control).",
        """\
[sweep]
commands = { from = 8, to = 30, step = 2 }   # or a list, e.g. [8, 10, 12]
settle_s = 2.5
readings = 20
model = "linear"          # or "hunt-crossley"
""",
    ),
    "spec": (
        "study spec (TOML, 'flexdigit study sensitivity|design FILE'; shipped: 'flexdigit list specs')",
        "The study's name and seed, its settings, and each uncertain parameter by its params path.",
        """\
[study]
name = "my-study"
seed = 0

[sensitivity]
sobol_n = 64

[parameters.material.youngs_modulus_pa]
distribution = "uniform"
low = 195e9
high = 215e9
""",
    ),
    "robot": (
        "tendon robot (TOML, 'flexdigit tdcr statics|dynamics|shape|contact FILE', 'simulate release|step --robot "
        "FILE'; built-ins: 'flexdigit list robots')",
        "The backbone rod ([backbone]: Young's modulus, Poisson's ratio, radius, density; SI units), its segments "
        "([[segments]]: length and disk count, disks equally spaced, the last at the segment's end) and the tendons "
        "([[tendons]]: offset from the axis, angle from the disk's x axis, the disk it ends on, counted from the "
        "base over all segments); every key optional but one segment.",
        """\
name = "my-robot"
[backbone]
youngs_modulus_pa = 54e9
poisson_ratio = 0.3
radius_m = 0.0007
density_kg_m3 = 6450.0
[[segments]]
length_m = 0.2
disk_count = 10
[[tendons]]
offset_m = 0.01
angle_deg = 90.0
disk = 10
""",
    ),
    "kept_design": (
        "kept 20 ms design (JSON, written by 'flexdigit design 20ms --out FILE', read by 'flexdigit run "
        "--controller FILE')",
        "The weights a digit's 20 ms design chose and what they were chosen for: the fingerprints of the digit's "
        "parameters and of its twin calibration, its mounting, the loop's period (s) and the model's rotation per "
        "command (deg); a run refuses a file made for another digit. Written by the command, not by hand.",
        """\
{
  "format": "flexdigit-20ms-design-1",
  "params_fingerprint": "66e059881a8e0150",
  "params_file": null,
  "calibration_fingerprint": "8f8caa6bdc5c8198",
  "orientation": "vertical",
  "period_s": 0.02,
  "deg_per_command": 1.7349701366069392,
  "weights": {"q_rate": 100.0, "r_u": 30.0, "q_disturbance": 0.1, "q_input": 1.0, "r_measurement": 10.0,
              "q_shape": 0.0},
  "search": null
}
""",
    ),
    "gauge_readings": (
        "tendon robot gauge readings (CSV, 'flexdigit tdcr shape|contact ROBOT --readings FILE')",
        "A header s_m,angle_deg,strain[,tilt_deg] and one row per gauge: its arc length from the base (m), its "
        "face's angle from the cross-section's x axis (deg), its reading as a strain (m/m) and, for a rosette, "
        "its grid's tilt from the backbone's axis (deg, default 0).",
        """\
s_m,angle_deg,strain
0.1,0,0.00012
0.1,90,-0.00003
0.3,0,0.00025
0.3,90,0.00001
""",
    ),
    "record": (
        "recorded test (CSV or Parquet, 'flexdigit identify release|step FILE', 'flexdigit calibrate "
        "--release-bare FILE')",
        "A header row, then one row per sample: a time column (time_s, time_ms, or time with --time-unit) and "
        "channels named with their unit (sg1_v .. sg3_v or gauge1_v .., pot_v; _mv for millivolts), separated by "
        "commas, semicolons, tabs or spaces; '#' lines are comments; an optional command column gives a step's "
        "input.",
        """\
# a step test, sampled at 1 kHz (an identification needs 20 samples or more)
time_s,command,pot_v,sg1_v
0.000,0,0.467,-0.121
0.001,0,0.468,-0.120
0.002,51,0.468,-0.121
0.003,51,0.471,-0.119
""",
    ),
}


#: Where each format is described (the top-level help lists them).
WHERE = {
    "params": "flexdigit params --help",
    "calibration": "flexdigit calibrate --help",
    "protocol": "flexdigit collect --help",
    "dataset": "flexdigit dataset import --help",
    "tissue": "flexdigit palpate --help",
    "palpation": "flexdigit palpate --help",
    "spec": "flexdigit study --help",
    "robot": "flexdigit tdcr statics --help",
    "record": "flexdigit identify --help",
    "kept_design": "flexdigit design 20ms --help",
    "gauge_readings": "flexdigit tdcr shape --help",
}


def index() -> str:
    """The top-level help's list of the file formats and where each is described."""
    return "File formats, each described with an example in:\n\n" + "\n".join(
        f"  {FORMATS[name][0].split(' (')[0]:<34} {where}" for name, where in WHERE.items()
    )


def epilog(*names: str) -> str:
    """The help's closing section describing the formats ``names``, each with its example indented (kept as
    written by the command line's help formatter)."""
    parts = []
    for name in names:
        title, what, example = FORMATS[name]
        parts.append(f"File format: {title}. {what} For example:\n\n" + _indent(example))
    return "\n\n".join(parts)


def _indent(text: str) -> str:
    return "\n".join("    " + line if line else "" for line in text.rstrip("\n").splitlines())
