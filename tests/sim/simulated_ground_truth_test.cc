// SPDX-License-Identifier: Apache-2.0
// The simulated rig's ground truth: the data SimulatedRig::GroundTruth returns, and the files
// rigcal_io writes of it, read back with the project's own readers (TUM and rig YAML), equal to
// the rig's truth, consistent with the thesis' rig constraint and laid out as they always were.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "rigcal/base/format.h"
#include "rigcal/base/time_format.h"
#include "rigcal/io/ground_truth_files.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/sim/simulated_rig.h"
#include "support/ideal_cameras.h"

namespace rigcal::sim {
namespace {

namespace fs = std::filesystem;

SimulatedRigSpec::Waypoint Waypoint(const Eigen::Vector3d& p, double yaw, double pitch,
                                    double roll) {
  SimulatedRigSpec::Waypoint w;
  w.position = p;
  w.world_from_master = WaypointOrientationFromYpr(yaw, pitch, roll);
  return w;
}

SimulatedRigSpec Spec() {
  SimulatedRigSpec spec;
  spec.names = {"front", "side", "back"};
  for (int i = 0; i < 3; ++i) spec.cameras.push_back(support::PinholeWithFov(32, 24, 60));
  Pose side, back;
  side.q = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()));
  side.C = Eigen::Vector3d(-1, 1, 3);
  back.q = Eigen::Quaterniond(0, 0, 1, 0);
  back.C = Eigen::Vector3d(0.1, 0.2, -1.5);
  spec.master_from_camera = {Pose(), side, back};
  spec.waypoints = {Waypoint({-1, 0, 3}, 0, 0, 0), Waypoint({0, 1, 3.2}, 30, 10, -5),
                    Waypoint({1, 0, 2.9}, -20, -10, 10)};
  spec.waypoint_interval_s = 1.0;
  spec.frame_rate_hz = 20;
  spec.start_time_ns = 5'000'000'123;
  return spec;
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(SimulatedGroundTruth, IsTheRigsTruthAsData) {
  auto rig = MakeSimulatedRig(Spec());
  ASSERT_TRUE(rig) << rig.error();
  const SimulatedGroundTruth truth = rig->GroundTruth();
  ASSERT_EQ(truth.cameras.size(), 3u);
  const std::vector<Similarity> expected = rig->TrueRig();
  for (int c = 0; c < 3; ++c) {
    const SimulatedCameraTruth& camera = truth.cameras[c];
    EXPECT_EQ(camera.name, rig->spec().names[c]);  // rig order, the master first
    const Similarity mounting = c == 0 ? Similarity() : expected[c - 1];
    EXPECT_LT(camera.master_from_camera.q.angularDistance(mounting.q), 1e-12);
    EXPECT_LT((camera.master_from_camera.C - mounting.C).norm(), 1e-12);
    EXPECT_EQ(camera.master_from_camera.scale, 1.0);
    ASSERT_EQ(static_cast<int64_t>(camera.t_ns.size()), rig->num_frames());
    ASSERT_EQ(camera.world_from_camera.size(), camera.t_ns.size());
    ASSERT_EQ(camera.origin_from_camera.size(), camera.t_ns.size());
    const Pose origin = rig->WorldFromCameraAt(c, 0.0);
    for (int64_t k = 0; k < rig->num_frames(); ++k) {
      EXPECT_EQ(camera.t_ns[k], rig->FrameTimeNs(k));
      const Pose world = rig->WorldFromCameraAt(c, rig->FrameStreamTime(k));
      EXPECT_EQ(camera.world_from_camera[k].C, world.C);
      EXPECT_EQ(camera.world_from_camera[k].q.coeffs(), world.q.coeffs());
      const Pose local = origin.Between(world);
      EXPECT_EQ(camera.origin_from_camera[k].C, local.C);
      EXPECT_EQ(camera.origin_from_camera[k].q.coeffs(), local.q.coeffs());
    }
    EXPECT_LT(camera.origin_from_camera[0].C.norm(), 1e-15);
  }
}

// The files' text, which scripts and older readers see: comments, the slaves in rig order (not
// by name) after `master`, flow lists, shortest round-trip numbers.
TEST(SimulatedGroundTruth, FilesKeepTheirLayout) {
  auto rig = MakeSimulatedRig(Spec());
  ASSERT_TRUE(rig) << rig.error();
  const fs::path dir =
      fs::temp_directory_path() / ("rigcal_sim_truth_layout_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const Status written = io::WriteGroundTruth(rig->GroundTruth(), dir.string());
  ASSERT_TRUE(written.ok()) << written.message();

  std::string yaml =
      "# True rig of a simulated source: every slave's orientation and centre in the master\n"
      "# frame (metres); scale 1 because the simulated truth is metric.\n"
      "master: front\n";
  const std::vector<Similarity> rig_truth = rig->TrueRig();
  for (int i = 0; i < 2; ++i) {
    const Similarity& s = rig_truth[i];
    yaml += rig->spec().names[i + 1] + ":\n  q_wxyz: [" + ShortestText(s.q.w()) + ", " +
            ShortestText(s.q.x()) + ", " + ShortestText(s.q.y()) + ", " + ShortestText(s.q.z()) +
            "]\n  C: [" + ShortestText(s.C.x()) + ", " + ShortestText(s.C.y()) + ", " +
            ShortestText(s.C.z()) + "]\n  scale: 1\n";
  }
  EXPECT_EQ(ReadText(dir / "truth.yaml"), yaml);

  const Pose world = rig->WorldFromCameraAt(1, rig->FrameStreamTime(1));
  const std::string line = FormatNsAsSeconds(rig->FrameTimeNs(1)) + " " +
                           ShortestText(world.C.x()) + " " + ShortestText(world.C.y()) + " " +
                           ShortestText(world.C.z()) + " " + ShortestText(world.q.x()) + " " +
                           ShortestText(world.q.y()) + " " + ShortestText(world.q.z()) + " " +
                           ShortestText(world.q.w()) + "\n";
  const std::string text = ReadText(dir / "world_side.txt");
  const std::string head =
      "# simulated ground truth of camera side (TUM: t tx ty tz qx qy qz qw; world_from_camera, "
      "metres)\n# frame: the simulated world (z up)\n";
  EXPECT_EQ(text.substr(0, head.size()), head);
  EXPECT_NE(text.find("\n" + line), std::string::npos) << text.substr(0, 400);
  const std::string local_head =
      "# simulated ground truth of camera side (TUM: t tx ty tz qx qy qz qw; world_from_camera, "
      "metres)\n# frame: the camera's pose at frame 0\n" +
      FormatNsAsSeconds(rig->FrameTimeNs(0)) + " ";
  EXPECT_EQ(ReadText(dir / "side.txt").substr(0, local_head.size()), local_head);
  fs::remove_all(dir);
}

TEST(SimulatedGroundTruth, FilesRoundTrip) {
  auto rig = MakeSimulatedRig(Spec());
  ASSERT_TRUE(rig) << rig.error();
  const fs::path dir =
      fs::temp_directory_path() / ("rigcal_sim_truth_" + std::to_string(::getpid())) / "sub";
  fs::remove_all(dir.parent_path());
  const Status written = io::WriteGroundTruth(rig->GroundTruth(), dir.string());
  ASSERT_TRUE(written.ok()) << written.message();

  // truth.yaml: one entry per slave, readable by `rigcal solve --truth`.
  auto truth = io::ReadRigYaml((dir / "truth.yaml").string());
  ASSERT_TRUE(truth) << truth.error();
  ASSERT_EQ(truth->size(), 2u);
  const std::vector<Similarity> expected = rig->TrueRig();
  for (int i = 0; i < 2; ++i) {
    const Similarity& s = truth->at(rig->spec().names[i + 1]);
    EXPECT_LT(s.q.angularDistance(expected[i].q), 1e-12);
    EXPECT_LT((s.C - expected[i].C).norm(), 1e-12);
    EXPECT_DOUBLE_EQ(s.scale, 1.0);
  }

  // <camera>.txt: camera-local TUM trajectories at the nominal frame stamps.
  std::vector<TimedTrajectory> local;
  for (int c = 0; c < 3; ++c) {
    const std::string name = rig->spec().names[c];
    io::TrajectoryFormat format;
    auto trajectory = io::ReadTrajectory((dir / (name + ".txt")).string(), {}, &format);
    ASSERT_TRUE(trajectory) << trajectory.error();
    EXPECT_EQ(format, io::TrajectoryFormat::kTum);
    ASSERT_EQ(static_cast<int64_t>(trajectory->size()), rig->num_frames());
    auto world = io::ReadTrajectory((dir / ("world_" + name + ".txt")).string());
    ASSERT_TRUE(world) << world.error();
    const Pose first = rig->WorldFromCameraAt(c, 0.0);
    for (int64_t k = 0; k < rig->num_frames(); ++k) {
      EXPECT_EQ(trajectory->t_ns[k], rig->FrameTimeNs(k));
      const Pose truth_world = rig->WorldFromCameraAt(c, rig->FrameStreamTime(k));
      EXPECT_LT((world->poses[k].C - truth_world.C).norm(), 1e-12);
      EXPECT_LT(world->poses[k].q.angularDistance(truth_world.q), 1e-9);
      const Pose truth_local = first.Between(truth_world);
      EXPECT_LT((trajectory->poses[k].C - truth_local.C).norm(), 1e-12);
      EXPECT_LT(trajectory->poses[k].q.angularDistance(truth_local.q), 1e-9);
    }
    EXPECT_LT(trajectory->poses[0].C.norm(), 1e-15);
    local.push_back(std::move(*trajectory));
  }
  // The thesis constraint holds between the camera-local trajectories and the true rig:
  // T_0^k dT_i = dT_i T_i^k.
  for (int i = 0; i < 2; ++i) {
    Pose d;
    d.q = expected[i].q;
    d.C = expected[i].C;
    for (int64_t k = 0; k < rig->num_frames(); k += 7) {
      const Pose lhs = local[0].poses[k] * d;
      const Pose rhs = d * local[i + 1].poses[k];
      EXPECT_LT((lhs.C - rhs.C).norm(), 1e-9) << i << " " << k;
      EXPECT_LT(lhs.q.angularDistance(rhs.q), 1e-9) << i << " " << k;
    }
  }
  // No temporary files are left behind.
  for (const auto& entry : fs::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << entry.path();
  }
  // An unwritable directory is an error that names it.
  const Status unwritable = io::WriteGroundTruth(rig->GroundTruth(), "/proc/rigcal_no_such_dir");
  EXPECT_FALSE(unwritable.ok());
  EXPECT_NE(unwritable.message().find("/proc/rigcal_no_such_dir"), std::string::npos)
      << unwritable.message();
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace rigcal::sim
