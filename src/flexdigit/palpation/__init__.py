"""Palpation beyond the thesis (chapter 8): contact from the gauges, tissue stiffness, force control, active sensing.

- :mod:`~flexdigit.palpation.contact_estimation`: contact yes / no, where, how hard, point or distributed;
- :mod:`~flexdigit.palpation.palpation`: sweeps into tissue, the stiffness fit and its bound, scans for an inclusion;
- :mod:`~flexdigit.palpation.palpation_files`: tissue and palpation-protocol files (built-ins in ``palpation_data/``);
- :mod:`~flexdigit.palpation.active`: active sensing (hangs at several commands);
- :mod:`~flexdigit.palpation.palpation_studies`: the studies report chapter 8 shows.

Above tactile in the import chain (it uses tactile's bounds); only the report and the CLI import it.
"""
