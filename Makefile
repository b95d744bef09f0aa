# RROSFuzz. Quick start (README): `make run` and `make test`; both install what they need.
SHELL := /bin/bash
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.rrosfuzz-installed
MODULES := build/python-modules.txt
# The editable install maps each Python module to its file when it is installed: a module added,
# moved or removed since then needs setup again. The list is rewritten only when it changes.
$(shell mkdir -p build && find fuzzer python_impl robot_api native adapters -name '*.py' -not -path '*/__pycache__/*' \
	| LC_ALL=C sort > build/python-modules.new && (cmp -s build/python-modules.new $(MODULES) \
	|| mv build/python-modules.new $(MODULES)); rm -f build/python-modules.new)
BUILD_INPUTS := $(shell find native/src fuzzer -name '*.cpp' -o -name '*.hpp') CMakeLists.txt pyproject.toml scripts/setup.sh \
	constraints.txt \
	$(MODULES)

.PHONY: setup run test lint native-cov fuzz-native bench bench-deep bench-deep-full bench-paired bench-quick profile

setup: $(STAMP)

$(STAMP): $(BUILD_INPUTS)
	scripts/setup.sh
	@touch $(STAMP)

## The main job: fuzz scenarios (scripts of calls on one live MoveGroup) on the shipped default
## robot for a bounded time. The paper's single-move experiment: $(PY) fuzz_diff.py corpus/ -max_total_time=60
run: setup
	$(PY) fuzz_diff.py --op scenario corpus-scenario/ -max_total_time=60

## The test suite (what CI runs). It ends with its 25 slowest tests, so that every run (CI's
## included) says where the suite's time goes.
test: setup
	scripts/ros-ensure.sh --viz  # ROS 1, RViz and Xvfb from apt, for the ROS tests only (tests/test_ros_*.py)
	RROSFUZZ_REQUIRE_ADAPTERS=1 $(PY) -m pytest -q --durations=25

## Bug-finding power and throughput (BENCHMARKS.md). Full: every zoo bug x 5 engines x 5 seeds,
## then every deep bug x 6 engines x 10 trials x 60 s (3 h 23 min on 2 cores on 2063e32), then every zoo
## bug x 5 engines x 10 trials x 10 s with the deep bugs' statistics (25 minutes on 2063e32); about 6 hours
## in all, the sum of the steps (BENCHMARKS.md, "Reproducing"). Each step keeps
## its finished trials in a journal (benchmarks/results/*.jsonl): stopped, `make bench` goes on.
bench: setup
	$(PY) -m benchmarks.bench_zoo --mode full --write-md $$(test -f benchmarks/results/zoo-full.jsonl && echo --resume)
	$(MAKE) bench-deep-full
	$(PY) -m benchmarks.bench_deep --mode zoo --write-md $$(test -f benchmarks/results/deep-zoo.jsonl && echo --resume)

## The deep bugs' 60-s part alone. It keeps each finished trial in benchmarks/results/deep-full.jsonl:
## stopped or killed, the same command goes on with the trials that are missing (--resume).
bench-deep-full: setup
	$(PY) -m benchmarks.bench_deep --mode full --write-md $$(test -f benchmarks/results/deep-full.jsonl && echo --resume)

## The deep bugs against the goal's baselines, 10 trials x 10 s, each stopping at its first detection
## (41 minutes on 2 cores on 0dcf0f0, an Intel Xeon; 39 on 2063e32; every baseline on every bug).
bench-deep: setup
	$(PY) -m benchmarks.bench_deep --mode short --write-md $$(test -f benchmarks/results/deep-short.jsonl && echo --resume)

## The full engine against uniform sampling in pairs (benchmarks/bench_ab.py: both at once, one per
## CPU; Wilcoxon signed-rank), 100 pairs per bug, on the bugs a 10-trial table could not separate
## from uniform sampling (BENCHMARKS.md, "Paired A/B"; about 12 minutes on 5d8f753, AMD EPYC).
## Stopped, the same command goes on with the pairs missing, on the same commit.
PAIRED_BUGS = computed_branch atan2_quadrant calibration_entry wrap_past_pi execute_skips_start_check \
	wrap_positive axis_not_normalized missing_axis_z float32_integration mimic_ignored last_sample_dropped \
	ik_status_misread continuous_accumulates start_state_home cached_pose duplicate_start_point \
	execute_stops_short remember_aliases_state
bench-paired: setup
	$(PY) -m benchmarks.bench_ab --arm full . --arm uniform . --engines full uniform --bugs $(PAIRED_BUGS) \
		--trials 100 --first-seed 10 --out benchmarks/results/ab-paired-full-uniform.jsonl \
		$$(test -f benchmarks/results/ab-paired-full-uniform.jsonl && echo --resume)

## CI-sized: a few zoo bugs, and two deep bugs x 2 engines x 2 trials (tests/test_zoo_deep.py runs the deep part).
bench-quick: setup
	$(PY) -m benchmarks.bench_zoo --mode quick --restart
	$(PY) -m benchmarks.bench_deep --mode quick --restart

## Where a campaign's time goes (BENCHMARKS.md): a py-spy profile of one campaign, by part of the
## engine. PROFILE_OP=fk|move|ik|scenario (default fk), PROFILE_SECONDS (default 30); pinned to
## core 1 when the machine has two.
PROFILE_OP ?= fk
PROFILE_SECONDS ?= 30
profile: setup
	$$(test "$$(nproc)" -gt 1 && echo taskset -c 1) $(PY) -m benchmarks.profile --op $(PROFILE_OP) --seconds $(PROFILE_SECONDS)

lint: setup
	$(PY) -m ruff check . && $(PY) -m ruff format --check . && $(PY) -m mypy robot_api native python_impl fuzzer adapters benchmarks

## Native coverage: the C++ module built by clang with libFuzzer's edge counters and
## AddressSanitizer, run under Atheris' preload (docs/engine.md, "Instrumentation").
COV_BUILD := build/coverage
ATHERIS_PRELOAD = $$($(PY) -c "import atheris, os; print(os.path.join(atheris.path(), 'asan_with_fuzzer.so'))")
COV_MODULE = $$(ls $(CURDIR)/$(COV_BUILD)/_native*.so)
## libFuzzer preloaded this way resolves its weak custom-mutator hooks at start-up, before
## Atheris defines them: the shim defines them and forwards to Atheris (native/coverage/).
MUTATOR_SHIM := $(COV_BUILD)/librrosfuzz_mutator_shim.so
FUZZ_ARGS ?= corpus/ -max_total_time=60

## LD_PRELOAD splits its list at spaces, and these recipes name absolute paths: a checkout in a
## path with a space is refused with a word (CMake failed on "Cannot run the interpreter").
NO_SPACE = @case "$(CURDIR)" in *" "*) echo "make $@: $(CURDIR) has a space in its path, which LD_PRELOAD cannot take; use a clone in a path without spaces (make run and make test work in this one)" >&2; exit 2;; esac

native-cov: setup
	$(NO_SPACE)
	scripts/apt-ensure.sh clang libclang-rt-14-dev
	$(PY) -m pip install -q "pybind11>=2.12"
	cmake -S . -B $(COV_BUILD) -DRROSFUZZ_COVERAGE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DCMAKE_CXX_COMPILER=clang++ -DPython_EXECUTABLE="$(CURDIR)/$(PY)" \
	  -Dpybind11_DIR=$$($(PY) -m pybind11 --cmakedir) > /dev/null
	cmake --build $(COV_BUILD) -j2
	cc -shared -fPIC -O2 -Wall -o $(MUTATOR_SHIM) native/coverage/mutator_shim.c -ldl

fuzz-native: native-cov
	$(NO_SPACE)
	LD_PRELOAD="$(ATHERIS_PRELOAD) $(CURDIR)/$(MUTATOR_SHIM)" ASAN_OPTIONS=detect_leaks=0 RROSFUZZ_NATIVE_MODULE=$(COV_MODULE) \
	  $(PY) fuzz_diff.py $(FUZZ_ARGS)

## The native URDF loader under ASan for 10 minutes (tests/fuzz_urdf_loader.py; CI runs a
## bounded version in tests/test_fuzz_urdf_loader.py). Corpus and crash files: FUZZ_URDF_DIR.
FUZZ_URDF_DIR ?= build/fuzz-urdf
FUZZ_URDF_ARGS ?= -max_total_time=600 -timeout=30
.PHONY: fuzz-urdf
fuzz-urdf: native-cov
	$(NO_SPACE)
	mkdir -p $(FUZZ_URDF_DIR)/corpus
	LD_PRELOAD=$(ATHERIS_PRELOAD) ASAN_OPTIONS=detect_leaks=0 RROSFUZZ_NATIVE_MODULE=$(COV_MODULE) \
	  $(PY) tests/fuzz_urdf_loader.py $(FUZZ_URDF_ARGS) -artifact_prefix=$(CURDIR)/$(FUZZ_URDF_DIR)/ \
	  $(FUZZ_URDF_DIR)/corpus
