#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Creates the arm64 sysroot the cross build links against (cmake/toolchain-arm64.cmake):
# Debian's own arm64 -dev packages of every rigcal dependency and their closure, unpacked by
# mmdebstrap (variant extract, apt resolving the arm64 dependencies) into a directory with the
# multiarch layout (usr/lib/aarch64-linux-gnu). Nothing is installed into this machine's dpkg
# database: libopencv-dev, libyaml-cpp-dev, liblcm-dev and libgoogle-glog-dev are not
# `Multi-Arch: same`, so `dpkg --add-architecture arm64; apt-get install libopencv-dev:arm64`
# would remove their amd64 versions and break the native build. The same directory is the
# QEMU_LD_PREFIX of qemu-aarch64 (the arm64 loader and shared libraries).
#
# usage: scripts/arm64-sysroot.sh [SYSROOT]   (default $RIGCAL_ARM64_SYSROOT or
#        /var/cache/rigcal/arm64-sysroot). Idempotent: a complete sysroot (stamp file listing
#        the packages) is kept. Needs root (or sudo), mmdebstrap and Debian's mirrors.
set -euo pipefail

SYSROOT=${RIGCAL_ARM64_SYSROOT:-/var/cache/rigcal/arm64-sysroot}
if [ $# -gt 0 ] && [ "$1" != --fix-only ]; then SYSROOT=$1; fi

# The arm64 counterparts of scripts/install-deps.sh's libraries (build-time only, no tools).
PACKAGES=(
  libc6-dev libstdc++-12-dev
  libeigen3-dev libceres-dev libspdlog-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  liblcm-dev libglib2.0-dev libopencv-dev libsystemd-dev libcamera-dev
)
wanted="${PACKAGES[*]}"

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
if ! command -v mmdebstrap >/dev/null 2>&1; then
  echo "arm64-sysroot: mmdebstrap missing (apt-get install mmdebstrap)" >&2
  exit 1
fi

# Debian 12 (bookworm), as this machine and the target boards run.
mirrors=(
  "deb http://deb.debian.org/debian bookworm main"
  "deb http://deb.debian.org/debian bookworm-updates main"
  "deb http://deb.debian.org/debian-security bookworm-security main"
)

# Unpacked, not installed: no maintainer script ran, and the files were made for /. What
# matters to a linker working in a sysroot:
# - absolute symlinks (libz.so -> /lib/aarch64-linux-gnu/libz.so.1) would point into this
#   machine's root: made relative to the sysroot;
# - update-alternatives provides libblas.so.3 / liblapack.so.3 (Ceres needs them): linked to
#   the implementation that was unpacked (reference BLAS, ATLAS or OpenBLAS).
rigcal_fix_sysroot() {
  local root=$1 link target rel dir impl name
  while IFS= read -r -d '' link; do
    target=$(readlink "$link")
    case "$target" in /*) ;; *) continue ;; esac
    rel=$(realpath -m --relative-to="$(dirname "$link")" "$root$target")
    $SUDO ln -sfn "$rel" "$link"
  done < <(find "$root/usr" -type l -print0)
  dir="$root/usr/lib/aarch64-linux-gnu"
  # Ceres's exported targets name BLAS/LAPACK by absolute path: prefix the sysroot (empty in a
  # native build, so the files mean what they meant).
  grep -l 'INTERFACE_LINK_LIBRARIES.*[";]/usr/lib/' "$dir"/cmake/*/*.cmake 2>/dev/null |
    while IFS= read -r file; do
      $SUDO sed -i '/INTERFACE_LINK_LIBRARIES/ s#\([";]\)/usr/lib/#\1${CMAKE_SYSROOT}/usr/lib/#g' "$file"
    done
  for name in blas lapack; do
    for impl in "$name" openblas-pthread atlas; do
      if [ -e "$dir/$impl/lib$name.so.3" ]; then
        [ -e "$dir/lib$name.so.3" ] || $SUDO ln -sfn "$impl/lib$name.so.3" "$dir/lib$name.so.3"
        [ -e "$dir/lib$name.so" ] || $SUDO ln -sfn "lib$name.so.3" "$dir/lib$name.so"
        break
      fi
    done
  done
}

if [ "${1:-}" = --fix-only ]; then  # repair an existing sysroot (development)
  SYSROOT=${2:-$SYSROOT}
  rigcal_fix_sysroot "$SYSROOT"
  exit 0
fi

stamp="$SYSROOT/.rigcal-sysroot"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$wanted" ]; then
  echo "arm64-sysroot: $SYSROOT is complete"
  exit 0
fi

tmp="$SYSROOT.partial"
$SUDO rm -rf "$tmp"
$SUDO mkdir -p "$(dirname "$SYSROOT")"
include=$(IFS=,; echo "${PACKAGES[*]}")
echo "arm64-sysroot: unpacking ${#PACKAGES[@]} arm64 -dev packages and their dependencies into $SYSROOT"
$SUDO mmdebstrap --quiet --variant=extract --architectures=arm64 --include="$include" \
  --skip=cleanup/apt/lists --format=directory bookworm "$tmp" "${mirrors[@]}"
# The toolchain looks in the multiarch directories; Debian 12 merged /usr, so /lib is usr/lib.
for d in lib bin sbin; do
  if [ ! -e "$tmp/$d" ]; then $SUDO ln -s "usr/$d" "$tmp/$d"; fi
done
rigcal_fix_sysroot "$tmp"
echo "$wanted" | $SUDO tee "$tmp/.rigcal-sysroot" >/dev/null
$SUDO rm -rf "$SYSROOT"
$SUDO mv "$tmp" "$SYSROOT"
echo "arm64-sysroot: done ($(du -sh "$SYSROOT" | cut -f1))"
