"""The Rig interface and its backends (sim, serial, daq, replay) and the real-time loop (thesis chapter 5)."""
