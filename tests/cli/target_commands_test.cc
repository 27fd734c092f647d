// SPDX-License-Identifier: Apache-2.0
// `rigcal intrinsics`, `rigcal reference-compare` and `rigcal solve --reference target /
// --metric-target / --master-metric` through the built binary, on OpenCV's 13 real stereo
// chessboard pairs (../shared/data/opencv_stereo_chessboard).

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include "command_test.h"
#include "rigcal/io/camera_files.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/log_writer.h"
#include "rigcal/pipeline/image_codec.h"
#include "support/skip.h"

namespace rigcal {
namespace {

std::string DataDir() { return std::string(RIGCAL_SHARED_DATA_DIR) + "/opencv_stereo_chessboard"; }

class TargetCommandsTest : public cli_test::CommandTest {
 protected:
  void SetUp() override {
    CommandTest::SetUp();
    if (HasFatalFailure()) return;
    if (!std::filesystem::exists(DataDir() + "/left01.jpg")) {
      RIGCAL_SKIP_MISSING() << "real chessboard images not found in " << DataDir();
    }
  }
  std::string Cameras() const {
    return "--camera " + cli_test::Quote("left=" + DataDir() + "/left*.jpg") + " --camera " +
           cli_test::Quote("right=" + DataDir() + "/right*.jpg");
  }
};

TEST_F(TargetCommandsTest, IntrinsicsWriteConfigCamchainPosesAndSolveUsesThem) {
  const cli_test::RunResult r =
      Run("intrinsics " + Cameras() + " --chessboard 9x6 --square 1 --json --camchain " +
          Path("camchain.yaml") + " --config-out " + Path("rig.yaml") + " --poses-out " +
          Path("poses"));
  ASSERT_EQ(r.exit_code, 0) << r.Explain();
  const auto json = nlohmann::json::parse(r.out, nullptr, false);
  ASSERT_FALSE(json.is_discarded()) << r.out;
  ASSERT_EQ(json["cameras"].size(), 2u);
  EXPECT_EQ(json["cameras"][0]["views"].size(), 13u);
  EXPECT_LT(json["cameras"][0]["rms_px"].get<double>(), 0.6);
  EXPECT_GE(json["cameras"][0]["views_rejected"].get<int>(), 0);
  // sigma of every parameter, named; a chessboard's corners fix the focal length to a fraction
  // of a percent (finite, positive, far below 1 % of 450 px).
  const auto& sigma = json["cameras"][0]["parameter_std"];
  ASSERT_TRUE(sigma.is_object()) << sigma.dump();
  EXPECT_EQ(sigma.size(), 8u);
  EXPECT_GT(sigma["fx"].get<double>(), 0.0);
  EXPECT_LT(sigma["fx"].get<double>(), 4.5);

  // The camchain: complete (Kalibr's keys) and read back.
  auto specs = io::ReadKalibrIntrinsics(Path("camchain.yaml"));
  ASSERT_TRUE(specs.ok()) << specs.error();
  ASSERT_EQ(specs->size(), 2u);
  EXPECT_EQ((*specs)[1].name, "right");
  EXPECT_EQ((*specs)[0].width, 640);
  EXPECT_NEAR((*specs)[0].intrinsics[0], json["cameras"][0]["intrinsics"][0].get<double>(), 1e-9);
  auto chain = io::ReadCamchain(Path("camchain.yaml"));
  ASSERT_TRUE(chain.ok()) << chain.error();
  // The right camera ~3.34 squares from the left one.
  const Eigen::Vector3d t = (*chain)[1].cn_from_cnm1.topRightCorner(3, 1);
  EXPECT_NEAR(t.norm(), 3.34, 0.1);
  const std::string text = cli_test::Slurp(Path("camchain.yaml"));
  for (const char* key : {"camera_model", "intrinsics", "distortion_model", "distortion_coeffs",
                          "resolution", "T_cn_cnm1", "rostopic"}) {
    EXPECT_NE(text.find(key), std::string::npos) << key << " missing:\n" << text;
  }
  // The rig config.
  auto config = io::LoadRigConfig(Path("rig.yaml"));
  ASSERT_TRUE(config.ok()) << config.error();
  ASSERT_EQ(config->cameras.size(), 2u);
  ASSERT_TRUE(config->cameras[0].spec.has_value());

  // solve --reference target on the written target poses.
  const cli_test::RunResult ref =
      Run("solve --reference target --master left=" + Path("poses/left.tum") +
          " --slave right=" + Path("poses/right.tum") + " --json");
  ASSERT_EQ(ref.exit_code, 0) << ref.Explain();
  const auto ref_json = nlohmann::json::parse(ref.out, nullptr, false);
  ASSERT_FALSE(ref_json.is_discarded()) << ref.out;
  EXPECT_EQ(ref_json["unit"]["source"], "target reference");
  const auto& slave = ref_json["slaves"][0];
  const double baseline = std::hypot(slave["C"][0].get<double>(), slave["C"][1].get<double>(),
                                     slave["C"][2].get<double>());
  EXPECT_NEAR(baseline, 3.34, 0.1) << ref.out;
  EXPECT_EQ(slave["state"], "converged");

  // The individual reference pose model on the same poses: it does not know that both cameras
  // see one board (it fits the boards' relative pose W too), so it must agree with the global
  // model within their σ (5 σ of the difference per axis).
  const cli_test::RunResult ind = Run(
      "solve --reference target --pose-model individual --master left=" + Path("poses/left.tum") +
      " --slave right=" + Path("poses/right.tum") + " --json");
  ASSERT_EQ(ind.exit_code, 0) << ind.Explain();
  const auto ind_json = nlohmann::json::parse(ind.out, nullptr, false);
  ASSERT_FALSE(ind_json.is_discarded()) << ind.out;
  const auto& ind_slave = ind_json["slaves"][0];
  for (int a = 0; a < 3; ++a) {
    const double diff = ind_slave["C"][a].get<double>() - slave["C"][a].get<double>();
    const double sigma =
        std::hypot(ind_slave["std"]["pos"][a].get<double>(), slave["std"]["pos"][a].get<double>());
    EXPECT_GT(ind_slave["std"]["pos"][a].get<double>(), 0.0) << ind.out;
    EXPECT_LT(std::abs(diff), 5.0 * sigma) << "axis " << a << "\n" << ind.out << "\n" << ref.out;
  }
  EXPECT_NE(ind_slave["message"].get<std::string>().find("individual reference pose model"),
            std::string::npos)
      << ind.out;
  // Without --reference target: a usage error.
  const cli_test::RunResult misuse =
      Run("solve --pose-model individual --master " + Path("poses/left.tum") + " --slave " +
          Path("poses/right.tum"));
  EXPECT_NE(misuse.exit_code, 0) << misuse.Explain();
  EXPECT_NE(misuse.err.find("--pose-model individual needs --reference target"), std::string::npos)
      << misuse.err;

  // The motion-based solve with the master's scale from its target poses: the odometry here
  // is the target poses themselves, so lambda_world is 1 and the output says metres.
  const cli_test::RunResult metric =
      Run("solve --master left=" + Path("poses/left.tum") +
          " --slave right=" + Path("poses/right.tum") + " --metric-target " +
          Path("poses/left.tum") + " --json" + " --out " + Path("result.yaml"));
  ASSERT_TRUE(metric.exit_code == 0 || metric.exit_code == 3) << metric.Explain();
  const auto metric_json = nlohmann::json::parse(metric.out, nullptr, false);
  ASSERT_FALSE(metric_json.is_discarded()) << metric.out;
  EXPECT_TRUE(metric_json["unit"]["metric"].get<bool>());
  EXPECT_NEAR(metric_json["unit"]["metres_per_master_unit"].get<double>(), 1.0, 1e-9);
  EXPECT_NE(metric.err.find("positions are in metres"), std::string::npos) << metric.err;
  EXPECT_NE(cli_test::Slurp(Path("result.yaml")).find("# units: metric scale"), std::string::npos);

  // --master-metric with --metric-target: a usage error.
  const cli_test::RunResult both =
      Run("solve --master " + Path("poses/left.tum") + " --slave " + Path("poses/right.tum") +
          " --master-metric" + " --metric-target " + Path("poses/left.tum"));
  EXPECT_EQ(both.exit_code, 2) << both.Explain();
}

// The same 13 pairs as RIGCAL_IMAGE_left / RIGCAL_IMAGE_right events of an LCM log (raw image_t,
// pixel-exact, stamped 1 s apart as the file numbers): the images reach the same detector, so
// the intrinsics, view counts and the stereo extrinsics equal those from the image files.
TEST_F(TargetCommandsTest, IntrinsicsFromAnLcmImageLog) {
  const std::string log_path = Path("stereo.lcmlog");
  {
    auto writer = lcm::LogWriter::Open(log_path);
    ASSERT_TRUE(writer.ok()) << writer.error();
    const lcm::CameraNames names = {"left", "right"};
    pipeline::ImageEncodeOptions raw;
    raw.encoding = pipeline::ImageEncoding::kRaw;
    for (int k = 1; k <= 14; ++k) {
      for (int c = 0; c < 2; ++c) {
        char file[64];
        std::snprintf(file, sizeof(file), "/%s%02d.jpg", c == 0 ? "left" : "right", k);
        if (!std::filesystem::exists(DataDir() + file)) continue;  // there is no pair 10
        capture::Frame frame;
        frame.camera = c;
        frame.t_ns = k * 1000000000LL;
        frame.image = cv::imread(DataDir() + file, cv::IMREAD_GRAYSCALE);
        ASSERT_FALSE(frame.image.empty()) << file;
        auto data = pipeline::EncodeImageEvent(frame, names, c, raw);
        ASSERT_TRUE(data.ok()) << data.error();
        ASSERT_TRUE((*writer)
                        ->Write(lcm::ImageChannel(names[static_cast<size_t>(c)]),
                                frame.t_ns / 1000, data->data(), data->size())
                        .ok());
      }
    }
    ASSERT_TRUE((*writer)->Close().ok());
  }
  const cli_test::RunResult from_log =
      Run("intrinsics --camera left=" + log_path + " --camera right=" + log_path +
          " --chessboard 9x6 --square 1 --json");
  ASSERT_EQ(from_log.exit_code, 0) << from_log.Explain();
  const cli_test::RunResult from_files =
      Run("intrinsics " + Cameras() + " --chessboard 9x6 --square 1 --json");
  ASSERT_EQ(from_files.exit_code, 0) << from_files.Explain();
  const auto log_json = nlohmann::json::parse(from_log.out, nullptr, false);
  const auto file_json = nlohmann::json::parse(from_files.out, nullptr, false);
  ASSERT_FALSE(log_json.is_discarded()) << from_log.out;
  ASSERT_FALSE(file_json.is_discarded()) << from_files.out;
  for (size_t c = 0; c < 2; ++c) {
    const auto& a = log_json["cameras"][c];
    const auto& b = file_json["cameras"][c];
    EXPECT_EQ(a["files"], 13);
    EXPECT_EQ(a["views"].size(), b["views"].size());
    EXPECT_EQ(a["views_used"], b["views_used"]);
    for (size_t i = 0; i < 4; ++i) {
      // Identical pixels and detector: equal up to the summation order, far below 1e-9 px.
      EXPECT_NEAR(a["intrinsics"][i].get<double>(), b["intrinsics"][i].get<double>(), 1e-9)
          << "camera " << c << " intrinsics[" << i << "]";
    }
  }
  ASSERT_EQ(log_json["extrinsics"].size(), 1u) << from_log.out;
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(log_json["extrinsics"][0]["C"][i].get<double>(),
                file_json["extrinsics"][0]["C"][i].get<double>(), 1e-9);
  }
  // A camera the log has no images of: a clear error listing what the log has.
  const cli_test::RunResult missing = Run("intrinsics --camera top=" + log_path);
  EXPECT_EQ(missing.exit_code, 1) << missing.Explain();
  EXPECT_NE(missing.err.find("no RIGCAL_IMAGE_top events (camera 'top')"), std::string::npos)
      << missing.err;
  EXPECT_NE(missing.err.find("RIGCAL_IMAGE_left (13)"), std::string::npos) << missing.err;
}

TEST_F(TargetCommandsTest, ReferenceCompareTable) {
  const cli_test::RunResult r = Run("reference-compare " + Cameras() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.Explain();
  const auto json = nlohmann::json::parse(r.out, nullptr, false);
  ASSERT_FALSE(json.is_discarded()) << r.out;
  ASSERT_EQ(json["slaves"].size(), 1u);
  EXPECT_EQ(json["slaves"][0]["reference"], "stereo");
  bool saw_nl = false;
  for (const auto& row : json["slaves"][0]["rows"]) {
    if (row["method"] != "motion-based NL") continue;
    saw_nl = true;
    EXPECT_LE(row["rot_err_deg"].get<double>(), 0.15) << row.dump();
    EXPECT_LE(row["dir_err_deg"].get<double>(), 0.5) << row.dump();
    EXPECT_LE(row["length_err_pct"].get<double>(), 0.3) << row.dump();
  }
  EXPECT_TRUE(saw_nl) << r.out;
  const cli_test::RunResult text = Run("reference-compare " + Cameras());
  ASSERT_EQ(text.exit_code, 0) << text.Explain();
  EXPECT_NE(text.out.find("rot_deg  dir_deg  len_pct"), std::string::npos) << text.out;
}

TEST_F(TargetCommandsTest, NoChessboardIsAClearError) {
  const cli_test::RunResult r =
      Run("intrinsics --camera " + cli_test::Quote("left=" + DataDir() + "/left*.jpg") +
          " --chessboard 10x7");
  EXPECT_EQ(r.exit_code, 1) << r.Explain();
  EXPECT_NE(r.err.find("no 10x7 chessboard (inner corners) found in any of the 13 images"),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace rigcal
