"""
A first step on the twin
========================

The digital twin of the thesis rig: an integer servo command goes in on the 20 ms serial frame, three gauge
voltages and the servo potentiometer come out through the sensor chain (bridge, amplifier, filter, 16-bit ADC,
seeded noise). Here the servo steps from rest to command 20 and the gauges follow the digit as it bends.
"""

import matplotlib.pyplot as plt
import numpy as np

from flexdigit.twin import Twin

twin = Twin(seed=1)  # calibrated to the thesis, upright (tip up)
twin.command(20)  # latched on the next serial frame
times_s = np.arange(1, 1501) / 1000  # 1.5 s read at 1 kHz
series = twin.read_at(times_s)  # the same numbers as advance + read, taken together
gauges_v, pot_v = series.gauges_v, series.pot_v

fig, ax = plt.subplots(figsize=(7, 4))
for k in range(3):
    ax.plot(times_s, gauges_v[:, k], label=f"gauge {k + 1}")
ax.plot(times_s, pot_v, "k--", label="servo pot")
ax.set_xlabel("time (s)")
ax.set_ylabel("voltage (V)")
ax.set_title("Command 0 -> 20 on the twin")
ax.legend()
fig.tight_layout()
print(f"gauges after 1.5 s: {np.round(gauges_v[-1], 3)} V")

plt.show()
