# RROSFuzz. Quick start (README): `make run` and `make test`; both install what they need.
SHELL := /bin/bash
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.rrosfuzz-installed
BUILD_INPUTS := $(shell find native/src -name '*.cpp' -o -name '*.hpp') CMakeLists.txt pyproject.toml scripts/setup.sh

.PHONY: setup run test lint

setup: $(STAMP)

$(STAMP): $(BUILD_INPUTS)
	scripts/setup.sh
	@touch $(STAMP)

## The main job: fuzz the shipped default robot for a bounded time.
run: setup
	$(PY) fuzz_diff.py corpus/ -max_total_time=60

## The test suite (what CI runs).
test: setup
	$(PY) -m pytest -q

lint: setup
	$(PY) -m ruff check . && $(PY) -m mypy robot_api native python_impl fuzzer
