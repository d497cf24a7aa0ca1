"""
Chapter 3: identifying the servo from its step test
===================================================

The servo's step test (3.2.4: command 0 -> 51) recorded on the twin, then :func:`flexdigit.identify.identify`
finds the step itself and fits a second-order model to the whole record (robust least squares, with confidence
intervals). The thesis identified wn = 20.53 rad/s, zeta = 0.5629.
"""

import matplotlib.pyplot as plt

from flexdigit.identify import TimeSeries, identify
from flexdigit.twin import servo_step_test

record = servo_step_test(seed=0)
series = TimeSeries(
    t_s=record.column("time_s"),
    y=record.column("pot_v"),
    channel="pot",
    unit="V",
    source="twin",
    u=record.column("command"),
    input_name="command",
)
fit = identify(series, "step")
print(f"wn = {fit.wn_rad_s:.2f} rad/s, zeta = {fit.zeta:.3f}, corr2 = {fit.corr2:.4f} (thesis 20.53, 0.5629)")

fig, ax = plt.subplots(figsize=(7, 4))
ax.plot(series.t_s, series.y, ".", ms=2, color="0.6", label="record (twin)")
ax.plot(series.t_s, fit.predict(series.t_s), "C3", label=f"fit: wn {fit.wn_rad_s:.1f} rad/s, zeta {fit.zeta:.2f}")
ax.set_xlabel("time (s)")
ax.set_ylabel("servo pot (V)")
ax.set_title("Servo step test identified")
ax.legend()
fig.tight_layout()

plt.show()
