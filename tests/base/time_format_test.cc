// SPDX-License-Identifier: Apache-2.0
// Tests of time_format.h: stamps as text.
#include "rigcal/base/time_format.h"

#include <gtest/gtest.h>

#include <cstdint>

namespace rigcal {
namespace {

TEST(FormatNsAsSeconds, ExactWithNineDecimals) {
  EXPECT_EQ(FormatNsAsSeconds(0), "0.000000000");
  EXPECT_EQ(FormatNsAsSeconds(-1), "-0.000000001");
  EXPECT_EQ(FormatNsAsSeconds(1403715524907143168LL), "1403715524.907143168");
  EXPECT_EQ(FormatNsAsSeconds(12'500'000'000LL), "12.500000000");
  EXPECT_EQ(FormatNsAsSeconds(INT64_MAX), "9223372036.854775807");
  EXPECT_EQ(FormatNsAsSeconds(INT64_MIN), "-9223372036.854775808");
}

}  // namespace
}  // namespace rigcal
