#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# `cmake --install` of this build tree into a temporary prefix, then a small project
# (tests/install/consumer) configured, built and run against it with find_package(rigcal) only.
# Fails when a file the install promises is missing, when find_package or the exported
# targets do not work, or when the consumer's calibration is wrong.
# usage: install_consumer_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$(readlink -f "$1")
source_dir=$(readlink -f "$2")
# Fixed paths inside the build tree (not mktemp): ccache then hits on the consumer's one file.
work="$build/install-test"
prefix="$work/prefix"
rm -rf "$work"
mkdir -p "$work"

cmake --install "$build" --prefix "$prefix" > "$work/install.log"
fail=0
check() {  # check NAME EXPR
  if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi
}
check "bin/rigcal installed" '[ -x "$prefix/bin/rigcal" ]'
check "installed rigcal --version" '"$prefix/bin/rigcal" --version | grep -q "^rigcal [0-9]"'
for header in base/types.h calib/rig_calibrator.h camera/camera_model.h capture/frame.h \
              vo/monocular_vo.h io/rig_config.h lcm/message_validation.h pipeline/pipeline.h \
              camera_pose_t.hpp rig_status_t.hpp; do
  check "include/rigcal/$header" '[ -f "$prefix/include/rigcal/$header" ]'
done
check "no private header installed" '[ -z "$(find "$prefix/include" -path "*/src/*")" ]'
check "static libraries" '[ -f "$prefix/lib/librigcal_base.a" ] && [ -f "$prefix/lib/librigcal_calib.a" ] &&
                          [ -f "$prefix/lib/librigcal_vo.a" ]'
check "CMake package" '[ -f "$prefix/lib/cmake/rigcal/rigcalConfig.cmake" ] &&
                       [ -f "$prefix/lib/cmake/rigcal/rigcalTargets.cmake" ]'
check "LCM definitions" '[ -f "$prefix/share/rigcal/lcmtypes/rig_status_t.lcm" ]'
check "Python LCM types" '[ -f "$prefix/lib/python3/dist-packages/rigcal/rig_status_t.py" ]'
if [ -f "$build/lcmtypes/rigcal_lcmtypes.jar" ]; then
  check "Java LCM types jar" '[ -f "$prefix/share/java/rigcal-lcmtypes.jar" ]'
  # lcm-spy with the installed jar, as docs/deployment.md invokes it (headless: it lists the
  # types it found on the class path, then cannot open its window).
  ntypes=$(ls "$source_dir"/lcmtypes/*.lcm | wc -l)
  if command -v java >/dev/null && [ -f /usr/share/java/lcm.jar ]; then
    java -Djava.awt.headless=true -Djava.net.preferIPv4Stack=true -Xmx128m \
      -cp "/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar:$prefix/share/java/rigcal-lcmtypes.jar" \
      lcm.spy.Spy --lcm-url=memq:// > "$work/lcm-spy.log" 2>&1 || true
    check "lcm-spy finds the $ntypes rigcal types in the installed jar" \
      'grep -q "Found $ntypes LCM types" "$work/lcm-spy.log"'
  fi
fi
check "example configs" '[ -f "$prefix/share/rigcal/config/sim_thesis_virtual.yaml" ]'
if command -v python3 >/dev/null && python3 -c 'import lcm' 2>/dev/null; then
  check "Python types import and encode" \
    'PYTHONPATH="$prefix/lib/python3/dist-packages" python3 -c "import rigcal; m = rigcal.rig_status_t(); assert len(m.encode()) > 8"'
fi

generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# The static libraries of a sanitizer tree call the sanitizer's runtime: the consumer links it,
# with the tree's compiler.
sanitizer=()
if grep -q '^RIGCAL_ASAN_ENABLED:BOOL=ON$' "$build/CMakeCache.txt"; then
  sanitizer=(-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined)
elif grep -q '^RIGCAL_TSAN_ENABLED:BOOL=ON$' "$build/CMakeCache.txt"; then
  sanitizer=(-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=thread)
fi
if [ ${#sanitizer[@]} -gt 0 ]; then
  sanitizer+=("-DCMAKE_CXX_COMPILER=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt")")
fi
cmake -S "$source_dir/tests/install/consumer" -B "$work/consumer" "${generator[@]}" "${launcher[@]}" \
  "${sanitizer[@]}" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
  > "$work/consumer-configure.log" 2>&1 ||
  { cat "$work/consumer-configure.log"; echo "FAIL: consumer configure (find_package(rigcal))"; exit 1; }
cmake --build "$work/consumer" > "$work/consumer-build.log" 2>&1 ||
  { cat "$work/consumer-build.log"; echo "FAIL: consumer build against the installed tree"; exit 1; }
check "consumer found rigcal in the prefix" \
  'grep -q "rigcal_DIR:PATH=$prefix/lib/cmake/rigcal" "$work/consumer/CMakeCache.txt"'
check "consumer runs and calibrates" '"$work/consumer/rigcal_consumer"'
if [ "$fail" -ne 0 ]; then echo "install_consumer: FAILED"; exit 1; fi
echo "install_consumer: passed"
