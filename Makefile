# Two commands on a fresh machine with Python 3.11+ and make:
#   make demo   the main job on the simulated rig
#   make test   linters, import contracts, the documentation site and the whole test suite
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
PIP    := $(BIN)/python -m pip --disable-pip-version-check -q

.PHONY: demo test lint docs pytest bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# Stamps re-run the install whenever pyproject.toml changes.
$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(PIP) install -e .
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(PIP) install -e '.[test,docs]'
	touch $@ $(VENV)/.installed $(VENV)/.installed-docs

$(VENV)/.installed-docs: pyproject.toml | $(BIN)/python
	$(PIP) install -e '.[docs]'
	touch $@ $(VENV)/.installed

# The main job on the simulated rig, then what its run file holds and how well its
# reconstruction matches the scene (re-running replaces it).
demo: $(VENV)/.installed
	@mkdir -p runs
	$(BIN)/gonio acquire configs/plans/quickstart.yaml --scene configs/scenes/glossy_metal.yaml \
		-o runs/quickstart.sqlite --overwrite
	$(BIN)/gonio info runs/quickstart.sqlite
	$(BIN)/gonio evaluate runs/quickstart.sqlite --method rbf

lint: $(VENV)/.installed-test
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy
	$(BIN)/lint-imports

# The documentation site (mkdocs.yml) into site/; --strict makes a broken link, a missing
# anchor or a page left out of the navigation an error.
docs: $(VENV)/.installed-docs
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

# Three workers on two cores: the tests that talk to a pty run one after another on one
# worker (their devices keep real time; see tests/conftest.py) and its waits are filled
# by CPU-bound tests from the other two.
pytest: $(VENV)/.installed-test
	$(BIN)/python -m pytest -q -n 3 --dist loadgroup

test: lint docs pytest

bench: $(VENV)/.installed-test
	$(BIN)/python benchmarks/params.py
	$(BIN)/python benchmarks/lobes.py
	$(BIN)/python benchmarks/extremes.py
	$(BIN)/python benchmarks/extremes_study.py
	$(BIN)/python benchmarks/bus.py
	$(BIN)/python benchmarks/handoff.py --load 3
	$(BIN)/python benchmarks/rehearsal.py
	$(BIN)/python benchmarks/planner.py
	$(BIN)/python benchmarks/simulator.py
	$(BIN)/python benchmarks/fit.py
	$(BIN)/python benchmarks/tradeoff.py

clean:
	rm -rf $(VENV) site .mypy_cache .ruff_cache .pytest_cache .hypothesis .import_linter_cache
