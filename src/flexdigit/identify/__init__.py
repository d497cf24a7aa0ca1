"""System identification (thesis 3.1.2, 3.2.4, 3.4): response analysis, fits, filters, validation."""
