// SPDX-License-Identifier: Apache-2.0
// WriteTrajectoryTum and WriteTrajectoryNative: a trajectory as a line-per-pose file, its columns
// laid out by the same table the reader uses (trajectory_formats.h).
#include <algorithm>
#include <array>
#include <sstream>
#include <string>

#include "rigcal/base/format.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/io/trajectory_io.h"
#include "trajectory_formats.h"
#include "trajectory_text.h"

namespace rigcal::io {
namespace {

// `comment`: written instead of the column legend when not empty.
Status WriteTrajectory(const std::string& path, const TimedTrajectory& trajectory,
                       TrajectoryFormat format, const std::string& comment) {
  if (trajectory.poses.size() != trajectory.t_ns.size() ||
      (!trajectory.segment.empty() && trajectory.segment.size() != trajectory.t_ns.size())) {
    return Error{"cannot write '" + path + "': t_ns, poses and segment differ in size"};
  }
  const internal::PoseLineFormat& layout = internal::LineFormatOf(format);
  const bool with_segment =
      format == TrajectoryFormat::kNative ||
      std::any_of(trajectory.segment.begin(), trajectory.segment.end(), [](int s) { return s; });
  std::string out;
  if (!comment.empty()) {
    std::istringstream lines(comment);
    for (std::string line; std::getline(lines, line);) out += "# " + line + '\n';
  } else if (format == TrajectoryFormat::kNative) {
    out += "# rigcal poses\n# t_ns qw qx qy qz Cx Cy Cz segment\n";
  } else {
    out += with_segment ? "# t tx ty tz qx qy qz qw segment\n" : "# t tx ty tz qx qy qz qw\n";
  }
  for (size_t k = 0; k < trajectory.size(); ++k) {
    const Pose& pose = trajectory.poses[k];
    const std::array<double, 4> q_wxyz = {pose.q.w(), pose.q.x(), pose.q.y(), pose.q.z()};
    std::array<double, internal::kPoseColumns> columns{};  // column 0, the stamp, unused
    for (int i = 0; i < 3; ++i) columns[layout.c_cols[i]] = pose.C[i];
    for (int i = 0; i < 4; ++i) columns[layout.q_cols[i]] = q_wxyz[i];
    out +=
        layout.seconds ? FormatNsAsSeconds(trajectory.t_ns[k]) : std::to_string(trajectory.t_ns[k]);
    for (int col = 1; col < internal::kPoseColumns; ++col) {
      out += ' ' + ShortestText(columns[col]);
    }
    if (with_segment) {
      out += ' ' + std::to_string(trajectory.segment.empty() ? 0 : trajectory.segment[k]);
    }
    out += '\n';
  }
  return WriteFileAtomically(path, out);
}

}  // namespace

Status WriteTrajectoryTum(const std::string& path, const TimedTrajectory& trajectory,
                          const std::string& comment) {
  return WriteTrajectory(path, trajectory, TrajectoryFormat::kTum, comment);
}

Status WriteTrajectoryNative(const std::string& path, const TimedTrajectory& trajectory) {
  return WriteTrajectory(path, trajectory, TrajectoryFormat::kNative, "");
}

}  // namespace rigcal::io
