"""Tactile sensing (thesis chapters 6-7): protocols, datasets, estimators, metrics and the thesis pipeline."""
