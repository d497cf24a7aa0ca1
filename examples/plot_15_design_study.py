"""
A design study: where to put the gauges, which bridge, which servo
==================================================================

The thesis's first item of future work is a study of all system parameters. :func:`flexdigit.studies.run_design`
evaluates candidate digits (gauge count and layout, bridge, ADC bits, servo gearing, cable eccentricity, one cable
or the antagonistic pair, size), each with its own 20 ms controller, scores them on chapter 6's localisation
Bayes limit against the loop's settling time, and returns the Pareto front. A tiny sample here (12 designs, the
thesis design always among them); ``flexdigit study design thesis-design --out design/`` runs the full one.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from flexdigit.studies import DesignSettings, load_spec, run_design

spec = load_spec("thesis-design")
settings = DesignSettings(samples=12, bayes_samples=100)  # small: the shipped study samples 2916 designs
with tempfile.TemporaryDirectory() as folder:
    result = run_design(spec, Path(folder) / "design", settings=settings, workers=0, progress=False)

limit_mm = result.outputs["bayes_position_limit_mm"]
settling_s = result.outputs["settling_time_s"]
on_front = np.zeros(len(limit_mm), dtype=bool)
on_front[result.front] = True
for i in result.front:
    c = result.candidates[i]
    print(
        f"on the front: {c.gauge_count} gauges {c.layout}, {c.bridge} bridge, {c.adc_bits} bit: "
        f"{limit_mm[i]:.2f} mm, {settling_s[i]:.2f} s"
    )

fig, ax = plt.subplots(figsize=(6, 4.5))
ax.plot(settling_s[~on_front], limit_mm[~on_front], "o", color="0.6", label="design")
ax.plot(settling_s[on_front], limit_mm[on_front], "C3*", ms=12, label="Pareto front")
ax.set_xlabel("settling time of the 20 ms loop (s)")
ax.set_ylabel("localisation Bayes limit (mm)")
ax.set_yscale("log")
ax.set_title("12 sampled designs")
ax.legend()
fig.tight_layout()

plt.show()
