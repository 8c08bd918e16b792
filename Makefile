# clik: the two commands of the README, and a few more.
#   make demo   creates .venv, installs clik, runs the case study (out/demo)
#   make test   creates .venv with the test extras, runs every test and notebook
#   make test-ros  adds the ros extra (ROS 2 wheels, rosbags) and runs the tests that need it
#   make lint   ruff (style, docstrings) and mypy (types) on clik/ and benchmarks/
#   make bench  installs the bench extra (pink, mink, MuJoCo), runs benchmarks/ into out/bench
#   make docs   the documentation site (MkDocs, mkdocs.yml), built strictly into site/
#   make sanitize  the engine built with AddressSanitizer and UBSan (.venv-sanitize,
#               build/sanitize), the engine's tests run under it; fails on any report

PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
PIP    := $(PY) -m pip --disable-pip-version-check
NOTEBOOKS := $(wildcard notebooks/*.ipynb)
ENGINE  := $(shell find src/engine -type f)
# The build's output (pip, the compiler) goes to one log; the terminal gets one line per
# step, and on a failure the log's last 40 lines and its path.
LOG    ?= out/build.log
# The requirements to install before the engine compiles (one per line): the engine's
# build requirements (pip then builds without isolation and rebuilds incrementally in
# build/), cmake, ninja, clik's dependencies and those of the extras named in $(1).
REQUIREMENTS = $(PY) -c "import sys, tomllib; p = tomllib.load(open('pyproject.toml', 'rb')); o = p['project']['optional-dependencies']; print('\n'.join(p['build-system']['requires'] + ['cmake', 'ninja'] + p['project']['dependencies'] + [r for e in sys.argv[1].split(',') if e for r in o[e]]))" "$(1)"
TEST_EXTRAS := test,notebooks,bench,lint,docs
# $(call logged,COMMAND): COMMAND with its output appended to $(LOG); on failure, the
# log's last 40 lines and its path on stderr, and make stops.
logged = mkdir -p $(dir $(LOG)) && { $(1); } >>$(LOG) 2>&1 || { echo "clik: failed; the last 40 lines of $(LOG):" >&2; tail -n 40 $(LOG) >&2; echo "clik: the full log is $(LOG)" >&2; exit 1; }
NEED_CXX = command -v c++ >/dev/null 2>&1 || { echo "clik compiles its engine (C++17): no C++ compiler found; install one (Debian/Ubuntu: sudo apt-get install g++)" >&2; exit 1; }
COMPILE_MSG = compiling the engine (the first time about 5-9 min on 2 cores, peak about 2.5 GB of memory; log: $(LOG))...

.PHONY: demo test test-ros lint docs bench sanitize clean

VENV_NEW = test -x $(PY) || { $(PYTHON) -m venv $(VENV) && $(PIP) install --upgrade pip; }

# Step 1: dependencies (Pinocchio, coal, meshcat, Dask...; about 1.7 GB in $(VENV)).
$(VENV)/.deps: pyproject.toml
	@echo "clik: 1/3 installing dependencies into $(VENV) (log: $(LOG))..."
	@$(call logged,$(VENV_NEW) && $(call REQUIREMENTS,) > $(VENV)/requirements.txt && $(PIP) install -r $(VENV)/requirements.txt)
	@touch $@

$(VENV)/.deps-test: pyproject.toml
	@echo "clik: 1/3 installing dependencies with the extras $(TEST_EXTRAS) into $(VENV) (log: $(LOG))..."
	@$(call logged,$(VENV_NEW) && $(call REQUIREMENTS,$(TEST_EXTRAS)) > $(VENV)/requirements-test.txt && $(PIP) install -r $(VENV)/requirements-test.txt)
	@touch $@ $(VENV)/.deps

# Step 2: clik itself, editable, with its engine compiled (src/engine).
$(VENV)/.installed: $(VENV)/.deps pyproject.toml $(ENGINE)
	@$(NEED_CXX)
	@echo "clik: 2/3 $(COMPILE_MSG)"
	@$(call logged,$(PIP) install --no-deps --no-build-isolation -e .)
	@touch $@

$(VENV)/.installed-test: $(VENV)/.deps-test pyproject.toml $(ENGINE)
	@$(NEED_CXX)
	@echo "clik: 2/3 $(COMPILE_MSG)"
	@$(call logged,$(PIP) install --no-deps --no-build-isolation -e .)
	@touch $@ $(VENV)/.installed

demo: $(VENV)/.installed
	@echo "clik: 3/3 running the demo ($(VENV)/bin/clik demo --out out/demo)..."
	@$(VENV)/bin/clik demo --out out/demo --force
	@echo "clik: done; run clik as $(VENV)/bin/clik (or 'source $(VENV)/bin/activate', then clik); see README.md"

test: $(VENV)/.installed-test
	@echo "clik: 3/3 running the tests ($(PY) -m pytest tests ...)"
	$(PY) -m pytest tests $(if $(NOTEBOOKS),--nbmake --nbmake-timeout=120 $(NOTEBOOKS)) --timeout=600 -q

# The ros extra (rclpy and the ROS 2 message wheels from PyPI, rosbags) into $(VENV), then
# the tests that need it: the ROS 2 loop (tests/ros: in a private network namespace, as
# root) and the rosbag export. (The message wheels bring lark-parser 0.12, whose files
# replace lark's; lark is put back, as jsonschema's format checks import it.)
test-ros: $(VENV)/.installed-test
	@echo "clik: installing the ros extra into $(VENV) (log: $(LOG))..."
	@$(call logged,$(call REQUIREMENTS,ros) > $(VENV)/requirements-ros.txt && $(PIP) install -r $(VENV)/requirements-ros.txt && $(PIP) install --force-reinstall --no-deps "lark>=1.2")
	$(PY) -m pytest tests/ros tests/outputs/test_export_rosbag.py --timeout=600 -q -rs -s

lint: $(VENV)/.installed-test
	$(VENV)/bin/ruff check clik benchmarks tests
	$(VENV)/bin/ruff format --check clik benchmarks tests
	$(VENV)/bin/mypy

# The site (docs/, mkdocs.yml) into site/; --strict: a broken link, a page missing from the
# navigation or an API entry that does not resolve fails the build.
docs: $(VENV)/.installed-test
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --site-dir site

bench: $(VENV)/.installed
	@echo "clik: installing the bench extra into $(VENV) (log: $(LOG))..."
	@$(call logged,$(call REQUIREMENTS,bench) > $(VENV)/requirements-bench.txt && $(PIP) install -r $(VENV)/requirements-bench.txt)
	$(VENV)/bin/clik bench --out out/bench

# -- make sanitize ---------------------------------------------------------------------
# The engine compiled with ASan and UBSan (float-cast-overflow included: GCC's
# -fsanitize=undefined leaves it out), symbols kept (RelWithDebInfo, not stripped), with
# the wheels' allocation settings (EIGEN_MALLOC_ALREADY_ALIGNED: pinocchio::Data is
# allocated in the wheel's library and freed in the engine), into its own venv and build
# folder, with clik._sanitize_probe (CLIK_SANITIZE_PROBE: reports on request, in no other
# build). Then, under the sanitizers:
#   1/2 a self-check: SAN_PROBE plants a UBSan report, then an ASan one; unless each fails
#       its run and shows in its log, the target fails ("FAILED self-check").
#   2/2 SAN_TESTS, `pytest -v`: the loop, constraint, solve, task, controller, zoo,
#       bad-input, hardened-number, boundary and thread tests, every tests/*/ fuzz file,
#       and SAN_PROBE (skipped; `CLIK_PLANT_SANITIZER=ubsan make sanitize` must fail).
# GCC's UBSan runtime (libubsan.so.1) ignores UBSAN_OPTIONS=log_path and writes its
# reports to fd 2: pytest runs with --capture=sys (fd 2 not captured), its output goes to
# the terminal and to build/sanitize-logs/*.log, and .ci/sanitize-pytest reads the log
# ("runtime error:", "ERROR: AddressSanitizer", "SUMMARY: ...Sanitizer"). UBSan keeps
# going (one run lists every report); ASan's first report ends the run. A report or a
# failed test fails the target, which lists the distinct reports; each part prints its
# time and test count. A subprocess a test starts stops at its first UBSan report
# (tests/conftest.py), so the test fails even when it captures that stderr.
# Memory-budget and browser tests stay in `make test` (ASan's RSS; Chromium does not
# start under the preload); tests/control's long session reads ASan's own count of the
# bytes allocated instead (its quarantine keeps freed blocks resident). See ../shared/NOTES.md, "Sanitizer builds of the engine".
SAN_VENV  := .venv-sanitize
SAN_PY    := $(SAN_VENV)/bin/python
SAN_PIP   := $(SAN_PY) -m pip --disable-pip-version-check
SAN_LOG   := build/sanitize-logs
SAN_FLAGS := -fsanitize=address,undefined -fsanitize=float-cast-overflow -fno-omit-frame-pointer -g -O1 -DEIGEN_MALLOC_ALREADY_ALIGNED=1
SAN_PROBE := tests/robustness/test_sanitizer_probe.py
SAN_TESTS := tests/loop tests/constraints tests/solving tests/tasks tests/control \
             tests/robustness/test_zoo.py tests/robustness/test_bad_input.py \
             tests/robustness/test_hardened_numbers.py $(wildcard tests/robustness/test_*boundary*.py) \
             $(wildcard tests/*/test_*fuzz*.py) $(wildcard tests/robustness/test_threads*.py) $(SAN_PROBE)
# pytest under the sanitizers: libasan preloaded, then libstdc++ (else the first C++
# exception CHECK-fails); no leak check (Python leaks by design); fd 2 not captured;
# .ci/ubsan.supp: third-party reports known safe (one: nanobind's memcpy of 0 bytes).
SAN_PYTEST = env LD_PRELOAD="$$(c++ -print-file-name=libasan.so) $$(c++ -print-file-name=libstdc++.so)" \
             ASAN_OPTIONS=detect_leaks=0 CLIK_SANITIZE=1 \
             UBSAN_OPTIONS=print_stacktrace=1:suppressions=$(CURDIR)/.ci/ubsan.supp \
             $(SAN_PY) -u -m pytest -v -m "not browser" --capture=sys --timeout=900 -p no:cacheprovider
SAN_RUN   := .ci/sanitize-pytest

$(SAN_PY):
	$(PYTHON) -m venv $(SAN_VENV)
	$(SAN_PIP) install --quiet --upgrade pip

$(SAN_VENV)/.installed: $(SAN_PY) pyproject.toml $(ENGINE)
	@command -v c++ >/dev/null 2>&1 || { echo "make sanitize compiles the engine: no C++ compiler found (Debian/Ubuntu: apt-get install g++)" >&2; exit 1; }
	@echo "make sanitize: the engine with ASan + UBSan into $(SAN_VENV) (build/sanitize; several tens of minutes the first time on 2 cores)"
	$(SAN_PIP) install --quiet $(shell $(PYTHON) -c "import tomllib; print(' '.join(repr(r) for r in tomllib.load(open('pyproject.toml', 'rb'))['build-system']['requires']))") cmake ninja
	@start=$$(date +%s) && $(SAN_PIP) install --quiet --no-build-isolation -e ".[test]" \
	    -C cmake.build-type=RelWithDebInfo -C build-dir=build/sanitize -C install.strip=false \
	    -C cmake.define.CMAKE_CXX_FLAGS="$(SAN_FLAGS)" \
	    -C cmake.define.CMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
	    -C cmake.define.CLIK_SANITIZE_PROBE=ON \
	    && echo "make sanitize: the build took $$(( $$(date +%s) - start )) s"
	touch $@

sanitize: $(SAN_VENV)/.installed
	@rm -rf $(SAN_LOG) && mkdir -p $(SAN_LOG)
	@echo "make sanitize: 1/2 self-check: a planted UBSan report, then an ASan one, must each fail its run ($(SAN_PROBE))"
	@CLIK_PLANT_SANITIZER=ubsan $(SAN_RUN) --planted UBSan 'sanitize_probe\.cpp:[0-9]+:[0-9]+: runtime error: signed integer overflow' \
	    $(SAN_LOG)/planted-ubsan.log $(SAN_PYTEST) $(SAN_PROBE)
	@CLIK_PLANT_SANITIZER=asan $(SAN_RUN) --planted ASan 'SUMMARY: AddressSanitizer: heap-buffer-overflow .*sanitize_probe\.cpp' \
	    $(SAN_LOG)/planted-asan.log $(SAN_PYTEST) $(SAN_PROBE)
	@echo "make sanitize: 2/2 the engine's tests under the sanitizers (log: $(SAN_LOG)/tests.log)"
	@$(SAN_RUN) $(SAN_LOG)/tests.log $(SAN_PYTEST) $(SAN_TESTS)

clean:
	rm -rf out .pytest_cache build
