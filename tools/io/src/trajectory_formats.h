// SPDX-License-Identifier: Apache-2.0
#pragma once
// The line-per-pose trajectory formats (private to rigcal_io): the column layout of TUM, EuRoC CSV
// and rigcal native lines (trajectory_io.h describes them), read and written from the same
// table, and the detection of a file's format.

#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/io/trajectory_io.h"
#include "trajectory_text.h"

namespace rigcal::io::internal {

// Columns of a pose: the time stamp and the 7 numbers of q and C; an optional 9th column.
inline constexpr int kPoseColumns = 8;

// The columns of one format's data lines.
struct PoseLineFormat {
  TrajectoryFormat format;
  // EuRoC CSV: comma-separated, further columns ignored. Else whitespace-separated with 8 or 9
  // columns, the same count on every line of a file.
  bool comma_separated;
  bool seconds;               // column 0 is a time in seconds; else integer nanoseconds
  std::array<int, 3> c_cols;  // columns of C (x, y, z)
  std::array<int, 4> q_cols;  // columns of q (w, x, y, z)
  bool segment_column;        // column 9, when present, is the scale segment id
  std::array<const char*, kPoseColumns + 1> column_names;  // for errors (nullptr: no column)
};

// The layout of `format`.
const PoseLineFormat& LineFormatOf(TrajectoryFormat format);

// The format of a file from its first data line and whether a leading comment line read
// `# rigcal poses` (the rules in trajectory_io.h).
TrajectoryFormat DetectFormat(std::string_view first_data_line, bool native_header);

// The values of one data line.
struct ParsedLine {
  int64_t t_ns = 0;
  double q_wxyz[4] = {1, 0, 0, 0};
  double c[3] = {0, 0, 0};
  int segment = 0;
};

// Parses the fields of one data line of `format`; `fields` has a valid column count. The first
// unparsable field is the error: the stamp, then C (x, y, z), then q (w, x, y, z), then the
// segment.
Expected<ParsedLine> ParseFields(const std::vector<std::string_view>& fields,
                                 const PoseLineFormat& format, const LineParser& p);

}  // namespace rigcal::io::internal
