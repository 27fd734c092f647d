#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Multi-process test over real udpm:// LCM: `rigcal calib` listens, lcm-logplayer publishes the
# poses of a simulated drive, lcm-logger records the bus. Everything runs inside a private
# network namespace this script creates (unshare --net), with a multicast route on its own lo;
# nothing is ever sent in the host's network namespace.
# Usage: lcm_udpm_netns_test.sh <path to rigcal>. Exit 77 = skipped (no namespace support).
set -euo pipefail
rigcal=$(readlink -f "$1")

RIGCAL_NETNS_TOOLS="lcm-logger lcm-logplayer"
# shellcheck source=../support/private_netns.sh
source "$(dirname "$0")/../support/private_netns.sh" "$0" "$@"

cat > "$dir/rig.yaml" <<YAML
rig: {name: netns_test, master: front}
cameras:
  - name: front
  - name: left
    truth: {q_wxyz: [0.7071068, 0, 0.7071068, 0], C: [0.5, 0, -0.2], scale: 2}
  - name: back
    truth: {q_wxyz: [0, 0, 1, 0], C: [0, 0.1, -1.5], scale: 0.5}
publish: {extrinsics_rate_hz: 5, status_rate_hz: 2}
state: {path: $dir/state.txt, save_interval_s: 1}
YAML

"$rigcal" synth-log --config "$dir/rig.yaml" --out "$dir/poses.lcmlog" --frames 1200 \
  --truth-out "$dir/truth.yaml"

# The bus stays on this host unless --lcm-network: a TTL above 0, or a group routed through a
# network link (a veth pair in this namespace), is refused with both ways out named.
refused_rc=0
"$rigcal" calib --config "$dir/rig.yaml" --lcm "udpm://239.255.76.67:7667?ttl=1" \
  --duration 1 --out "$dir/refused.yaml" 2> "$dir/refused.txt" || refused_rc=$?
check "ttl=1 refused with exit 1 (got $refused_rc)" '[ "$refused_rc" -eq 1 ]'
check "the refusal names ttl=1 and --lcm-network" \
  'grep -q "ttl=1" "$dir/refused.txt" && grep -q -- "--lcm-network" "$dir/refused.txt"'
check "nothing written by the refused run" '[ ! -e "$dir/refused.yaml" ]'
ip link add rigcal-veth0 type veth peer name rigcal-veth1 ||
  rigcal_netns_skip "cannot create a veth pair in the private namespace"
ip link set rigcal-veth0 up multicast on
ip route add 239.255.76.68/32 dev rigcal-veth0
status_rc=0
"$rigcal" status --lcm "udpm://239.255.76.68:7667?ttl=0" --once --timeout 1 \
  2> "$dir/status_refused.txt" || status_rc=$?
check "status refuses a group routed through a network link (exit $status_rc)" \
  '[ "$status_rc" -eq 3 ] && grep -q "goes through .rigcal-veth0." "$dir/status_refused.txt"'
allowed_rc=0
"$rigcal" status --lcm "udpm://239.255.76.68:7667?ttl=0" --lcm-network --once --timeout 1 \
  > /dev/null 2> "$dir/status_allowed.txt" || allowed_rc=$?
check "with --lcm-network it listens (no data: exit 3, no refusal)" \
  '[ "$allowed_rc" -eq 3 ] && ! grep -q "goes through" "$dir/status_allowed.txt"'
ip link del rigcal-veth0  # its peer goes with it

lcm-logger --lcm-url="$url" "$dir/bus.lcmlog" >/dev/null 2>&1 &
logger_pid=$!
pids+=("$logger_pid")
"$rigcal" calib --config "$dir/rig.yaml" --lcm "$url" --out "$dir/result.yaml" \
  --report-every 2 --json > "$dir/result.json" &
node_pid=$!
pids+=("$node_pid")
sleep 1
# 60 s of poses at 6x speed.
lcm-logplayer --lcm-url="$url" --speed=6 "$dir/poses.lcmlog"
sleep 1

stop "$node_pid"
node_rc=0
wait "$node_pid" || node_rc=$?
stop "$logger_pid"
wait "$logger_pid" || true
pids=()

check "rigcal calib exits 0 after SIGINT (got $node_rc)" '[ "$node_rc" -eq 0 ]'
check "result YAML written" '[ -s "$dir/result.yaml" ]'
check "both slaves usable in the result" \
  '[ "$(grep -c "usable: true" "$dir/result.yaml")" -eq 2 ]'
check "state file saved" '[ -s "$dir/state.txt" ]'
check "RIGCAL_EXTRINSICS seen on the bus" 'grep -aq RIGCAL_EXTRINSICS "$dir/bus.lcmlog"'
check "RIGCAL_STATUS seen on the bus" 'grep -aq RIGCAL_STATUS "$dir/bus.lcmlog"'
# Accuracy against the truth, from the JSON "errors" of each slave: rotation error < 0.3 deg.
rot_errors=$(awk '/"errors": \{/ {inside=1} inside && /"rot_deg"/ {gsub(/[",]/, "", $2); print $2; inside=0}' \
  "$dir/result.json" | tr '\n' ' ')
echo "rotation errors (deg): $rot_errors"
check "two slaves with rotation errors below 0.3 deg" \
  '[ "$(echo $rot_errors | wc -w)" -eq 2 ] && awk -v e="$rot_errors" "BEGIN { n = split(e, a, \" \"); for (i = 1; i <= n; ++i) if (a[i] + 0 >= 0.3) exit 1 }"'
exit $fail
