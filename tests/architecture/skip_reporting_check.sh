#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Skipped tests are reported as skipped, never as passed, and under CI=true a skip for a missing
# input fails (tests/support/skip.h, tests/support/main). Runs the fixture binary
# (fixtures/skips) on one outcome at a time and checks its exit code and output.
#   skip_reporting_check.sh <skips_fixture binary>
set -u
bin=$1
fail=0
expect() {  # expect <exit code> <output substring> <env...> -- <gtest filter>
  local want=$1 text=$2
  shift 2
  local env=()
  while [ "$1" != -- ]; do env+=("$1"); shift; done
  local filter=$2 out rc
  out=$(env -u CI "${env[@]}" "$bin" --gtest_filter="$filter" 2>&1)
  rc=$?
  if [ "$rc" = "$want" ] && grep -qF -- "$text" <<<"$out"; then
    echo "ok: $filter ${env[*]} -> $rc"
  else
    echo "FAIL: $filter ${env[*]}: exit $rc (want $want), output without '$text':"
    echo "$out"
    fail=1
  fi
}
expect 0 "[  PASSED  ] 1 test" -- 'Outcome.Passes'
expect 77 "fixture data /nonexistent not found" -- 'Outcome.SkipsForMissingData'
expect 77 "[  SKIPPED ] 1 test" -- 'Outcome.Passes:Outcome.SkipsForMissingData'
expect 77 "meaningless here" CI=true -- 'Outcome.SkipsForAnotherReason'
expect 1 "this test fails on purpose" -- 'Outcome.Fails:Outcome.SkipsForMissingData'
expect 1 "CI=true: a test may not skip for a missing input" CI=true -- 'Outcome.SkipsForMissingData'
expect 1 "fixture data /nonexistent not found" CI=true -- 'Outcome.SkipsForMissingData'
exit $fail
