"""Debian's chromium as the live page's tests and benchmark drive it (Playwright, no browser download).

The flags are the ones that work on a machine with no network but the package registries: no sandbox (root in
CI), no GPU, and none of chromium's background traffic (which this machine refuses, many connections at a time).
"""

from __future__ import annotations

__all__ = ["CHROMIUM", "CHROMIUM_FLAGS", "launch"]

#: Debian's chromium (``apt-get install chromium``; ``make test`` installs it when missing).
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)


def launch(playwright):
    """A headless chromium from ``playwright.sync_api.sync_playwright()``, with a fresh profile of its own."""
    return playwright.chromium.launch(executable_path=CHROMIUM, headless=True, args=list(CHROMIUM_FLAGS))
