# clik: the two commands of the README, and a few more.
#   make demo   creates .venv, installs clik, runs the case study (out/demo)
#   make test   creates .venv with the test extras, runs every test and notebook
#   make lint   ruff (style, docstrings) and mypy (types) on clik/
#   make sanitize  the engine built with AddressSanitizer and UBSan (.venv-sanitize,
#               build/sanitize), the engine's tests run under it; fails on any report

PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
PIP    := $(PY) -m pip --disable-pip-version-check
NOTEBOOKS := $(wildcard notebooks/*.ipynb)
ENGINE  := $(shell find src/engine -type f)
# The engine's build requirements, read from pyproject.toml (one list): installed into
# the venv first, so that pip builds without isolation and rebuilds incrementally (build/).
BUILD_REQUIRES = $(shell $(PY) -c "import tomllib; print(' '.join(repr(r) for r in tomllib.load(open('pyproject.toml', 'rb'))['build-system']['requires']))")

.PHONY: demo test lint bench sanitize clean

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

# -- make sanitize ---------------------------------------------------------------------
# The engine compiled with ASan and UBSan (float-cast-overflow included: GCC's
# -fsanitize=undefined leaves it out), symbols kept (RelWithDebInfo, not stripped), with
# the wheels' allocation settings (EIGEN_MALLOC_ALREADY_ALIGNED: pinocchio::Data is
# allocated in the wheel's library and freed in the engine), into its own venv and build
# folder; then the engine, constraint, solve, status, property, zoo and boundary tests
# run under it. Reports go to files (pytest holds fd 2); any report fails the target.
# Memory-budget and browser tests stay in `make test` (ASan's RSS; Chromium does not
# start under the preload). See ../shared/NOTES.md, "Sanitizer builds of the engine".
SAN_VENV  := .venv-sanitize
SAN_PY    := $(SAN_VENV)/bin/python
SAN_PIP   := $(SAN_PY) -m pip --disable-pip-version-check
SAN_LOG   := build/sanitize-logs
SAN_FLAGS := -fsanitize=address,undefined -fsanitize=float-cast-overflow -fno-omit-frame-pointer -g -O1 -DEIGEN_MALLOC_ALREADY_ALIGNED=1
SAN_TESTS := tests/loop tests/constraints tests/solving tests/tasks \
             tests/robustness/test_zoo.py tests/robustness/test_bad_input.py \
             tests/robustness/test_hardened_numbers.py $(wildcard tests/robustness/test_*boundary*.py) \
             $(wildcard tests/robustness/test_*fuzz*.py) $(wildcard tests/robustness/test_threads*.py)

$(SAN_PY):
	$(PYTHON) -m venv $(SAN_VENV)
	$(SAN_PIP) install --quiet --upgrade pip

$(SAN_VENV)/.installed: $(SAN_PY) pyproject.toml $(ENGINE)
	@command -v c++ >/dev/null 2>&1 || { echo "make sanitize compiles the engine: no C++ compiler found (Debian/Ubuntu: apt-get install g++)" >&2; exit 1; }
	@echo "make sanitize: the engine with ASan + UBSan into $(SAN_VENV) (build/sanitize; several minutes the first time)"
	$(SAN_PIP) install --quiet $(shell $(PYTHON) -c "import tomllib; print(' '.join(repr(r) for r in tomllib.load(open('pyproject.toml', 'rb'))['build-system']['requires']))") cmake ninja
	$(SAN_PIP) install --quiet --no-build-isolation -e ".[test]" \
	    -C cmake.build-type=RelWithDebInfo -C build-dir=build/sanitize -C install.strip=false \
	    -C cmake.define.CMAKE_CXX_FLAGS="$(SAN_FLAGS)" \
	    -C cmake.define.CMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined"
	touch $@

sanitize: $(SAN_VENV)/.installed
	rm -rf $(SAN_LOG) && mkdir -p $(SAN_LOG)
	LD_PRELOAD="$$(c++ -print-file-name=libasan.so) $$(c++ -print-file-name=libstdc++.so)" \
	ASAN_OPTIONS="detect_leaks=0:log_path=$(CURDIR)/$(SAN_LOG)/asan" \
	UBSAN_OPTIONS="print_stacktrace=1:log_path=$(CURDIR)/$(SAN_LOG)/ubsan" \
	CLIK_SANITIZE=1 $(SAN_PY) -m pytest $(SAN_TESTS) -m "not browser" --timeout=900 -q -p no:cacheprovider
	@if [ -n "$$(ls -A $(SAN_LOG))" ]; then echo "make sanitize: sanitizer reports:" >&2; cat $(SAN_LOG)/* >&2; exit 1; fi
	@echo "make sanitize: no sanitizer report"

clean:
	rm -rf out .pytest_cache build
