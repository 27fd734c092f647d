// SPDX-License-Identifier: Apache-2.0
// KITTI odometry trajectories: poses and times, errors that name file, line and column, and the
// KITTI 00 ground truth.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "io/trajectory_fixtures.h"
#include "rigcal/io/trajectory_io.h"
#include "support/skip.h"

namespace rigcal::io::trajectory_test {
namespace {

TEST_F(TrajectoryIoTest, ReadsKittiPosesAndTimes) {
  // Pose 1: a rotation of 90 deg about y (x -> -z) at (1, 2, 3); printed with 7 digits.
  const std::string poses = Write("00.txt",
                                  "1 0 0 0 0 1 0 0 0 0 1 0\n"
                                  "0 0 1.000000e+00 1 0 1 0 2 -1.000000e+00 0 0 3\n");
  const std::string times = Write("00_times.txt", "0.000000e+00\n1.037359e-01\n");
  const auto t = ReadKittiTrajectory(poses, times);
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(t->name, "00");
  ASSERT_EQ(t->size(), 2u);
  EXPECT_EQ(t->t_ns, (std::vector<int64_t>{0, 103735900}));
  EXPECT_EQ(t->poses[0].C, Eigen::Vector3d::Zero());
  EXPECT_EQ(t->poses[1].C, Eigen::Vector3d(1, 2, 3));
  // R = world_from_camera: the camera's x axis points along world -z.
  EXPECT_LT((t->poses[1].q * Eigen::Vector3d::UnitX() - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
  EXPECT_EQ(t->segment, (std::vector<int>{0, 0}));
}

TEST_F(TrajectoryIoTest, KittiErrorsNameFileLineAndColumn) {
  const std::string times = Write("t.txt", "0\n0.1\n");
  auto error = [&](const std::string& poses, const std::string& time_file) {
    const auto t = ReadKittiTrajectory(Write("p.txt", poses), time_file);
    EXPECT_FALSE(t.ok());
    return t.ok() ? "" : t.error();
  };
  const std::string identity = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  EXPECT_THAT(error(identity + "1 0 0 0 0 1 0 0 0 0 1\n", times),
              HasSubstr("p.txt:2: expected 12 numbers"));
  EXPECT_THAT(error(identity + "1 0 0 0 0 1 0 x 0 0 1 0\n", times),
              HasSubstr("p.txt:2: column 8 (ty): 'x' is not a number"));
  EXPECT_THAT(error(identity + "1 0 0 0 0 1 0 0 0 0 1.1 0\n", times),
              HasSubstr("p.txt:2: the rotation block is not a rotation"));
  EXPECT_THAT(error(identity + "-1 0 0 0 0 1 0 0 0 0 1 0\n", times), HasSubstr("det -1"));
  EXPECT_THAT(error(identity + identity + identity, times), HasSubstr("2 times for 3 poses"));
  EXPECT_THAT(error(identity + identity, Write("t2.txt", "0.1\n0.1\n")),
              HasSubstr("t2.txt:2: time does not increase"));
  EXPECT_THAT(error("", times), HasSubstr("p.txt: no poses"));
  EXPECT_THAT(error(identity, (dir_ / "missing.txt").string()), HasSubstr("cannot open"));
}

TEST(TrajectoryIoDataTest, KittiGroundTruth) {
  const fs::path dir = fs::path(RIGCAL_SHARED_DATA_DIR) / "trajectories";
  if (!fs::exists(dir / "KITTI_00_gt.txt"))
    RIGCAL_SKIP_MISSING() << dir << " has no KITTI_00_gt.txt";
  const auto t = ReadKittiTrajectory((dir / "KITTI_00_gt.txt").string(),
                                     (dir / "KITTI_00_gt_times.txt").string());
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(t->size(), 4541u);
  // The drive is ~3.7 km long, on a road: mostly in the camera's x-z plane.
  double length = 0.0;
  for (size_t k = 1; k < t->size(); ++k) length += (t->poses[k].C - t->poses[k - 1].C).norm();
  EXPECT_GT(length, 3000.0);
  EXPECT_LT(length, 4500.0);
}
}  // namespace
}  // namespace rigcal::io::trajectory_test
