#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The command reference from the help texts of a built rigcal, so it cannot drift from them:
#   scripts/gen-command-docs.sh RIGCAL markdown [docs/commands.md]  (ctest cli/commands_doc
#                                                                   checks that it is current)
#   scripts/gen-command-docs.sh RIGCAL man [rigcal.1]               (the rigcal(1) man page of
#                                                                   the .deb, built by tools/cli)
# Without the output file, the text goes to stdout.
# RIGCAL is the rigcal binary; its help is taken as `rigcal [SUBCOMMAND] --help` with the program
# named `rigcal` and 100 columns.
set -euo pipefail
[ $# -eq 2 ] || [ $# -eq 3 ] ||
  { echo "usage: scripts/gen-command-docs.sh RIGCAL markdown|man [OUT]" >&2; exit 2; }
if [ $# -eq 3 ]; then exec > "$3"; fi
binary=$(realpath "$1")
format="$2"
bindir=$(mktemp -d)
trap 'rm -rf "$bindir"' EXIT
ln -s "$binary" "$bindir/rigcal"
help() { COLUMNS=100 PATH="$bindir:$PATH" rigcal "$@" --help; }
subcommands=$(help | sed -n '/^Subcommands:/,$p' | grep -E '^  [a-z][a-z0-9-]+ ' | awk '{print $1}')

markdown() {
  echo "# Command reference"
  echo
  echo "Generated from the help texts by \`scripts/gen-command-docs.sh\` (do not edit; ctest"
  echo "\`docs/commands\` fails when this page differs from the built \`rigcal\`). Exit codes:"
  echo "[the table](#exit-codes)."
  echo
  for sub in $subcommands; do echo "- [rigcal $sub](#rigcal-$sub)"; done
  echo
  echo "## rigcal"
  echo
  echo '```text'
  help
  echo '```'
  for sub in $subcommands; do
    echo
    echo "## rigcal $sub"
    echo
    echo '```text'
    help "$sub"
    echo '```'
  done
  echo
  echo "## Exit codes"
  echo
  echo "| code | meaning (every subcommand) |"
  echo "|---|---|"
  echo "| 0 | done; for the calibrating commands every slave usable |"
  echo "| 1 | bad input: a file missing, unreadable or malformed (the message names file, line, field), a device that fails |"
  echo "| 2 | usage: unknown subcommand or option, a missing or invalid argument |"
  echo "| 3 | ran, but some slave could not be calibrated (insufficient motion, nothing received) |"
  echo
  echo "\`rigcal status --once\` exits with the rig's health instead: 0 converged, 1 converging,"
  echo "2 decalibration alarm, 3 no data within \`--timeout\`."
}

# roff: a backslash doubled, a leading dot or quote escaped.
roff_text() { sed -e 's/\\/\\e/g' -e "s/^\\([.']\\)/\\\\\\&\\1/"; }

man() {
  local version
  version=$(PATH="$bindir:$PATH" rigcal --version | awk '{print $2}')
  echo ".TH RIGCAL 1 \"\" \"rigcal $version\" \"User Commands\""
  echo ".SH NAME"
  echo "rigcal \\- online extrinsic calibration of multi-camera rigs"
  echo ".SH SYNOPSIS"
  echo ".B rigcal"
  echo "[\\fIOPTIONS\\fR] \\fISUBCOMMAND\\fR [\\fIARGS\\fR]"
  echo ".SH DESCRIPTION"
  echo ".nf"
  help | roff_text
  echo ".fi"
  for sub in $subcommands; do
    echo ".SH \"RIGCAL ${sub^^}\""
    echo ".nf"
    help "$sub" | roff_text
    echo ".fi"
  done
  echo ".SH \"EXIT STATUS\""
  echo "0 done (every slave usable); 1 bad input; 2 usage; 3 some slave not calibrated."
  echo "rigcal status \-\-once: 0 converged, 1 converging, 2 decalibration alarm, 3 no data."
  echo ".SH \"SEE ALSO\""
  echo "/usr/share/doc/rigcal, lcm-logger(1), lcm-logplayer(1)"
}

case "$format" in
  markdown) markdown ;;
  man) man ;;
  *) echo "unknown format '$format' (markdown or man)" >&2; exit 2 ;;
esac
