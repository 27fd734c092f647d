// SPDX-License-Identifier: Apache-2.0
// Tests of format.h: numbers as text.
#include "rigcal/base/format.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace rigcal {
namespace {

TEST(ShortestText, ReadsBackExactly) {
  EXPECT_EQ(ShortestText(0.1), "0.1");
  EXPECT_EQ(ShortestText(20.0), "20");
  EXPECT_EQ(ShortestText(1e-5), "1e-05");
  EXPECT_EQ(ShortestText(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(ShortestText(std::nan("")), "nan");
  for (const double v : {1.0 / 3.0, -2.718281828459045, 6.02214076e23, 5e-324}) {
    EXPECT_EQ(std::strtod(ShortestText(v).c_str(), nullptr), v) << ShortestText(v);
  }
}

TEST(SignificantText, IsPrintfG) {
  EXPECT_EQ(SignificantText(8.333333333, 6), "8.33333");
  EXPECT_EQ(SignificantText(1e6, 6), "1e+06");
  EXPECT_EQ(SignificantText(0.5, 10), "0.5");
  EXPECT_EQ(SignificantText(std::nan(""), 6), "nan");
  // The same text as an ostream with that precision (what the messages used before).
  for (const double v : {123.456789012345, -0.000123456789, 42.0, 9.87654321e12}) {
    for (const int digits : {6, 9, 10}) {
      std::ostringstream out;
      out.precision(digits);
      out << v;
      EXPECT_EQ(SignificantText(v, digits), out.str()) << v << " " << digits;
    }
  }
}

TEST(FixedText, IsPrintfF) {
  EXPECT_EQ(FixedText(0.25, 3), "0.250");
  EXPECT_EQ(FixedText(-1.005, 0), "-1");
  EXPECT_EQ(FixedText(2.0 / 3.0, 4), "0.6667");
  EXPECT_EQ(FixedText(1e300, 2).size(), 301u + 3u);  // no truncation of large values
}

TEST(VectorText, FixedDecimalsPerCoordinate) {
  EXPECT_EQ(VectorText(Eigen::Vector3d(0.1, -2.0, 3.14159), 3), "[0.100, -2.000, 3.142]");
}

}  // namespace
}  // namespace rigcal
