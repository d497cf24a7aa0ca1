"""The benchmarks behind the site's benchmark page: ``make bench`` runs ``python -m benchmarks``; never in the tests."""
