# clik: the two commands of the README, and a few more.
#   make demo   creates .venv, installs clik, runs the case study (out/demo)
#   make test   creates .venv with the test extras, runs every test and notebook
#   make lint   ruff (style, docstrings) and mypy (types) on clik/

PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
PIP    := $(PY) -m pip --disable-pip-version-check
NOTEBOOKS := $(wildcard notebooks/*.ipynb)

.PHONY: demo test lint bench clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PIP) install --quiet --upgrade pip

$(VENV)/.installed: $(PY) pyproject.toml
	@echo "installing clik and its dependencies (Pinocchio, coal, meshcat, Dask...) into $(VENV)"
	$(PIP) install --progress-bar on -e .
	touch $@

$(VENV)/.installed-test: $(PY) pyproject.toml
	@echo "installing clik with its test, notebook, benchmark and lint extras into $(VENV)"
	$(PIP) install --progress-bar on -e ".[test,notebooks,bench,lint]"
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
	rm -rf out .pytest_cache
