#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs the Debian packages rigcal needs to build and test. Idempotent: packages
# already present are skipped, so a second run changes nothing and needs no network.
# Works as root, or through sudo for a normal user.
#   scripts/install-deps.sh           everything rigcal builds and tests with
#   scripts/install-deps.sh --runtime only what building and running the `rigcal` command needs
#                                     (`make demo`): the compiler, CMake and the libraries it
#                                     links; no test, packaging, emulation or cross tools
#   scripts/install-deps.sh --flash   only what `make flash` needs: the ARM cross toolchain and the
#                                     flashing tools (st-flash, openocd, dfu-util); they are in no
#                                     other list (docs/firmware.md "Flashing")
set -euo pipefail

# One line per package, with why it is there (docs/testing.md "Dependencies").
# What building and running `rigcal` needs (`make demo`, `--runtime`).
RUNTIME_PACKAGES=(
  build-essential      # compiler
  cmake                # build system
  ninja-build          # faster builds
  pkg-config           # finds libraries without CMake configs
  libeigen3-dev        # linear algebra of calib/
  libceres-dev         # non-linear refinement and covariance
  libyaml-cpp-dev      # config, truth and result files
  libcli11-dev         # command line of the rigcal tool
  libspdlog-dev        # logging, one logger per module
  nlohmann-json3-dev   # --json output
  libopencv-dev        # VO, the simulated renderer's images, calibration patterns (with contrib)
  liblcm-dev           # LCM messaging: RIGCAL_EXTRINSICS/STATUS/POSE/IMAGE (lcmtypes/, tools/)
  liblcm-bin           # lcm-gen (build-time message generation), lcm-logger, lcm-logplayer
  libglib2.0-dev       # lcm.pc requires glib-2.0 and gthread-2.0
  libcamera-dev        # the libcamera capture source (optional at build time: disabled without it)
  libsystemd-dev       # sd_notify: READY=1 and the watchdog of rigcal.service (optional at build)
)
# What the tests, packaging checks, emulators and cross builds need besides (`make test`).
TEST_PACKAGES=(
  libgtest-dev         # unit tests
  libgmock-dev         # unit tests (matchers)
  libbenchmark-dev     # benchmarks under tests/bench
  clang                # ctest architecture/threads: clang's -Wthread-safety on the annotated locks
  libclang-rt-14-dev   # make test-tsan/test-asan-clang/test-fuzz: the sanitizer and libFuzzer runtimes of clang
  chromium             # ctest report/report_browser: renders `rigcal report`'s HTML headless
  libcamera-ipa        # ctest device/qemu: libcamera's vimc IPA module, copied into the test VM
  qemu-system-x86      # ctest device/qemu: a Debian kernel with real V4L2 drivers, emulated
  busybox-static       # ctest device/qemu: the test VM's userland
  cpio                 # ctest device/qemu: packs the test VM's initramfs
  linux-headers-amd64  # ctest device/qemu: builds vimc and v4l2loopback for the VM's kernel
  linux-source-6.1     # ctest device/qemu: vimc's source (Debian's kernel does not enable it)
  v4l2loopback-dkms    # ctest device/qemu: v4l2loopback's source
  gcc-arm-none-eabi    # cross-builds the trigger firmware (firmware/board/stm32f405)
  libnewlib-arm-none-eabi          # its C library (nano specs)
  libstdc++-arm-none-eabi-newlib   # its freestanding C++ headers
  qemu-system-arm      # ctest label firmware: runs the firmware on an emulated STM32F405
  default-jdk-headless # javac: rigcal_lcmtypes.jar for lcm-spy (install, deb tests)
  liblcm-java          # lcm.jar (javac classpath) and lcm-spy
  libjchart2d-java     # lcm-spy's charts (its start script names the jar; liblcm-java lacks it)
  lintian              # ctest install/deb_package: lints the rigcal .deb packages
  systemd              # ctest install/systemd_units: systemd-analyze verify of config/systemd
  python3              # ctest install/sd_notify: stands in for systemd's notify socket
  python3-yaml         # ctest io/camchain_kalibr: reads --camchain as Kalibr's camchain schema
  universal-ctags      # ctest architecture/function_length: each function's first and last line
  crossbuild-essential-arm64  # ctest install/arm64_qemu: the arm64 cross compiler
  qemu-user            # ctest install/arm64_qemu: qemu-aarch64 runs the arm64 build here
  mmdebstrap           # scripts/arm64-sysroot.sh: Debian's arm64 -dev packages in a sysroot
)
PACKAGES=("${RUNTIME_PACKAGES[@]}" "${TEST_PACKAGES[@]}")

case "${1:-}" in
  "" | --runtime | --flash) ;;
  *) echo "usage: scripts/install-deps.sh [--runtime | --flash]" >&2; exit 2 ;;
esac
if [ "${1:-}" = "--runtime" ]; then
  PACKAGES=("${RUNTIME_PACKAGES[@]}")
elif [ "${1:-}" = "--flash" ]; then
  PACKAGES=(
    gcc-arm-none-eabi                # cross-builds the trigger firmware
    libnewlib-arm-none-eabi          # its C library (nano specs)
    libstdc++-arm-none-eabi-newlib   # its freestanding C++ headers
    stlink-tools                     # st-flash: make flash FLASH_TOOL=st-flash (ST-LINK probe)
    openocd                          # make flash FLASH_TOOL=openocd (ST-LINK or CMSIS-DAP probe)
    dfu-util                         # make flash FLASH_TOOL=dfu-util (USB DFU, BOOT0 high)
  )
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "install-deps: need root or sudo to install: ${missing[*]}" >&2
    exit 1
  fi
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "install-deps: done"
