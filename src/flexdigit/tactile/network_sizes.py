"""The thesis network's plausible sizes (6.3) and how long ``train`` trains it: declared once, apart from
:mod:`~flexdigit.tactile.netlab` so that the command line declares its ``train`` flags with them without importing
scikit-learn."""

from __future__ import annotations

from flexdigit._validation import Plausible

#: Hidden nodes of the thesis's two-layer network: it swept 1 to 40; 10,000 bounds the memory and the time.
HIDDEN = Plausible("", 1, 10_000, "hidden nodes: the thesis swept 1 to 40", integer=True)
#: The SCG stopping tolerance (the thesis's "learning gradient", 1e-7 to 1e-1): below 1e-15 it never stops on
#: float64 round-off, above 1 it stops at once.
TOL = Plausible("", 1e-15, 1.0, "the SCG tolerance ('learning gradient'): the thesis swept 1e-7 to 1e-1")

#: Epochs of the size and tolerance sweep, each 50 SCG iterations (``iterations_per_epoch``), the network kept at
#: its best validation epoch: the thesis trained 50.
EPOCHS = Plausible("", 1, 10_000, "epochs of 50 SCG iterations: the thesis trained 50", integer=True)
#: ``train``'s chosen network size is trained again with doubled epochs up to this many
#: (:func:`flexdigit.tactile.localisation.train_network`) ...
EPOCHS_MAX = 800
#: ... and a longer training kept where it lowers the validation MSE by more than this fraction
LONGER_GAIN = 0.02
