# Two commands set everything up on a fresh clone: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
PIP := $(PY) -m pip --disable-pip-version-check -q

.PHONY: demo test lint fuzz bench clean

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PIP) install -e .
	touch $@

$(VENV)/.installed-dev: $(VENV)/.installed
	$(PIP) install -e '.[dev]'
	touch $@

$(VENV)/.installed-bench: $(VENV)/.installed-dev
	$(PIP) install -e '.[dev,bench]'
	touch $@

demo: $(VENV)/.installed
	$(VENV)/bin/llfsm run machines/counter.machine --clock sim -v

lint: $(VENV)/.installed-dev
	$(VENV)/bin/ruff check llfsm tests bench

test: $(VENV)/.installed-dev lint
	$(PY) -m pytest -q

fuzz: $(VENV)/.installed-dev
	$(PY) -m pytest -q -m slow tests

bench: $(VENV)/.installed-bench
	$(PY) bench/run.py

clean:
	rm -rf $(VENV) build demo-output .pytest_cache .ruff_cache
