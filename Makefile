# Two commands on a fresh machine with Python 3.11+ and make:
#   make demo   the main job on the simulated rig
#   make test   linters and the whole test suite
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
PIP    := $(BIN)/python -m pip --disable-pip-version-check -q

.PHONY: demo test lint pytest bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# Stamps re-run the install whenever pyproject.toml changes.
$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(PIP) install -e .
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(PIP) install -e '.[test]'
	touch $@ $(VENV)/.installed

demo: $(VENV)/.installed
	$(BIN)/gonio demo

lint: $(VENV)/.installed-test
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

pytest: $(VENV)/.installed-test
	$(BIN)/python -m pytest -q

test: lint pytest

bench: $(VENV)/.installed-test
	$(BIN)/python benchmarks/params.py
	$(BIN)/python benchmarks/lobes.py
	$(BIN)/python benchmarks/extremes.py
	$(BIN)/python benchmarks/bus.py
	$(BIN)/python benchmarks/planner.py
	$(BIN)/python benchmarks/simulator.py

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache .hypothesis
