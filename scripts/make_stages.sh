#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs make targets one after the other and says how long each took, so that a slow `make test`
# shows where its time goes (the CI log ends with the table, also when a stage fails).
#   scripts/make_stages.sh TARGET...
# Exit code: that of the first failing stage (later stages do not run), else 0.
set -uo pipefail
make=${MAKE:-make}
names=()
times=()
rc=0
report() {
  local i total=0
  echo
  echo "make test stages (wall time):"
  for i in "${!names[@]}"; do
    printf '  %-16s %6d s\n' "${names[i]}" "${times[i]}"
    total=$((total + times[i]))
  done
  printf '  %-16s %6d s\n' total "$total"
}
for target in "$@"; do
  start=$(date +%s)
  echo "=== make $target"
  $make --no-print-directory "$target"
  rc=$?
  names+=("$target")
  times+=($(($(date +%s) - start)))
  if [ $rc -ne 0 ]; then
    names[-1]="$target (FAILED)"
    break
  fi
done
report
exit $rc
