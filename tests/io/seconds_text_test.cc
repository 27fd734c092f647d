// SPDX-License-Identifier: Apache-2.0
// Time stamps as text: decimal seconds to exact nanoseconds (rounding, overflow, rejected text)
// and back.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "rigcal/io/trajectory_io.h"

namespace rigcal::io::trajectory_test {
namespace {

TEST(ParseSecondsToNsTest, ExactDecimalConversion) {
  EXPECT_EQ(ParseSecondsToNs("1305031102.175304"), 1305031102175304000LL);
  // 1403715524.907143168 is not representable as a double; the string path keeps every digit.
  EXPECT_EQ(ParseSecondsToNs("1403715524.907143168"), 1403715524907143168LL);
  EXPECT_EQ(ParseSecondsToNs("0"), 0);
  EXPECT_EQ(ParseSecondsToNs("-0.5"), -500000000LL);
  EXPECT_EQ(ParseSecondsToNs("+2"), 2000000000LL);
  EXPECT_EQ(ParseSecondsToNs(".25"), 250000000LL);
  EXPECT_EQ(ParseSecondsToNs("7."), 7000000000LL);
  EXPECT_EQ(ParseSecondsToNs("1.037359e-01"), 103735900LL);
  EXPECT_EQ(ParseSecondsToNs("1.5E3"), 1500000000000LL);
  EXPECT_EQ(ParseSecondsToNs("0.000000001"), 1);
  EXPECT_EQ(ParseSecondsToNs("1.00000000000000000000"), 1000000000LL);
  // Below the nanosecond: round half away from zero.
  EXPECT_EQ(ParseSecondsToNs("1.0000000005"), 1000000001LL);
  EXPECT_EQ(ParseSecondsToNs("1.0000000004999"), 1000000000LL);
  EXPECT_EQ(ParseSecondsToNs("-1.0000000005"), -1000000001LL);
  EXPECT_EQ(ParseSecondsToNs("4e-10"), 0);
  EXPECT_EQ(ParseSecondsToNs("9223372036.854775807"), INT64_MAX);
}

TEST(ParseSecondsToNsTest, RejectsNonNumbersAndOverflow) {
  for (const char* bad : {"", "-", ".", "abc", "1.2.3", "1e", "1e+", "12s", "nan", "inf", "0x10",
                          "1 2", "9223372036.854775808", "1e30", "99999999999999999999"}) {
    EXPECT_FALSE(ParseSecondsToNs(bad).has_value()) << "'" << bad << "'";
  }
}

TEST(FormatNsAsSecondsTest, ExactAndRoundTrips) {
  EXPECT_EQ(FormatNsAsSeconds(0), "0.000000000");
  EXPECT_EQ(FormatNsAsSeconds(-1), "-0.000000001");
  EXPECT_EQ(FormatNsAsSeconds(1403715524907143168LL), "1403715524.907143168");
  for (const int64_t t : std::vector<int64_t>{INT64_MIN + 1, -1234567890123LL, 42, INT64_MAX}) {
    EXPECT_EQ(ParseSecondsToNs(FormatNsAsSeconds(t)), t);
  }
}
}  // namespace
}  // namespace rigcal::io::trajectory_test
