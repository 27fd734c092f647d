# The README's entry points. `make demo` and `make test` set up the machine
# (scripts/install-deps.sh), configure, build and run.
BUILD_DIR ?= build
ASAN_DIR  ?= build-asan
TSAN_DIR  ?= build-tsan
JOBS      ?= $(shell nproc)
CTEST_ARGS ?=
# ctest, then the number of skipped tests and why (scripts/ctest_with_skips.sh).
CTEST     = bash scripts/ctest_with_skips.sh

.PHONY: all deps configure build demo test test-fast test-asan test-tsan eval bench format tidy clean

all: build

deps:
	@bash scripts/install-deps.sh

# Ninja when it is there, else Makefiles.
define cmake_configure
	@if [ ! -f $(1)/CMakeCache.txt ]; then \
	  gen=""; command -v ninja >/dev/null 2>&1 && gen="-G Ninja"; \
	  cmake -S . -B $(1) $$gen -DCMAKE_BUILD_TYPE=$(2) $(3); \
	fi
endef

configure: deps
	$(call cmake_configure,$(BUILD_DIR),Release,)

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

# The whole live pipeline on the built-in simulated rig (thesis 5.4 virtual scene): rendered
# images -> VO per camera -> SyncBuffer -> RigEstimator, errors against the truth at the end.
demo: build
	./$(BUILD_DIR)/tools/rigcal run --config config/sim_thesis_virtual.yaml --eval --out $(BUILD_DIR)/demo_result.yaml

# Whole suite, then the calib tests once more under ASan+UBSan and the threaded ones under TSan
# (sanitizer builds compile only the calib library and its own tests: label calib_core). The
# suite includes the static thread-contract check (label threads: clang -Wthread-safety over
# the threaded sources with $(BUILD_DIR)/compile_commands.json, no extra build tree).
test: build test-asan test-tsan
	$(CTEST) $(BUILD_DIR) --output-on-failure -j $(JOBS) -LE 'eval|soak' $(CTEST_ARGS)

test-fast: build
	$(CTEST) $(BUILD_DIR) --output-on-failure -j $(JOBS) -LE 'eval|soak' $(CTEST_ARGS)

test-asan: deps
	$(call cmake_configure,$(ASAN_DIR),RelWithDebInfo,-DRIGCAL_ASAN_ENABLED=ON -DRIGCAL_BUILD_BENCHMARKS=OFF)
	cmake --build $(ASAN_DIR) -j $(JOBS) --target rigcal_calib_tests
	ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  $(CTEST) $(ASAN_DIR) --output-on-failure -j $(JOBS) -L calib_core -LE eval

# The multi-threaded calib tests (SyncBuffer producers, PoseMerge, OnlineCalibrator threads)
# under TSan.
test-tsan: deps
	$(call cmake_configure,$(TSAN_DIR),RelWithDebInfo,-DRIGCAL_TSAN_ENABLED=ON -DRIGCAL_BUILD_BENCHMARKS=OFF)
	cmake --build $(TSAN_DIR) -j $(JOBS) --target calib_sync_buffer_threads_test calib_online_calibrator_test \
	  calib_pose_merge_test calib_online_calibrator_lossless_test
	TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 \
	  $(CTEST) $(TSAN_DIR) --output-on-failure -j $(JOBS) -R 'calib/(sync_buffer_threads|online_calibrator|pose_merge)'

# Long evaluations (not part of make test).
eval: build
	$(CTEST) $(BUILD_DIR) --output-on-failure -L eval

bench: build
	./$(BUILD_DIR)/tests/bench/rigcal_calib_bench

format:
	find calib vo drivers tools tests -name '*.h' -o -name '*.cc' | xargs clang-format -i

tidy: build
	find calib/src calib/camera/src vo/src drivers/src tools/*/src tools/cli -name '*.cc' | xargs clang-tidy -p $(BUILD_DIR) --quiet

clean:
	rm -rf $(BUILD_DIR) $(ASAN_DIR) $(TSAN_DIR)
