// SPDX-License-Identifier: Apache-2.0
// Real data through `rigcal import` and a replay (issue 12, section 5):
//  - the EuRoC "imu_april" AprilGrid poses (PnP per frame, support/euroc_aprilgrid.h; cam1 in an
//    odometry unit of its own as in the batch test) imported into a pose log and replayed with
//    `rigcal calib --log` reach the batch test's accuracy;
//  - the static EuRoC V1_01 frames imported into an image log hold the recording's pixels, and
//    replayed through the image pipeline (`rigcal replay`) report insufficient motion (exit 3).
// Data under RIGCAL_SHARED_DATA_DIR; without it the tests are skipped (a failure under CI=true).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "cli/command_test.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/pipeline/image_codec.h"
#include "support/command_runner.h"
#include "support/euroc_aprilgrid.h"
#include "support/lcm_log_events.h"

namespace rigcal {
namespace {

namespace fs = std::filesystem;
using cli_test::Quote;

// As tests/calib/euroc_aprilgrid_test.cc: cam1's positions in an arbitrary unit, and the batch
// test's accuracy targets.
constexpr double kCam1Unit = 2.7;
constexpr double kMaxRotDeg = 0.15;
constexpr double kMaxTransMm = 2.5;
constexpr double kMaxScalePct = 0.3;

using EurocImportReplayTest = cli_test::CommandTest;

Similarity SlaveEstimate(const nlohmann::json& slave) {
  Similarity s;
  const auto& q = slave.at("q_wxyz");
  s.q = Eigen::Quaterniond(q[0].get<double>(), q[1].get<double>(), q[2].get<double>(),
                           q[3].get<double>());
  const auto& c = slave.at("C");
  s.C = Eigen::Vector3d(c[0].get<double>(), c[1].get<double>(), c[2].get<double>());
  s.scale = slave.at("scale").get<double>();
  return s;
}

TEST_F(EurocImportReplayTest, AprilGridPoseLogReplayReachesBatchAccuracy) {
  std::string reason;
  if (!support::EurocAprilGridAvailable(&reason)) RIGCAL_SKIP_UNLESS_CI(reason);
  auto rig = support::LoadEurocAprilGridRig();
  ASSERT_TRUE(rig.ok()) << rig.error();
  RigRecording rec = rig->recording;
  support::ScalePositions(&rec.slaves[0], kCam1Unit);
  Similarity truth = rig->truth;
  truth.scale = 1.0 / kCam1Unit;
  std::string error;
  ASSERT_TRUE(support::WriteTumTrajectory(Path("cam0.txt"), rec.t_ns, rec.master, &error)) << error;
  ASSERT_TRUE(support::WriteTumTrajectory(Path("cam1.txt"), rec.t_ns, rec.slaves[0], &error))
      << error;

  const auto imported =
      Run("import tum cam0=" + Quote(Path("cam0.txt")) + " cam1=" + Quote(Path("cam1.txt")) +
          " -o " + Quote(Path("april.lcmlog")));
  ASSERT_EQ(imported.exit_code, 0) << imported.err;
  const auto replay =
      Run("calib --config " + Quote(Path("april.lcmlog.yaml")) + " --log " +
          Quote(Path("april.lcmlog")) + " --json --out " + Quote(Path("result.yaml")));
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_NE(replay.err.find("decoder: accepted " + std::to_string(2 * rec.size()) + ", rejected 0"),
            std::string::npos)
      << replay.err;
  const auto json = nlohmann::json::parse(replay.out, nullptr, /*allow_exceptions=*/false);
  ASSERT_FALSE(json.is_discarded()) << replay.out;
  ASSERT_EQ(json.at("slaves").size(), 1u);
  const auto& slave = json["slaves"][0];
  const CalibrationError e = CompareToTruth(SlaveEstimate(slave), truth);
  // A replay that drops matched sets (the sync buffer's consumer_overflow) calibrates from a
  // fraction of the motions: say so when the targets are missed.
  const size_t overflow = replay.err.find("consumer_overflow ");
  const std::string drops =
      overflow == std::string::npos
          ? "no sets dropped"
          : "the replay dropped sets: " +
                replay.err.substr(overflow, replay.err.find_first_of(")\n", overflow) - overflow);
  EXPECT_EQ(slave.value("state", ""), "converged") << drops << "\n" << slave.dump(2);
  std::cout << "AprilGrid pose log replayed by rigcal calib --log: rot " << e.rot_deg
            << " deg, trans " << e.trans_err * 1000.0 << " mm, scale " << e.scale_pct << " % ("
            << slave.value("motions_used", 0) << " motions)\n";
  RecordProperty("replay_rot_deg", std::to_string(e.rot_deg));
  RecordProperty("replay_trans_mm", std::to_string(e.trans_err * 1000.0));
  RecordProperty("replay_scale_pct", std::to_string(e.scale_pct));
  EXPECT_LE(e.rot_deg, kMaxRotDeg) << drops;
  EXPECT_LE(e.trans_err * 1000.0, kMaxTransMm) << drops;
  EXPECT_LE(e.scale_pct, kMaxScalePct) << drops;
}

TEST_F(EurocImportReplayTest, StaticFramesImageLogReportsInsufficientMotion) {
  const fs::path data = fs::path(RIGCAL_SHARED_DATA_DIR) / "euroc_v101_static";
  if (!fs::exists(data / "mav0" / "cam0" / "data.csv")) {
    RIGCAL_SKIP_UNLESS_CI(data.string() +
                          " not found (set RIGCAL_SHARED_DATA_DIR at configure "
                          "time)");
  }
  const auto imported =
      Run("import euroc " + Quote(data.string()) + " -o " + Quote(Path("static.lcmlog")));
  ASSERT_EQ(imported.exit_code, 0) << imported.err;
  // README-provenance.txt: 95 frames per camera, 4 PNGs of cam1 listed but absent.
  EXPECT_NE(imported.err.find("camera 'cam1': 4 listed images missing or unreadable"),
            std::string::npos)
      << imported.err;

  // Every frame in the log is the recording's PNG, pixel for pixel.
  std::map<std::string, int> frames;
  lcm::MessageValidator validator({"cam0", "cam1"});
  for (const support::LoggedEvent& e : support::ReadLcmLog(Path("static.lcmlog"))) {
    auto msg = validator.Decode<image_t>(e.channel, e.data.data(), e.data.size());
    ASSERT_TRUE(msg.ok()) << msg.error();
    ++frames[msg->camera];
    auto image = pipeline::FrameFromImage(*msg, 0);
    ASSERT_TRUE(image.ok()) << image.error();
    const fs::path png =
        data / "mav0" / msg->camera / "data" / (std::to_string(msg->t_ns) + ".png");
    const cv::Mat original = cv::imread(png.string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(original.empty()) << png;
    ASSERT_EQ(cv::norm(image->image, original, cv::NORM_INF), 0.0) << png;
  }
  EXPECT_EQ(frames["cam0"], 95);
  EXPECT_EQ(frames["cam1"], 95);

  // The image log through the image pipeline (images -> VO -> sync -> estimator).
  if (Run("--help").out.find("\n  replay ") == std::string::npos) {
    RIGCAL_SKIP_UNLESS_CI(
        "`rigcal replay` (image-log replay, issue 12 section 1) is not in this "
        "build");
  }
  const auto replay =
      Run("replay " + Quote(Path("static.lcmlog")) + " --config " +
          Quote(Path("static.lcmlog.yaml")) + " --out " + Quote(Path("result.yaml")));
  EXPECT_EQ(replay.exit_code, 3) << replay.out << replay.err;
  // The reason, in words or as the termination name (insufficient_motion).
  const std::string text = replay.out + replay.err;
  EXPECT_TRUE(text.find("insufficient motion") != std::string::npos ||
              text.find("insufficient_motion") != std::string::npos)
      << text;
}

}  // namespace
}  // namespace rigcal
