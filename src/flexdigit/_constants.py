"""Physical constants flexdigit uses, each defined once (docs/conventions.md: one definition of a physical constant).

A shared leaf module: every domain may import it, it imports nothing of flexdigit.
"""

from __future__ import annotations

__all__ = ["G_STANDARD_M_S2"]

#: Standard acceleration of gravity, m/s^2 (exact by definition: 3rd CGPM, 1901; ISO 80000-3). The rig's weights
#: are given in grams and turned into newtons with it (thesis 6.1's loads; the twin's and the shape estimator's
#: self-weight).
G_STANDARD_M_S2 = 9.80665
