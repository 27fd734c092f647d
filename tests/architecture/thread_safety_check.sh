#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Clang's thread-safety analysis (-Wthread-safety, rigcal/base/thread_annotations.h) over every
# source file of rigcal that uses threads or locks, with the flags of the normal (GCC) build
# tree from its compile_commands.json, syntax-only (no objects, no second build tree); the
# sources of a unity batch (RIGCAL_UNITY_BUILD) each on its own, with the batch's flags.
#
#   thread_safety_check.sh <build>/compile_commands.json <source dir>
#       checks calib/, drivers/, vo/ and tools/: every source that itself mentions a thread,
#       mutex, condition variable, atomic or a thread annotation, and every header that does
#       through a checked source that includes it (a header no checked source includes is an
#       error). tests/ is not checked: its locks are plain std::mutex locals, which the analysis
#       cannot see.
#   thread_safety_check.sh <build>/compile_commands.json <source dir> --only FILE...
#       checks just FILE... with the flags of calib/src/ (the fixture that must be rejected).
#
# Every warning fails the check (-Werror), and so does a file that does not compile. Prints
# each file it checked. Exit 0: clean; 1: a warning or error; 77 (ctest SKIP_RETURN_CODE): no
# clang++ on the machine, except under CI=true, where that is a failure. CLANGXX overrides the
# compiler.
set -uo pipefail

if [ $# -lt 2 ]; then
  echo "usage: $0 <compile_commands.json> <source dir> [--only FILE...]" >&2
  exit 2
fi
db=$1
src=$(cd "$2" && pwd)
shift 2
only=()
if [ "${1:-}" = "--only" ]; then
  shift
  only=("$@")
fi

clang=${CLANGXX:-}
if [ -z "$clang" ]; then
  clang=$(command -v clang++ || true)
  if [ -z "$clang" ]; then  # a versioned one (clang++-14, ...), newest first
    clang=$(compgen -c clang++- | grep -E '^clang\+\+-[0-9]+$' | sort -t- -k2 -n -r | head -n1 || true)
  fi
fi
if [ -z "$clang" ] || ! command -v "$clang" >/dev/null 2>&1; then
  if [ "${CI:-}" = "true" ]; then
    echo "thread-safety: FAILED: clang++ not found (CI=true; scripts/install-deps.sh installs clang)"
    exit 1
  fi
  echo "SKIP: thread-safety: clang++ not found (scripts/install-deps.sh installs package clang)"
  exit 77
fi
if [ ! -f "$db" ]; then
  echo "thread-safety: FAILED: $db missing (configure the build tree first)"
  exit 1
fi

# compile_commands.json as CMake writes it: one "key": "value" per line, values JSON-escaped
# (only \\ and \" occur in them). files[i] is compiled in dirs[i] by cmds[i] (a shell command).
files=()
dirs=()
cmds=()
unescape() {  # JSON \\ and \" in $1, without a subprocess (the file has hundreds of lines)
  local v=${1//\\\\/$'\x01'}
  v=${v//\\\"/\"}
  REPLY=${v//$'\x01'/\\}
}
dir="" cmd=""
while IFS= read -r line; do
  if [[ $line =~ ^[[:space:]]*\"directory\":[[:space:]]*\"(.*)\",?$ ]]; then
    unescape "${BASH_REMATCH[1]}"
    dir=$REPLY
  elif [[ $line =~ ^[[:space:]]*\"command\":[[:space:]]*\"(.*)\",?$ ]]; then
    unescape "${BASH_REMATCH[1]}"
    cmd=$REPLY
  elif [[ $line =~ ^[[:space:]]*\"file\":[[:space:]]*\"(.*)\",?$ ]]; then
    unescape "${BASH_REMATCH[1]}"
    if [[ $REPLY == */Unity/unity_*.cxx ]]; then
      # A unity batch (RIGCAL_UNITY_BUILD): each source it includes, with the batch's flags,
      # checked on its own.
      while IFS= read -r member; do
        files+=("$member")
        dirs+=("$dir")
        cmds+=("${cmd//"$REPLY"/$member}")
      done < <(sed -n 's/^#include "\(.*\)"$/\1/p' "$REPLY")
    else
      files+=("$REPLY")
      dirs+=("$dir")
      cmds+=("$cmd")
    fi
  fi
done <"$db"
if [ ${#files[@]} -eq 0 ]; then
  echo "thread-safety: FAILED: no entry in $db"
  exit 1
fi

# What "uses threads or locks" means, in a file's text.
uses='std::(mutex|recursive_mutex|shared_mutex|timed_mutex|thread|jthread|condition_variable|atomic|lock_guard|unique_lock|scoped_lock)\b|rigcal/base/thread_annotations\.h|\bMutex(Lock)?\b|RIGCAL_(GUARDED_BY|PT_GUARDED_BY|REQUIRES|EXCLUDES|ACQUIRE|RELEASE)\b'
layers=(calib drivers vo tools)
in_layers() {
  local rel=${1#"$src"/} l
  for l in "${layers[@]}"; do [[ $rel == "$l"/* ]] && return 0; done
  return 1
}

# The compile command of entry $1, as clang++ syntax-only with the analysis, into array `args`.
clang_args() {
  local -a words
  eval "words=(${cmds[$1]})"
  args=("$clang")
  local i=1
  [[ $(basename "${words[0]}") == ccache ]] && i=2  # a launcher, then the compiler
  for (( ; i < ${#words[@]}; ++i)); do
    case ${words[i]} in
      -o) ((++i)) ;;  # no object
      -c) ;;
      *) args+=("${words[i]}") ;;
    esac
  done
  # -Wno-unknown-warning-option: GCC-only warning flags of the build are no finding.
  args+=(-fsyntax-only -Wthread-safety -Werror -Wno-unknown-warning-option)
}

failed=0
checked=0
declare -A seen_headers=()
# check_file <entry index> <file>: runs clang on <file> with the flags of the entry.
check_file() {
  local entry=$1 file=$2 log
  clang_args "$entry"
  if [ "$file" != "${files[entry]}" ]; then  # another file with this entry's flags
    local -a swapped=()
    local a
    for a in "${args[@]}"; do
      [ "$a" = "${files[entry]}" ] && a=$file
      swapped+=("$a")
    done
    args=("${swapped[@]}")
  fi
  # -H lists every included header as ". path" (dots = depth), and may add a list of headers
  # without include guards (bare paths); everything else is a diagnostic.
  log=$(cd "${dirs[entry]}" && "${args[@]}" -H 2>&1)
  local status=$?
  local h
  # The project's headers are found through absolute -I paths or next to an absolute source.
  while IFS= read -r h; do
    seen_headers[$h]=1
  done < <(grep -E '^\.+ ' <<<"$log" | sed -E 's/^\.+ //' | grep -F "$src/")
  ((++checked))
  if [ $status -ne 0 ] || grep -qE 'warning:|error:' <<<"$log"; then
    echo "FAILED  ${file#"$src"/}"
    grep -vE '^\.+ |^Multiple include guards may be useful for:$|^[^ :]+$' <<<"$log" |
      sed 's/^/    /'
    failed=1
  else
    echo "checked ${file#"$src"/}"
  fi
}

if [ ${#only[@]} -gt 0 ]; then
  reference=-1
  for i in "${!files[@]}"; do
    if [[ ${files[i]} == "$src"/calib/src/*.cc ]]; then reference=$i; break; fi
  done
  if [ $reference -lt 0 ]; then
    echo "thread-safety: FAILED: no calib/src/ entry in $db for the flags"
    exit 1
  fi
  for f in "${only[@]}"; do check_file "$reference" "$(realpath "$f")"; done
else
  for i in "${!files[@]}"; do
    f=${files[i]}
    in_layers "$f" || continue
    grep -qE "$uses" "$f" || continue
    check_file "$i" "$f"
  done
  # Headers that use threads or locks are checked through a source that includes them.
  while IFS= read -r h; do
    if [ -n "${seen_headers[$h]:-}" ]; then
      echo "checked ${h#"$src"/} (included)"
    else
      echo "FAILED  ${h#"$src"/}: uses threads or locks but no checked source includes it"
      failed=1
    fi
  done < <(for l in "${layers[@]}"; do
             find "$src/$l" -name '*.h' -print0 | xargs -0 grep -lE "$uses" || true
           done | sort)
fi

if [ $failed -ne 0 ]; then
  echo "thread-safety: FAILED ($clang -Wthread-safety -Werror, $checked sources)"
  exit 1
fi
echo "thread-safety: OK ($clang -Wthread-safety -Werror, $checked sources)"
