"""
Beyond the thesis: the digit's shape from its three gauges
==========================================================

The thesis promises the surgeon "a sense of feeling and shape". :class:`flexdigit.shape.ShapeEstimator` turns one
reading of the three gauges (and the command) into the centre line with its two-standard-deviation band; the
twin's own tip is marked beside it.
"""

import matplotlib.pyplot as plt
import numpy as np

from flexdigit.shape import ShapeEstimator
from flexdigit.twin import static_gauges_v

commands = [10, 25, 40]
gauges_v, truth = static_gauges_v([0.0] * 3, [0.0] * 3, commands, orientation="vertical", return_solution=True)
estimate = ShapeEstimator().estimate(gauges_v, command=np.array(commands))

fig, ax = plt.subplots(figsize=(5, 5))
for i, command in enumerate(commands):
    along_mm, across_mm = 1e3 * estimate.centre_line_m[i].T
    band_mm = 2e3 * estimate.sd_normal_m[i]
    ax.plot(across_mm, along_mm, f"C{i}", label=f"estimate, command {command}")
    ax.fill_betweenx(along_mm, across_mm - band_mm, across_mm + band_mm, color=f"C{i}", alpha=0.2)
    ax.plot(1e3 * truth.tip_m[i, 1], 1e3 * truth.tip_m[i, 0], f"C{i}x", ms=10)
    error_mm = 1e3 * np.hypot(*(estimate.centre_line_m[i, -1] - truth.tip_m[i]))
    print(f"command {command}: tip off the twin's by {error_mm:.2f} mm")
ax.set_aspect("equal")
ax.set_xlabel("towards the cable (mm)")
ax.set_ylabel("along the digit (mm)")
ax.set_title("Shape from the gauges, 2 sd band (x: the twin's tip)")
ax.legend(fontsize=8)
fig.tight_layout()

plt.show()
