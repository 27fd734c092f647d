#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Figure (label eval): start-up time of the calibrator to its first published RIGCAL_STATUS, on
# real udpm:// LCM inside a private network namespace: lcm-logger records the bus, the time from
# launching `rigcal calib` (what rigcal.service runs) and `rigcal run` (simulated rig) to the
# first RIGCAL_STATUS event is printed. With RIGCAL_ARM64=<arm64 rigcal> and the sysroot
# (RIGCAL_ARM64_SYSROOT) the arm64 build is measured too, under qemu-aarch64 (emulated: slower
# than a board). The status period of the config (publish.status_rate_hz) bounds the figure
# from below for `calib`, which publishes its first status one period after start-up.
# usage: startup_eval.sh RIGCAL SOURCE_DIR
set -euo pipefail
rigcal=$(readlink -f "$1")
source_dir=$(readlink -f "$2")
RIGCAL_NETNS_TOOLS="lcm-logger python3"
# shellcheck source=../support/private_netns.sh
source "$source_dir/tests/support/private_netns.sh" "$0" "$@"
config="$source_dir/config/sim_thesis_virtual.yaml"
cd "$dir"

first_status_us() {  # first_status_us LOG: timestamp (µs) of its first RIGCAL_STATUS event
  python3 - "$1" <<'PY'
import struct, sys
data = open(sys.argv[1], "rb").read()
i = 0
while i + 28 <= len(data):
    sync, _, utime, clen, dlen = struct.unpack(">IqqII", data[i:i + 28])
    if sync != 0xEDA1DA01:
        break
    channel = data[i + 28:i + 28 + clen].decode()
    if channel == "RIGCAL_STATUS":
        print(utime)
        sys.exit(0)
    i += 28 + clen + dlen
print(-1)
PY
}

measure() {  # measure LABEL COMMAND...: launch, wait for the first status, stop
  local label=$1
  shift
  rm -f bus.lcmlog
  lcm-logger --lcm-url="$url" bus.lcmlog > /dev/null 2>&1 &
  local logger=$!
  pids+=("$logger")
  sleep 0.5
  local t0 t1
  t0=$(( $(date +%s%N) / 1000 ))
  "$@" > /dev/null 2>&1 &
  local pid=$!
  pids+=("$pid")
  for _ in $(seq 200); do
    t1=$(first_status_us bus.lcmlog 2> /dev/null || echo -1)
    [ "$t1" -gt 0 ] && break
    sleep 0.1
  done
  stop "$pid"
  wait "$pid" 2> /dev/null || true
  stop "$logger"
  wait "$logger" 2> /dev/null || true
  if [ "$t1" -gt 0 ]; then
    printf '%-40s first RIGCAL_STATUS after %6.0f ms\n' "$label" "$(( t1 - t0 ))e-3"
  else
    echo "$label: no RIGCAL_STATUS within 20 s"
    fail=1
  fi
}

measure "amd64 rigcal calib" "$rigcal" calib --config "$config" --lcm "$url" --out calib.yaml --state state.txt
measure "amd64 rigcal run (simulated rig)" "$rigcal" run --config "$config" --lcm "$url" --out run.yaml --status-every 0
if [ -n "${RIGCAL_ARM64:-}" ]; then
  sysroot=${RIGCAL_ARM64_SYSROOT:-/var/cache/rigcal/arm64-sysroot}
  measure "arm64 rigcal calib (qemu-aarch64)" qemu-aarch64 -L "$sysroot" "$RIGCAL_ARM64" calib --config "$config" --lcm "$url" --out calib.yaml --state state.txt
  measure "arm64 rigcal run (qemu-aarch64)" qemu-aarch64 -L "$sysroot" "$RIGCAL_ARM64" run --config "$config" --lcm "$url" --out run.yaml --status-every 0
fi
exit "$fail"
