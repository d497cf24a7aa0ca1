"""A closed-form cantilever rig for the tactile, palpation and CLI tests, independent of the twin.

Strain at gauge i from a point load m at a (from the base) is proportional to the bending moment there,
m g (a - x_i) for a > x_i and 0 otherwise (Euler-Bernoulli cantilever); plus seeded white noise. A helper module
(not a conftest), so that every test folder can use it.
"""

from __future__ import annotations

import numpy as np

from flexdigit.rig.base import Rig
from flexdigit.tactile.protocols import Protocol
from oracles import cantilever_gauges_v

NOISE_V = 0.002
#: The tactile command-line tests' dataset on this rig: 2 loads at 6 positions (a tip's 10 cm), 10 repetitions and
#: 10 no-load readings (240 readings; every position bends gauges 1 and 2).
SMALL_PROTOCOL = Protocol(
    "small",
    loads_kg=(0.0125, 0.025),
    positions_from_tip_m=(0.0, 0.02, 0.04, 0.06, 0.08, 0.10),
    repetitions=10,
    no_load_repetitions=10,
)


class CantileverRig(Rig):
    """A Rig on the closed-form model, with a virtual clock and an optional failure after N reads."""

    name = "cantilever"

    def __init__(self, seed=0, fail_after=None, error=KeyboardInterrupt):
        self._t = 0.0
        super().__init__(clock=lambda: self._t, sleep=self._advance, operator=lambda msg: None)
        self.rng = np.random.default_rng(seed)
        self.fail_after = fail_after
        self.error = error
        self.reads = 0
        self.url = "cantilever"

    def _advance(self, s):
        self._t += s

    def _read(self):
        if self.fail_after is not None and self.reads >= self.fail_after:
            raise self.error()
        self.reads += 1
        self._t += 0.01
        v = np.zeros(3)
        for mass, pos in self.loads:
            v = v + cantilever_gauges_v(pos, mass)[0]
        return v + NOISE_V * self.rng.standard_normal(3), 1.0

    def _send(self, command):
        pass

    def _apply_load(self, mass_kg, position_from_base_m):
        pass

    def _remove_loads(self):
        pass
