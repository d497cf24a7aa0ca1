"""Component models of the rig (thesis chapter 3): bridge/amplifier/ADC, beam, digit, motor, servo, cable,
conversion coefficients, and the plant G(s) assembled from them."""
