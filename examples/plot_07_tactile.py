"""
Chapters 6-7: where does the weight hang?
=========================================

Chapter 6 hangs weights along the digit, reads the three gauges 25 times per setting and trains a NETLAB MLP
to say where the weight hangs. Here table 6.1's protocol is collected on the twin (cable detached, digit
horizontal), split 1/2-1/3-1/6 as the thesis did (6.6), and the thesis's network trained on the loaded
readings; predicted against actual positions on the test set.

The twin is opened as ``flexdigit collect --backend "sim?compiled=1"`` opens it: its digit stepped by the compiled
kernel, whose readings are the numpy twin's bit for bit (the ADC's 16-bit quantum is far coarser than where the
two differ) for about a fifth of the CPU.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from flexdigit.tactile import ThesisNetwork, collect_on, load_protocol, thesis_split

with tempfile.TemporaryDirectory() as folder:  # the twin set up for the protocol; written as Parquet
    dataset = collect_on("sim?compiled=1", load_protocol("thesis-6.1"), Path(folder) / "d6.parquet", seed=0)
columns = dataset.columns
loaded = columns["load_kg"] > 0
x = np.column_stack([columns[f"gauge{k}_v"] for k in (1, 2, 3)])[loaded]
y_m = columns["position_from_tip_m"][loaded]

split = thesis_split(len(y_m), seed=0)
network = ThesisNetwork(hidden=18, random_state=0)
network.fit(x[split.train], y_m[split.train], x[split.val], y_m[split.val])
predicted_m = network.predict(x[split.test])
error_mm = 1e3 * np.sqrt(np.mean((predicted_m - y_m[split.test]) ** 2))
corr2 = np.corrcoef(predicted_m, y_m[split.test])[0, 1] ** 2
print(f"{len(y_m)} loaded readings; test RMS error {error_mm:.1f} mm, corr2 {corr2:.3f} (thesis corr2 0.9823)")

fig, ax = plt.subplots(figsize=(5, 5))
ax.plot(1e3 * y_m[split.test], 1e3 * predicted_m, ".", alpha=0.5)
ax.plot([0, 270], [0, 270], "k--", lw=1)
ax.set_xlabel("actual position from the tip (mm)")
ax.set_ylabel("predicted (mm)")
ax.set_title(f"Chapter 6 on the twin: RMS {error_mm:.1f} mm")
fig.tight_layout()

plt.show()
