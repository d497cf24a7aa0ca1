"""
Your own data: tactile readings from another rig
================================================

Readings taken elsewhere come with their own column names, units and separators. A
:class:`flexdigit.tactile.ColumnMap` says which column is what, :func:`flexdigit.tactile.import_readings` turns
the file into a dataset that every estimator takes. Here the file is made from the twin's closed-form statics in
another lab's layout (``;``-separated, decimal commas, millivolts, grams, millimetres from the clamp), then the
thesis's network is trained on it.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from flexdigit.tactile import ColumnMap, ThesisNetwork, import_readings, thesis_split
from flexdigit.twin import static_gauges_v

rng = np.random.default_rng(0)
masses_g = rng.choice([12.5, 25.0, 37.5], size=400)
positions_mm = rng.choice(np.arange(100.0, 271.0, 10.0), size=400)
gauges_v = static_gauges_v(masses_g / 1e3, positions_mm / 1e3) + rng.normal(0.0, 0.002, size=(400, 3))

lines = ['"SG1 [mV]";"SG2 [mV]";"SG3 [mV]";"mass (g)";"x (mm)"']
for v, m, x in zip(1e3 * gauges_v, masses_g, positions_mm, strict=True):
    lines.append(";".join(f"{value:.3f}".replace(".", ",") for value in (*v, m, x)))

column_map = ColumnMap(
    gauges=("SG1 [mV]", "SG2 [mV]", "SG3 [mV]"),
    gauge_unit="mV",
    load="mass (g)",
    load_unit="g",
    position="x (mm)",
    position_unit="mm",
    position_from="clamp",
    decimal=",",
)
with tempfile.TemporaryDirectory() as folder:
    path = Path(folder) / "readings.csv"
    path.write_text("\n".join(lines) + "\n")
    dataset = import_readings(path, column_map)
c = dataset.columns
x = np.column_stack([c["gauge1_v"], c["gauge2_v"], c["gauge3_v"]])
y_m = c["position_from_base_m"]
split = thesis_split(len(y_m), seed=0)
net = ThesisNetwork(hidden=10, random_state=0).fit(x[split.train], y_m[split.train], x[split.val], y_m[split.val])
predicted_m = net.predict(x[split.test])
rms_mm = 1e3 * np.sqrt(np.mean((predicted_m - y_m[split.test]) ** 2))
print(f"{len(y_m)} readings imported; position RMS error {rms_mm:.1f} mm on the test set")

fig, ax = plt.subplots(figsize=(5, 5))
ax.plot(1e3 * y_m[split.test], 1e3 * predicted_m, ".", alpha=0.6)
ax.plot([100, 270], [100, 270], "k--", lw=1)
ax.set_xlabel("actual position from the clamp (mm)")
ax.set_ylabel("predicted (mm)")
ax.set_title(f"Imported readings: RMS {rms_mm:.1f} mm")
fig.tight_layout()

plt.show()
