"""A real ``flexdigit live`` server in a subprocess, and Debian's chromium driven by Playwright (no browser download).

The Makefile installs chromium when it is missing (``make test``); without it the browser tests fail, saying so.
"""

from __future__ import annotations

import os

import pytest

from flexdigit.live.browser import CHROMIUM, launch

from .live_helpers import LiveServer


@pytest.fixture
def live_server(tmp_path):
    servers = []

    def start(*args: str, port: int = 0) -> LiveServer:
        server = LiveServer(tmp_path, *args, port=port)
        servers.append(server)
        return server

    yield start
    for server in servers:
        if server.proc.poll() is None:
            server.proc.kill()
            server.proc.wait()


@pytest.fixture(scope="module")
def browser():
    if not os.path.exists(CHROMIUM):
        pytest.fail(f"{CHROMIUM} is missing: `make test` installs Debian's chromium (apt-get install chromium)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        browser = launch(pw)
        yield browser
        browser.close()


@pytest.fixture
def page(browser):
    context = browser.new_context(viewport={"width": 1280, "height": 900})
    page = context.new_page()
    page.console_errors = []
    page.on("console", lambda m: page.console_errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: page.console_errors.append(str(e)))
    yield page
    context.close()
