// SPDX-License-Identifier: Apache-2.0
#pragma once
// Line parsing shared by the trajectory readers (private to rigcal_io): splitting a line into
// fields, strict number parsing, number formatting, and LineParser, whose errors name the file,
// the line and the column.

#include <charconv>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal::io::internal {

// `s` without leading and trailing blanks (space, tab, CR, LF).
std::string_view Trim(std::string_view s);

// The fields of `s` separated by runs of spaces and tabs.
std::vector<std::string_view> SplitWhitespace(std::string_view s);

// The fields of `s` separated by commas, each trimmed; an empty `s` is one empty field.
std::vector<std::string_view> SplitComma(std::string_view s);

// An optional sign and at least one decimal digit, nothing else.
bool IsPlainInteger(std::string_view s);

// The whole of `s` as an integer (an optional '+' or '-' sign, then digits); nullopt otherwise
// or when it does not fit in Int.
template <typename Int>
std::optional<Int> ParseInteger(std::string_view s) {
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  Int value{};
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || ptr != s.data() + s.size() || s.empty()) return std::nullopt;
  return value;
}

// The whole of `s` as a double (from_chars syntax after an optional '+'); nullopt otherwise.
std::optional<double> ParseDouble(std::string_view s);

// Parser of the fields of one data line; every error starts with "<path>:<line>: " and names the
// column by number and meaning. Keeps references: `path` and `column_names` must outlive it.
class LineParser {
 public:
  LineParser(const std::string& path, int line, const char* const* column_names)
      : path_(path), line_(line), names_(column_names) {}

  // "<path>:<line>: ".
  std::string Where() const { return path_ + ":" + std::to_string(line_) + ": "; }

  // "column <index + 1> (<name>)".
  std::string Column(int index) const {
    return "column " + std::to_string(index + 1) + " (" + names_[index] + ")";
  }

  // A finite double.
  Expected<double> Number(std::string_view field, int index) const;
  // An integer time stamp in nanoseconds.
  Expected<int64_t> NanosecondStamp(std::string_view field, int index) const;
  // A decimal time in seconds, converted to nanoseconds exactly (ParseSecondsToNs).
  Expected<int64_t> SecondsStamp(std::string_view field, int index) const;
  // An integer scale segment id.
  Expected<int> Segment(std::string_view field, int index) const;

 private:
  const std::string& path_;
  int line_;
  const char* const* names_;
};

}  // namespace rigcal::io::internal
