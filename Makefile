# SPDX-License-Identifier: Apache-2.0
# The README's entry points. `make demo` and `make test` set up the machine
# (scripts/install-deps.sh: `--runtime` for the demo, everything for the tests), configure, build
# and run.
BUILD_DIR ?= build
ASAN_DIR  ?= build-asan
ASAN_ALL_DIR ?= build-asan-clang
TSAN_DIR  ?= build-tsan
JOBS      ?= $(shell nproc)
CTEST_ARGS ?=
# ctest, then the number of skipped tests and why (scripts/ctest_with_skips.sh).
CTEST     = bash scripts/ctest_with_skips.sh

.PHONY: all deps deps-runtime configure demo-configure build demo test test-suite test-fast test-core test-asan-core test-asan-core-clang test-tsan-core \
	asan-configure test-asan test-asan-gcc \
	test-fuzz fuzz tsan-configure test-tsan test-arm64 eval bench format tidy clean firmware flash docs

all: build

deps:
	@bash scripts/install-deps.sh

deps-runtime:
	@bash scripts/install-deps.sh --runtime

# Ninja when it is there, else Makefiles.
define cmake_configure
	@if [ ! -f $(1)/CMakeCache.txt ]; then \
	  gen=""; command -v ninja >/dev/null 2>&1 && gen="-G Ninja"; \
	  cmake -S . -B $(1) $$gen -DCMAKE_BUILD_TYPE=$(2) $(3); \
	fi
endef

# The evaluations and benchmarks are built by `make eval` / `make bench` (not by make test,
# which does not run them).
RELEASE_ARGS = -DRIGCAL_BUILD_EVAL_TESTS=OFF -DRIGCAL_BUILD_BENCHMARKS=OFF

# A tree configured by `make demo` (tests off: GoogleTest is not installed by --runtime) gets its
# tests turned on here.
configure: deps
	$(call cmake_configure,$(BUILD_DIR),Release,$(RELEASE_ARGS))
	@if grep -q '^RIGCAL_BUILD_TESTS:BOOL=OFF' $(BUILD_DIR)/CMakeCache.txt; then \
	  cmake -S . -B $(BUILD_DIR) -DRIGCAL_BUILD_TESTS=ON; fi

demo-configure: deps-runtime
	$(call cmake_configure,$(BUILD_DIR),Release,$(RELEASE_ARGS) -DRIGCAL_BUILD_TESTS=OFF)

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

# The whole live pipeline on the built-in simulated rig (thesis 5.4 virtual scene): rendered
# images -> VO per camera -> SyncBuffer -> RigEstimator, errors against the truth at the end.
# Installs only the runtime packages and builds only the `rigcal` target.
demo: demo-configure
	cmake --build $(BUILD_DIR) -j $(JOBS) --target rigcal
	./$(BUILD_DIR)/tools/rigcal run --config config/sim_thesis_virtual.yaml --eval --out $(BUILD_DIR)/demo_result.yaml

# docs/commands.md from the help texts of the built rigcal (ctest cli/commands_doc checks it).
docs:
	cmake --build $(BUILD_DIR) -j $(JOBS) --target rigcal
	bash scripts/gen-command-docs.sh $(BUILD_DIR)/tools/rigcal markdown docs/commands.md

# The Release tree's build, the threaded calib tests under TSan (test-tsan-core), the arm64 build
# under qemu-aarch64 (test-arm64, below; excluded from the suite run), then the whole suite in the
# Release tree. The suite includes the static thread-contract check (label threads: clang
# -Wthread-safety over the threaded sources with the tree's compile_commands.json, no extra tree).
# The sanitizer runs are not part of make test, for its time (it took 50-58 min on CI with the
# calib core under GCC's ASan, 873 s of it here): the calib core under ASan+UBSan
# (test-asan-core), the whole suite under ASan+UBSan in the clang tree (test-asan), the fuzz runs
# (test-fuzz) and every threaded test under TSan (test-tsan) run before an issue that touches
# threads, parsers, file handling or the estimator state is resolved; docs/testing.md
# "Sanitizers and fuzzing".
# Each stage is timed (scripts/make_stages.sh prints the table at the end).
test:
	@bash scripts/make_stages.sh build test-tsan-core test-arm64 test-suite

# The suite in the Release tree, without the arm64 test (test-arm64) and the long evaluations.
test-suite: build
	$(CTEST) $(BUILD_DIR) --output-on-failure -j $(JOBS) -LE 'eval|soak|arm64' $(CTEST_ARGS)

# The whole suite in the Release tree (the quick loop while working; no sanitizer).
test-fast: build
	$(CTEST) $(BUILD_DIR) --output-on-failure -j $(JOBS) -LE 'eval|soak' $(CTEST_ARGS)

# The calib core tests (label calib_core: they link only the calib library) in the Release tree;
# builds only them (target rigcal_calib_tests), `make build` builds the rest of the tree.
test-core: configure
	cmake --build $(BUILD_DIR) -j $(JOBS) --target rigcal_calib_tests
	$(CTEST) $(BUILD_DIR) --output-on-failure --no-tests=error -j $(JOBS) -L calib_core -LE eval $(CTEST_ARGS)

SAN_ENV = ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

# The sanitizer tree of make test: clang, ASan+UBSan (any finding is an error), -O1 with line
# tables, NDEBUG as in Release; the libraries the fuzz targets exercise carry libFuzzer's coverage
# feedback (-fsanitize=fuzzer-no-link), the targets link -fsanitize=fuzzer
# (cmake/RigcalFuzz.cmake). It builds every test and fuzz target; no benchmarks, no evaluations.
SAN_CMAKE_ARGS = -DCMAKE_CXX_COMPILER=clang++ -DRIGCAL_BUILD_BENCHMARKS=OFF \
  -DRIGCAL_BUILD_EVAL_TESTS=OFF "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only -DNDEBUG"
FUZZ_SECONDS ?= 600

asan-configure: deps
	$(call cmake_configure,$(ASAN_ALL_DIR),RelWithDebInfo,$(SAN_CMAKE_ARGS) -DRIGCAL_ASAN_ENABLED=ON -DRIGCAL_FUZZ_ENABLED=ON)

# Not run under the sanitizers (they run in the Release tree), as their subject is not our code
# in this process: the evaluations and the soak (too slow); `device` (QEMU guest with the kernel's
# V4L2/libcamera drivers), firmware/qemu_firmware (the ARM firmware image under QEMU);
# `architecture` (CMake checks of the layers and clang's static -Wthread-safety check: no code of
# the tree runs); install/consumer, deb_package, systemd_units (packaging: cmake --install, dpkg,
# systemd-analyze); cli/doc_examples (README's live `rigcal run` at 20 Hz: a sanitized VO takes
# ~270 ms a frame and drops nine frames in ten, so the example's result says so; the commands it
# runs are sanitized in cli/run_command and the other cli tests). The fuzz label runs in test-fuzz.
SAN_EXCLUDE_LABELS = eval|soak|fuzz|device|architecture
SAN_EXCLUDE_TESTS = ^(firmware/qemu_firmware|install/(consumer|deb_package|systemd_units)|cli/doc_examples)$$

# Every other test under ASan+UBSan in the clang tree.
test-asan: asan-configure
	cmake --build $(ASAN_ALL_DIR) -j $(JOBS)
	$(SAN_ENV) $(CTEST) $(ASAN_ALL_DIR) --output-on-failure -j $(JOBS) \
	  -LE '$(SAN_EXCLUDE_LABELS)' -E '$(SAN_EXCLUDE_TESTS)' $(CTEST_ARGS)

# The calib core tests (label calib_core: they link only the calib library) under ASan+UBSan,
# with GCC, in the tree of test-asan-gcc (of which it builds only rigcal_calib_tests; configured
# -O1 -g1 when it comes first, as make test runs it on CI: line tables for the reports). GCC's
# ASan+UBSan is costly to compile: rig_estimator.cc takes 21 s at -O1 -g1, 34 s at -O2 -g1 and
# ~1.5x that at -O2 -g (10 s in Release).
test-asan-core: deps
	$(call cmake_configure,$(ASAN_DIR),RelWithDebInfo,-DRIGCAL_ASAN_ENABLED=ON -DRIGCAL_BUILD_BENCHMARKS=OFF "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG")
	cmake --build $(ASAN_DIR) -j $(JOBS) --target rigcal_calib_tests
	$(SAN_ENV) $(CTEST) $(ASAN_DIR) --output-on-failure -j $(JOBS) -L calib_core -LE eval $(CTEST_ARGS)

# The same in the clang tree (build-asan-clang/), building only them.
test-asan-core-clang: asan-configure
	cmake --build $(ASAN_ALL_DIR) -j $(JOBS) --target rigcal_calib_tests
	$(SAN_ENV) $(CTEST) $(ASAN_ALL_DIR) --output-on-failure --no-tests=error -j $(JOBS) -L calib_core -LE eval $(CTEST_ARGS)

# The same suite under GCC's ASan+UBSan (build-asan/, -O1 -g1; not part of make test), for a
# second compiler's view; the tree builds everything, benchmarks and evaluations included.
test-asan-gcc: deps
	$(call cmake_configure,$(ASAN_DIR),RelWithDebInfo,-DRIGCAL_ASAN_ENABLED=ON "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG")
	cmake --build $(ASAN_DIR) -j $(JOBS)
	$(SAN_ENV) $(CTEST) $(ASAN_DIR) --output-on-failure -j $(JOBS) \
	  -LE '$(SAN_EXCLUDE_LABELS)' -E '$(SAN_EXCLUDE_TESTS)' $(CTEST_ARGS)

# Each fuzz target for the configured time (label fuzz, RIGCAL_FUZZ_SECONDS, 30 s), two at a
# time; `make fuzz` for FUZZ_SECONDS each (default 600), one at a time. Findings:
# $(ASAN_ALL_DIR)/fuzz/<target>/.
test-fuzz: asan-configure
	cmake --build $(ASAN_ALL_DIR) -j $(JOBS) --target rigcal_fuzz_targets
	$(CTEST) $(ASAN_ALL_DIR) --output-on-failure --no-tests=error -j 2 -L fuzz

fuzz: asan-configure
	cmake --build $(ASAN_ALL_DIR) -j $(JOBS) --target rigcal_fuzz_targets
	RIGCAL_FUZZ_SECONDS=$(FUZZ_SECONDS) $(CTEST) $(ASAN_ALL_DIR) --output-on-failure --no-tests=error -V -L fuzz

TSAN_ENV = TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1:suppressions=$(CURDIR)/tests/sanitizers/tsan.supp
tsan-configure: deps
	$(call cmake_configure,$(TSAN_DIR),RelWithDebInfo,$(SAN_CMAKE_ARGS) -DRIGCAL_TSAN_ENABLED=ON)

# Every test that starts threads (label threaded: the Pipeline, the calib node, capture loops, the
# log recorder, online replay, OnlineCalibrator, SyncBuffer, the research runners) under TSan; the
# tree builds only those tests (target rigcal_threaded_tests) and what they link.
test-tsan: tsan-configure
	cmake --build $(TSAN_DIR) -j $(JOBS) --target rigcal_threaded_tests
	$(TSAN_ENV) $(CTEST) $(TSAN_DIR) --output-on-failure --no-tests=error -j $(JOBS) -L threaded -LE 'eval|soak|device' $(CTEST_ARGS)

# The multi-threaded calib tests (SyncBuffer producers, PoseMerge, OnlineCalibrator threads)
# under TSan, in the tree of test-tsan.
test-tsan-core: tsan-configure
	cmake --build $(TSAN_DIR) -j $(JOBS) --target calib_sync_buffer_threads_test calib_online_calibrator_test \
	  calib_pose_merge_test calib_online_calibrator_lossless_test
	$(TSAN_ENV) $(CTEST) $(TSAN_DIR) --output-on-failure -j $(JOBS) -R 'calib/(sync_buffer_threads|online_calibrator|pose_merge)' $(CTEST_ARGS)

# arm64 (docs/deployment.md): ctest install/arm64_qemu (label arm64, registered by
# -DRIGCAL_TEST_ARM64=ON) cross-builds `rigcal` into $(BUILD_DIR)/arm64 against an arm64 sysroot
# of Debian's -dev packages (kept in $(ARM64_SYSROOT) across builds) and runs it under
# qemu-aarch64. Skipped with its reason when the arm64 packages cannot be had (a failure under
# CI=true). Cold: sysroot 1.5-2 min of downloads, cross build 86 min on the loaded 2-core
# machine; with a warm ccache a fresh cross tree builds in ~1 min, the test then runs ~70 s.
ARM64_SYSROOT ?= /var/cache/rigcal/arm64-sysroot
test-arm64: build
	cmake -S . -B $(BUILD_DIR) -DRIGCAL_TEST_ARM64=ON > /dev/null
	RIGCAL_ARM64_SYSROOT=$(ARM64_SYSROOT) $(CTEST) $(BUILD_DIR) --output-on-failure --no-tests=error -L arm64 $(CTEST_ARGS)

# Long evaluations (not part of make test).
eval: configure
	cmake -S . -B $(BUILD_DIR) -DRIGCAL_BUILD_EVAL_TESTS=ON > /dev/null
	cmake --build $(BUILD_DIR) -j $(JOBS)
	$(CTEST) $(BUILD_DIR) --output-on-failure -L eval

bench: configure
	cmake -S . -B $(BUILD_DIR) -DRIGCAL_BUILD_BENCHMARKS=ON > /dev/null
	cmake --build $(BUILD_DIR) -j $(JOBS) --target rigcal_calib_bench
	./$(BUILD_DIR)/tests/bench/rigcal_calib_bench

# The trigger firmware on its own (no host libraries needed): firmware/board/stm32f405 cross-built
# for the board's crystal, HSE_MHZ (8, 12, 16 or 25). Images: $(FW_BUILD_DIR)/trigger_firmware.elf,
# .bin, .hex, with a flash / RAM report; docs/firmware.md.
FW_BUILD_DIR ?= build-fw
HSE_MHZ ?= 8
FW_IMAGE = $(FW_BUILD_DIR)/trigger_firmware
firmware:
	@bash scripts/install-deps.sh --flash
	cmake -S firmware/board/stm32f405 -B $(FW_BUILD_DIR) -DCMAKE_BUILD_TYPE=MinSizeRel \
	  -DCMAKE_TOOLCHAIN_FILE=$(CURDIR)/firmware/board/stm32f405/arm-none-eabi.cmake \
	  -DTRIGGER_HSE_HZ=$(HSE_MHZ)000000
	cmake --build $(FW_BUILD_DIR) --target trigger_firmware.elf

# Writes the firmware into a connected STM32F405 board at 0x08000000 (docs/firmware.md
# "Flashing"). FLASH_TOOL: st-flash (an ST-LINK on SWD; default), openocd (ST-LINK through
# OpenOCD, verifies), dfu-util (the ROM bootloader over USB: BOOT0 high, USB on PA11/PA12).
FLASH_TOOL ?= st-flash
flash: firmware
	@case "$(FLASH_TOOL)" in \
	  st-flash) st-flash --reset write $(FW_IMAGE).bin 0x08000000 ;; \
	  openocd) openocd -f interface/stlink.cfg -f target/stm32f4x.cfg \
	             -c "program $(FW_IMAGE).elf verify reset exit" ;; \
	  dfu-util) dfu-util -a 0 -s 0x08000000:leave -D $(FW_IMAGE).bin ;; \
	  *) echo "FLASH_TOOL must be st-flash, openocd or dfu-util" >&2; exit 2 ;; \
	esac

format:
	find calib vo drivers tools tests -name '*.h' -o -name '*.cc' | xargs clang-format -i

# clang-tidy needs one compile command per source: a configure-only tree without unity batches
# (and the generated LCM headers).
TIDY_DIR ?= build-tidy
tidy: deps
	$(call cmake_configure,$(TIDY_DIR),Release,-DRIGCAL_UNITY_BUILD=OFF)
	cmake --build $(TIDY_DIR) --target rigcal_lcmtypes_cpp
	find calib/base/src calib/src calib/camera/src vo/src drivers/*/src tools/*/src tools/cli -name '*.cc' | xargs clang-tidy -p $(TIDY_DIR) --quiet

clean:
	rm -rf $(BUILD_DIR) $(ASAN_DIR) $(ASAN_ALL_DIR) $(TSAN_DIR) $(TIDY_DIR) $(FW_BUILD_DIR)
