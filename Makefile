# The two commands of the README:
#   make reproduce   set up everything and run the whole pipeline (dvc repro)
#   make test        set up everything and run the test suite (what CI runs)
# Both are idempotent: the virtual environment is built once and reused.
PYTHON ?= python3
VENV   ?= .venv
PY      = $(VENV)/bin/python
STAMP   = $(VENV)/.installed

.PHONY: setup reproduce test test-slow lint bench clean-venv

setup: $(STAMP)

# torch first and pinned: 2.13.0 is the CPU build that lies on disk here;
# any other spec would pull gigabytes of CUDA wheels.
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet torch==2.13.0
	$(PY) -m pip install --quiet -e ".[test]"
	touch $(STAMP)

reproduce: setup
	$(VENV)/bin/dvc repro

test: setup
	$(PY) -m pytest

# lint and type check: ruff (rules in pyproject.toml) and mypy on src/ (the force-model contract)
lint: setup
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy

test-slow: setup
	$(PY) -m pytest -m slow

bench: setup
	$(PY) benchmarks/bench_solver.py
	$(PY) benchmarks/bench_rotor.py
	$(PY) benchmarks/bench_conical.py

clean-venv:
	rm -rf $(VENV)
