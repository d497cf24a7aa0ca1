"""The surgeon's view: the live page and its server (thesis 1.1, 8)."""
