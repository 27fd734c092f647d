# The README's entry points. `make demo` and `make test` set up the machine
# (scripts/install-deps.sh), configure, build and run.
BUILD_DIR ?= build
ASAN_DIR  ?= build-asan
ASAN_ALL_DIR ?= build-asan-clang
TSAN_DIR  ?= build-tsan
JOBS      ?= $(shell nproc)
CTEST_ARGS ?=
# ctest, then the number of skipped tests and why (scripts/ctest_with_skips.sh).
CTEST     = bash scripts/ctest_with_skips.sh

.PHONY: all deps configure build demo test test-fast asan-configure test-asan test-asan-all test-fuzz \
	fuzz tsan-configure test-tsan test-tsan-all eval bench format tidy clean

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

# Whole suite; then the calib core tests once more under ASan+UBSan and the threaded calib tests
# under TSan. The suite includes the static thread-contract check (label threads: clang
# -Wthread-safety over the threaded sources with $(BUILD_DIR)/compile_commands.json, no extra
# build tree). The fuzz runs and the whole suite under the sanitizers (test-fuzz,
# test-asan-all, test-tsan-all) are not yet part of make test: README "Sanitizers and fuzzing".
test: build test-asan test-tsan
	$(CTEST) $(BUILD_DIR) --output-on-failure -j $(JOBS) -LE 'eval|soak' $(CTEST_ARGS)

test-fast: build
	$(CTEST) $(BUILD_DIR) --output-on-failure -j $(JOBS) -LE 'eval|soak' $(CTEST_ARGS)

SAN_ENV = ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

# The calib core tests (label calib_core: they link only the calib library) under ASan+UBSan,
# with GCC, the compiler of the normal build.
test-asan: deps
	$(call cmake_configure,$(ASAN_DIR),RelWithDebInfo,-DRIGCAL_ASAN_ENABLED=ON -DRIGCAL_BUILD_BENCHMARKS=OFF)
	cmake --build $(ASAN_DIR) -j $(JOBS) --target rigcal_calib_tests
	$(SAN_ENV) $(CTEST) $(ASAN_DIR) --output-on-failure -j $(JOBS) -L calib_core -LE eval

# The clang sanitizer trees: -O1 with line tables only (cheap to build, readable stacks), no
# benchmarks, no evaluations. $(ASAN_ALL_DIR) is one tree for ASan+UBSan and libFuzzer: the
# libraries the fuzz targets exercise carry coverage feedback (-fsanitize=fuzzer-no-link), the
# targets link -fsanitize=fuzzer (cmake/RigcalFuzz.cmake).
SAN_CMAKE_ARGS = -DCMAKE_CXX_COMPILER=clang++ -DRIGCAL_BUILD_BENCHMARKS=OFF \
  -DRIGCAL_BUILD_EVAL_TESTS=OFF "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only -DNDEBUG"
FUZZ_SECONDS ?= 600

asan-configure: deps
	$(call cmake_configure,$(ASAN_ALL_DIR),RelWithDebInfo,$(SAN_CMAKE_ARGS) -DRIGCAL_ASAN_ENABLED=ON -DRIGCAL_FUZZ_ENABLED=ON)

# Every test except the evaluations, the fuzz runs, the soak and the VM tests, under ASan+UBSan.
test-asan-all: asan-configure
	cmake --build $(ASAN_ALL_DIR) -j $(JOBS)
	$(SAN_ENV) $(CTEST) $(ASAN_ALL_DIR) --output-on-failure -j $(JOBS) -LE 'eval|fuzz|soak|device' $(CTEST_ARGS)

# Each fuzz target for the configured time (label fuzz, RIGCAL_FUZZ_SECONDS); `make fuzz` for
# FUZZ_SECONDS each (default 600), one at a time. Findings: $(ASAN_ALL_DIR)/fuzz/<target>/.
test-fuzz: asan-configure
	cmake --build $(ASAN_ALL_DIR) -j $(JOBS) --target rigcal_fuzz_targets
	$(CTEST) $(ASAN_ALL_DIR) --output-on-failure --no-tests=error -j $(JOBS) -L fuzz

fuzz: asan-configure
	cmake --build $(ASAN_ALL_DIR) -j $(JOBS) --target rigcal_fuzz_targets
	RIGCAL_FUZZ_SECONDS=$(FUZZ_SECONDS) $(CTEST) $(ASAN_ALL_DIR) --output-on-failure --no-tests=error -V -L fuzz

TSAN_ENV = TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1
tsan-configure: deps
	$(call cmake_configure,$(TSAN_DIR),RelWithDebInfo,$(SAN_CMAKE_ARGS) -DRIGCAL_TSAN_ENABLED=ON)

# The multi-threaded calib tests (SyncBuffer producers, PoseMerge, OnlineCalibrator threads)
# under TSan.
test-tsan: tsan-configure
	cmake --build $(TSAN_DIR) -j $(JOBS) --target calib_sync_buffer_threads_test calib_online_calibrator_test \
	  calib_pose_merge_test calib_online_calibrator_lossless_test
	$(TSAN_ENV) $(CTEST) $(TSAN_DIR) --output-on-failure -j $(JOBS) -R 'calib/(sync_buffer_threads|online_calibrator|pose_merge)'

# Every test that starts threads (label threaded: the Pipeline, the calib node, capture loops, the
# log recorder, online replay, OnlineCalibrator, SyncBuffer, the research runners) under TSan; the
# tree builds only those tests (target rigcal_threaded_tests) and what they link.
test-tsan-all: tsan-configure
	cmake --build $(TSAN_DIR) -j $(JOBS) --target rigcal_threaded_tests
	$(TSAN_ENV) $(CTEST) $(TSAN_DIR) --output-on-failure --no-tests=error -j $(JOBS) -L threaded -LE 'eval|soak|device'

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
	rm -rf $(BUILD_DIR) $(ASAN_DIR) $(ASAN_ALL_DIR) $(TSAN_DIR)
