// SPDX-License-Identifier: Apache-2.0
// ReadTrajectory: a TUM, EuRoC CSV or rigcal native trajectory file, its format detected from the
// file (trajectory_formats.h), every line checked.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>
#include <vector>

#include "rigcal/base/format.h"
#include "rigcal/base/logging.h"
#include "rigcal/io/camera_name.h"
#include "rigcal/io/trajectory_io.h"
#include "trajectory_formats.h"
#include "trajectory_text.h"

namespace rigcal::io {
namespace {

using internal::kPoseColumns;
using internal::LineParser;
using internal::ParsedLine;
using internal::PoseLineFormat;

// Deviations of |q| from 1 below this are print rounding of a unit quaternion (>= 9
// decimals) and are normalised without being counted in the warning.
constexpr double kSilentNormError = 1e-9;

// Digits after the decimal point of a number as printed ("0.5" -> 1, "1e-3" -> 3 + exponent).
int PrintedDecimals(std::string_view text) {
  const size_t e = text.find_first_of("eE");
  const std::string_view mantissa = text.substr(0, e);
  const size_t dot = mantissa.find('.');
  int decimals = dot == std::string_view::npos ? 0 : static_cast<int>(mantissa.size() - dot - 1);
  if (e != std::string_view::npos) decimals -= std::atoi(std::string(text.substr(e + 1)).c_str());
  return std::max(decimals, 0);
}

// How far from 1 the norm of a unit quaternion printed with these texts can be: a component
// printed with d > 0 decimals is off by at most 0.5e-d (one printed without decimals, "0" or
// "1", is exact), and |q| by at most the length of those errors.
double PrintRoundingNormError(const std::array<std::string_view, 4>& texts) {
  double sum_sq = 0.0;
  for (const std::string_view text : texts) {
    const int decimals = PrintedDecimals(text);
    if (decimals > 0) sum_sq += std::pow(0.5 * std::pow(10.0, -decimals), 2);
  }
  return std::sqrt(sum_sq);
}

// The state of one file's reading, line after line.
struct Reader {
  Reader(const std::string& path_in, const TrajectoryReadOptions& options_in)
      : path(path_in), options(options_in) {}
  const std::string& path;
  const TrajectoryReadOptions& options;
  TimedTrajectory trajectory;
  std::optional<TrajectoryFormat> format;
  const PoseLineFormat* layout = nullptr;
  bool native_header = false;
  size_t expected_columns = 0;
  int first_data_line = 0;
  std::vector<int> line_of_pose;
  int normalised = 0;            // beyond print rounding of 9 decimals
  int normalised_by_digits = 0;  // beyond the configured tolerance, within the printed digits'
  double max_norm_error = 0.0;

  // The column count of a data line against the format and the first data line.
  Status CheckColumns(const LineParser& parser, size_t count) {
    if (layout->comma_separated) {
      if (count >= kPoseColumns) return Status::Ok();
      return Error{parser.Where() + "expected at least 8 comma-separated columns " +
                   "(timestamp [ns], p_x, p_y, p_z, q_w, q_x, q_y, q_z), got " +
                   std::to_string(count)};
    }
    if (expected_columns == 0) {
      if (count != kPoseColumns && count != kPoseColumns + 1) {
        return Error{parser.Where() + "expected 8 or 9 columns (" + ToString(*format) +
                     " format), got " + std::to_string(count)};
      }
      expected_columns = count;
    } else if (count != expected_columns) {
      return Error{parser.Where() + "expected " + std::to_string(expected_columns) +
                   " columns like line " + std::to_string(first_data_line) + ", got " +
                   std::to_string(count)};
    }
    return Status::Ok();
  }

  // Stamps strictly increasing.
  Status CheckTime(const LineParser& parser, int64_t t_ns) const {
    if (trajectory.t_ns.empty() || t_ns > trajectory.t_ns.back()) return Status::Ok();
    const std::string previous = std::to_string(line_of_pose.back());
    if (t_ns == trajectory.t_ns.back()) {
      return Error{parser.Where() + "duplicate time stamp " + FormatNsAsSeconds(t_ns) +
                   " s (same as line " + previous + ")"};
    }
    return Error{parser.Where() + "time goes backwards: " + FormatNsAsSeconds(t_ns) + " s after " +
                 FormatNsAsSeconds(trajectory.t_ns.back()) + " s on line " + previous};
  }

  // The unit quaternion of a line: normalised when its norm is 1 within the configured tolerance
  // or within what the printed digits explain (EuRoC prints 6 decimals), else an error.
  Expected<Eigen::Quaterniond> UnitQuaternion(const LineParser& parser, const ParsedLine& p,
                                              const std::vector<std::string_view>& fields) {
    const Eigen::Vector4d q(p.q_wxyz[0], p.q_wxyz[1], p.q_wxyz[2], p.q_wxyz[3]);
    const double norm = q.norm();
    const double norm_error = std::abs(norm - 1.0);
    std::array<std::string_view, 4> texts;
    for (int k = 0; k < 4; ++k) texts[k] = fields[static_cast<size_t>(layout->q_cols[k])];
    const double printed = PrintRoundingNormError(texts);
    if (!(norm_error <= std::max(options.max_quaternion_norm_error, printed))) {
      return Error{parser.Where() + "quaternion (w, x, y, z) = (" + SignificantText(q[0], 9) +
                   ", " + SignificantText(q[1], 9) + ", " + SignificantText(q[2], 9) + ", " +
                   SignificantText(q[3], 9) + ") has norm " + SignificantText(norm, 9) +
                   ", not 1 within " + SignificantText(options.max_quaternion_norm_error, 9) +
                   " (nor within " + SignificantText(printed, 2) +
                   ", the rounding of its printed digits)"};
    }
    if (norm_error > kSilentNormError) {
      ++normalised;
      if (norm_error > options.max_quaternion_norm_error) ++normalised_by_digits;
      max_norm_error = std::max(max_norm_error, norm_error);
    }
    return Eigen::Quaterniond(q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm);
  }

  // One non-empty, non-comment line.
  Status ReadLine(std::string_view text, int line) {
    if (!format) {
      format = internal::DetectFormat(text, native_header);
      layout = &internal::LineFormatOf(*format);
      first_data_line = line;
    }
    const LineParser parser(path, line, layout->column_names.data());
    const auto fields =
        layout->comma_separated ? internal::SplitComma(text) : internal::SplitWhitespace(text);
    if (Status s = CheckColumns(parser, fields.size()); !s.ok()) return s;
    auto parsed = internal::ParseFields(fields, *layout, parser);
    if (!parsed) return Error{parsed.error()};
    if (Status s = CheckTime(parser, parsed->t_ns); !s.ok()) return s;
    auto q = UnitQuaternion(parser, *parsed, fields);
    if (!q) return Error{q.error()};
    Pose pose;
    pose.q = *q;
    pose.C = Eigen::Vector3d(parsed->c[0], parsed->c[1], parsed->c[2]);
    trajectory.t_ns.push_back(parsed->t_ns);
    trajectory.poses.push_back(pose);
    trajectory.segment.push_back(parsed->segment);
    line_of_pose.push_back(line);
    return Status::Ok();
  }

  void WarnNormalised() const {
    if (normalised == 0) return;
    ModuleLogger("tools")->warn(
        "{}: normalised {} of {} quaternions (norms off by up to {:.2g}{})", path, normalised,
        trajectory.size(), max_norm_error,
        normalised_by_digits > 0
            ? "; " + std::to_string(normalised_by_digits) +
                  " beyond the tolerance but within the rounding of their printed digits"
            : std::string());
  }
};

}  // namespace

Expected<TimedTrajectory> ReadTrajectory(const std::string& path,
                                         const TrajectoryReadOptions& options,
                                         TrajectoryFormat* format_out) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return Error{path + ": is a directory"};
  std::ifstream in(path);
  if (!in) return Error{path + ": cannot open: " + std::strerror(errno)};
  Reader reader(path, options);
  reader.trajectory.name = std::filesystem::path(path).stem().string();
  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const std::string_view text = internal::Trim(raw);
    if (text.empty()) continue;
    if (text[0] == '#') {
      if (!reader.format && internal::Trim(text.substr(1)).starts_with("rigcal poses")) {
        reader.native_header = true;
      }
      continue;
    }
    if (Status s = reader.ReadLine(text, line); !s.ok()) return Error{s.message()};
  }
  if (in.bad()) return Error{path + ": read error after line " + std::to_string(line)};
  if (reader.trajectory.t_ns.empty()) {
    return Error{path + ": no poses (the file is empty or has only comments)"};
  }
  reader.WarnNormalised();
  if (format_out) *format_out = *reader.format;
  return std::move(reader.trajectory);
}

NamedTrajectoryPath ParseNamedTrajectoryPath(const std::string& argument) {
  std::error_code ec;
  const size_t eq = argument.find('=');
  if (eq == std::string::npos || eq == 0 || std::filesystem::is_regular_file(argument, ec)) {
    return {"", argument};
  }
  return {argument.substr(0, eq), argument.substr(eq + 1)};
}

Expected<TimedTrajectory> ReadNamedTrajectory(const std::string& argument,
                                              const TrajectoryReadOptions& options,
                                              TrajectoryFormat* format) {
  const NamedTrajectoryPath named = ParseNamedTrajectoryPath(argument);
  if (!named.name.empty()) {
    if (const std::string problem = CameraNameProblem(named.name); !problem.empty()) {
      return Error{argument + ": " + problem};
    }
  }
  auto trajectory = ReadTrajectory(named.path, options, format);
  if (trajectory && !named.name.empty()) trajectory->name = named.name;
  return trajectory;
}

}  // namespace rigcal::io
