#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# /init of the device-test VM (scripts/vm/build-assets.sh puts it in base.cpio.gz): loads the
# media drivers, starts udevd (Debian's, without rules: it records the devices for libudev and
# forwards add/remove events to libudev's monitors; without it the devices are marked
# initialised by hand), runs /tests/run (the
# second initramfs archive, from run-device-tests.sh) and powers off. Markers on the console:
#   RIGCAL-VM: <problem>     set-up trouble
#   RIGCAL-VM-READY          drivers loaded
#   (the lines of /tests/run, which ends with RIGCAL-DEVICE-RESULT rc=<exit code>)
export PATH=/bin:/sbin
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
mount -t tmpfs tmpfs /tmp
mkdir -p /run/udev/data
# The library disk of run-device-tests.sh (read-only ext2 on virtio), mounted on /tests/lib.
for m in /modules/disk/*.ko; do insmod "$m" || echo "RIGCAL-VM: insmod $m failed"; done
if [ -d /sys/bus/pci/drivers/virtio-pci ] && grep -q 0x1af4 /sys/bus/pci/devices/*/vendor; then
  for i in $(seq 50); do [ -b /dev/vda ] && break; sleep 0.1; done
  mkdir -p /tests/lib
  mount -t ext4 -o ro /dev/vda /tests/lib || echo "RIGCAL-VM: mounting the library disk failed"
fi
for m in /modules/[0-9]*.ko; do
  case "$m" in
    *-vivid.ko) insmod "$m" n_devs=2 node_types=0x1,0x1 input_types=0x81,0x81 ;;
    *) insmod "$m" ;;
  esac || echo "RIGCAL-VM: insmod $m failed"
done
insmod /modules/v4l2loopback.ko devices=2 video_nr=20,21 exclusive_caps=0,0 \
  card_label=rigcal-loop-0,rigcal-loop-1 || echo "RIGCAL-VM: insmod v4l2loopback failed"
insmod /modules/vimc.ko || echo "RIGCAL-VM: insmod vimc failed"
# libudev reports a device only when udev has "initialised" it: /run/udev/data/c<maj:min>.
if [ -x /lib/systemd/systemd-udevd ]; then
  /lib/systemd/systemd-udevd --daemon --resolve-names=never 2>/dev/null &&
    udevadm trigger --action=add && udevadm settle --timeout=60 ||
    echo "RIGCAL-VM: udevd did not start"
else
  for d in /sys/bus/media/devices/* /sys/class/video4linux/*; do
    [ -f "$d/dev" ] && echo "I:1" > "/run/udev/data/c$(cat "$d/dev")"
  done
fi
read -r uptime_s _ </proc/uptime
echo "RIGCAL-VM-READY after $uptime_s s of uptime"
if [ -x /tests/run ]; then
  /tests/run
else
  echo "RIGCAL-VM: no /tests/run"
fi
echo "RIGCAL-VM-DONE"
poweroff -f
