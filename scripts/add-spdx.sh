#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Puts the licence's SPDX line first in every source file of the repository (after a `#!` line):
#   // SPDX-License-Identifier: Apache-2.0    .h .hpp .cc .cpp .c .lcm
#   # SPDX-License-Identifier: Apache-2.0     .cmake .cmake.in CMakeLists.txt .sh .py Makefile
#   /* SPDX-License-Identifier: Apache-2.0 */ .ld
# Files under version control only (git ls-files); test fixtures, corpora, configs and data are
# not source. Idempotent: a file whose first two lines hold an SPDX line is left alone.
#   scripts/add-spdx.sh           adds the line where it is missing
#   scripts/add-spdx.sh --check   changes nothing; lists the files without it, exit 1 if any
#                                 (ctest architecture/spdx)
set -euo pipefail
cd "$(dirname "$0")/.."
readonly ID="SPDX-License-Identifier: Apache-2.0"
mode="${1:-add}"
case "$mode" in add | --check) ;; *) echo "usage: scripts/add-spdx.sh [--check]" >&2; exit 2 ;; esac

# The comment line for a path, empty when the path is not a source file.
comment_for() {
  case "$1" in
    */fixtures/* | */corpus/* | */fuzz_corpus/*) echo "" ;;
    *.h | *.hpp | *.cc | *.cpp | *.c | *.lcm) echo "// $ID" ;;
    *.cmake | *.cmake.in | */CMakeLists.txt | CMakeLists.txt | *.sh | *.py | Makefile) echo "# $ID" ;;
    *.ld) echo "/* $ID */" ;;
    *) echo "" ;;
  esac
}

missing=0
while IFS= read -r path; do
  line=$(comment_for "$path")
  [ -n "$line" ] && [ -f "$path" ] || continue
  if head -n 2 "$path" | grep -q 'SPDX-License-Identifier:'; then continue; fi
  if [ "$mode" = "--check" ]; then
    echo "no SPDX line: $path"
    missing=$((missing + 1))
    continue
  fi
  tmp="$path.spdx.$$"
  if head -n 1 "$path" | grep -q '^#!'; then
    { head -n 1 "$path"; echo "$line"; tail -n +2 "$path"; } > "$tmp"
  else
    { echo "$line"; cat "$path"; } > "$tmp"
  fi
  chmod --reference="$path" "$tmp"
  mv "$tmp" "$path"
done < <(git ls-files)

if [ "$mode" = "--check" ]; then
  if [ "$missing" -gt 0 ]; then
    echo "add-spdx: $missing source file(s) without '$ID' (run scripts/add-spdx.sh)" >&2
    exit 1
  fi
  echo "add-spdx: every source file carries '$ID'"
fi
