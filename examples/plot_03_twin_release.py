"""
Chapter 3: a release test on the twin
=====================================

The thesis identified the digit from release tests (3.1.2): deflect the tip, let go, record the gauges. The twin
runs the same experiment on its large-deflection model with the housing on; the free decay is the digit's first
bending mode.
"""

import matplotlib.pyplot as plt

from flexdigit.twin import release_test

record = release_test(housing=True, duration_s=3.0, sample_rate_hz=500.0, seed=0)
t_s = record.column("time_s")

fig, ax = plt.subplots(figsize=(7, 4))
for k in range(1, 4):
    ax.plot(t_s, record.column(f"gauge{k}_v"), label=f"gauge {k}")
ax.set_xlabel("time (s)")
ax.set_ylabel("voltage (V)")
ax.set_title("Release test, housed digit (thesis 3.1.2)")
ax.legend()
fig.tight_layout()
print(record.summary() if callable(getattr(record, "summary", None)) else record.metadata)

plt.show()
