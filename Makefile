# clik: the two commands of the README, and a few more.
#   make demo   creates .venv, installs clik, runs the case study (out/demo)
#   make test   creates .venv with the test extras, runs every test and notebook
#   make lint   ruff (style, docstrings) and mypy (types) on clik/

PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
PIP    := $(PY) -m pip --disable-pip-version-check
NOTEBOOKS := $(wildcard notebooks/*.ipynb)
ENGINE  := $(shell find src/engine -type f)
# The engine's build requirements, read from pyproject.toml (one list): installed into
# the venv first, so that pip builds without isolation and rebuilds incrementally (build/).
BUILD_REQUIRES = $(shell $(PY) -c "import tomllib; print(' '.join(repr(r) for r in tomllib.load(open('pyproject.toml', 'rb'))['build-system']['requires']))")

.PHONY: demo test lint bench clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PIP) install --quiet --upgrade pip

$(VENV)/.build-requires: $(PY) pyproject.toml
	@command -v c++ >/dev/null 2>&1 || { echo "clik compiles its engine (C++17): no C++ compiler found; install one (Debian/Ubuntu: sudo apt-get install g++)" >&2; exit 1; }
	@echo "installing the engine's build requirements into $(VENV): $(BUILD_REQUIRES) cmake ninja"
	$(PIP) install --progress-bar on $(BUILD_REQUIRES) cmake ninja
	touch $@

$(VENV)/.installed: $(VENV)/.build-requires pyproject.toml $(ENGINE)
	@echo "installing clik and its dependencies (Pinocchio, coal, meshcat, Dask...) into $(VENV), compiling its engine (a few minutes the first time)"
	$(PIP) install --progress-bar on --no-build-isolation -e .
	touch $@

$(VENV)/.installed-test: $(VENV)/.build-requires pyproject.toml $(ENGINE)
	@echo "installing clik with its test, notebook, benchmark and lint extras into $(VENV), compiling its engine (a few minutes the first time)"
	$(PIP) install --progress-bar on --no-build-isolation -e ".[test,notebooks,bench,lint]"
	touch $@ $(VENV)/.installed

demo: $(VENV)/.installed
	$(VENV)/bin/clik demo --out out/demo --force

test: $(VENV)/.installed-test
	$(PY) -m pytest tests $(if $(NOTEBOOKS),--nbmake --nbmake-timeout=120 $(NOTEBOOKS)) --timeout=600 -q

lint: $(VENV)/.installed-test
	$(VENV)/bin/ruff check clik tests
	$(VENV)/bin/ruff format --check clik tests
	$(VENV)/bin/mypy

bench: $(VENV)/.installed
	$(PIP) install --quiet -e ".[bench]"
	$(VENV)/bin/clik bench --out out/bench

clean:
	rm -rf out .pytest_cache build
