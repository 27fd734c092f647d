#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Functions short enough to read at once: every function definition in the given source folders
# is at most LIMIT lines long (Universal Ctags finds each definition's first and last line),
# unless the comment directly above it says why, with a line containing "long because".
#
#   function_length_check.sh LIMIT DIR...
#
# Prints each function over the limit. Exit 0: none without a reason; 1: some; 77 (ctest
# SKIP_RETURN_CODE): no Universal Ctags on the machine (Debian: universal-ctags), except under
# CI=true, where that is a failure.
set -uo pipefail

if [ $# -lt 2 ]; then
  echo "usage: $0 LIMIT DIR..." >&2
  exit 2
fi
limit=$1
shift

ctags_bin=""
for candidate in ctags-universal universal-ctags ctags; do
  if command -v "$candidate" > /dev/null && "$candidate" --version 2>/dev/null | grep -q Universal; then
    ctags_bin=$candidate
    break
  fi
done
if [ -z "$ctags_bin" ]; then
  echo "function length: Universal Ctags not found (Debian: universal-ctags)"
  if [ "${CI:-}" = "true" ]; then exit 1; fi
  exit 77
fi

# One line per function: FILE START END NAME.
functions=$("$ctags_bin" -R --languages=C++ --kinds-C++=f --fields=+ne -f - "$@" |
  awk -F'\t' '{
    start = ""; end = "";
    for (i = 4; i <= NF; ++i) {
      if ($i ~ /^line:/) start = substr($i, 6);
      if ($i ~ /^end:/) end = substr($i, 5);
    }
    if (start != "" && end != "") print $2 "\t" start "\t" end "\t" $1;
  }')

# True when the comment lines directly above line START of FILE contain "long because".
has_reason() {
  awk -v start="$2" '
    { line[NR] = $0 }
    END {
      for (i = start - 1; i > 0 && line[i] ~ /^[ \t]*(\/\/|\*|\/\*)/; --i)
        if (tolower(line[i]) ~ /long because/) exit 0;
      exit 1;
    }' "$1"
}

failed=0
checked=0
while IFS=$'\t' read -r file start end name; do
  [ -n "$file" ] || continue
  checked=$((checked + 1))
  length=$((end - start + 1))
  if [ "$length" -gt "$limit" ]; then
    if has_reason "$file" "$start"; then
      echo "over $limit lines with a reason: $file:$start $name ($length lines)"
    else
      echo "FAIL: $file:$start $name is $length lines (limit $limit; split it into named steps," \
        "or say why in a comment above it with \"long because\")"
      failed=1
    fi
  fi
done <<< "$functions"

echo "function length: $checked functions checked, limit $limit lines"
if [ "$failed" -ne 0 ]; then
  echo "function length: FAILED"
  exit 1
fi
echo "function length: passed"
