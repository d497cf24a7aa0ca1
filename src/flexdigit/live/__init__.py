"""The surgeon's view: the live page and its server, and the ``shape`` command (thesis 1.1, 8)."""
