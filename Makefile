# Two commands on a fresh machine:
#   make run    - set up everything, then run the main job (headless, CPU)
#   make test   - set up everything, then run the test suite
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: run test test-docs-slow lint format typecheck setup system-deps bench docs clean

$(STAMP): pyproject.toml scripts/setup_env.sh $(wildcard plugins/*/pyproject.toml)
	PYTHON=$(PYTHON) bash scripts/setup_env.sh
	touch $(STAMP)

setup: $(STAMP)

# The main job: scripted PickFork-v1 demonstrations on the DexForce W1, 2 envs, recorded as a
# LeRobot dataset (stereo camera as mp4) under outputs/datasets/. The built-in demo scene of the
# core alone: `.venv/bin/embodichain run-env`.
MAIN_JOB := plugins/embodichain-tasks/embodichain_tasks/configs/main_job.json
run: $(STAMP)
	$(VENV)/bin/embodichain run-env --gym_config $(MAIN_JOB) --headless

# Both runs spread their test files over TEST_WORKERS processes (pytest-xdist; "auto": one per
# core, at most 4, as each process grows to 2-4 GB; 0: a single process). A test file (a docs
# page) runs whole in one process, in order, so its module fixtures are built once. The docs
# harness runs in its own session (conftest.py, docs/contributing.md): every shell and Python
# block of README.md and docs/*.md, in fast mode; the blocks marked slow run in .ci/run.
TEST_WORKERS ?= auto
XDIST := -n $(TEST_WORKERS) --maxprocesses 4 --dist loadfile
test: $(STAMP)
	$(PY) -m pytest -q -m "not slow" $(XDIST) tests $(wildcard plugins/*/tests)
	$(PY) -m pytest -q -m "not slow" $(XDIST) README.md docs

test-docs-slow: $(STAMP)
	$(PY) -m pytest -q -m slow README.md docs

# Lint gate (ruff: the lint rules and the formatter's check; settings in pyproject.toml [tool.ruff]).
# `make format` applies the formatter.
lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

format: $(STAMP)
	$(VENV)/bin/ruff format .

# Type gate (mypy, basic mode; the core and every plugin package, settings in pyproject.toml [tool.mypy]).
typecheck: $(STAMP)
	$(VENV)/bin/mypy

test-all: $(STAMP)
	$(PY) -m pytest -q tests $(wildcard plugins/*/tests)
	$(PY) -m pytest -q README.md docs

# The docs site (mkdocs, material theme) into site/; strict: a broken link or anchor, or a
# page missing from the nav in mkdocs.yml, fails the build.
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict --site-dir site

bench: $(STAMP)
	$(PY) benchmarks/env_throughput.py

clean:
	rm -rf $(VENV)
