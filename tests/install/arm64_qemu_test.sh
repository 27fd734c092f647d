#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The arm64 build, proven to run: scripts/cross-arm64.sh cross-builds `rigcal` for arm64 into
# BUILD_DIR/arm64 (Debian's cross compiler, Debian's arm64 libraries in a sysroot), then
# qemu-aarch64 runs it here with the sysroot as its library root (-L):
#   - `rigcal --version` prints the version of the amd64 build;
#   - `rigcal solve --json` on a small trajectory set (VO poses of 120 simulated frames by the
#     amd64 build) gives the same rotations, centres and scales as the amd64 build, to 1e-9;
#   - `rigcal demo` calibrates; a short `rigcal run` on the simulated rig (30 frames, lossless:
#     NEON renderer, VO, estimator under emulation) matches frame sets and stops cleanly.
# Prints the arm64 binary's size and NEEDED list and compares the list with the amd64 one.
# Skipped (a failure under CI=true) when the cross tools or the arm64 packages cannot be had.
# usage: arm64_qemu_test.sh AMD64_RIGCAL SOURCE_DIR BUILD_DIR
set -euo pipefail
amd64=$(readlink -f "$1")
source_dir=$(readlink -f "$2")
build=$(readlink -f "$3")
skip() {
  if [ "${CI:-}" = true ]; then echo "FAILED (CI=true, a skip is a failure): $1"; exit 1; fi
  echo "SKIP: $1"
  exit 77
}
sysroot=${RIGCAL_ARM64_SYSROOT:-/var/cache/rigcal/arm64-sysroot}
export RIGCAL_ARM64_SYSROOT="$sysroot"
work="$build/arm64-test"
arm_build="$build/arm64"
rm -rf "$work"
mkdir -p "$work"

# The cross tools and the arm64 packages (scripts/cross-arm64.sh --setup installs the tools when
# missing and makes the sysroot): what cannot be had is a skip; a build that fails with both at
# hand is a failure.
start=$(date +%s)
if ! bash "$source_dir/scripts/cross-arm64.sh" --setup > "$work/setup.log" 2>&1; then
  tail -5 "$work/setup.log"
  skip "the arm64 cross tools or the arm64 packages (sysroot $sysroot) could not be had (see above)"
fi
echo "arm64 tools and sysroot: $(( $(date +%s) - start )) s"
start=$(date +%s)
if ! bash "$source_dir/scripts/cross-arm64.sh" --build-dir "$arm_build" > "$work/build.log" 2>&1; then
  tail -30 "$work/build.log"
  echo "FAIL: cross build of rigcal for arm64"
  exit 1
fi
echo "arm64 build (rigcal target, ccache): $(( $(date +%s) - start )) s"
arm="$arm_build/tools/rigcal"
qemu=(qemu-aarch64 -L "$sysroot")

fail=0
check() {  # check NAME EXPR
  if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi
}
header=$(readelf -h "$arm")
check "the binary is AArch64" '[[ "$header" == *"Machine:"*AArch64* ]]'
aarch64-linux-gnu-strip -o "$work/rigcal.stripped" "$arm"
echo "arm64 rigcal: $(stat -c %s "$arm") bytes ($(stat -c %s "$work/rigcal.stripped") stripped)"
# Without the program loader (ld-linux-aarch64.so.1 is NEEDED on arm64, not on amd64; libc6
# provides both).
needed() { readelf -d "$1" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p' | grep -v '^ld-linux' | sort; }
needed_arm=$(needed "$arm")
needed_amd=$(needed "$amd64")
echo "arm64 NEEDED: $(echo $needed_arm)"
check "same NEEDED sonames as the amd64 build (so the same Debian Depends)" \
  '[ "$needed_arm" = "$needed_amd" ] || diff <(echo "$needed_amd") <(echo "$needed_arm")'

# The version without the `git describe` part, which is that of the commit each tree was
# configured at.
version_arm=$("${qemu[@]}" "$arm" --version) || version_arm="(failed)"
version_amd=$("$amd64" --version)
echo "arm64: $version_arm; amd64: $version_amd"
check "rigcal --version under qemu-aarch64 gives the amd64 version" \
  '[ "${version_arm%% (*}" = "${version_amd%% (*}" ]'
check "rigcal demo under qemu-aarch64" '"${qemu[@]}" "$arm" demo > "$work/demo.txt" 2>&1'

# A small trajectory set: the VO poses of the first 120 frames (6 s) of the simulated rig, by
# the amd64 build, lossless (--fast), so the same every time.
cd "$work"
sed 's/^  num_frames: 468/  num_frames: 120/' "$source_dir/config/sim_thesis_virtual.yaml" > "$work/rig.yaml"
grep -q "^  num_frames: 120" "$work/rig.yaml" || { echo "FAIL: could not shorten the simulated run"; exit 1; }
"$amd64" run --config "$work/rig.yaml" --fast --status-every 0 --poses-out "$work/poses" \
  --out "$work/amd64_run.yaml" > /dev/null 2>&1 || true
[ -f "$work/poses/cam0.txt" ] || { echo "FAIL: no VO poses from the amd64 run"; exit 1; }
slaves=()
for f in "$work"/poses/*.txt; do
  name=$(basename "$f" .txt)
  [ "$name" = cam0 ] || slaves+=(--slave "$name=$f")
done
"$amd64" solve --master "cam0=$work/poses/cam0.txt" "${slaves[@]}" --json > "$work/amd64.json" 2> "$work/amd64.err" || true
"${qemu[@]}" "$arm" solve --master "cam0=$work/poses/cam0.txt" "${slaves[@]}" --json > "$work/arm64.json" 2> "$work/arm64.err" || true
check "rigcal solve: arm64 and amd64 agree to 1e-9" 'python3 - "$work/amd64.json" "$work/arm64.json" <<"PY"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
worst = 0.0
assert len(a["slaves"]) == len(b["slaves"]) > 0, "no slaves"
for sa, sb in zip(a["slaves"], b["slaves"]):
    assert sa["name"] == sb["name"] and sa["state"] == sb["state"], (sa["state"], sb["state"])
    va = sa["q_wxyz"] + sa["C"] + [sa.get("scale") or 0.0]
    vb = sb["q_wxyz"] + sb["C"] + [sb.get("scale") or 0.0]
    assert None not in va + vb, "unknown value"
    worst = max([worst] + [abs(x - y) for x, y in zip(va, vb)])
    print("%s: %s, q %s, C %s, scale %s" % (sa["name"], sa["state"], sa["q_wxyz"], sa["C"], sa.get("scale")))
print("largest difference arm64 - amd64 over q, C, scale: %.3g" % worst)
sys.exit(0 if worst <= 1e-9 else 1)
PY'

# The live pipeline under emulation: 30 frames of the simulated rig (renderer with NeonLanes,
# VO per camera, SyncBuffer, estimator), lossless (--fast: no real-time pacing, so no frame is
# dropped however slow the emulation is); VO initialises and matched sets reach the estimator.
sed 's/^  num_frames: 120/  num_frames: 30/' "$work/rig.yaml" > "$work/rig30.yaml"
rc=0
start=$(date +%s)
"${qemu[@]}" "$arm" run --config "$work/rig30.yaml" --fast --status-every 1 \
  --out "$work/arm64_run.yaml" > "$work/run.txt" 2> "$work/run.err" || rc=$?
tail -3 "$work/run.err"
echo "rigcal run of 30 frames under qemu-aarch64: $(( $(date +%s) - start )) s"
check "rigcal run under qemu-aarch64 stops cleanly (exit 0 or 3, got $rc)" '[ "$rc" -eq 0 ] || [ "$rc" -eq 3 ]'
# The sync buffer's summary at the end of the run: "sync: sets 21 (popped 21, ready 0) | ...".
check "rigcal run under qemu-aarch64 matched frame sets" 'grep -Eq "sync: sets [1-9][0-9]* " "$work/run.err"'

if [ "$fail" -ne 0 ]; then echo "arm64_qemu: FAILED"; exit 1; fi
echo "arm64_qemu: passed"
