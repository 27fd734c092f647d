// SPDX-License-Identifier: Apache-2.0
// `rigcal intrinsics --model scaramuzza` through the built binary: simulated detections of a
// 200-degree camera (support/omni_views.h, 0.1 px noise) written as AprilGrid-format CSVs for
// two cameras that see the same views;
// the polynomial model goes into the rig config (read back and built), Kalibr's omni model
// into the camchain, the target poses into poses/NAME.tum. Tolerances as in
// target/polynomial_intrinsics (centre within 1 px, RMS at the noise's 0.141 px).

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "command_test.h"
#include "rigcal/io/camera_files.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/rig_files.h"
#include "support/omni_views.h"

namespace rigcal {
namespace {

class OmniIntrinsicsCommandTest : public cli_test::CommandTest {
 protected:
  // One <frame>.csv per view (frame = t_ns in seconds):
  // ts,tag_rows,tag_cols,tag_size,tag_spacing,kp_x,kp_y,p_x,p_y,p_z, tag_id,corner_idx.
  void WriteDetections(const pattern::CameraViews& views, const std::string& folder) {
    std::filesystem::create_directories(folder);
    for (const pattern::TargetView& view : views.views) {
      std::ofstream out(folder + "/" + std::to_string(view.t_ns / 1000000000) + ".csv");
      out.precision(10);
      out << "# ts,tag_rows,tag_cols,tag_size,tag_spacing,kp_x,kp_y,p_x,p_y,p_z,tag_id,corner\n";
      for (size_t j = 0; j < view.pixels.size(); ++j) {
        out << view.t_ns << ",6,9,0.04,0.3," << view.pixels[j].x() << "," << view.pixels[j].y()
            << "," << view.target_points[j].x() << "," << view.target_points[j].y() << ","
            << view.target_points[j].z() << "," << j << ",0\n";
      }
    }
  }
};

TEST_F(OmniIntrinsicsCommandTest, PolynomialModelIntoRigConfigOmniIntoCamchain) {
  const camera::CameraSpec truth = test_support::WideOmniCamera("fish");
  const pattern::CameraViews views = test_support::SimulatedOmniViews(truth, 24, 21, 0.1);
  // Two cameras of the same views (a rig config has at least two; their poses coincide).
  WriteDetections(views, Path("fish"));
  WriteDetections(views, Path("twin"));
  const std::string cameras = "--camera fish=" + Path("fish") + " --camera twin=" + Path("twin");
  const cli_test::RunResult alone =
      Run("intrinsics --camera fish=" + Path("fish") +
          " --resolution 800x600 --model scaramuzza --config-out " + Path("alone.yaml"));
  EXPECT_EQ(alone.exit_code, 1) << alone.Explain();
  EXPECT_NE(alone.err.find("at least two cameras"), std::string::npos) << alone.Explain();
  EXPECT_FALSE(std::filesystem::exists(Path("alone.yaml")));
  const cli_test::RunResult r = Run(
      "intrinsics " + cameras + " --resolution 800x600 --model scaramuzza --json --config-out " +
      Path("rig.yaml") + " --camchain " + Path("camchain.yaml") + " --poses-out " + Path("poses"));
  ASSERT_EQ(r.exit_code, 0) << r.Explain();
  const auto json = nlohmann::json::parse(r.out, nullptr, false);
  ASSERT_FALSE(json.is_discarded()) << r.out;
  const auto& camera = json["cameras"][0];
  EXPECT_EQ(camera["model"], "scaramuzza");
  EXPECT_LT(camera["rms_px"].get<double>(), 0.16);
  EXPECT_TRUE(camera["parameter_std"].is_null());  // not computed for the polynomial model
  EXPECT_NEAR(camera["center"][0].get<double>(), truth.center[0], 1.0);
  EXPECT_NEAR(camera["center"][1].get<double>(), truth.center[1], 1.0);
  EXPECT_GE(camera["poly"].size(), 4u);

  // The rig config holds the polynomial model, and it is a camera rigcal can build.
  auto config = io::LoadRigConfig(Path("rig.yaml"));
  ASSERT_TRUE(config.ok()) << config.error();
  ASSERT_EQ(config->cameras.size(), 2u);
  ASSERT_TRUE(config->cameras[0].spec.has_value());
  const camera::CameraSpec& spec = *config->cameras[0].spec;
  EXPECT_EQ(spec.model, camera::CameraSpec::Model::kScaramuzza);
  EXPECT_NEAR(spec.center[0], camera["center"][0].get<double>(), 1e-6);
  auto model = camera::MakeCameraModel(spec);
  ASSERT_TRUE(model.ok()) << model.error();
  int count = 0;
  EXPECT_LT(test_support::WorstProjectionDifference(truth, spec, 80.0, &count), 0.5);

  // Kalibr's camchain: the omni (unified) model, five intrinsics.
  const std::string chain = cli_test::Slurp(Path("camchain.yaml"));
  EXPECT_NE(chain.find("camera_model: omni"), std::string::npos) << chain;
  EXPECT_NE(chain.find("distortion_model: radtan"), std::string::npos) << chain;
  auto links = io::ReadCamchain(Path("camchain.yaml"));
  ASSERT_TRUE(links.ok()) << links.error();
  ASSERT_EQ(links->size(), 2u);
  EXPECT_LT((*links)[1].cn_from_cnm1.topRightCorner(3, 1).norm(), 1e-3);  // the same poses

  // One target pose per view.
  std::ifstream poses(Path("poses/fish.tum"));
  int lines = 0;
  for (std::string line; std::getline(poses, line);) lines += !line.empty() && line[0] != '#';
  EXPECT_EQ(lines, 24);
}

TEST_F(OmniIntrinsicsCommandTest, AnUnknownModelIsAUsageError) {
  const cli_test::RunResult r =
      Run("intrinsics --camera fish=" + Path("none") + " --resolution 800x600 --model omni");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--model"), std::string::npos) << r.Explain();
  EXPECT_NE(r.err.find("scaramuzza"), std::string::npos) << r.Explain();
}

}  // namespace
}  // namespace rigcal
