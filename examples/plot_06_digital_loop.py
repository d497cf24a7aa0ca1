"""
Chapter 5: the digital loop at 20 ms on the twin
================================================

The thesis's rig failed at the 20 ms period its serial board imposed. flexdigit's ``digital20`` controller is
designed for that period (hold, one sample of delay, integer commands) and closed here on the twin through the
same :func:`flexdigit.rig.run_loop` a real rig uses: a 30 deg step of the beam rotation the gauges estimate.
"""

import matplotlib.pyplot as plt

from flexdigit.rig import make_controller, open_rig, run_loop

with open_rig("sim?seed=0") as rig:
    controller = make_controller("digital20", rig)
    result = run_loop(rig, controller, 30.0, 2.0)
print(result.status, result.message)

fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
ax1.plot(result.time_s, result.setpoint, "k--", label="setpoint")
ax1.plot(result.time_s, result.measurement, label="rotation from the gauges")
ax1.set_ylabel("beam rotation (deg)")
ax1.legend()
ax2.step(result.time_s, result.command, where="post")
ax2.set_xlabel("time (s)")
ax2.set_ylabel("servo command")
fig.suptitle("digital20 on the twin, 20 ms period")
fig.tight_layout()

plt.show()
