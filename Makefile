# flexdigit: `make run` reproduces the thesis on the twin; `make test` runs lint and the test suite (the docs build in it);
# `make docs` builds the documentation site (docs/_build/html, offline, warnings are errors); `make bench` runs the
# benchmarks and writes benchmarks/results.json, from which the site's benchmark page is generated; `make fuzz` runs
# the loader fuzz tests at 10,000 examples each (FUZZ_SEED=N for another seed). Each sets up .venv first when needed.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
BENCH_STAMP := $(VENV)/.installed-bench
PIP    := $(BIN)/python -m pip --disable-pip-version-check -q

# The live page's tests drive Debian's chromium (no browser download); installed here when missing (CI runs as root).
CHROMIUM := /usr/bin/chromium

# The 3D robot page draws with three.js from npm, vendored into the package data here (nothing from a CDN at run
# time); the file is built, not committed.
THREE_VERSION := 0.187.0
THREE_JS := src/flexdigit/live/static/vendor/three.module.js

.PHONY: setup run test lint docs bench fuzz clean browser avr firmware three

setup: $(STAMP) $(THREE_JS)

three: $(THREE_JS)

$(THREE_JS):
	@command -v npm >/dev/null || { echo "the 3D robot page needs npm to vendor three.js: apt-get install npm"; exit 1; }
	npm install --silent --no-save --no-audit --no-fund --prefix build/npm three@$(THREE_VERSION)
	mkdir -p $(dir $(THREE_JS))
	cp build/npm/node_modules/three/build/three.core.js $(dir $(THREE_JS))
	cp build/npm/node_modules/three/build/three.module.js $(THREE_JS)

$(STAMP): pyproject.toml constraints.txt
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11))' || { echo "flexdigit needs Python >= 3.11 (found: $$($(PYTHON) --version))"; exit 1; }
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV) || { \
	    echo "python venv module missing: installing python3-venv"; \
	    apt-get update -qq && apt-get install -y -qq python3-venv && $(PYTHON) -m venv $(VENV); }
	$(PIP) install -c constraints.txt -e '.[dev,docs]'
	@touch $(STAMP)

run: $(STAMP)
	$(BIN)/flexdigit reproduce --out report/ --force

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks docs examples
	$(BIN)/ruff format --check src tests benchmarks docs examples

# The suite runs on two pytest-xdist workers, each taking whole files (--dist loadfile: a module's set-up, a live
# server or a firmware image, is made once), the longest files first (tests/conftest.py). Measured on this 2-core
# machine: tests/live, rig and firmware (449 tests) 354 s in one process, 195 s on two workers; one process used
# 0.7-0.9 of one core (live servers, browsers, ptys and simavr wait on the wall clock), so a second worker all
# but halves the run. The site's build is not a step of its own: tests/test_docs.py runs the same command, offline,
# first, on one worker while the other runs the tests (before, `make docs` ran alone for a minute, one core idle).
# PYTEST_WORKERS=0: one process, as `pytest` alone runs. Every run ends with its 30 longest files
# (tests/conftest.py): where the suite's 15 minutes go, for LONGEST_S.
PYTEST_WORKERS ?= 2
PYTEST := $(BIN)/pytest -n $(PYTEST_WORKERS) --dist loadfile

# The numbers must not depend on the BLAS kernel (docs/guide/reliability.md, "Portable numbers"): the tests marked `blas` run again under
# OpenBLAS's own choice for this CPU (when the environment forces one) and under Nehalem (SSE only, what any x86-64
# runs; unless the suite just ran there). 33-35 s each in one process on an idle machine; on the two workers 30 and
# 35 s with other work loading the machine (load 4-5). pytest's header names the kernel in use.
BLAS_RUN := $(PYTEST) tests -m blas -p no:cacheprovider

# The site (Sphinx, numpydoc, myst, sphinx-gallery: every examples/plot_*.py runs in the build). Offline: no
# intersphinx, nothing fetched. -W --keep-going: every warning is reported, and any one fails the build.
# tests/test_docs.py runs the same command (incremental: nothing to redo right after this target); `make test` leaves
# the build to it.
SPHINXOPTS ?= -W --keep-going -q
docs: $(STAMP)
	$(BIN)/python -m sphinx -b html $(SPHINXOPTS) docs docs/_build/html
	@echo "the site: docs/_build/html/index.html"

test: lint browser three avr $(STAMP)
	$(PYTEST)
	@if [ -n "$$OPENBLAS_CORETYPE" ]; then echo "blas tests, OpenBLAS's own kernel (OPENBLAS_CORETYPE unset)"; \
	    env -u OPENBLAS_CORETYPE $(BLAS_RUN); fi
	@if [ "$$OPENBLAS_CORETYPE" != Nehalem ]; then echo "blas tests, OPENBLAS_CORETYPE=Nehalem"; \
	    OPENBLAS_CORETYPE=Nehalem $(BLAS_RUN); fi

# The reference firmware (issue 25): Debian's AVR toolchain and simavr, installed here when missing; and the host's
# C compiler, which builds the simavr harness and compiles the exported controller in its tests (a slim image has
# none: gcc-avr does not bring it).
AVR_PACKAGES := gcc-avr avr-libc binutils-avr simavr libsimavr-dev gcc libc6-dev
avr:
	@{ command -v avr-gcc >/dev/null && test -f /usr/lib/avr/include/avr/io.h && test -f /usr/include/simavr/sim_avr.h \
	    && command -v gcc >/dev/null && test -f /usr/include/stdio.h; } || { \
	    echo "the firmware and its HIL tests need Debian's $(AVR_PACKAGES): installing them"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $(AVR_PACKAGES) >/dev/null; } \
	    || { echo "could not install them: run 'apt-get install $(AVR_PACKAGES)' as root"; exit 1; }

firmware: $(STAMP) avr
	$(MAKE) -C firmware FLEXDIGIT=$(abspath $(BIN))/flexdigit

browser:
	@test -x $(CHROMIUM) || { \
	    echo "the live page's tests need Debian's chromium: installing it (apt-get install chromium)"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; } \
	    || { echo "could not install chromium: run 'apt-get install chromium' as root"; exit 1; }

$(BENCH_STAMP): $(STAMP)
	$(PIP) install -c constraints.txt -e '.[dev,docs,bench]'
	@touch $(BENCH_STAMP)

bench: $(BENCH_STAMP) browser avr
	$(BIN)/python -m benchmarks --out benchmarks/results.json --force

FUZZ_SEED ?= 0
fuzz: $(STAMP)
	HYPOTHESIS_PROFILE=fuzz $(BIN)/pytest tests/fuzz -q -p no:cacheprovider --hypothesis-seed=$(FUZZ_SEED)

clean:
	rm -rf $(VENV) report .pytest_cache .ruff_cache docs/_build docs/api/generated docs/auto_examples docs/_generated
