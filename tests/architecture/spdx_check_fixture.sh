#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# ctest architecture/spdx_fixture: scripts/add-spdx.sh --check fails on a repository with a
# source file without the SPDX line, adds the line (after a shebang, nothing else changed) and
# then passes; a fixture, a config and a README are left alone.
set -euo pipefail
source_dir="$1"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
git init -q .
mkdir -p scripts tests/io/fixtures config
cp "$source_dir/scripts/add-spdx.sh" scripts/
printf 'int main() { return 0; }\n' > a.cc
printf '#!/usr/bin/env bash\necho hi\n' > scripts/run.sh && chmod +x scripts/run.sh
printf 'data\n' > tests/io/fixtures/data.h
printf 'rig: {}\n' > config/rig.yaml
printf '# readme\n' > README.md
git add -A
fail() { echo "FAIL: $*"; exit 1; }
if bash scripts/add-spdx.sh --check >/dev/null 2>&1; then fail "--check passed with a.cc lacking the line"; fi
bash scripts/add-spdx.sh
[ "$(head -n 1 a.cc)" = "// SPDX-License-Identifier: Apache-2.0" ] || fail "a.cc: $(head -n 1 a.cc)"
[ "$(sed -n 2p a.cc)" = "int main() { return 0; }" ] || fail "a.cc body changed"
[ "$(head -n 1 scripts/run.sh)" = "#!/usr/bin/env bash" ] || fail "shebang moved"
[ "$(sed -n 2p scripts/run.sh)" = "# SPDX-License-Identifier: Apache-2.0" ] || fail "run.sh line 2"
[ -x scripts/run.sh ] || fail "run.sh lost its mode"
[ "$(cat tests/io/fixtures/data.h)" = "data" ] || fail "a fixture was changed"
[ "$(cat config/rig.yaml)" = "rig: {}" ] || fail "a config was changed"
bash scripts/add-spdx.sh
[ "$(grep -c SPDX a.cc)" = 1 ] || fail "a second run added another line"
bash scripts/add-spdx.sh --check >/dev/null || fail "--check failed after the run"
echo "PASS"
