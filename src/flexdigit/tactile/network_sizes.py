"""The thesis network's plausible sizes (6.3): declared once, apart from :mod:`~flexdigit.tactile.netlab` so that
the command line declares its ``train`` flags with them without importing scikit-learn."""

from __future__ import annotations

from flexdigit._validation import Plausible

#: Hidden nodes of the thesis's two-layer network: it swept 1 to 40; 10,000 bounds the memory and the time.
HIDDEN = Plausible("", 1, 10_000, "hidden nodes: the thesis swept 1 to 40", integer=True)
#: The SCG stopping tolerance (the thesis's "learning gradient", 1e-7 to 1e-1): below 1e-15 it never stops on
#: float64 round-off, above 1 it stops at once.
TOL = Plausible("", 1e-15, 1.0, "the SCG tolerance ('learning gradient'): the thesis swept 1e-7 to 1e-1")
