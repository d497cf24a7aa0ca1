"""The rig (thesis chapter 5): the Rig contract, the real-time loop, its log, safety; the backends in ``backends/``."""
