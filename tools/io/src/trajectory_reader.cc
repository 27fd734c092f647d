// ReadTrajectory: a TUM, EuRoC CSV or rigcal native trajectory file, its format detected from the
// file (trajectory_formats.h), every line checked.
#include <Eigen/Core>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>

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

}  // namespace

Expected<TimedTrajectory> ReadTrajectory(const std::string& path,
                                         const TrajectoryReadOptions& options,
                                         TrajectoryFormat* format_out) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return Error{path + ": is a directory"};
  std::ifstream in(path);
  if (!in) return Error{path + ": cannot open: " + std::strerror(errno)};

  TimedTrajectory trajectory;
  trajectory.name = std::filesystem::path(path).stem().string();
  std::optional<TrajectoryFormat> format;
  const PoseLineFormat* layout = nullptr;
  bool native_header = false;
  size_t expected_columns = 0;
  int first_data_line = 0;
  std::vector<int> line_of_pose;
  int normalised = 0;
  double max_norm_error = 0.0;

  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const std::string_view text = internal::Trim(raw);
    if (text.empty()) continue;
    if (text[0] == '#') {
      if (!format && internal::Trim(text.substr(1)).starts_with("rigcal poses")) {
        native_header = true;
      }
      continue;
    }
    if (!format) {
      format = internal::DetectFormat(text, native_header);
      layout = &internal::LineFormatOf(*format);
      first_data_line = line;
    }
    const LineParser parser(path, line, layout->column_names.data());
    const auto fields = layout->comma_separated ? internal::SplitComma(text)
                                                : internal::SplitWhitespace(text);
    if (layout->comma_separated) {
      if (fields.size() < kPoseColumns) {
        return Error{parser.Where() + "expected at least 8 comma-separated columns " +
                     "(timestamp [ns], p_x, p_y, p_z, q_w, q_x, q_y, q_z), got " +
                     std::to_string(fields.size())};
      }
    } else if (expected_columns == 0) {
      if (fields.size() != kPoseColumns && fields.size() != kPoseColumns + 1) {
        return Error{parser.Where() + "expected 8 or 9 columns (" + ToString(*format) +
                     " format), got " + std::to_string(fields.size())};
      }
      expected_columns = fields.size();
    } else if (fields.size() != expected_columns) {
      return Error{parser.Where() + "expected " + std::to_string(expected_columns) +
                   " columns like line " + std::to_string(first_data_line) + ", got " +
                   std::to_string(fields.size())};
    }

    auto parsed = internal::ParseFields(fields, *layout, parser);
    if (!parsed) return Error{parsed.error()};
    const ParsedLine& p = *parsed;

    if (!trajectory.t_ns.empty() && p.t_ns <= trajectory.t_ns.back()) {
      const std::string previous = std::to_string(line_of_pose.back());
      if (p.t_ns == trajectory.t_ns.back()) {
        return Error{parser.Where() + "duplicate time stamp " + FormatNsAsSeconds(p.t_ns) +
                     " s (same as line " + previous + ")"};
      }
      return Error{parser.Where() + "time goes backwards: " + FormatNsAsSeconds(p.t_ns) +
                   " s after " + FormatNsAsSeconds(trajectory.t_ns.back()) + " s on line " +
                   previous};
    }

    const Eigen::Vector4d q(p.q_wxyz[0], p.q_wxyz[1], p.q_wxyz[2], p.q_wxyz[3]);
    const double norm = q.norm();
    const double norm_error = std::abs(norm - 1.0);
    if (!(norm_error <= options.max_quaternion_norm_error)) {
      return Error{parser.Where() + "quaternion (w, x, y, z) = (" + SignificantText(q[0], 9) +
                   ", " + SignificantText(q[1], 9) + ", " + SignificantText(q[2], 9) + ", " +
                   SignificantText(q[3], 9) + ") has norm " + SignificantText(norm, 9) +
                   ", not 1 within " + SignificantText(options.max_quaternion_norm_error, 9)};
    }
    if (norm_error > kSilentNormError) {
      ++normalised;
      max_norm_error = std::max(max_norm_error, norm_error);
    }
    Pose pose;
    pose.q = Eigen::Quaterniond(q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm);
    pose.C = Eigen::Vector3d(p.c[0], p.c[1], p.c[2]);
    trajectory.t_ns.push_back(p.t_ns);
    trajectory.poses.push_back(pose);
    trajectory.segment.push_back(p.segment);
    line_of_pose.push_back(line);
  }
  if (in.bad()) return Error{path + ": read error after line " + std::to_string(line)};
  if (trajectory.t_ns.empty()) {
    return Error{path + ": no poses (the file is empty or has only comments)"};
  }
  if (normalised > 0) {
    ModuleLogger("tools")->warn("{}: normalised {} of {} quaternions (norms off by up to {:.2g})",
                                path, normalised, trajectory.size(), max_norm_error);
  }
  if (format_out) *format_out = *format;
  return trajectory;
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
