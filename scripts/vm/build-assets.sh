#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the assets of the device tests (scripts/vm/run-device-tests.sh) under OUT (default
# build/vm), once: they are kept and reused while the kernel version does not change.
#   OUT/<V>/vmlinuz           the Debian kernel (apt-get download linux-image-<V>, unpacked)
#   OUT/<V>/base.cpio.gz      busybox, the media modules (vivid, videobuf2, ...), vimc built out
#                             of tree from linux-source-6.1, v4l2loopback built from the dkms
#                             source, libcamera's IPA modules, systemd-udevd (unpacked from
#                             Debian's udev package, with its shared libraries) and the guest's /init
# <V> is the kernel of the installed linux-headers-amd64 (the headers the modules are built
# against). Needs the packages of scripts/install-deps.sh: linux-headers-amd64,
# linux-source-6.1, v4l2loopback-dkms, busybox-static, libcamera-ipa, cpio, qemu-system-x86.
# Prints "SKIP: <reason>" and exits 77 when something it needs is missing. Without the udev
# package (apt-get download udev fails) the guest runs without udevd (the tests that need it skip).
set -euo pipefail
OUT=$(realpath -m "${1:-build/vm}")
HERE=$(cd "$(dirname "$0")" && pwd)

skip() { echo "SKIP: $*"; exit 77; }

V=$(dpkg-query -W -f='${Depends}' linux-headers-amd64 2>/dev/null |
    sed -n 's/.*linux-headers-\([^ ,]*-amd64\).*/\1/p')
[ -n "$V" ] || skip "linux-headers-amd64 is not installed"
[ -d "/lib/modules/$V/build" ] || skip "no kernel headers at /lib/modules/$V/build"
SRC_TAR=$(ls /usr/src/linux-source-6.1.tar.* 2>/dev/null | head -1 || true)
[ -n "$SRC_TAR" ] || skip "linux-source-6.1 is not installed"
LOOPBACK_SRC=$(ls -d /usr/src/v4l2loopback-* 2>/dev/null | head -1 || true)
[ -n "$LOOPBACK_SRC" ] || skip "v4l2loopback-dkms is not installed"
BUSYBOX=$(command -v busybox || true)
[ -n "$BUSYBOX" ] && file -L "$BUSYBOX" | grep -q "statically linked" ||
  skip "busybox-static is not installed"
IPA_DIR=/usr/lib/x86_64-linux-gnu/libcamera
command -v cpio >/dev/null || skip "cpio is not installed"

DIR="$OUT/$V"
if [ -f "$DIR/vmlinuz" ] && [ -f "$DIR/base.cpio.gz" ] &&
   [ "$DIR/base.cpio.gz" -nt "$HERE/build-assets.sh" ] && [ "$DIR/base.cpio.gz" -nt "$HERE/guest-init.sh" ]; then
  echo "vm assets: $DIR (cached)"
  exit 0
fi
mkdir -p "$DIR"
WORK=$(mktemp -d "$DIR/work.XXXXXX")
trap 'rm -rf "$WORK"' EXIT

# The kernel package, unpacked (not installed).
if [ ! -f "$DIR/linux-image.deb" ]; then
  (cd "$WORK" && apt-get download "linux-image-$V" >/dev/null 2>&1) ||
    skip "apt-get download linux-image-$V failed (no package source?)"
  mv "$WORK"/linux-image-*.deb "$DIR/linux-image.deb"
fi
dpkg-deb -x "$DIR/linux-image.deb" "$WORK/image"
cp "$WORK/image/boot/vmlinuz-$V" "$WORK/vmlinuz"
MODS="$WORK/image/lib/modules/$V/kernel"

# Debian's udev, unpacked (not installed): udevd keeps the device database libcamera reads
# (libudev) and forwards add/remove events.
if [ ! -f "$DIR/udev.deb" ]; then
  (cd "$WORK" && apt-get download udev >/dev/null 2>&1 && mv udev_*.deb "$DIR/udev.deb") ||
    echo "apt-get download udev failed: the guest runs without udevd" >&2
fi
[ -f "$DIR/udev.deb" ] && dpkg-deb -x "$DIR/udev.deb" "$WORK/udev"

# vimc, out of tree (Debian's config does not enable it).
tar -xf "$SRC_TAR" -C "$WORK" --wildcards '*/drivers/media/test-drivers/vimc/*'
VIMC=$(ls -d "$WORK"/linux-source-*/drivers/media/test-drivers/vimc)
make -s -C "/lib/modules/$V/build" M="$VIMC" CONFIG_VIDEO_VIMC=m modules >"$WORK/vimc.log" 2>&1 ||
  { cat "$WORK/vimc.log"; echo "vimc build failed" >&2; exit 1; }
# v4l2loopback from the dkms source.
cp -r "$LOOPBACK_SRC" "$WORK/v4l2loopback"
make -s -C "/lib/modules/$V/build" M="$WORK/v4l2loopback" modules >"$WORK/loopback.log" 2>&1 ||
  { cat "$WORK/loopback.log"; echo "v4l2loopback build failed" >&2; exit 1; }

# The initramfs base: busybox, modules in load order, libcamera IPA, /init.
ROOT="$WORK/root"
mkdir -p "$ROOT"/{bin,sbin,proc,sys,dev,tmp,run/udev/data,modules,lib64,usr/lib}
cp "$BUSYBOX" "$ROOT/bin/busybox"
for tool in sh mount insmod rmmod poweroff mkdir cat echo ls sleep grep sed printf stat basename \
            readlink dmesg uname timeout seq; do
  ln -sf busybox "$ROOT/bin/$tool"
done
n=0
for m in media/mc/mc.ko media/v4l2-core/videodev.ko media/v4l2-core/v4l2-dv-timings.ko \
         media/common/v4l2-tpg/v4l2-tpg.ko media/common/videobuf2/videobuf2-common.ko \
         media/common/videobuf2/videobuf2-memops.ko media/common/videobuf2/videobuf2-v4l2.ko \
         media/common/videobuf2/videobuf2-vmalloc.ko media/common/videobuf2/videobuf2-dma-contig.ko \
         media/rc/rc-core.ko media/cec/core/cec.ko media/test-drivers/vivid/vivid.ko; do
  f=$(ls "$MODS/drivers/$m"* 2>/dev/null | head -1 || true)
  [ -n "$f" ] || { echo "module $m missing in linux-image-$V" >&2; exit 1; }
  n=$((n + 1))
  dest="$ROOT/modules/$(printf %02d $n)-$(basename "$m")"
  case "$f" in
    *.xz) xz -dc "$f" >"$dest" ;;
    *.zst) zstd -qdc "$f" >"$dest" ;;
    *) cp "$f" "$dest" ;;
  esac
done
# The read-only library disk of run-device-tests.sh: virtio-blk and ext4 (mounts ext2), in order.
mkdir -p "$ROOT/modules/disk"
n=0
for m in drivers/virtio/virtio_ring.ko drivers/virtio/virtio.ko \
         drivers/virtio/virtio_pci_modern_dev.ko drivers/virtio/virtio_pci_legacy_dev.ko \
         drivers/virtio/virtio_pci.ko drivers/block/virtio_blk.ko crypto/crc32c_generic.ko \
         lib/crc16.ko fs/mbcache.ko \
         fs/jbd2/jbd2.ko fs/ext4/ext4.ko; do
  f=$(ls "$MODS/$m"* 2>/dev/null | head -1 || true)
  [ -n "$f" ] || { echo "module $m missing in linux-image-$V" >&2; exit 1; }
  n=$((n + 1))
  dest="$ROOT/modules/disk/$(printf %02d $n)-$(basename "$m")"
  case "$f" in
    *.xz) xz -dc "$f" >"$dest" ;;
    *.zst) zstd -qdc "$f" >"$dest" ;;
    *) cp "$f" "$dest" ;;
  esac
done
cp "$VIMC/vimc.ko" "$ROOT/modules/vimc.ko"
cp "$WORK/v4l2loopback/v4l2loopback.ko" "$ROOT/modules/v4l2loopback.ko"
# libcamera's IPA modules (vimc's) are loaded at run time, not linked.
if [ -d "$IPA_DIR" ]; then
  mkdir -p "$ROOT$IPA_DIR" && cp -r "$IPA_DIR/." "$ROOT$IPA_DIR/"
  [ -d /usr/share/libcamera ] && mkdir -p "$ROOT/usr/share" && cp -r /usr/share/libcamera "$ROOT/usr/share/"
fi
# udevd (udevadm is both) with the libraries it links, without rules: it records every device in
# /run/udev/data and forwards the kernel's add/remove events to libudev's monitors.
if [ -x "$WORK/udev/bin/udevadm" ]; then
  mkdir -p "$ROOT/lib/systemd" "$ROOT/lib/x86_64-linux-gnu"
  cp "$WORK/udev/bin/udevadm" "$ROOT/bin/udevadm"
  ln -sf /bin/udevadm "$ROOT/lib/systemd/systemd-udevd"
  ldd "$WORK/udev/bin/udevadm" | awk '$2 == "=>" && $3 ~ /^\// {print $3} $1 ~ /^\/lib64\// {print $1}' |
    while read -r lib; do
      case "$lib" in
        /lib64/*) cp -L "$lib" "$ROOT/lib64/" ;;
        *) cp -L "$lib" "$ROOT/lib/x86_64-linux-gnu/" ;;
      esac
    done
fi
cp "$HERE/guest-init.sh" "$ROOT/init"
chmod +x "$ROOT/init"
(cd "$ROOT" && find . | cpio -o -H newc --quiet | gzip -1) >"$WORK/base.cpio.gz"
mv "$WORK/vmlinuz" "$DIR/vmlinuz"
mv "$WORK/base.cpio.gz" "$DIR/base.cpio.gz"
echo "vm assets: $DIR (built: kernel $V, vivid, vimc, v4l2loopback$([ -x "$WORK/udev/bin/udevadm" ] && echo ", udevd"))"
