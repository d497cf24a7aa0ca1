"""The digital twin: a calibrated large-deflection simulator of the whole rig (digit, servo, sensors)."""
