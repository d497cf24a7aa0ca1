"""
Getting started in Python: the whole pipeline
=============================================

The thesis end to end in one script, as a notebook would run it: the twin, a step test identified, the
H-infinity design, the 20 ms loop, a tactile dataset, the thesis's network trained on it, and a contact read
from the gauges. Every name comes from a domain (``from flexdigit.<domain> import ...``).
"""

# %%
# The twin and a step test, identified
# ------------------------------------
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from flexdigit.control import thesis_design
from flexdigit.identify import TimeSeries, identify
from flexdigit.rig import make_controller, open_rig, run_loop
from flexdigit.tactile import ThesisNetwork, collect_on, load_protocol, thesis_split
from flexdigit.twin import Twin, servo_step_test

record = servo_step_test(seed=0)
pot = TimeSeries(t_s=record.column("time_s"), y=record.column("pot_v"), channel="pot", unit="V", source="twin")
servo = identify(pot, "step", input_step=51)
print(f"servo: wn {servo.wn_rad_s:.2f} rad/s, zeta {servo.zeta:.3f}")

# %%
# The H-infinity design of chapter 4
# ----------------------------------
design = thesis_design(5.0)
print(f"5 Hz design: gamma {design.gamma:.4g}, a controller of order {design.controller.nstates}")

# %%
# The 20 ms loop on the twin (chapter 5)
# --------------------------------------
with open_rig("sim?seed=0") as rig:
    loop = run_loop(rig, make_controller("digital20", rig), 20.0, 1.5)
print(loop.status, f"final rotation {loop.measurement[-1]:.1f} deg")

# %%
# A tactile dataset and the thesis's network (chapter 6)
# ------------------------------------------------------
# On the twin stepped by its compiled kernel (``sim?compiled=1``): the numpy twin's readings for less CPU.
with tempfile.TemporaryDirectory() as folder:
    dataset = collect_on("sim?compiled=1", load_protocol("thesis-6.1"), Path(folder) / "d6.parquet", seed=0)
c = dataset.columns
loaded = c["load_kg"] > 0
x = np.column_stack([c["gauge1_v"], c["gauge2_v"], c["gauge3_v"]])[loaded]
y_m = c["position_from_tip_m"][loaded]
split = thesis_split(len(y_m), seed=0)
net = ThesisNetwork(hidden=18, random_state=0).fit(x[split.train], y_m[split.train], x[split.val], y_m[split.val])
rms_mm = 1e3 * np.sqrt(np.mean((net.predict(x[split.test]) - y_m[split.test]) ** 2))
print(f"position RMS error on the test set: {rms_mm:.1f} mm")

# %%
# A contact, read back
# --------------------
# Hang 25 g 200 mm from the clamp of a horizontal twin without its cable (chapter 6's set-up) and ask the
# network where it is.
twin = Twin(seed=2, orientation="horizontal", cable=False)
twin.place_load(0.025, 0.20)
twin.advance(15.0)  # the digit rings for seconds after a weight is hung
gauges_v, _ = twin.read()
where_m = float(net.predict(np.asarray(gauges_v)[None, :])[0])
print(f"network: {1e3 * where_m:.0f} mm from the tip (true {1e3 * (0.27 - 0.20):.0f} mm)")

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.8))
ax1.plot(loop.time_s, loop.measurement, label="rotation (gauges)")
ax1.plot(loop.time_s, loop.setpoint, "k--", label="setpoint")
ax1.set_xlabel("time (s)")
ax1.set_ylabel("beam rotation (deg)")
ax1.legend()
ax2.plot(1e3 * y_m[split.test], 1e3 * net.predict(x[split.test]), ".", alpha=0.4)
ax2.plot(70, 1e3 * where_m, "r*", ms=14, label="the 25 g weight")
ax2.set_xlabel("actual (mm from tip)")
ax2.set_ylabel("predicted (mm)")
ax2.legend()
fig.tight_layout()

plt.show()
