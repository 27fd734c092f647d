// SPDX-License-Identifier: Apache-2.0
#include "rigcal/base/time_format.h"

#include <array>
#include <cstdio>

namespace rigcal {

std::string FormatNsAsSeconds(int64_t t_ns) {
  const bool negative = t_ns < 0;
  // The magnitude in unsigned arithmetic, so that INT64_MIN does not overflow.
  const uint64_t magnitude =
      negative ? ~static_cast<uint64_t>(t_ns) + 1 : static_cast<uint64_t>(t_ns);
  std::array<char, 40> buf{};
  std::snprintf(buf.data(), buf.size(), "%s%llu.%09llu", negative ? "-" : "",
                static_cast<unsigned long long>(magnitude / 1'000'000'000ULL),
                static_cast<unsigned long long>(magnitude % 1'000'000'000ULL));
  return buf.data();
}

}  // namespace rigcal
