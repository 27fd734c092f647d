// SPDX-License-Identifier: Apache-2.0
// ReadKittiTrajectory: a KITTI odometry pose file (3x4 matrices) and its time file.
#include <Eigen/Core>
#include <Eigen/SVD>
#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "rigcal/base/format.h"
#include "rigcal/io/trajectory_io.h"
#include "trajectory_text.h"

namespace rigcal::io {

using internal::LineParser;
using internal::SplitWhitespace;
using internal::Trim;

Expected<TimedTrajectory> ReadKittiTrajectory(const std::string& poses_path,
                                              const std::string& times_path) {
  constexpr double kOrthonormalTolerance = 1e-4;
  static constexpr std::array<const char*, 12> kKittiColumns = {
      "r11", "r12", "r13", "tx", "r21", "r22", "r23", "ty", "r31", "r32", "r33", "tz"};
  static constexpr std::array<const char*, 1> kTimeColumns = {"t [s]"};
  std::error_code ec;
  for (const std::string* path : {&poses_path, &times_path}) {
    if (std::filesystem::is_directory(*path, ec)) return Error{*path + ": is a directory"};
  }
  std::ifstream poses_in(poses_path);
  if (!poses_in) return Error{poses_path + ": cannot open: " + std::strerror(errno)};
  std::ifstream times_in(times_path);
  if (!times_in) return Error{times_path + ": cannot open: " + std::strerror(errno)};

  TimedTrajectory trajectory;
  trajectory.name = std::filesystem::path(poses_path).stem().string();
  std::string text;
  int line = 0;
  while (std::getline(poses_in, text)) {
    ++line;
    const std::string_view trimmed = Trim(text);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    const auto fields = SplitWhitespace(trimmed);
    const LineParser p(poses_path, line, kKittiColumns.data());
    if (fields.size() != kKittiColumns.size()) {
      return Error{p.Where() + "expected 12 numbers (a row-major 3x4 matrix [R | t]), got " +
                   std::to_string(fields.size())};
    }
    Eigen::Matrix<double, 3, 4> m;
    for (int i = 0; i < 12; ++i) {
      auto v = p.Number(fields[i], i);
      if (!v) return Error{v.error()};
      m(i / 4, i % 4) = *v;
    }
    const Eigen::Matrix3d r = m.leftCols<3>();
    const double error = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!(error <= kOrthonormalTolerance) || !(r.determinant() > 0.0)) {
      return Error{p.Where() + "the rotation block is not a rotation (|R^T R - I| = " +
                   SignificantText(error, 9) + ", det " + SignificantText(r.determinant(), 9) +
                   ")"};
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Pose pose;
    pose.q = Eigen::Quaterniond(svd.matrixU() * svd.matrixV().transpose()).normalized();
    pose.C = m.col(3);
    trajectory.poses.push_back(pose);
  }
  line = 0;
  std::vector<int> line_of_time;
  while (std::getline(times_in, text)) {
    ++line;
    const std::string_view trimmed = Trim(text);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    const auto fields = SplitWhitespace(trimmed);
    const LineParser p(times_path, line, kTimeColumns.data());
    if (fields.size() != 1) {
      return Error{p.Where() + "expected one time in seconds, got " +
                   std::to_string(fields.size()) + " columns"};
    }
    auto t = p.SecondsStamp(fields[0], 0);
    if (!t) return Error{t.error()};
    if (!trajectory.t_ns.empty() && *t <= trajectory.t_ns.back()) {
      return Error{p.Where() + "time does not increase (line " +
                   std::to_string(line_of_time.back()) + " has " +
                   FormatNsAsSeconds(trajectory.t_ns.back()) + " s)"};
    }
    trajectory.t_ns.push_back(*t);
    line_of_time.push_back(line);
  }
  if (trajectory.poses.empty()) return Error{poses_path + ": no poses"};
  if (trajectory.t_ns.size() != trajectory.poses.size()) {
    return Error{times_path + ": " + std::to_string(trajectory.t_ns.size()) + " times for " +
                 std::to_string(trajectory.poses.size()) + " poses in " + poses_path};
  }
  trajectory.segment.assign(trajectory.size(), 0);
  return trajectory;
}

}  // namespace rigcal::io
