#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The Debian packages of this build tree (cpack -G DEB, cmake/RigcalPackaging.cmake), installed
# with dpkg into a private root: dpkg --root=DIR with a copy of this machine's package database,
# so dpkg checks the Depends against what is really installed here, unpacks into DIR and
# records the package there, while this machine's own /usr and dpkg database stay untouched
# (no `dpkg -i` into the host, nothing to remove afterwards). Then the installed rigcal runs
# from DIR: --version and `rigcal demo`. Also: a database without one of the Depends makes
# dpkg refuse the package (the Depends are real), and lintian's remarks are only those docs/deployment.md
# explains (tests/install/lintian-explained.txt), when lintian is installed.
# usage: deb_package_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$(readlink -f "$1")
source_dir=$(readlink -f "$2")
skip() {
  if [ "${CI:-}" = true ]; then echo "FAILED (CI=true, a skip is a failure): $1"; exit 1; fi
  echo "SKIP: $1"
  exit 77
}
for tool in cpack dpkg dpkg-deb dpkg-shlibdeps; do
  command -v "$tool" >/dev/null || skip "$tool not found (dpkg-dev)"
done
work="$build/deb-test"
rm -rf "$work"
mkdir -p "$work/packages"

(cd "$build" && cpack -G DEB -B "$work/packages" > "$work/cpack.log" 2>&1) ||
  { cat "$work/cpack.log"; echo "FAIL: cpack -G DEB"; exit 1; }
runtime=$(ls "$work"/packages/rigcal_*_amd64.deb 2>/dev/null || true)
dev=$(ls "$work"/packages/rigcal-dev_*_amd64.deb 2>/dev/null || true)
[ -n "$runtime" ] && [ -n "$dev" ] || { ls "$work/packages"; echo "FAIL: rigcal and rigcal-dev .deb expected"; exit 1; }

fail=0
check() {  # check NAME EXPR
  if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi
}
depends=$(dpkg-deb -f "$runtime" Depends)
echo "rigcal Depends: $depends"
# Ceres is linked statically (Debian's CeresConfig names libceres.a), its solvers are not.
check "Depends found by dpkg-shlibdeps (libc6, OpenCV, LCM, yaml-cpp, SuiteSparse)" \
  '[[ "$depends" == *libc6* && "$depends" == *libopencv-core* && "$depends" == *liblcm1* &&
     "$depends" == *libyaml-cpp* && "$depends" == *libcholmod* ]]'
for f in "$runtime" "$dev"; do
  printf '%s: %s bytes (installed %s KiB)\n' "$(basename "$f")" "$(stat -c %s "$f")" \
    "$(dpkg-deb -f "$f" Installed-Size)"
done

# A private root whose package database is this machine's.
new_root() {
  local root=$1
  mkdir -p "$root/var/lib/dpkg/info" "$root/var/lib/dpkg/updates" "$root/var/lib/dpkg/triggers"
  cp /var/lib/dpkg/status "$root/var/lib/dpkg/status"
  touch "$root/var/lib/dpkg/available"
}
root="$work/root"
new_root "$root"
dpkg --root="$root" --log=/dev/null -i "$runtime" "$dev" > "$work/dpkg.log" 2>&1 ||
  { cat "$work/dpkg.log"; echo "FAIL: dpkg -i of the packages into $root"; exit 1; }
check "dpkg records rigcal as installed" \
  '[ "$(dpkg-query --admindir="$root/var/lib/dpkg" -W -f="\${Status}" rigcal)" = "install ok installed" ]'
check "the host's dpkg database does not know rigcal" '! dpkg-query -W rigcal >/dev/null 2>&1'
check "installed rigcal --version" \
  '"$root/usr/bin/rigcal" --version | tee "$work/version.txt" | grep -q "^rigcal [0-9]"'
check "installed rigcal demo" '"$root/usr/bin/rigcal" demo > "$work/demo.txt" 2>&1'
check "demo printed the simulated rig's calibration" 'grep -q "^Simulated rig" "$work/demo.txt"'
check "units in the package" '[ -f "$root/usr/lib/systemd/system/rigcal.service" ] &&
   grep -q "^ExecStart=/usr/bin/rigcal calib" "$root/usr/lib/systemd/system/rigcal.service"'
check "CMake package in rigcal-dev" '[ -f "$root/usr/lib/cmake/rigcal/rigcalConfig.cmake" ] ||
   ls "$root"/usr/lib/*/cmake/rigcal/rigcalConfig.cmake >/dev/null 2>&1'
for pkg in rigcal rigcal-dev; do
  check "copyright and changelog.Debian.gz of $pkg (Debian policy 12.5, 12.7)" \
    '[ -f "$root/usr/share/doc/$pkg/copyright" ] &&
     gzip -dc "$root/usr/share/doc/$pkg/changelog.Debian.gz" | head -1 |
       grep -q "^rigcal ($(dpkg-deb -f "$runtime" Version)) "'
done
if [ -f "$build/lcmtypes/rigcal_lcmtypes.jar" ]; then
  check "jar in rigcal-dev" '[ -f "$root/usr/share/java/rigcal-lcmtypes.jar" ]'
fi

# The Depends are real: without OpenCV's core library package in the database dpkg refuses.
missing_pkg=$(echo "$depends" | tr ',' '\n' | awk '{print $1}' | grep -m1 '^libopencv-core' || true)
root2="$work/root-missing-dep"
new_root "$root2"
awk -v p="$missing_pkg" 'BEGIN{RS=""; ORS="\n\n"} $0 !~ ("(^|\n)Package: " p "\n")' \
  /var/lib/dpkg/status > "$root2/var/lib/dpkg/status"
missing_rc=0
dpkg --root="$root2" --log=/dev/null -i "$runtime" > "$work/dpkg-missing.log" 2>&1 || missing_rc=$?
check "without ${missing_pkg:-libopencv-core} dpkg refuses rigcal (rc $missing_rc)" \
  '[ -n "$missing_pkg" ] && [ "$missing_rc" -ne 0 ] && grep -q "depends on $missing_pkg" "$work/dpkg-missing.log"'

if command -v lintian >/dev/null; then
  lintian --tag-display-limit 0 "$runtime" "$dev" 2>&1 | grep -E '^[EWIXPO]: ' > "$work/lintian.txt" || true
  cat "$work/lintian.txt"
  explained="$source_dir/tests/install/lintian-explained.txt"
  unexplained=$(awk '{print $3}' "$work/lintian.txt" | sort -u |
                grep -vxF -f <(grep -v '^#' "$explained" | awk 'NF{print $1}') || true)
  check "lintian: every remark explained in docs/deployment.md (unexplained: ${unexplained:-none})" '[ -z "$unexplained" ]'
else
  echo "note: lintian not installed, packages not linted"
fi

if [ "$fail" -ne 0 ]; then echo "deb_package: FAILED"; exit 1; fi
echo "deb_package: passed"
