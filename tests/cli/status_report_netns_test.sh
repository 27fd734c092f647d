#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# `rigcal status` and `rigcal report` on a live session over real udpm:// LCM: `rigcal calib`
# listens, lcm-logplayer publishes the poses of a simulated drive, lcm-logger records the bus.
# While the session runs, `rigcal status` watches it (plain lines, and --once --json with its
# health exit code); afterwards `rigcal report` turns the recording into the HTML report.
# Everything runs inside a private network namespace this script creates (unshare --net) with a
# multicast route on its own lo; nothing is ever sent in the host's network namespace.
# Usage: status_report_netns_test.sh <path to rigcal>. Exit 77 = skipped (no namespace support;
# under CI=true a skip is a failure).
set -euo pipefail
rigcal=$(readlink -f "$1")

RIGCAL_NETNS_TOOLS="lcm-logger lcm-logplayer"
# shellcheck source=../support/private_netns.sh
source "$(dirname "$0")/../support/private_netns.sh" "$0" "$@"

cat > "$dir/rig.yaml" <<YAML
rig: {name: status_test, master: front}
cameras:
  - name: front
  - name: left
    truth: {q_wxyz: [0.7071068, 0, 0.7071068, 0], C: [0.5, 0, -0.2], scale: 2}
  - name: back
    truth: {q_wxyz: [0, 0, 1, 0], C: [0, 0.1, -1.5], scale: 0.5}
publish: {extrinsics_rate_hz: 5, status_rate_hz: 4}
YAML

"$rigcal" synth-log --config "$dir/rig.yaml" --out "$dir/poses.lcmlog" --frames 1200



# Nobody publishes yet: no data within the timeout.
no_data_rc=0
"$rigcal" status --lcm "$url" --once --json --timeout 1 > "$dir/no_data.json" || no_data_rc=$?
check "status --once without a calibrator exits 3 (got $no_data_rc)" '[ "$no_data_rc" -eq 3 ]'
check "its JSON says no_data" 'grep -q "\"health\": \"no_data\"" "$dir/no_data.json"'

lcm-logger --lcm-url="$url" "$dir/bus.lcmlog" >/dev/null 2>&1 &
pids+=($!)
logger_pid=$!
"$rigcal" calib --config "$dir/rig.yaml" --lcm "$url" --out "$dir/result.yaml" \
  --report-every 0 > "$dir/calib.out" 2>&1 &
node_pid=$!
pids+=("$node_pid")
"$rigcal" status --lcm "$url" > "$dir/watch.txt" 2>&1 &
watch_pid=$!
pids+=("$watch_pid")
sleep 1
# 60 s of poses at 6x speed; a snapshot halfway.
lcm-logplayer --lcm-url="$url" --speed=6 "$dir/poses.lcmlog" &
player_pid=$!
pids+=("$player_pid")
sleep 4
mid_rc=0
"$rigcal" status --lcm "$url" --once --json --timeout 5 > "$dir/mid.json" || mid_rc=$?
wait "$player_pid"
sleep 1
end_rc=0
"$rigcal" status --lcm "$url" --once --json --timeout 5 > "$dir/end.json" || end_rc=$?
stop "$watch_pid"
watch_rc=0
wait "$watch_pid" || watch_rc=$?
stop "$node_pid"
wait "$node_pid" || true
stop "$logger_pid"
wait "$logger_pid" || true
pids=()

echo "status --once during the drive: exit $mid_rc; at its end: exit $end_rc"
check "a snapshot during the drive has data (exit 0 or 1, got $mid_rc)" '[ "$mid_rc" -le 1 ]'
check "its JSON names the three cameras" \
  '[ "$(grep -cE "\"name\": \"(front|left|back)\"" "$dir/mid.json")" -ge 3 ]'
check "its exit code is its health's" \
  'grep -q "\"exit_code\": $mid_rc" "$dir/mid.json"'
# 60 s of a general drive: both slaves converge (the calib node's own result says so too).
check "the rig has converged at the end of the drive (exit 0, got $end_rc)" '[ "$end_rc" -eq 0 ]'
check "the end snapshot has both slaves converged" \
  '[ "$(grep -c "\"state\": \"converged\"" "$dir/end.json")" -eq 2 ]'
blocks=$(grep -c '^---$' "$dir/watch.txt" || true)
echo "rigcal status printed $blocks plain blocks"
check "rigcal status (not a TTY) printed a block per RIGCAL_STATUS (>= 20)" '[ "$blocks" -ge 20 ]'
check "... as plain lines without terminal control codes" '! grep -q $'"'"'\x1b'"'"' "$dir/watch.txt"'
check "rigcal status ended on SIGINT with a health code (got $watch_rc)" '[ "$watch_rc" -le 2 ]'

# The recording of the bus (poses, extrinsics, status) becomes the report.
report_rc=0
"$rigcal" report "$dir/bus.lcmlog" --truth "$dir/rig.yaml" -o "$dir/report.html" || report_rc=$?
check "rigcal report on the recording exits 0 (got $report_rc)" '[ "$report_rc" -eq 0 ]'
plots=$( (grep -o '<figure class="plot"' "$dir/report.html" || true) | wc -l)
missing=$( (grep -o '<figure class="plot missing"' "$dir/report.html" || true) | wc -l)
echo "report: $plots plots, $missing missing"
check "every plot of the report has data (10 plots with the residual histograms, none missing)" \
  '[ "$plots" -eq 10 ] && [ "$missing" -eq 0 ]'
exit $fail
