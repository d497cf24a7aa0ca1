"""
Beyond the thesis: palpating a tissue's stiffness
=================================================

The thesis's conclusion asks for "low frequency palpations" and "variability in tissue stiffness". Here the digit
presses a soft block placed beside it on the twin: a staircase of commands, the plateaus' gauges read, then the
tissue's gap and modulus fitted by maximum likelihood through the digit's contact statics. The force-indentation
curve comes from the gauges alone; the twin's true contact force is drawn beside it.
"""

import matplotlib.pyplot as plt
import numpy as np

from flexdigit.palpation import ContactGaugeModel, analyse, load_palpation_protocol, load_tissue, simulate_sweep

tissue, _ = load_tissue("soft-block")  # placed on the twin: 30 mm away, modulus 1000 N/m^2
protocol = load_palpation_protocol("sweep").sweep
model = ContactGaugeModel()
record = simulate_sweep(model, tissue, protocol, seed=0)  # the twin's statics with its noise and drift
result = analyse(record, tissue, protocol, model)
fit = result.fit
print(
    f"modulus {fit.modulus_n_m2:.0f} +- {fit.modulus_sd_n_m2:.0f} N/m^2 (true {tissue.modulus_n_m2:.0f}); "
    f"gap {1e3 * fit.gap_m:.2f} mm (true {1e3 * tissue.gap_m:.0f})"
)

curve = {key: np.asarray(value) for key, value in result.curve.items()}
touching = curve["indentation_m"] > 0  # the plateaus before contact say nothing about the tissue
depth_mm = 1e3 * curve["indentation_m"][touching]
fig, ax = plt.subplots(figsize=(6, 4))
ax.errorbar(depth_mm, curve["force_n"][touching], yerr=curve["force_sd_n"][touching], fmt=".", label="from the gauges")
ax.plot(depth_mm, curve["model_force_n"][touching], "-", label="fitted tissue")
if "true_force_n" in curve:
    ax.plot(depth_mm, curve["true_force_n"][touching], "k+", label="twin's true force")
ax.set_xlabel("indentation (mm)")
ax.set_ylabel("contact force (N)")
ax.set_title(f"Soft block: {fit.modulus_n_m2:.0f} N/m^2 fitted")
ax.legend()
fig.tight_layout()

plt.show()
