"""
A tendon-driven continuum robot in 3D
=====================================

Beyond the planar digit: :mod:`flexdigit.tdcr` models tendon-driven continuum robots as Cosserat rods with
tendons. ``rao2021`` is the benchmark robot of Rao et al. (2021); pulling one tendon of each segment bends it
out of plane, and :func:`flexdigit.tdcr.solve_statics` gives its backbone.
"""

import matplotlib.pyplot as plt
import numpy as np

from flexdigit.tdcr import ROBOTS, solve_statics

robot = ROBOTS["rao2021"]
fig = plt.figure(figsize=(6, 6))
ax = fig.add_subplot(projection="3d")
for pull_n in (0.0, 1.0, 2.0, 3.0):
    tensions_n = np.zeros(6)
    tensions_n[0] = pull_n  # a tendon of the first segment
    tensions_n[4] = pull_n / 2  # and one of the second, on another side
    solution = solve_statics(robot, tensions_n)
    x, y, z = solution.positions_m.T
    ax.plot(x, y, z, label=f"{pull_n:.0f} N / {pull_n / 2:.1f} N")
    print(f"{pull_n:.0f} N: tip at {np.round(solution.tip_position_m, 4)} m, converged {solution.converged}")
ax.set_xlabel("x (m)")
ax.set_ylabel("y (m)")
ax.set_zlabel("z (m)")
ax.set_title("rao2021 under tendon tension")
ax.legend(fontsize=8)
fig.tight_layout()

plt.show()
