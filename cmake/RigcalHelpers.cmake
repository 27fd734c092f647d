# SPDX-License-Identifier: Apache-2.0
# Helpers that give every module the same shape (one library target per folder,
# tests registered as <module>/<name>).
include(GNUInstallDirs)

# rigcal_add_library(NAME <target> SRCS ... PUBLIC_DEPS ... PRIVATE_DEPS ...)
# Public headers live in <folder>/include/rigcal/<folder>/ (installed to <prefix>/include).
function(rigcal_add_library)
  cmake_parse_arguments(ARG "" "NAME" "SRCS;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${ARG_NAME} ${ARG_SRCS})
  target_include_directories(${ARG_NAME} PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
                                                $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  # The folder whose rigcal/<module>/ headers `cmake --install` copies (cmake/RigcalInstall.cmake).
  set_property(TARGET ${ARG_NAME} PROPERTY RIGCAL_PUBLIC_HEADER_DIR ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(${ARG_NAME} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  target_compile_options(${ARG_NAME} PRIVATE ${RIGCAL_WARNING_FLAGS})
  set_target_properties(${ARG_NAME} PROPERTIES UNITY_BUILD ${RIGCAL_UNITY_BUILD})
endfunction()

# rigcal_add_test(MODULE <module> NAME <name> SRCS ... DEPS ... [LABELS ...] [TIMEOUT s])
# Builds <module>_<name>_test and registers it with ctest as <module>/<name>. The binary's main
# (rigcal_gtest_main, tests/support/main) exits 77 when a test skipped and none failed, which
# ctest reports as skipped (SKIP_RETURN_CODE), never as passed.
function(rigcal_add_test)
  cmake_parse_arguments(ARG "" "MODULE;NAME;TIMEOUT" "SRCS;DEPS;LABELS" ${ARGN})
  set(target ${ARG_MODULE}_${ARG_NAME}_test)
  add_executable(${target} ${ARG_SRCS})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} rigcal_gtest_main GTest::gtest GTest::gmock)
  target_compile_options(${target} PRIVATE ${RIGCAL_WARNING_FLAGS})
  if(TARGET rigcal_test_pch)  # tests/CMakeLists.txt, RIGCAL_TEST_PCH
    target_precompile_headers(${target} REUSE_FROM rigcal_test_pch)
    target_compile_options(${target} PRIVATE -pthread -Winvalid-pch)
  endif()
  target_compile_definitions(${target} PRIVATE
    RIGCAL_SHARED_DATA_DIR="${RIGCAL_SHARED_DATA_DIR}"
    RIGCAL_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  add_test(NAME ${ARG_MODULE}/${ARG_NAME} COMMAND ${target})
  set(labels ${ARG_MODULE} ${ARG_LABELS})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  set_tests_properties(${ARG_MODULE}/${ARG_NAME} PROPERTIES LABELS "${labels}" TIMEOUT ${ARG_TIMEOUT}
                       SKIP_RETURN_CODE 77)
endfunction()

# Sanitized code runs several times slower (ASan at -O1: up to ~10x on the Eigen-heavy
# estimators): the ctest TIMEOUT of every test, a guard against hangs and no check of speed, is
# multiplied by RIGCAL_TEST_TIMEOUT_SCALE (default 3 in a sanitizer tree, 1 otherwise).
if(RIGCAL_ASAN_ENABLED OR RIGCAL_TSAN_ENABLED)
  set(RIGCAL_TEST_TIMEOUT_SCALE 3 CACHE STRING "Factor on every test's ctest TIMEOUT")
else()
  set(RIGCAL_TEST_TIMEOUT_SCALE 1 CACHE STRING "Factor on every test's ctest TIMEOUT")
endif()

# rigcal_scale_test_timeouts(): applies RIGCAL_TEST_TIMEOUT_SCALE to the tests of the current
# directory; called at the end of each CMakeLists.txt that adds tests.
function(rigcal_scale_test_timeouts)
  if(RIGCAL_TEST_TIMEOUT_SCALE EQUAL 1)
    return()
  endif()
  get_property(tests DIRECTORY PROPERTY TESTS)
  foreach(test ${tests})
    get_test_property(${test} TIMEOUT timeout)
    if(timeout)
      math(EXPR timeout "${timeout} * ${RIGCAL_TEST_TIMEOUT_SCALE}")
      set_tests_properties(${test} PROPERTIES TIMEOUT ${timeout})
    endif()
  endforeach()
endfunction()
