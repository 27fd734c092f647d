// SPDX-License-Identifier: Apache-2.0
#include "trajectory_text.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "rigcal/io/trajectory_io.h"

namespace rigcal::io::internal {

std::string_view Trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

std::vector<std::string_view> SplitWhitespace(std::string_view s) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    if (i == s.size()) break;
    size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
    out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

std::vector<std::string_view> SplitComma(std::string_view s) {
  std::vector<std::string_view> out;
  size_t start = 0;
  while (true) {
    const size_t comma = s.find(',', start);
    out.push_back(Trim(s.substr(start, comma == std::string_view::npos ? s.npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

bool IsPlainInteger(std::string_view s) {
  if (!s.empty() && (s[0] == '-' || s[0] == '+')) s.remove_prefix(1);
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

std::optional<double> ParseDouble(std::string_view s) {
  if (s.size() > 1 && s[0] == '+') s.remove_prefix(1);
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || ptr != s.data() + s.size() || s.empty()) return std::nullopt;
  return value;
}

Expected<double> LineParser::Number(std::string_view field, int index) const {
  const auto value = ParseDouble(field);
  if (!value) {
    return Error{Where() + Column(index) + ": '" + std::string(field) + "' is not a number"};
  }
  if (!std::isfinite(*value)) {
    return Error{Where() + Column(index) + " is not finite ('" + std::string(field) + "')"};
  }
  return *value;
}

Expected<int64_t> LineParser::NanosecondStamp(std::string_view field, int index) const {
  const auto value = ParseInteger<int64_t>(field);
  if (!value) {
    return Error{Where() + Column(index) + ": '" + std::string(field) +
                 "' is not an integer nanosecond stamp"};
  }
  return *value;
}

Expected<int64_t> LineParser::SecondsStamp(std::string_view field, int index) const {
  const auto value = ParseSecondsToNs(field);
  if (!value) {
    return Error{Where() + Column(index) + ": '" + std::string(field) +
                 "' is not a time in seconds"};
  }
  return *value;
}

Expected<int> LineParser::Segment(std::string_view field, int index) const {
  const auto value = ParseInteger<int>(field);
  if (!value) {
    return Error{Where() + Column(index) + ": '" + std::string(field) +
                 "' is not an integer segment id"};
  }
  return *value;
}

}  // namespace rigcal::io::internal
