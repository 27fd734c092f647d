#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The systemd units (config/systemd) as `cmake --install` writes them: installed with DESTDIR
# into a private root next to a copy of this machine's system units, then
# `systemd-analyze verify --root` must accept them without a single remark; a copy with an
# unknown key must be flagged (the check can fail). Also prints the offline security exposure
# (`systemd-analyze security`) and checks the least-privilege settings docs/deployment.md
# promises. Skipped without systemd-analyze (a failure under CI=true).
# usage: systemd_units_test.sh BUILD_DIR
set -euo pipefail
build=$(readlink -f "$1")
skip() {
  if [ "${CI:-}" = true ]; then echo "FAILED (CI=true, a skip is a failure): $1"; exit 1; fi
  echo "SKIP: $1"
  exit 77
}
command -v systemd-analyze >/dev/null || skip "systemd-analyze not found (package systemd)"
[ -d /usr/lib/systemd/system ] || [ -d /lib/systemd/system ] || skip "no system units to verify against"

work="$build/units-test"
root="$work/root"
rm -rf "$work"
mkdir -p "$work"
DESTDIR="$root" cmake --install "$build" --prefix /usr --component runtime > "$work/install.log"
units=/usr/lib/systemd/system
# The targets and slices the units refer to (sysinit.target, multi-user.target, ...).
for dir in /lib/systemd/system /usr/lib/systemd/system; do
  [ -d "$dir" ] && cp -rn "$dir/." "$root$units/"
done

fail=0
check() {  # check NAME EXPR
  if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi
}
verify() {  # verify UNIT...: systemd-analyze's remarks on stdout, its exit code
  systemd-analyze verify --root="$root" --man=no "$@" 2>&1
}
rc=0
out=$(verify $units/rigcal.service $units/rigcal-run.service $units/rigcal-health.service \
  $units/rigcal-health.timer) || rc=$?
[ -n "$out" ] && echo "$out"
check "systemd-analyze verify: exit 0 (got $rc)" '[ "$rc" -eq 0 ]'
check "systemd-analyze verify: no remark" '[ -z "$out" ]'

sed 's/^Restart=on-failure/Restart=on-failure\nWatchdogSecs=10s/' "$root$units/rigcal.service" \
  > "$root$units/rigcal-typo.service"
out=$(verify $units/rigcal-typo.service || true)
check "an unknown key is flagged" '[[ "$out" == *"Unknown key"*WatchdogSecs* ]]'
rm "$root$units/rigcal-typo.service"

unit="$root$units/rigcal.service"
for setting in Type=notify WatchdogSec= Restart=on-failure StateDirectory=rigcal DynamicUser=yes \
               SupplementaryGroups=video ProtectSystem=strict ProtectHome=yes NoNewPrivileges=yes \
               CapabilityBoundingSet= DevicePolicy=closed "DeviceAllow=char-video4linux rw" \
               "ExecStart=/usr/bin/rigcal calib"; do
  check "rigcal.service: $setting" 'grep -q "^$setting" "$unit"'
done
unit="$root$units/rigcal-run.service"
for setting in Type=notify WatchdogSec= Restart=on-failure StateDirectory=rigcal DynamicUser=yes \
               "SupplementaryGroups=video dialout" ProtectSystem=strict ProtectHome=yes \
               NoNewPrivileges=yes CapabilityBoundingSet= DevicePolicy=closed \
               "DeviceAllow=char-video4linux rw" "DeviceAllow=char-media rw" \
               "DeviceAllow=char-ttyUSB rw" "ExecStart=/usr/bin/rigcal run .*--state /var/lib/rigcal/.* --resume"; do
  check "rigcal-run.service: $setting" 'grep -q "^$setting" "$unit"'
done
check "rigcal-run.service: no root" '! grep -q "^User=root" "$unit"'
check "examples installed" '[ -f "$root/usr/share/rigcal/examples/surround4_v4l2.yaml" ] &&
  [ -f "$root/usr/share/rigcal/examples/libcamera_stereo.yaml" ] &&
  [ -f "$root/usr/share/rigcal/examples/stereo_v4l2_trigger.yaml" ]'
check "/etc/rigcal/rig.yaml installed" '[ -f "$root/etc/rigcal/rig.yaml" ]'
check "health check runs rigcal status --once" \
  'grep -q "^ExecStart=/usr/bin/rigcal status .*--once" "$root$units/rigcal-health.service"'
check "health timer repeats" 'grep -q "^OnUnitActiveSec=" "$root$units/rigcal-health.timer"'

security=$(systemd-analyze security --offline=yes --root="$root" $units/rigcal.service 2>&1 | tail -1 || true)
echo "rigcal.service ${security#→ }"

if [ "$fail" -ne 0 ]; then echo "systemd_units: FAILED"; exit 1; fi
echo "systemd_units: passed"
