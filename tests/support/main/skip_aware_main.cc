// SPDX-License-Identifier: Apache-2.0
// main() of every GoogleTest binary: like gtest_main, but when no test failed and at least one
// was skipped it exits 77, which ctest (SKIP_RETURN_CODE 77) reports as "Skipped" rather than
// "Passed". A failure always wins: the exit code is then 1 whatever was skipped.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace {
constexpr int kSkippedExitCode = 77;
}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleMock(&argc, argv);
  const int result = RUN_ALL_TESTS();
  if (result != 0) return result;
  const ::testing::UnitTest& unit = *::testing::UnitTest::GetInstance();
  if (unit.skipped_test_count() > 0) return kSkippedExitCode;
  return 0;
}
