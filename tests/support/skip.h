// SPDX-License-Identifier: Apache-2.0
#pragma once
// Skipping a test for something the machine lacks (recorded data, a tool, a permission).
// RIGCAL_SKIP_MISSING() << reason; is GTEST_SKIP() << reason; except under CI=true, where a
// missing input means the CI machine is set up wrong: the test then fails with the reason.
// Skips that are not about missing inputs (e.g. a check that is meaningless under a sanitizer)
// keep using GTEST_SKIP.

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

namespace rigcal::support {

inline bool InCi() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && std::strcmp(ci, "true") == 0;
}

inline ::testing::TestPartResult::Type MissingInputResult() {
  return InCi() ? ::testing::TestPartResult::kFatalFailure : ::testing::TestPartResult::kSkip;
}

inline const char* MissingInputHeader() {
  return InCi() ? "CI=true: a test may not skip for a missing input" : "";
}

}  // namespace rigcal::support

// Use like GTEST_SKIP(): returns from the current function.
#define RIGCAL_SKIP_MISSING()                                                           \
  return GTEST_MESSAGE_AT_(__FILE__, __LINE__, ::rigcal::support::MissingInputHeader(), \
                           ::rigcal::support::MissingInputResult())
