"""Benchmarks quoted in the README: ``make bench`` runs ``python -m benchmarks``; never part of the tests."""
