// SPDX-License-Identifier: Apache-2.0
#pragma once
// Fixtures of the trajectory file tests in tests/io/: a temporary directory to write files to and
// read them back, and a synthetic trajectory.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "rigcal/io/trajectory_io.h"

namespace rigcal::io::trajectory_test {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// A temporary directory for the files of one test, removed afterwards.
class TrajectoryIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::path(::testing::TempDir()) / "trajectory_io_XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::string Write(const std::string& name, const std::string& contents) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << contents;
    return path;
  }

  // Reads a file expected to be rejected and returns the error message.
  std::string ErrorOf(const std::string& name, const std::string& contents,
                      const TrajectoryReadOptions& options = {}) {
    const auto result = ReadTrajectory(Write(name, contents), options);
    EXPECT_FALSE(result.ok()) << name << " was accepted";
    return result.ok() ? "" : result.error();
  }

  fs::path dir_;
};

// A trajectory named `name` with poses at `stamps`: a slow rotation and translation, a new
// scale segment every 4 poses.
inline TimedTrajectory MakeTrajectory(const std::string& name, const std::vector<int64_t>& stamps) {
  TimedTrajectory t;
  t.name = name;
  t.t_ns = stamps;
  for (size_t k = 0; k < stamps.size(); ++k) {
    Pose p;
    p.q = Eigen::Quaterniond(
        Eigen::AngleAxisd(0.01 * static_cast<double>(k), Eigen::Vector3d(1, 2, 3).normalized()));
    p.C = Eigen::Vector3d(0.1 * static_cast<double>(k), -0.2, 0.3);
    t.poses.push_back(p);
    t.segment.push_back(static_cast<int>(k / 4));
  }
  return t;
}

}  // namespace rigcal::io::trajectory_test
