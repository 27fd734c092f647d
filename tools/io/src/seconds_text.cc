// SPDX-License-Identifier: Apache-2.0
// Time stamps as text: decimal seconds to integer nanoseconds and back, exactly (no double in
// between).
#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <string>

#include "rigcal/io/trajectory_io.h"

namespace rigcal::io {

std::optional<int64_t> ParseSecondsToNs(std::string_view text) {
  size_t i = 0;
  bool negative = false;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) negative = text[i++] == '-';
  std::string digits;
  int64_t frac_len = 0;
  bool seen_point = false;
  bool any_digit = false;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (c >= '0' && c <= '9') {
      any_digit = true;
      if (!digits.empty() || c != '0') digits += c;  // leading zeros carry no value
      if (seen_point) ++frac_len;
    } else if (c == '.' && !seen_point) {
      seen_point = true;
    } else {
      break;
    }
  }
  if (!any_digit) return std::nullopt;
  int64_t exponent = 0;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    bool exp_negative = false;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) exp_negative = text[i++] == '-';
    if (i == text.size()) return std::nullopt;
    for (; i < text.size() && text[i] >= '0' && text[i] <= '9'; ++i) {
      exponent = std::min<int64_t>(exponent * 10 + (text[i] - '0'), 100000);
    }
    if (exp_negative) exponent = -exponent;
  }
  if (i != text.size()) return std::nullopt;

  // Value in ns = digits * 10^shift. Trailing zeros of a fraction were kept in `digits` and
  // counted in frac_len, so they cancel here.
  const int64_t shift = exponent - frac_len + 9;
  bool round_up = false;
  if (shift < 0) {
    const auto drop = static_cast<size_t>(-shift);
    if (drop > digits.size()) {
      digits.clear();
    } else {
      round_up = digits[digits.size() - drop] >= '5';
      digits.erase(digits.size() - drop);  // resize() here trips GCC 12's -Wrestrict
    }
  } else if (!digits.empty()) {
    if (shift > 19) return std::nullopt;
    digits.append(static_cast<size_t>(shift), '0');
  }
  if (digits.size() > 19) return std::nullopt;
  uint64_t magnitude = 0;
  for (const char c : digits) magnitude = magnitude * 10 + static_cast<uint64_t>(c - '0');
  if (digits.size() == 19 && digits > "9223372036854775807") return std::nullopt;
  if (round_up) ++magnitude;
  constexpr auto kMax = static_cast<uint64_t>(std::numeric_limits<int64_t>::max());
  if (magnitude > kMax) return std::nullopt;
  const auto value = static_cast<int64_t>(magnitude);
  return negative ? -value : value;
}

}  // namespace rigcal::io
