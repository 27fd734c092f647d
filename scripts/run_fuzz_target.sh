#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs one libFuzzer target (ctest label `fuzz`, `make fuzz`) for a fixed time and says how many
# inputs it tried.
#   scripts/run_fuzz_target.sh <fuzz binary> <seed corpus dir> <work dir> <seconds> [max_len]
# RIGCAL_FUZZ_SECONDS in the environment overrides <seconds>; RIGCAL_FUZZ_RUNS=N stops after N
# inputs instead (no time limit). The seeds (in the repository) are
# only read; inputs that reach new code go to <work dir>/corpus/, so later runs start from them.
# A crash, sanitizer report, leak, out-of-memory or an input taking > 10 s fails the run
# (libFuzzer's exit code) and leaves the input as <work dir>/crash-*, leak-*, oom-*, timeout-*;
# reproduce with `<fuzz binary> <that file>`.
set -uo pipefail
binary=$1
seeds=$2
work=$3
seconds=${RIGCAL_FUZZ_SECONDS:-$4}
max_len=${5:-4096}
limit=(-max_total_time="$seconds")
if [ -n "${RIGCAL_FUZZ_RUNS:-}" ]; then
  limit=(-runs="$RIGCAL_FUZZ_RUNS")
  seconds="(no limit, $RIGCAL_FUZZ_RUNS runs)"
fi

if [ ! -d "$seeds" ] || [ -z "$(ls -A "$seeds" 2>/dev/null)" ]; then
  echo "run_fuzz_target: no seed corpus in $seeds" >&2
  exit 1
fi
mkdir -p "$work/corpus"
log="$work/last_run.log"
# UBSan findings are errors; ASan's leak check runs at the end of every input (libFuzzer).
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
start=$(date +%s)
"$binary" "$work/corpus" "$seeds" "${limit[@]}" -max_len="$max_len" -timeout=10 \
  -rss_limit_mb=2048 -malloc_limit_mb=1024 -print_final_stats=1 -artifact_prefix="$work/" \
  >"$log" 2>&1
rc=$?
elapsed=$(($(date +%s) - start))
runs=$(sed -n -E 's/^stat::number_of_executed_units:[[:space:]]*([0-9]+).*/\1/p' "$log" | tail -1)
corpus=$(find "$work/corpus" -type f | wc -l)
if [ "$rc" -ne 0 ]; then
  # The report: from the sanitizer's or libFuzzer's first error line on.
  grep -n -m1 -E '^==[0-9]+==ERROR|runtime error:|property broken|^==[0-9]+== ERROR: libFuzzer' "$log" >/dev/null &&
    sed -n -E '/^==[0-9]+==ERROR|runtime error:|property broken|ERROR: libFuzzer/,$p' "$log" | head -80 ||
    tail -40 "$log"
  echo "fuzz $(basename "$binary"): FAILED (exit $rc) after ${runs:-?} inputs in ${elapsed} s;" \
    "the input: $(ls "$work"/crash-* "$work"/leak-* "$work"/oom-* "$work"/timeout-* 2>/dev/null | tail -1)"
  exit "$rc"
fi
echo "fuzz $(basename "$binary"): ${runs:-?} inputs in ${elapsed} s, no finding;" \
  "corpus $corpus inputs ($work/corpus)"
