# SPDX-License-Identifier: Apache-2.0
# Sourced at the top of a multi-process LCM test script: runs the script inside a private network
# namespace (unshare --net) whose only link, lo, gets a multicast route, so udpm:// traffic never
# leaves it (docs/architecture.md "LCM"); sets `url` to the udpm URL to use there. Also gives the script
# what a multi-process test needs: `dir`, a temporary directory removed at exit; `pids`, the
# processes it started (add with pids+=("$pid"); TERMed at exit unless emptied); `stop PID`;
# `check NAME EXPR` (prints ok/FAIL, sets `fail` to 1 on a failure).
#   source "$(dirname "$0")/../support/private_netns.sh" "$0" "$@"
# Needs unshare, ip and the tools named in RIGCAL_NETNS_TOOLS (space-separated). A missing tool
# or no namespace support skips the test (exit 77); under CI=true that is a failure (exit 1).

rigcal_netns_skip() {
  if [ "${CI:-}" = true ]; then echo "FAILED (CI=true, a skip is a failure): $1"; exit 1; fi
  echo "SKIP: $1"
  exit 77
}

if [ "${RIGCAL_IN_PRIVATE_NETNS:-}" != 1 ]; then
  for tool in unshare ip ${RIGCAL_NETNS_TOOLS:-}; do
    command -v "$tool" >/dev/null || rigcal_netns_skip "$tool not found"
  done
  unshare --net true 2>/dev/null ||
    rigcal_netns_skip "cannot create a network namespace here (needs root or user namespaces)"
  RIGCAL_IN_PRIVATE_NETNS=1 exec unshare --net --fork bash "$@"
fi

# Inside the new namespace: lo must be the only link, or this is not a private namespace.
rigcal_netns_links=$(ip -o link show | awk -F': ' '{print $2}' | tr '\n' ' ')
if [ "$rigcal_netns_links" != "lo " ]; then
  echo "FAIL: expected only lo in the private namespace, found: $rigcal_netns_links"
  exit 1
fi
ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
url='udpm://239.255.76.67:7667?ttl=0'

dir=$(mktemp -d)
pids=()
rigcal_netns_cleanup() {
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  rm -rf "$dir"
}
trap rigcal_netns_cleanup EXIT

stop() {  # stop a process we started, by PID: SIGINT, then SIGTERM if it does not end
  local pid=$1
  kill -INT "$pid" 2>/dev/null || return 0
  for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || return 0; sleep 0.1; done
  kill -TERM "$pid" 2>/dev/null || true
}

fail=0
check() { if ! eval "$2"; then echo "FAIL: $1"; fail=1; else echo "ok: $1"; fi; }
