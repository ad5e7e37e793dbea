# Two commands on a fresh machine with Python 3.11+ and make:
#   make demo   the main job on the simulated rig
#   make test   linters, import contracts, the documentation site and the whole test suite
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
PIP    := $(BIN)/python -m pip --disable-pip-version-check -q
TEST_EXTRAS := [test,docs,instruments]
MYPY_NICE ?= 0

# Python writes the byte code of what it imports (a machine may set
# PYTHONDONTWRITEBYTECODE; then every process the tests start would compile numpy,
# scipy and the package again): each module is compiled once, by the first process that
# imports it, and only the modules something imports.
unexport PYTHONDONTWRITEBYTECODE

# Installs the project with its extras $(1) into the venv: by uv (resolving and
# unpacking in parallel: about 10 s where pip takes 60-70 on the 2-core machine, the
# same versions), itself installed by pip; by pip alone if uv cannot be had or fails.
define install
	{ $(PIP) install uv && $(BIN)/uv pip install -q --python $(BIN)/python -e '.$(1)'; } \
		|| $(PIP) install -e '.$(1)'
endef

.PHONY: demo test lint style typecheck docs pytest suite warm warm-kernels warm-collect browser bench bench-studies clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# Stamps re-run the install whenever pyproject.toml changes.
$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(call install,)
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(call install,$(TEST_EXTRAS))
	touch $@ $(VENV)/.installed $(VENV)/.installed-docs

$(VENV)/.installed-docs: pyproject.toml | $(BIN)/python
	$(call install,[docs])
	touch $@ $(VENV)/.installed

# The main job on the simulated rig, then what its run file holds and how well its
# reconstruction matches the scene (re-running replaces it).
demo: $(VENV)/.installed
	@mkdir -p runs
	$(BIN)/gonio acquire configs/plans/quickstart.yaml --scene configs/scenes/glossy_metal.yaml \
		-o runs/demo.sqlite --overwrite
	$(BIN)/gonio info runs/demo.sqlite
	$(BIN)/gonio evaluate runs/demo.sqlite --method rbf

lint: style typecheck

style: $(VENV)/.installed-test
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/lint-imports

typecheck: $(VENV)/.installed-test
	nice -n $(MYPY_NICE) $(BIN)/mypy

# The documentation site (mkdocs.yml) into site/; --strict makes a broken link, a missing
# anchor or a page left out of the navigation an error.
docs: $(VENV)/.installed-docs
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

# Three workers on two cores: the tests that talk to a pty run one after another on one
# worker (their devices keep real time; see tests/conftest.py) and its waits are filled
# by CPU-bound tests from the other two.
# BUILT_SITE: a site `make docs` has just built, which the site's browser tests open
# instead of building their own (`make test` passes it; alone, they build one).
pytest: $(VENV)/.installed-test browser warm
	@$(MAKE) --no-print-directory suite

suite:
	GONIO_BUILT_SITE=$(BUILT_SITE) $(BIN)/python -m pytest -q -n 3 --dist loadgroup

# What every test process would otherwise redo, once: the planner's numba kernels
# compiled into their on-disk cache (some seconds, not in each worker at the same time),
# and, by one collection of the suite, the byte code of everything the tests import and
# of the test modules as pytest rewrites their asserts (each worker reads them: its
# collection 8 CPU-s instead of 17).
# The two side by side (under make -j): neither needs the other.
warm: warm-kernels warm-collect

warm-kernels: $(VENV)/.installed-test
	$(BIN)/python -c "from gonio.planner.ordering import compile_kernels; compile_kernels()"

warm-collect: $(VENV)/.installed-test
	@out=$$($(BIN)/python -m pytest -q --collect-only -p no:cacheprovider) \
		|| { echo "$$out"; exit 1; }


# The browser tests (tests/gonio/live/test_browser.py) drive Debian's Chromium: installed
# here when missing and running as root (as CI does); elsewhere they skip, saying why
# (never in CI, where they fail instead).
browser:
	@if [ ! -x /usr/bin/chromium ] && [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
		echo "installing chromium for the browser tests"; \
		{ apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
			chromium >/dev/null; } || echo "could not install chromium"; \
	fi

# Once installed: ruff and the import contracts, the site and the warm-up side by side;
# then the suite with the type checker beside it, at a lower priority (its 30 CPU-s fill
# the suite's waits on real time instead of holding the suite back).
test: $(VENV)/.installed-test
	@echo "checks: ruff, the import contracts, the site and the warm-up side by side"
	@$(MAKE) --no-print-directory -j4 -O style docs warm browser
	@echo "the suite, and mypy beside it"
	@$(MAKE) --no-print-directory -j2 suite typecheck MYPY_NICE=10 BUILT_SITE=$(CURDIR)/site

# Every speed benchmark (benchmarks/) and accuracy study (studies/), one after another,
# each writing its page docs/results/<script>.md (and docs/results/index.md) with the
# command, the machine, the date, the load and the wall time, besides printing it
# (`--no-page`: print only). Fast ones first; about 45 min on
# the 2-core machine, of which planner.py takes about 25 (LKH-3's tours, a plan of a million)
# and load_suite.py about 25 (the real-time tests ten times beside busy processes).
bench: $(VENV)/.installed-test
	$(BIN)/python benchmarks/params.py --repeat 11
	$(BIN)/python studies/extremes.py --near-horizon 4000
	$(BIN)/python studies/extremes_study.py
	$(BIN)/python studies/lobes.py
	$(BIN)/python benchmarks/bus.py
	$(BIN)/python benchmarks/bus_retries.py
	$(BIN)/python benchmarks/fly_bus.py
	$(BIN)/python benchmarks/trajectory_bus.py
	$(BIN)/python benchmarks/fly_rehearsal.py --runs 3
	$(BIN)/python studies/fly_blur.py
	$(BIN)/python benchmarks/stream.py
	$(BIN)/python benchmarks/handoff.py --load 3
	$(BIN)/python benchmarks/rehearsal.py --runs 5
	$(BIN)/python benchmarks/instruments.py
	$(BIN)/python studies/lockin.py
	$(BIN)/python benchmarks/simulator.py
	$(BIN)/python benchmarks/acquire.py
	$(BIN)/python benchmarks/soak.py
	$(BIN)/python benchmarks/live.py --screenshot docs/img/live-page.png
	$(BIN)/python studies/fit.py
	$(BIN)/python studies/calibration.py
	$(BIN)/python studies/evaluation.py
	$(BIN)/python benchmarks/reconstruct.py
	$(BIN)/python benchmarks/reconstruct.py --transforms
	$(BIN)/python studies/line_reconstruction.py
	$(BIN)/python studies/factored.py
	$(BIN)/python benchmarks/export.py
	$(BIN)/python studies/point_source.py
	$(BIN)/python studies/misalignment.py
	$(BIN)/python studies/align.py
	$(BIN)/python studies/utia.py
	$(BIN)/python studies/rgl.py
	$(BIN)/python benchmarks/plots.py
	$(BIN)/python benchmarks/tradeoff.py
	$(BIN)/python studies/accuracy.py
	$(BIN)/python studies/adaptive.py --targets 250 500 1000 2000 4000 --random 10
	$(BIN)/python studies/adaptive.py --scenes glossy --targets 250 500 1000 2000 4000 \
		--random 10 --random-first 12
	$(BIN)/python studies/adaptive.py --scenes brushed --targets 500 1000 2000 \
		--adaptive-in rusinkiewicz
	$(BIN)/python studies/adaptive.py --scenes brushed --targets 500 1000 2000 \
		--adaptive-in rusinkiewicz --model survey
	$(BIN)/python studies/adaptive_weights.py
	$(BIN)/python studies/adaptive_limit.py
	$(BIN)/python benchmarks/planner.py
	$(BIN)/python benchmarks/fly_plan.py
	$(BIN)/python benchmarks/load_suite.py
	$(BIN)/python benchmarks/make_test.py

# The study (docs/explanations/tradeoff.md "The study"): the `gonio tradeoff` sweeps of
# configs/sweeps/study_*.yaml into runs/study_* (a rerun resumes them), the noise-free
# curves into runs/study*/curves.csv (resumable too), then the pages docs/results/study-*.md
# and study_engine-*.md and the figures docs/img/study-*.png. About 30 min on the 2-core
# machine (the sweeps 15, the curves 11).
STUDY_SWEEPS := uniform seed000 brushed exposure effects
bench-studies: $(VENV)/.installed-test
	@mkdir -p runs
	for s in $(STUDY_SWEEPS); do \
		$(BIN)/gonio tradeoff configs/sweeps/study_$$s.yaml -o runs/study_$$s -j 1 -q || exit 1; \
	done
	$(BIN)/gonio tradeoff configs/sweeps/study_adaptive.yaml -o runs/study_adaptive_engine -j 1 -q
	$(BIN)/python studies/study_engine.py exposure --runs runs/study_exposure
	$(BIN)/python studies/study_engine.py effects --runs runs/study_effects
	$(BIN)/python studies/study_engine.py adaptive --runs runs/study_adaptive_engine
	$(BIN)/python studies/study_engine.py timing
	$(BIN)/python studies/study.py lobes
	$(BIN)/python studies/study.py budget --scenes matte glossy_metal seed000_specular
	$(BIN)/python studies/study.py where --scenes seed000_specular glossy_metal matte \
		--methods linear
	$(BIN)/python studies/study.py curves -o runs/study --targets 0.001 0.003 0.01 0.03 0.05 0.1
	$(BIN)/python studies/study_engine.py uniform --runs runs/study_uniform \
		runs/study_seed000 runs/study_brushed --curves runs/study/curves.csv --method rbf \
		--targets 0.001 0.003 0.01 0.03 0.05 0.1 \
		--img docs/img
	$(BIN)/python studies/study.py curves -o runs/study_adaptive --sampling sobol adaptive \
		--params rusinkiewicz hybrid --targets 0.001 0.003 0.01 0.03
	$(BIN)/python studies/fly_trade.py --runs runs/fly_trade

clean:
	rm -rf $(VENV) site .mypy_cache .ruff_cache .pytest_cache .hypothesis .import_linter_cache
