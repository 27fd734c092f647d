#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Cross-builds the rigcal command for arm64 (aarch64 Debian 12) with Debian's cross compiler
# and Debian's arm64 libraries (docs/deployment.md):
#   1. host tools: crossbuild-essential-arm64 (aarch64-linux-gnu-g++), qemu-user (qemu-aarch64,
#      to run the result here), mmdebstrap (the sysroot); installed when missing (root/sudo);
#   2. scripts/arm64-sysroot.sh: the arm64 -dev packages of every dependency in a sysroot;
#   3. cmake with cmake/toolchain-arm64.cmake into BUILD_DIR (default build-arm64): the
#      `rigcal` target only (no tests, no benchmarks), through ccache when present;
#   4. with --package: `cpack` of the rigcal and rigcal-dev packages for arm64, with the
#      Debian dependencies dpkg-shlibdeps found for the amd64 package (--depends-from DEB).
# --setup: steps 1 and 2 only (exit 0 when the tools and the sysroot are there).
# usage: scripts/cross-arm64.sh [--setup] [--build-dir DIR] [--package] [--depends-from AMD64.deb]
# Environment: RIGCAL_ARM64_SYSROOT (default /var/cache/rigcal/arm64-sysroot), JOBS (2),
# NICE (5). Exit 0 when bin/rigcal was built (and packaged).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build_dir="$here/build-arm64"
package=0
setup_only=0
depends_from=""
while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) build_dir=$(readlink -f "$2"); shift 2 ;;
    --package) package=1; shift ;;
    --setup) setup_only=1; shift ;;
    --depends-from) depends_from=$(readlink -f "$2"); shift 2 ;;
    -h | --help) awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "$0"; exit 0 ;;
    *) echo "cross-arm64: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
sysroot=${RIGCAL_ARM64_SYSROOT:-/var/cache/rigcal/arm64-sysroot}
jobs=${JOBS:-2}
niceness=${NICE:-5}

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
missing=()
command -v aarch64-linux-gnu-g++ >/dev/null || missing+=(crossbuild-essential-arm64)
command -v qemu-aarch64 >/dev/null || missing+=(qemu-user)
command -v mmdebstrap >/dev/null || [ -f "$sysroot/.rigcal-sysroot" ] || missing+=(mmdebstrap)
if [ ${#missing[@]} -gt 0 ]; then
  echo "cross-arm64: installing ${missing[*]}"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

for tool in aarch64-linux-gnu-g++ qemu-aarch64; do
  command -v "$tool" >/dev/null || { echo "cross-arm64: $tool missing" >&2; exit 1; }
done
RIGCAL_ARM64_SYSROOT="$sysroot" bash "$here/scripts/arm64-sysroot.sh"
if [ "$setup_only" = 1 ]; then exit 0; fi

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
if [ ! -f "$build_dir/CMakeCache.txt" ]; then
  cmake -S "$here" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_TOOLCHAIN_FILE="$here/cmake/toolchain-arm64.cmake" -DRIGCAL_ARM64_SYSROOT="$sysroot" \
    "${launcher[@]}" -DRIGCAL_BUILD_TESTS=OFF -DRIGCAL_BUILD_BENCHMARKS=OFF \
    -DCPACK_DEBIAN_PACKAGE_ARCHITECTURE=arm64
fi
start=$(date +%s)
nice -n "$niceness" cmake --build "$build_dir" -j "$jobs" --target rigcal
echo "cross-arm64: $build_dir/tools/rigcal built in $(( $(date +%s) - start )) s"

if [ "$package" = 1 ]; then
  if [ -z "$depends_from" ]; then
    echo "cross-arm64: --package needs --depends-from AMD64.deb (the amd64 rigcal package)" >&2
    exit 2
  fi
  depends=$(dpkg-deb -f "$depends_from" Depends)
  # cpack installs every component, so the jar and Python types need their targets built.
  nice -n "$niceness" cmake --build "$build_dir" -j "$jobs" --target rigcal_lcmtypes_other
  (cd "$build_dir" && cpack -G DEB -D "CPACK_DEBIAN_RUNTIME_PACKAGE_DEPENDS=$depends" \
     -D CPACK_DEBIAN_RUNTIME_PACKAGE_SHLIBDEPS=OFF -D CPACK_DEBIAN_PACKAGE_ARCHITECTURE=arm64)
  ls -l "$build_dir"/*.deb
fi
