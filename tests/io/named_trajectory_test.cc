// SPDX-License-Identifier: Apache-2.0
// "NAME=FILE" camera arguments (rigcal solve, rigcal import tum) and the rig config written for
// imported logs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "rigcal/io/rig_config.h"
#include "rigcal/io/trajectory_io.h"
#include "support/temp_dir.h"

namespace rigcal::io {
namespace {

namespace fs = std::filesystem;

TEST(NamedTrajectoryPath, SplitsNameUnlessTheArgumentIsAFile) {
  const fs::path dir = support::FreshTempDir("named_parse");
  NamedTrajectoryPath p = ParseNamedTrajectoryPath("cam1=mav0/cam1/data.csv");
  EXPECT_EQ(p.name, "cam1");
  EXPECT_EQ(p.path, "mav0/cam1/data.csv");
  p = ParseNamedTrajectoryPath("mav0/cam1/data.csv");
  EXPECT_EQ(p.name, "");
  EXPECT_EQ(p.path, "mav0/cam1/data.csv");
  p = ParseNamedTrajectoryPath("=x.txt");  // no name before '='
  EXPECT_EQ(p.name, "");
  EXPECT_EQ(p.path, "=x.txt");
  const std::string odd = (dir / "a=b.txt").string();  // an existing file with '=' in its name
  std::ofstream(odd) << "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n";
  p = ParseNamedTrajectoryPath(odd);
  EXPECT_EQ(p.name, "");
  EXPECT_EQ(p.path, odd);

  auto named = ReadNamedTrajectory("front=" + odd);
  ASSERT_TRUE(named.ok()) << named.error();
  EXPECT_EQ(named->name, "front");
  EXPECT_EQ(named->size(), 2u);
  auto stem = ReadNamedTrajectory(odd);
  ASSERT_TRUE(stem.ok()) << stem.error();
  EXPECT_EQ(stem->name, "a=b");
  auto missing = ReadNamedTrajectory("front=" + (dir / "none.txt").string());
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("none.txt"), std::string::npos) << missing.error();
  // The name becomes file and channel names: checked as in the YAML files.
  auto tab = ReadNamedTrajectory("fr\tont=" + odd);
  ASSERT_FALSE(tab.ok());
  EXPECT_NE(tab.error().find("a control character in a camera name"), std::string::npos)
      << tab.error();
}

TEST(WriteRigConfig, RoundTripsThroughTheLoader) {
  const fs::path dir = support::FreshTempDir("named_config");
  std::vector<CameraConfig> cameras(2);
  cameras[0].name = "cam0";
  camera::CameraSpec spec;
  spec.model = camera::CameraSpec::Model::kFisheye;
  spec.width = 640;
  spec.height = 480;
  spec.intrinsics = {300.1234567890123, 301.5, 319.5, 239.25};
  spec.distortion = {0.01, -0.002, 0.0003, -4e-05};
  spec.rolling_shutter_s = 0.0125;
  cameras[0].spec = spec;
  cameras[1].name = "cam-1.b";
  const std::string path = (dir / "rig.yaml").string();
  ASSERT_TRUE(WriteRigConfig(path, "imported", cameras, "first line\nsecond line").ok());
  auto config = LoadRigConfig(path);
  ASSERT_TRUE(config.ok()) << config.error();
  EXPECT_EQ(config->name, "imported");
  ASSERT_EQ(config->CameraNames(), (std::vector<std::string>{"cam0", "cam-1.b"}));
  ASSERT_TRUE(config->cameras[0].spec.has_value());
  EXPECT_EQ(config->cameras[0].spec->model, camera::CameraSpec::Model::kFisheye);
  EXPECT_EQ(config->cameras[0].spec->intrinsics, spec.intrinsics);
  EXPECT_EQ(config->cameras[0].spec->distortion, spec.distortion);
  EXPECT_DOUBLE_EQ(config->cameras[0].spec->rolling_shutter_s, 0.0125);
  EXPECT_FALSE(config->cameras[1].spec.has_value());

  // The polynomial omnidirectional model, with a given field of view.
  auto omni = camera::ScaramuzzaSpecForEquidistant("omni", 800, 600, 180.0, 411.5, 287.5, 100.0);
  ASSERT_TRUE(omni.ok()) << omni.error();
  omni->affine = {1.004, 0.003, -0.001};
  omni->inverse_poly = {180.0 * M_PI / 2.0, 180.0};  // rho = f theta, theta = phi + 90 deg
  cameras[1].spec = *omni;
  ASSERT_TRUE(WriteRigConfig(path, "imported", cameras, "").ok());
  auto with_omni = LoadRigConfig(path);
  ASSERT_TRUE(with_omni.ok()) << with_omni.error();
  ASSERT_TRUE(with_omni->cameras[1].spec.has_value());
  const camera::CameraSpec& read = *with_omni->cameras[1].spec;
  EXPECT_EQ(read.model, camera::CameraSpec::Model::kScaramuzza);
  EXPECT_EQ(read.width, 800);
  EXPECT_EQ(read.poly, omni->poly);
  EXPECT_EQ(read.inverse_poly, omni->inverse_poly);
  EXPECT_EQ(read.center, omni->center);
  EXPECT_EQ(read.affine, omni->affine);
  EXPECT_EQ(read.max_field_angle_deg, 100.0);
  EXPECT_EQ(read.rolling_shutter_s, 0.0);  // a global shutter writes no key

  const Status none = WriteRigConfig(path, "x", {}, "");
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.message().find("needs a camera"), std::string::npos);
}

}  // namespace
}  // namespace rigcal::io
