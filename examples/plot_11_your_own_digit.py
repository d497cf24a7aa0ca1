"""
Your own digit
==============

A digit is described in a parameter TOML (``flexdigit params --template mine.toml`` writes an annotated one):
here two 100 mm sections with a full-bridge gauge on each, instead of the thesis's three 80 mm sections and
three half bridges. :func:`flexdigit.twin.calibration_for` scales the thesis's calibration to it, so its twin
runs before anything is measured; the same servo step on both digits.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from flexdigit.params import RigParams, derived_figures, load_params
from flexdigit.twin import Twin, calibration_for

MINE = """
[geometry]
section_count = 2
section_length_m = 0.10
strip_length_m = 0.20
digit_length_m = 0.22
gauge_positions_m = [0.055, 0.165]

[sensors]
bridge = "full"
adc_channels = [0, 1]
"""
with tempfile.TemporaryDirectory() as folder:
    path = Path(folder) / "mine.toml"
    path.write_text(MINE)
    mine = load_params(path)  # checked: a wrong key or an inconsistent geometry is one line naming it
print({k: round(v, 4) for k, v in derived_figures(mine).items() if k.endswith("per_command")})

times_s = np.arange(1, 751) / 500
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.8))
for name, params in (("thesis digit", RigParams()), ("my digit", mine)):
    twin = Twin(params=params, calibration=calibration_for(params), seed=0)
    twin.command(20)
    series = twin.read_at(times_s)
    ax1.plot(times_s, 1e3 * series.tip_m[:, 1], label=name)
    for k in range(series.gauges_v.shape[1]):
        ax2.plot(times_s, series.gauges_v[:, k], label=f"{name}, gauge {k + 1}")
ax1.set_xlabel("time (s)")
ax1.set_ylabel("tip towards the cable (mm)")
ax1.legend()
ax2.set_xlabel("time (s)")
ax2.set_ylabel("gauge (V)")
ax2.legend(fontsize=7)
fig.suptitle("Command 0 -> 20 on two digits")
fig.tight_layout()

plt.show()
