#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# ctest cli/doc_examples: every ```sh block of README.md and docs/*.md runs as written, in the
# order of its page, in a scratch directory where `rigcal` is on PATH and config/ is the
# repository's. Blocks that need what a test machine does not have carry a second word:
#   ```sh hardware   cameras, a trigger board, a network bus (never sent from a test)
#   ```sh data       files the text says how to get (pattern views, a dataset)
#   ```sh long       the build itself (make demo, make test)
# and are only counted. Any other word after `sh` fails the test, so no example is left unmarked.
# Usage: doc_examples_test.sh SOURCE_DIR RIGCAL [PAGE...]
set -uo pipefail
source_dir=$(realpath "$1")
rigcal=$(realpath "$2")
shift 2
pages=("$@")
if [ ${#pages[@]} -eq 0 ]; then
  pages=("$source_dir/README.md")
  for page in "$source_dir"/docs/*.md; do
    # commands.md holds help texts; firmware.md's examples need the trigger board.
    case "$(basename "$page")" in commands.md | firmware.md) ;; *) pages+=("$page") ;; esac
  done
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir "$work/bin"
ln -s "$rigcal" "$work/bin/rigcal"
failures=0
for page in "${pages[@]}"; do
  name=${page#"$source_dir"/}
  scratch="$work/$(echo "$name" | tr / _)"
  mkdir -p "$scratch"
  ln -s "$source_dir/config" "$scratch/config"
  # Blocks as "<line> <marker>" headers followed by their text, separated by NUL.
  awk -v name="$name" '
    /^ *```sh( |$)/ { inside = 1; start = NR; marker = $2; body = ""; next }
    inside && /^ *```/ { printf "%d %s\n%s%c", start, marker, body, 0; inside = 0; next }
    inside { sub(/^   /, ""); body = body $0 "\n" }
  ' "$page" > "$scratch/blocks"
  while IFS= read -r -d '' block; do
    header=${block%%$'\n'*}
    text=${block#*$'\n'}
    line=${header%% *}
    marker=${header#* }
    case "$marker" in
      "" | "$line") ;;
      hardware | data | long) echo "not run ($marker): $name:$line"; continue ;;
      *) echo "FAIL: $name:$line: unknown marker '$marker' (hardware, data or long)"
         failures=$((failures + 1)); continue ;;
    esac
    echo "run: $name:$line"
    if ! (cd "$scratch" && PATH="$work/bin:$PATH" bash -e -o pipefail -c "$text") \
        > "$scratch/out.txt" 2>&1; then
      echo "FAIL: $name:$line:"
      sed 's/^/    /' "$scratch/out.txt" | tail -n 30
      failures=$((failures + 1))
    fi
  done < "$scratch/blocks"
done
if [ "$failures" -gt 0 ]; then
  echo "$failures example(s) failed"
  exit 1
fi
echo "every runnable example ran"
