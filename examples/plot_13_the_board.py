"""
The controller on the board: C export and its analysis
======================================================

The thesis's loop failed because a PC could not keep a 20 ms serial period; it belongs on the microcontroller that
reads the gauges. :func:`flexdigit.control.export_controller` writes the 20 ms design as one C99 file and header
(no heap, no libm; float32 or fixed point) and analyses what the number format does to it. Here both formats
are exported and compared with the exact controller: poles, margins and the worst command error. (Building the
firmware and running it on simavr is ``make firmware`` and ``flexdigit run --backend hil://...``.)
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from flexdigit.control import ControllerSpec, design_20ms, export_controller
from flexdigit.params import RigParams

params = RigParams()
design = design_20ms(params, period_s=0.02)
spec = ControllerSpec.from_runtime(design.runtime(params))

results = {}
with tempfile.TemporaryDirectory() as folder:
    for fmt in ("float", "fixed"):
        result = export_controller(spec, Path(folder) / f"ctrl_{fmt}.c", format=fmt, plant_d=design.plant_d)
        results[fmt] = result.analysis
        lines = result.source_path.read_text().count("\n")
        a = result.analysis
        print(
            f"{fmt}: {lines} lines of C; margins {a.gain_margin_db:.1f} dB / {a.phase_margin_deg:.1f} deg "
            f"(exact {a.gain_margin_db_exact:.1f} / {a.phase_margin_deg_exact:.1f}); "
            f"command error <= {a.command_error_bound:.2g} commands"
        )

fig, ax = plt.subplots(figsize=(5, 5))
circle = np.exp(1j * np.linspace(0, 2 * np.pi, 200))
ax.plot(circle.real, circle.imag, "k:", lw=1)
exact = results["float"].poles_exact
ax.plot(exact.real, exact.imag, "ko", mfc="none", ms=10, label="controller poles, exact")
for fmt, marker in (("float", "x"), ("fixed", "+")):
    poles = results[fmt].poles_quantised
    ax.plot(poles.real, poles.imag, marker, ms=9, label=f"as exported ({fmt})")
ax.set_aspect("equal")
ax.set_xlabel("Re z")
ax.set_ylabel("Im z")
ax.set_title("digital20 at 20 ms, exported to C")
ax.legend(fontsize=8)
fig.tight_layout()

plt.show()
