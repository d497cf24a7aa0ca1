"""Tactile sensing (thesis chapters 6-7): the thesis's load localisation: protocols, datasets, estimators, accuracy."""
