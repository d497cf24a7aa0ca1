"""
Chapter 4: the H-infinity design
================================

The thesis's H-infinity problem (4.4) with its 5 Hz tracking-error weight, solved by the Riccati route with the
regularisation that reproduces the printed controller. The closed loop's maps (4.5-4.6) show what it does:
``T_yw`` (setpoint to deflection) and the weighted error ``T_zw``.
"""

import control as ct
import matplotlib.pyplot as plt
import numpy as np

from flexdigit.control import loop_maps, thesis_design, thesis_plant

design = thesis_design(5.0)
print(f"gamma = {design.gamma:.4g} (optimum {design.gamma_opt:.4g}); controller order {design.controller.nstates}")
maps = loop_maps(thesis_plant(), design.controller)

w_rad_s = np.logspace(-1, 3, 300)
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.8))
for name in ("T_yw", "T_zw"):
    mag = np.squeeze(ct.frequency_response(getattr(maps, name), w_rad_s).magnitude)
    ax1.semilogx(w_rad_s, 20 * np.log10(mag), label=name)
ax1.set_xlabel("frequency (rad/s)")
ax1.set_ylabel("gain (dB)")
ax1.legend()
t_s = np.linspace(0, 1.0, 500)
step = ct.step_response(maps.T_yw, t_s)
ax2.plot(step.time, np.squeeze(step.outputs))
ax2.set_xlabel("time (s)")
ax2.set_ylabel("deflection per unit setpoint")
ax2.set_title("T_yw step")
fig.tight_layout()

plt.show()
