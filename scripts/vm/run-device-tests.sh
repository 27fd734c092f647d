#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs the device tests (a GoogleTest binary, tests/device/) inside QEMU on a Debian kernel with
# real V4L2 drivers: two vivid devices, two v4l2loopback devices, vimc for libcamera.
#   run-device-tests.sh <test binary> [gtest filter, default: all but the long VividLongRun.*,
#                       LoopbackRun.* and ServiceUnitRun.*]
# Environment variables RIGCAL_DEVICE_* are passed on to the guest's tests. RIGCAL_VM_BINARIES:
# further programs (paths, space-separated) packed into the guest's /tests/bin, each named to the
# tests by RIGCAL_DEVICE_<NAME> (rigcal: RIGCAL_DEVICE_RIGCAL=/tests/bin/rigcal). RIGCAL_VM_FILES:
# data files (paths, space-separated) packed into /tests/share, each named to the tests by
# RIGCAL_DEVICE_FILE_<NAME> (rigcal-run.service: RIGCAL_DEVICE_FILE_RIGCAL_RUN_SERVICE).
# Builds or reuses the assets (build-assets.sh, under $RIGCAL_VM_DIR, default build/vm), packs
# the binary into a second initramfs archive and the shared libraries ldd lists (~200 MB: OpenCV
# brings GDAL and more) into a read-only ext2 disk (mke2fs -d) that the guest mounts on
# /tests/lib, so that only the pages the loader touches are read (in the archive, the kernel
# unpacks all of them before /init: ~25 s more under emulation); without mke2fs they go into
# the archive. Then it boots
# qemu-system-x86_64 (software emulation: KVM cannot run guests here) and reads the guest's
# result line "RIGCAL-DEVICE-RESULT rc=<n>" from the serial console.
# Exit: 0 passed, 1 failed, 77 skipped ("SKIP: <reason>" first; a failure under CI=true).
set -uo pipefail
binary=$(readlink -f "$1")
filter=${2:--VividLongRun.*:LoopbackRun.*:ServiceUnitRun.*}
HERE=$(cd "$(dirname "$0")" && pwd)
VM_DIR=${RIGCAL_VM_DIR:-$PWD/build/vm}
TIMEOUT_S=${RIGCAL_VM_TIMEOUT_S:-400}

skip() {
  echo "SKIP: $*"
  if [ "${CI:-}" = "true" ]; then echo "CI=true: the device tests may not skip"; exit 1; fi
  exit 77
}

command -v qemu-system-x86_64 >/dev/null || skip "qemu-system-x86_64 is not installed"
assets=$(bash "$HERE/build-assets.sh" "$VM_DIR")
rc=$?
if [ $rc -eq 77 ]; then skip "${assets#SKIP: }"; fi
[ $rc -eq 0 ] || { echo "$assets"; echo "building the VM assets failed"; exit 1; }
echo "$assets"
dir=$(echo "$assets" | sed -n 's/^vm assets: \([^ ]*\).*/\1/p')

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
root="$work/root"
mkdir -p "$root/tests/lib" "$root/tests/bin" "$root/tests/share" "$root/lib64"
cp "$binary" "$root/tests/device_tests"
extra_env=""
for program in ${RIGCAL_VM_BINARIES:-}; do
  [ -x "$program" ] || { echo "RIGCAL_VM_BINARIES: $program is not an executable"; exit 1; }
  name=$(basename "$program")
  cp "$program" "$root/tests/bin/$name"
  extra_env="$extra_env
export RIGCAL_DEVICE_$(echo "$name" | tr 'a-z-' 'A-Z_')=/tests/bin/$name"
done
for file in ${RIGCAL_VM_FILES:-}; do
  [ -f "$file" ] || { echo "RIGCAL_VM_FILES: $file is not a file"; exit 1; }
  name=$(basename "$file")
  cp "$file" "$root/tests/share/$name"
  extra_env="$extra_env
export RIGCAL_DEVICE_FILE_$(echo "$name" | tr 'a-z.-' 'A-Z__')=/tests/share/$name"
done
# Shared libraries of the programs and of libcamera's IPA modules (dlopen'ed).
libs() { ldd "$1" 2>/dev/null | awk '$2 == "=>" && $3 ~ /^\// {print $3} $1 ~ /^\/lib64\// {print $1}'; }
{
  libs "$binary"
  for program in ${RIGCAL_VM_BINARIES:-}; do libs "$program"; done
  for ipa in /usr/lib/x86_64-linux-gnu/libcamera/*.so; do [ -f "$ipa" ] && libs "$ipa"; done
} | sort -u | while read -r lib; do
  case "$lib" in
    /lib64/*) cp -L "$lib" "$root/lib64/" ;;
    *) cp -L "$lib" "$root/tests/lib/" ;;
  esac
done
disk=()
if command -v mke2fs >/dev/null; then
  mv "$root/tests/lib" "$work/lib" && mkdir "$root/tests/lib"
  size_kb=$(( $(du -sk "$work/lib" | cut -f1) * 11 / 10 + 8192 ))
  mke2fs -q -t ext2 -b 4096 -d "$work/lib" -L rigcal-lib "$work/lib.img" "${size_kb}k" ||
    { echo "mke2fs failed"; exit 1; }
  rm -rf "$work/lib"
  disk=(-drive "file=$work/lib.img,format=raw,if=virtio,readonly=on")
fi
cat > "$root/tests/run" <<RUN
#!/bin/sh
export LD_LIBRARY_PATH=/tests/lib HOME=/tmp RIGCAL_LOG_LEVEL=info PATH=/tests/bin:\$PATH$extra_env
$(env | grep '^RIGCAL_DEVICE_[A-Z_]*=' | sed "s/^\([^=]*\)=\(.*\)/export \1='\2'/")
cd /tmp
/tests/device_tests --gtest_filter='$filter' --gtest_color=no
echo "RIGCAL-DEVICE-RESULT rc=\$?"
RUN
chmod +x "$root/tests/run"
(cd "$root" && find . | cpio -o -H newc --quiet) >"$work/tests.cpio"
# The kernel reads an uncompressed archive after a compressed one only at a 4-byte boundary;
# zeros between archives are skipped.
cp "$dir/base.cpio.gz" "$work/initramfs.cpio"
truncate -s "$(( ($(stat -c %s "$work/initramfs.cpio") + 511) / 512 * 512 ))" "$work/initramfs.cpio"
cat "$work/tests.cpio" >>"$work/initramfs.cpio"

log="$work/console.log"
start=$(date +%s)
timeout "$TIMEOUT_S" qemu-system-x86_64 -accel tcg -cpu max -smp 2 -m 2048 -nic none \
  -nographic -no-reboot -kernel "$dir/vmlinuz" -initrd "$work/initramfs.cpio" "${disk[@]}" \
  -append "console=ttyS0 quiet panic=-1 loglevel=4" </dev/null >"$log" 2>&1
qemu_rc=$?
tr -d '\r' <"$log" | grep -v '^\s*$' | sed 's/^/guest: /'
echo "QEMU: exit $qemu_rc after $(( $(date +%s) - start )) s"
result=$(tr -d '\r' <"$log" | sed -n 's/.*RIGCAL-DEVICE-RESULT rc=\([0-9]*\).*/\1/p' | tail -1)
if [ -z "$result" ]; then
  echo "FAILED: no result from the guest (QEMU exit $qemu_rc)"
  exit 1
fi
if grep -q "RIGCAL-VM:" "$log"; then echo "FAILED: guest set-up problems (RIGCAL-VM lines)"; exit 1; fi
case "$result" in
  0) echo "PASSED"; exit 0 ;;
  77) skip "the guest skipped the device tests" ;;
  *) echo "FAILED: guest tests exit $result"; exit 1 ;;
esac
