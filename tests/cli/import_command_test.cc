// SPDX-License-Identifier: Apache-2.0
// `rigcal import` and `rigcal solve --slave NAME=FILE` through the built binary: per-camera
// trajectories (TUM, EuRoC CSV named data.csv) into a pose log that `rigcal calib --log` replays
// with the rig config written beside it, and a small EuRoC (ASL) image recording into an image
// log whose frames are the recording's pixels, in time order.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "cli/command_test.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/pipeline/image_codec.h"
#include "support/lcm_log_events.h"

namespace rigcal {
namespace {

namespace fs = std::filesystem;
using cli_test::Quote;

// One camera's track as a EuRoC CSV file (t_ns,p,q_wxyz).
void WriteEurocCsv(const fs::path& path, const std::vector<int64_t>& t_ns,
                   const CameraTrack& track) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path);
  out << "#timestamp [ns],p_x,p_y,p_z,q_w,q_x,q_y,q_z\n";
  char line[256];
  for (size_t k = 0; k < t_ns.size(); ++k) {
    const Pose& p = track.poses[k];
    std::snprintf(line, sizeof(line), "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                  static_cast<long long>(t_ns[k]), p.C.x(), p.C.y(), p.C.z(), p.q.w(), p.q.x(),
                  p.q.y(), p.q.z());
    out << line;
  }
}

class ImportCommandTest : public cli_test::CommandTest {
 protected:
  // A simulated drive of a 2-camera rig as EuRoC CSV files mav0/cam0/data.csv, mav0/cam1/...
  SyntheticDrive WriteDriveCsv() {
    DriveOptions drive;
    drive.num_frames = 600;
    Similarity rig;
    rig.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitY()));
    rig.C = Eigen::Vector3d(0.3, -0.1, 0.2);
    rig.scale = 0.5;
    SyntheticDrive sim = GenerateDrive({"cam0", "cam1"}, {rig}, drive);
    WriteEurocCsv(dir_ / "mav0/cam0/data.csv", sim.recording.t_ns, sim.recording.master);
    WriteEurocCsv(dir_ / "mav0/cam1/data.csv", sim.recording.t_ns, sim.recording.slaves[0]);
    return sim;
  }
};

TEST_F(ImportCommandTest, TumImportReplaysInCalib) {
  const SyntheticDrive sim = WriteDriveCsv();
  const std::string cam0 = Path("mav0/cam0/data.csv");
  const std::string cam1 = Path("mav0/cam1/data.csv");
  // Both files are "data": without names the cameras collide.
  const auto unnamed =
      Run("import tum " + Quote(cam0) + " " + Quote(cam1) + " -o " + Quote(Path("poses.lcmlog")));
  EXPECT_EQ(unnamed.exit_code, 1);
  EXPECT_NE(unnamed.err.find("a second camera named 'data' (name them with NAME=FILE)"),
            std::string::npos)
      << unnamed.err;
  EXPECT_FALSE(fs::exists(Path("poses.lcmlog")));

  const auto r = Run("import tum front=" + Quote(cam0) + " side=" + Quote(cam1) + " -o " +
                     Quote(Path("poses.lcmlog")));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("imported 1200 poses of 2 cameras"), std::string::npos) << r.out;
  const std::vector<support::LoggedEvent> events = support::ReadLcmLog(Path("poses.lcmlog"));
  ASSERT_EQ(events.size(), 1200u);
  EXPECT_EQ(events[0].channel, "RIGCAL_POSE_front");
  EXPECT_EQ(events[1].channel, "RIGCAL_POSE_side");
  EXPECT_EQ(events[0].timestamp, sim.recording.t_ns[0] / 1000);

  // The rig config beside the log names the cameras, master first.
  auto config = io::LoadRigConfig(Path("poses.lcmlog.yaml"));
  ASSERT_TRUE(config.ok()) << config.error();
  EXPECT_EQ(config->CameraNames(), (std::vector<std::string>{"front", "side"}));

  const auto replay =
      Run("calib --config " + Quote(Path("poses.lcmlog.yaml")) + " --log " +
          Quote(Path("poses.lcmlog")) + " --json --out " + Quote(Path("result.yaml")));
  EXPECT_TRUE(replay.exit_code == 0 || replay.exit_code == 3) << replay.err;
  EXPECT_NE(replay.err.find("decoder: accepted 1200, rejected 0; unknown cameras: 0"),
            std::string::npos)
      << replay.err;
  const auto json = nlohmann::json::parse(replay.out, nullptr, /*allow_exceptions=*/false);
  ASSERT_FALSE(json.is_discarded()) << replay.out;
  EXPECT_EQ(json.value("master", ""), "front");
  ASSERT_EQ(json.at("slaves").size(), 1u);
  EXPECT_EQ(json["slaves"][0].value("name", ""), "side");

  // Existing outputs are replaced (output_files.h; tests/cli/output_files_test.cc).
  const auto again = Run("import tum front=" + Quote(cam0) + " side=" + Quote(cam1) + " -o " +
                         Quote(Path("poses.lcmlog")));
  EXPECT_EQ(again.exit_code, 0) << again.err;
}

TEST_F(ImportCommandTest, SolveTakesNamedTrajectoryFiles) {
  WriteDriveCsv();
  const std::string cam0 = Path("mav0/cam0/data.csv");
  const std::string cam1 = Path("mav0/cam1/data.csv");
  const auto unnamed = Run("solve --master " + Quote(cam0) + " --slave " + Quote(cam1));
  EXPECT_EQ(unnamed.exit_code, 1);
  EXPECT_NE(unnamed.err.find("two cameras are named 'data'"), std::string::npos) << unnamed.err;
  const auto r =
      Run("solve --master cam0=" + Quote(cam0) + " --slave cam1=" + Quote(cam1) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto json = nlohmann::json::parse(r.out, nullptr, /*allow_exceptions=*/false);
  ASSERT_FALSE(json.is_discarded()) << r.out;
  EXPECT_EQ(json.value("master", ""), "cam0");
  ASSERT_EQ(json.at("slaves").size(), 1u);
  EXPECT_EQ(json["slaves"][0].value("name", ""), "cam1");
  EXPECT_NEAR(json["slaves"][0].value("scale", 0.0), 0.5, 0.01) << r.out;
  // A missing file after NAME= is named.
  const auto missing =
      Run("solve --master cam0=" + Quote(cam0) + " --slave cam1=/nonexistent/x.csv");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("/nonexistent/x.csv"), std::string::npos) << missing.err;
}

// A textured image per camera and frame.
cv::Mat EurocImage(int camera, int k) {
  cv::Mat image(48, 64, CV_8UC1);
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) {
      image.at<uint8_t>(r, c) = static_cast<uint8_t>(r * 5 + c * 3 + k * 17 + camera * 90);
    }
  }
  return image;
}

constexpr char kSensorYaml[] = R"(%YAML:1.0
sensor_type: camera
T_BS:
  cols: 4
  rows: 4
  data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
rate_hz: 20
resolution: [64, 48]
camera_model: pinhole
intrinsics: [50.5, 51.5, 31.5, 23.5] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [-0.28, 0.07, 0.0002, 1.7e-05]
)";

TEST_F(ImportCommandTest, EurocImagesInTimeOrder) {
  // cam0: frames 0..4 at 50 ms; cam1: the same stamps + 1 ms, frame 2 listed but missing.
  const fs::path mav0 = dir_ / "rec" / "mav0";
  for (int camera = 0; camera < 2; ++camera) {
    const fs::path folder = mav0 / ("cam" + std::to_string(camera));
    fs::create_directories(folder / "data");
    std::ofstream(folder / "sensor.yaml") << kSensorYaml;
    std::ofstream csv(folder / "data.csv");
    csv << "#timestamp [ns],filename\n";
    for (int k = 0; k < 5; ++k) {
      const int64_t t_ns = 1'403'715'273'262'142'976 + k * 50'000'000LL + camera * 1'000'000LL;
      csv << t_ns << "," << t_ns << ".png\n";
      if (camera == 1 && k == 2) continue;
      cv::imwrite((folder / "data" / (std::to_string(t_ns) + ".png")).string(),
                  EurocImage(camera, k));
    }
  }
  const auto r = Run("import euroc " + Quote((dir_ / "rec").string()) + " -o " +
                     Quote(Path("images.lcmlog")) + " --config-out " + Quote(Path("rig.yaml")));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("camera 'cam1': 1 listed images missing or unreadable"), std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("5 frames of cam0, 4 frames of cam1"), std::string::npos) << r.out;

  const std::vector<support::LoggedEvent> events = support::ReadLcmLog(Path("images.lcmlog"));
  ASSERT_EQ(events.size(), 9u);
  lcm::MessageValidator validator({"cam0", "cam1"});
  int64_t last_t_ns = 0;
  for (const support::LoggedEvent& e : events) {
    auto msg = validator.Decode<image_t>(e.channel, e.data.data(), e.data.size());
    ASSERT_TRUE(msg.ok()) << msg.error();
    EXPECT_EQ(e.channel, "RIGCAL_IMAGE_" + msg->camera);
    EXPECT_GT(msg->t_ns, last_t_ns);  // time order across the cameras
    last_t_ns = msg->t_ns;
    EXPECT_EQ(msg->encoding, image_t::ENCODING_PNG);  // the default for imports
    auto image = pipeline::FrameFromImage(*msg, 0);
    ASSERT_TRUE(image.ok()) << image.error();
    const int camera = msg->camera == "cam0" ? 0 : 1;
    const int k = static_cast<int>(msg->trigger_seq);  // the CSV line index
    EXPECT_EQ(cv::norm(image->image, EurocImage(camera, k), cv::NORM_INF), 0.0)
        << msg->camera << " frame " << k;
  }

  // The rig config carries the intrinsics of sensor.yaml.
  auto config = io::LoadRigConfig(Path("rig.yaml"));
  ASSERT_TRUE(config.ok()) << config.error();
  ASSERT_EQ(config->CameraNames(), (std::vector<std::string>{"cam0", "cam1"}));
  ASSERT_TRUE(config->cameras[1].spec.has_value());
  EXPECT_EQ(config->cameras[1].spec->intrinsics[1], 51.5);
  EXPECT_EQ(config->cameras[1].spec->width, 64);
  ASSERT_EQ(config->cameras[1].spec->distortion.size(), 4u);
  EXPECT_EQ(config->cameras[1].spec->distortion[3], 1.7e-05);

  // A broken sensor.yaml is named with its line.
  std::ofstream(mav0 / "cam1" / "sensor.yaml") << "camera_model: pinhole\n"
                                                  "distortion_model: radial-tangential\n"
                                                  "intrinsics: [1, 2, 3]\n"
                                                  "resolution: [64, 48]\n";
  const auto bad =
      Run("import euroc " + Quote((dir_ / "rec").string()) + " -o " + Quote(Path("bad.lcmlog")));
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("cam1/sensor.yaml:3: intrinsics"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(Path("bad.lcmlog")));
  const auto empty =
      Run("import euroc " + Quote(dir_.string()) + " -o " + Quote(Path("none.lcmlog")));
  EXPECT_EQ(empty.exit_code, 1);
  EXPECT_NE(empty.err.find("no camera folders"), std::string::npos) << empty.err;
}

}  // namespace
}  // namespace rigcal
