"""Control (thesis chapters 4-5): generalized plant, H-infinity synthesis, analysis, discretisation, runtime."""
