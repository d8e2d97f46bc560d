# The two entry points of the README.  Both create .venv and install the package on first use:
# `make run` installs only what running needs; `make test` adds the test extras (pytest,
# hypothesis, compliance-checker with pyproj/shapely/lxml) on top, once.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
TEST_STAMP := $(VENV)/.installed-test

.PHONY: run test test-fast test-tools clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip >/dev/null
	$(BIN)/python -m pip install -e .
	touch $(STAMP)

$(TEST_STAMP): $(STAMP) pyproject.toml
	$(BIN)/python -m pip install -e '.[test]'
	touch $(TEST_STAMP)

run: $(STAMP)
	$(BIN)/screening run studies/quick.toml

# ncdump (Debian netcdf-bin) for the `ncdump -h` test: installed when we are root with apt-get
# (as on CI; said before it is done), otherwise that one test is skipped with a note.
test-tools:
	@command -v ncdump >/dev/null 2>&1 || { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1 && \
	  echo "note: installing ncdump (Debian package netcdf-bin) with apt-get for the ncdump test" && \
	  apt-get update -qq >/dev/null 2>&1 && apt-get install -y -qq netcdf-bin >/dev/null 2>&1; } || \
	  echo "note: ncdump (Debian package netcdf-bin) is not installed: tests/test_netcdf_cf.py::test_ncdump_header_reads will be skipped"

test: $(TEST_STAMP) test-tools
	$(BIN)/python -m pytest

test-fast: $(TEST_STAMP)
	$(BIN)/python -m pytest -m "not slow"

clean:
	rm -rf $(VENV) .pytest_cache

# `make docs`: the documentation site (docs/*.md and the API pages from the docstrings) into site/,
# warnings as errors; the docs extras are installed once.
.PHONY: docs
DOCS_STAMP := $(VENV)/.installed-docs

$(DOCS_STAMP): $(STAMP) pyproject.toml
	$(BIN)/python -m pip install -q -e '.[docs]'
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	$(BIN)/python -m mkdocs build --strict
