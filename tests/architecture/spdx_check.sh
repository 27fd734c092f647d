#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# ctest architecture/spdx: every source file starts with the licence's SPDX line
# (scripts/add-spdx.sh --check). The lines are added by running scripts/add-spdx.sh over the
# whole tree once, after the parallel branches are merged; until that run no file has one, and
# the test skips saying so (exit 77; a failure under CI=true, tests/support/skip.h). Once any
# file has the line, a file without it fails the test.
set -euo pipefail
source_dir="$1"
cd "$source_dir"
if ! git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  echo "SKIP: $source_dir is not a git work tree (add-spdx.sh lists files with git ls-files)"
  [ "${CI:-}" = "true" ] && exit 1
  exit 77
fi
if ! git grep -q -l 'SPDX-License-Identifier: Apache-2.0' -- '*.cc' '*.h'; then
  echo "SKIP: no source file has an SPDX line yet: the tree has not been through"
  echo "      scripts/add-spdx.sh (run once after merging the branches, then commit)"
  [ "${CI:-}" = "true" ] && exit 1
  exit 77
fi
bash scripts/add-spdx.sh --check
