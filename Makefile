# Two commands set everything up on a fresh clone: `make demo` and `make test`.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
PIP := $(PY) -m pip --disable-pip-version-check -q

.PHONY: all web frontend-test demo test test-latest lint fuzz bench clean msgs ros-venv chromium spin asan lock

# `make`: the virtualenv and the page.
all: $(VENV)/.installed web

# What `make` installs is locked: requirements/lock.txt holds the exact versions of everything
# .venv gets (llfsm's dependencies, every extra, and the setuptools it is built with), and
# requirements/ros.lock.txt those of .venv-ros.  They are constraints (`pip install -c`), so
# pyproject.toml keeps the ranges a user's `pip install llfsm` resolves.  `make lock` regenerates
# both with uv; `make test-latest` empties LOCK and ROS_LOCK to run the suite on the newest releases.
LOCK ?= requirements/lock.txt
ROS_LOCK ?= requirements/ros.lock.txt
UV_VERSION := 0.13.8
constrain = $(if $(1),-c $(1))

# Real ROS 2 for the interop tests (pytest -m interop): rclpy, message packages and Fast DDS as
# wheels from PyPI (requirements/ros.in), in a virtualenv of their own (they bring numpy, lark,
# empy...).  There is no rmw_cyclonedds wheel.  About 20 s with a warm pip cache.
VENV_ROS ?= .venv-ros

# setup.py builds the recorder's tap and turtlesim's painter in C into the source tree: a changed
# C file reinstalls.  llfsm is built without build isolation, with the locked setuptools installed
# first: an isolated build would fetch whatever setuptools is newest that day.
$(VENV)/.installed: pyproject.toml setup.py llfsm/bag/_tap.c llfsm/sim/_paint.c requirements/build.in $(LOCK)
	$(PYTHON) -m venv $(VENV)
	$(PIP) install $(call constrain,$(LOCK)) -r requirements/build.in
	$(PIP) install --no-build-isolation $(call constrain,$(LOCK)) -e .
	touch $@

$(VENV)/.installed-dev: $(VENV)/.installed
	$(PIP) install --no-build-isolation $(call constrain,$(LOCK)) -e '.[dev]'
	touch $@

$(VENV)/.installed-bench: $(VENV)/.installed-dev
	$(PIP) install --no-build-isolation $(call constrain,$(LOCK)) -e '.[dev,bench]'
	touch $@

# The page (docs/architecture.md, "The front end"): frontend/ (TypeScript, Vite, CodeMirror 6,
# Preact) built into llfsm/web/static/app/, which the package ships (package-data).  Installed
# from the committed lockfile only (`npm ci`: the registry, nothing else); the built files are
# not committed, so `make`, `make demo` and `make test` build them on a fresh clone.
FRONTEND_SRC := $(shell find frontend/src -type f 2>/dev/null) frontend/vite.config.ts frontend/tsconfig.json
APP := llfsm/web/static/app/app.js

frontend/node_modules/.installed: frontend/package.json frontend/package-lock.json
	cd frontend && npm ci --no-audit --no-fund --loglevel=error
	touch $@

$(APP): frontend/node_modules/.installed $(FRONTEND_SRC)
	cd frontend && npm run --silent build

web: $(APP)

# The page's unit tests (Vitest, in happy-dom).
frontend-test: frontend/node_modules/.installed
	cd frontend && npm test --silent

DEMO_RUN := $(VENV)/bin/llfsm run --clock sim

demo: $(VENV)/.installed web
	@mkdir -p demo-output
	@echo "== ros2_ping_pong: /pingpong as ros2 topic echo shows it (3 s of simulated time)"
	$(DEMO_RUN) machines/ros2_ping_pong.machine --duration 3.5s --echo /pingpong
	@echo "== ros2_wall_turtle_bot with turtlesim and the pose service (60 s simulated)"
	$(DEMO_RUN) machines/ros2_wall_turtle_bot.machine --node turtlesim --node turtle_sensor_poster \
		--duration 60s --image demo-output/wall_turtle_bot.png
	@echo "== turtle_follower behind ros2_blind_turtle_bot (30 s simulated)"
	$(DEMO_RUN) machines/ros2_blind_turtle_bot.machine machines/turtle_follower.machine --node turtlesim \
		--duration 30s --image demo-output/turtle_follower.png
	@echo "pictures: demo-output/wall_turtle_bot.png demo-output/turtle_follower.png"

# lint-imports: the layers and contracts of [tool.importlinter] (docs/architecture.md); the test
# after it fails when a contract's list leaves out a module of the package it governs.
lint: $(VENV)/.installed-dev
	$(VENV)/bin/ruff check llfsm tests bench
	$(VENV)/bin/mypy
	$(VENV)/bin/lint-imports --no-logo
	$(PY) -m pytest -q --no-header -p no:cacheprovider tests/test_architecture.py::test_every_contract_names_every_module_of_its_package

# The web view's browser tests drive Debian's Chromium (Playwright never downloads a browser):
# installed here where we can (root with apt-get); elsewhere those tests skip and say why.
chromium:
	@if command -v chromium >/dev/null 2>&1; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
		(apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium) >/dev/null \
			|| echo "make: could not install chromium: the browser tests will skip"; \
	else echo "make: no chromium (apt-get install chromium as root): the browser tests will skip"; fi

# `llfsm verify`'s tests run SPIN (Debian's spin) on its Promela exports: installed here where we
# can (root with apt-get); elsewhere those tests skip and say why.
spin:
	@if command -v spin >/dev/null 2>&1; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
		(apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q spin) >/dev/null \
			|| echo "make: could not install spin: the SPIN tests of llfsm verify will skip"; \
	else echo "make: no spin (apt-get install spin as root): the SPIN tests of llfsm verify will skip"; fi

$(VENV_ROS)/.installed: requirements/ros.in $(ROS_LOCK)
	$(PYTHON) -m venv $(VENV_ROS)
	$(VENV_ROS)/bin/python -m pip --disable-pip-version-check -q install $(call constrain,$(ROS_LOCK)) -r requirements/ros.in
	touch $@

# `make test` tries to provide real ROS 2 but goes on without it: the interop tests then skip
# and say why.
ros-venv:
	@$(MAKE) --no-print-directory $(VENV_ROS)/.installed || echo "warning: $(VENV_ROS) not installed: interop tests will be skipped"

# LLFSM_REQUIRE_C=1: a C part that was not built fails its tests here instead of skipping them,
# so that `make test` measures what the docs claim (a plain `pytest` skips them, saying why).
test: $(VENV)/.installed-dev web lint frontend-test ros-venv chromium spin
	LLFSM_REQUIRE_C=1 LLFSM_ROS_VENV=$(abspath $(VENV_ROS)) $(PY) -m pytest -q
	@echo "== the same recorder and painter tests with the C parts disabled (the pure-Python fallback)"
	LLFSM_NO_C=1 $(PY) -m pytest -q tests/test_bag.py tests/test_sim.py tests/test_bag_tap.py

# The same suite on the newest releases of every dependency (no lock), in venvs of its own made
# anew each time: drift shows up here, as a failing target with this name, before it turns main red.
test-latest:
	rm -rf .venv-latest .venv-ros-latest
	$(MAKE) --no-print-directory test VENV=.venv-latest VENV_ROS=.venv-ros-latest LOCK= ROS_LOCK=

# Regenerates the locks from pyproject.toml (every extra) and requirements/*.in with uv, for
# Python 3.11 on any platform.
lock:
	$(PYTHON) -m venv .venv-lock
	.venv-lock/bin/python -m pip --disable-pip-version-check -q install uv==$(UV_VERSION)
	.venv-lock/bin/uv pip compile -q --universal --python-version 3.11 --all-extras --custom-compile-command 'make lock' \
		pyproject.toml requirements/build.in -o requirements/lock.txt
	.venv-lock/bin/uv pip compile -q --universal --python-version 3.11 --custom-compile-command 'make lock' \
		requirements/ros.in -o requirements/ros.lock.txt

fuzz: $(VENV)/.installed-dev
	$(PY) -m pytest -q -m slow tests

# The C parts (setup.py) built with AddressSanitizer and UBSan into a copy of the tree, and the
# tests that drive them run against those builds.  Not part of `make test`: run it after
# changing a .c file.
ASAN_TESTS := tests/test_bag_tap.py tests/test_sim.py tests/test_bag.py tests/test_turtlesim_node.py
asan: $(VENV)/.installed-dev
	rm -rf build/asan && git clone -q . build/asan && cp llfsm/bag/_tap.c build/asan/llfsm/bag/ && cp llfsm/sim/_paint.c build/asan/llfsm/sim/
	for m in bag/_tap sim/_paint; do \
		gcc -g -O1 -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer \
			-ffp-contract=off -fPIC -shared -I"$$($(PY) -c 'import sysconfig; print(sysconfig.get_paths()["include"])')" \
			build/asan/llfsm/$$m.c -o build/asan/llfsm/$$m$$($(PY) -c 'import sysconfig; print(sysconfig.get_config_var("EXT_SUFFIX"))') || exit 1; \
	done
	cd build/asan && LD_PRELOAD="$$(gcc -print-file-name=libasan.so) $$(gcc -print-file-name=libubsan.so)" \
		ASAN_OPTIONS=detect_leaks=0 PYTHONMALLOC=malloc PYTHONPATH=. LLFSM_NO_C= LLFSM_REQUIRE_C=1 \
		../../$(PY) -m pytest -q -p no:cacheprovider $(ASAN_TESTS)

bench: $(VENV)/.installed-bench
	$(PY) bench/run.py

msgs: $(VENV)/.installed-dev
	$(PY) -m llfsm.idl

clean:
	rm -rf llfsm/web/static/app frontend/node_modules
	rm -rf $(VENV) $(VENV_ROS) .venv-latest .venv-ros-latest .venv-lock build demo-output .pytest_cache .ruff_cache .import_linter_cache
	find llfsm -name '*.so' -delete
