# The two entry points of the README.  Both create .venv and install the package on first use:
# `make run` installs only what running needs; `make test` adds the test extras (pytest,
# hypothesis, compliance-checker with pyproj/shapely/lxml) and the cluster extra (dask-jobqueue, whose
# local cluster the slow tests of workers that come and go run on) on top, once.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
TEST_STAMP := $(VENV)/.installed-test
ENGINES := .venv-engines
ENGINES_STAMP := $(ENGINES)/.installed

.PHONY: run test test-quick test-slow test-portable engines clean

# setuptools says "Editable installation ... be careful with folders named like the package" on every
# editable install: information for packagers, noise for a user; silenced by its message, nothing else.
PIP_INSTALL := PYTHONWARNINGS="ignore:Editable installation" $(BIN)/python -m pip install -q

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(PIP_INSTALL) -e .
	touch $(STAMP)

$(TEST_STAMP): $(STAMP) pyproject.toml
	$(PIP_INSTALL) -e '.[test,cluster]'
	touch $(TEST_STAMP)

run: $(STAMP)
	$(BIN)/screening run studies/quick.toml

# `make test`: the suite a user runs in minutes (tests that need ncdump, CDO or NCO skip with a note
# when the tool is absent; no test target installs system packages).  `make test-slow`: the
# statistical and long-running tests (marked `slow`); CI runs both.
test: $(TEST_STAMP)
	$(BIN)/python -m pytest -m "not slow" --durations=10

# `make test-quick`: the unit tests (tests/unit, one folder per package folder) and the fast verification
# tables, for the edit-test loop, on every core (pytest-xdist); the README states its measured duration.
test-quick: $(TEST_STAMP)
	$(BIN)/python -m pytest tests/unit tests/verification -m "not slow" -q -n auto

test-slow: $(TEST_STAMP) $(ENGINES_STAMP)
	SCREENING_ENGINES_PYTHON=$(ENGINES)/bin/python $(BIN)/python -m pytest -m slow --durations=10

# `make engines`: pelicun and OpenQuake's NRML reader in their own environment .venv-engines (pelicun pins
# scipy<1.16 and pandas<3, below screening's pins; openquake-engine's GDAL pins need the GDAL C library,
# which its NRML reader does not use, so the engine goes in with --no-deps and the reader's imports from
# tests/engines/requirements.txt).  tests/integration/test_engine_exports.py loads the exports there.
engines: $(ENGINES_STAMP)

$(ENGINES_STAMP): tests/engines/requirements.txt
	$(PYTHON) -m venv $(ENGINES)
	$(ENGINES)/bin/python -m pip install -q -r tests/engines/requirements.txt
	$(ENGINES)/bin/python -m pip install -q --no-deps openquake-engine==3.26.2
	touch $(ENGINES_STAMP)

# `make test-portable`: the suite as another machine runs it: kernels compiled for a generic x86-64 CPU (no
# AVX, no FMA: other rounding, other adaptive steps) on one thread, in a cache of their own.  A test that
# passes here and with `make test` holds its numbers to the computation's accuracy, not to this machine's
# digits.  The cache starts empty each time (the package's stale-cache
# check looks only at its own __pycache__), so the first minutes compile.  PORTABLE_TESTS narrows it (CI: the
# unit tests and the stored numbers, where a machine's digits would show).
PORTABLE_TESTS ?=
test-portable: $(TEST_STAMP)
	rm -rf $(VENV)/numba-generic
	NUMBA_CPU_NAME=generic NUMBA_NUM_THREADS=1 NUMBA_CACHE_DIR=$(VENV)/numba-generic \
		$(BIN)/python -m pytest -m "not slow" -q -p no:cacheprovider $(PORTABLE_TESTS)

clean:
	rm -rf $(VENV) $(ENGINES) .pytest_cache

# `make docs`: the documentation site (docs/*.md and the API pages from the docstrings) into site/,
# warnings as errors; the docs extras are installed once.
.PHONY: docs
DOCS_STAMP := $(VENV)/.installed-docs

$(DOCS_STAMP): $(STAMP) pyproject.toml
	$(PIP_INSTALL) -e '.[docs]'
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	$(BIN)/python -m mkdocs build --strict
