#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs ctest and then says how many tests were skipped and why, so that a suite that "passes"
# by skipping is visible (make test, test-fast, test-asan, test-tsan, eval).
#   scripts/ctest_with_skips.sh <build dir> [ctest arguments...]
# A test is skipped when it exits 77 (ctest SKIP_RETURN_CODE): GoogleTest binaries do when a test
# called GTEST_SKIP/RIGCAL_SKIP_MISSING and none failed (tests/support/main); test scripts print
# a line "SKIP: <reason>" first. The reasons come from the tests' output in
# <build dir>/Testing/Temporary/LastTest.log. Exit code: ctest's.
set -uo pipefail
build=$1
shift
out="$build/Testing/ctest-output.txt"
mkdir -p "$build/Testing"
ctest --test-dir "$build" "$@" 2>&1 | tee "$out"
rc=${PIPESTATUS[0]}

mapfile -t skipped < <(sed -n -E 's/^[[:space:]]*[0-9]+ - (.*) \(Skipped\)$/\1/p' "$out")
echo
echo "Skipped tests: ${#skipped[@]}"
log="$build/Testing/Temporary/LastTest.log"
for name in "${skipped[@]}"; do
  # The test's output block: from "<i>/<n> Testing: <name>" to "<end of output>". GoogleTest
  # prints "<file>:<line>: Skipped", the reason, then "[  SKIPPED ] <Suite.Test>".
  awk -v name="$name" '
    $0 ~ /^[0-9]+\/[0-9]+ Testing: / { inside = (substr($0, index($0, ": ") + 2) == name); next }
    !inside { next }
    /^<end of output>$/ { inside = 0; next }
    /^\[ RUN      \] / { test = $4 }
    /: Skipped$/ { reason = 1; next }
    reason && /^\[  SKIPPED \] / { reason = 0; next }
    reason && NF { printf "  %s %s: %s\n", name, test, $0; found = 1; next }
    /^SKIP: / { printf "  %s: %s\n", name, substr($0, 7); found = 1 }
    END { if (!found) printf "  %s: (no reason printed)\n", name }
  ' "$log"
done
exit "$rc"
