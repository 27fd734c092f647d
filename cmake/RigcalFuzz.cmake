# SPDX-License-Identifier: Apache-2.0
# libFuzzer targets (RIGCAL_FUZZ_ENABLED: clang with RIGCAL_ASAN_ENABLED, so every target runs
# under ASan and UBSan). docs/testing.md "Sanitizers and fuzzing".
#
# rigcal_add_fuzz_target(NAME <name> SOURCES <file>... [LIBS <target>...]
#                        [INSTRUMENT <target>...] [CORPUS <dir>] [MAX_LEN <bytes>])
# Builds fuzz_<name> from SOURCES (they define LLVMFuzzerTestOneInput; linked with
# -fsanitize=fuzzer, which brings main) against LIBS, and registers the ctest test fuzz/<name>
# (label `fuzz`): scripts/run_fuzz_target.sh runs it for RIGCAL_FUZZ_SECONDS, starting from the
# seed corpus CORPUS (default tests/fuzz/corpus/<name>/) and the inputs earlier runs found
# (<build>/fuzz/<name>/corpus/); a crash, leak, sanitizer report or hang fails the test and
# leaves the input in <build>/fuzz/<name>/. INSTRUMENT: project libraries whose code the target
# exercises, compiled with coverage feedback (-fsanitize=fuzzer-no-link) so that the fuzzer sees
# which inputs reach new code; other libraries are only sanitized. MAX_LEN: largest input
# generated (default 4096). Without RIGCAL_FUZZ_ENABLED the function does nothing.
set(RIGCAL_FUZZ_SECONDS 30 CACHE STRING "Seconds each fuzz target runs in ctest (label fuzz)")
set(RIGCAL_FUZZ_RUNNER ${CMAKE_CURRENT_LIST_DIR}/../scripts/run_fuzz_target.sh)

function(rigcal_add_fuzz_target)
  if(NOT RIGCAL_FUZZ_ENABLED)
    return()
  endif()
  cmake_parse_arguments(ARG "" "NAME;CORPUS;MAX_LEN" "SOURCES;LIBS;INSTRUMENT" ${ARGN})
  if(NOT ARG_NAME OR NOT ARG_SOURCES)
    message(FATAL_ERROR "rigcal_add_fuzz_target: NAME and SOURCES are required")
  endif()
  if(NOT ARG_CORPUS)
    set(ARG_CORPUS ${PROJECT_SOURCE_DIR}/tests/fuzz/corpus/${ARG_NAME})
  endif()
  if(NOT ARG_MAX_LEN)
    set(ARG_MAX_LEN 4096)
  endif()
  set(target fuzz_${ARG_NAME})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_LIBS})
  target_compile_options(${target} PRIVATE -fsanitize=fuzzer ${RIGCAL_WARNING_FLAGS})
  target_link_options(${target} PRIVATE -fsanitize=fuzzer)
  foreach(lib ${ARG_INSTRUMENT})
    get_target_property(instrumented ${lib} RIGCAL_FUZZ_INSTRUMENTED)
    if(NOT instrumented)
      target_compile_options(${lib} PRIVATE -fsanitize=fuzzer-no-link)
      set_target_properties(${lib} PROPERTIES RIGCAL_FUZZ_INSTRUMENTED ON)
    endif()
  endforeach()
  add_dependencies(rigcal_fuzz_targets ${target})
  set(work ${PROJECT_BINARY_DIR}/fuzz/${ARG_NAME})
  add_test(NAME fuzz/${ARG_NAME}
           COMMAND bash ${RIGCAL_FUZZ_RUNNER} $<TARGET_FILE:${target}> ${ARG_CORPUS} ${work}
                   ${RIGCAL_FUZZ_SECONDS} ${ARG_MAX_LEN})
  # The script bounds its own run (RIGCAL_FUZZ_SECONDS in the environment overrides the
  # configured time: `make fuzz FUZZ_SECONDS=600`); the ctest timeout is only a backstop.
  set_tests_properties(fuzz/${ARG_NAME} PROPERTIES LABELS fuzz TIMEOUT 86400
                       SKIP_RETURN_CODE 77)
endfunction()

if(RIGCAL_FUZZ_ENABLED AND NOT TARGET rigcal_fuzz_targets)
  add_custom_target(rigcal_fuzz_targets)
endif()
