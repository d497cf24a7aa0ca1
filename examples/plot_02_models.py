"""
Chapter 3: the component models and the plant
=============================================

:func:`flexdigit.models.build_plant` assembles the thesis's plant G(s) (servo command to gauge-1 deflection)
from its component models: ``"printed"`` reproduces the thesis's printed G(s), unit slips included;
``"consistent"`` is the unit-correct chain command -> servo -> cable -> moment -> curvature -> deflection.
Their frequency responses side by side show where the printed one departs.
"""

import matplotlib.pyplot as plt
import numpy as np

from flexdigit.models import build_plant

w_rad_s = np.logspace(-1, 3, 400)
fig, ax = plt.subplots(figsize=(7, 4))
for variant in ("printed", "consistent"):
    plant = build_plant(variant)
    num, den = plant.poly.num, plant.poly.den
    response = np.polyval(num, 1j * w_rad_s) / np.polyval(den, 1j * w_rad_s)
    ax.loglog(w_rad_s, np.abs(response), label=variant)
    print(f"{variant}: DC gain {abs(response[0]):.3g} m per command, poles {np.round(np.roots(den), 2)}")
ax.set_xlabel("frequency (rad/s)")
ax.set_ylabel("|G(jw)| (m per command)")
ax.set_title("The plant G(s), printed and unit-consistent")
ax.legend()
fig.tight_layout()

plt.show()
