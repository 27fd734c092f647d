// SPDX-License-Identifier: Apache-2.0
// Reading a result back (ReadResultFile): the result YAML and the --json output round-trip the
// fields the report shows; unknown σ stay unknown; bad files are named with line and field.
#include "rigcal/io/result_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "rigcal/base/quaternion.h"
#include "rigcal/io/result_json.h"
#include "rigcal/io/rig_files.h"

namespace rigcal::io {
namespace {

using ::testing::HasSubstr;

RigCalibration MakeResult() {
  RigCalibration r;
  r.master = "front";
  r.pairs_selected = 77;
  SlaveCalibration left;
  left.name = "left";
  left.estimate.q = AxisAngle(Eigen::Vector3d(0.2, 1, 0.1).normalized(), 1.3);
  left.estimate.C = Eigen::Vector3d(-0.5, 0.25, 2.0);
  left.estimate.scale = 0.75;
  left.scales = {{0, 0.75, 0.001}};
  left.rot_std_deg = 0.05;
  left.pos_std = Eigen::Vector3d(0.01, 0.02, std::nan(""));
  left.axis_offset_std = std::nan("");
  left.motions.total = 120;
  left.motions.used = 100;
  left.motions.small_rotation = 12;
  left.motions.residual_outlier = 8;
  left.motion_model = MotionModel::kPlanar;
  left.scale_model = ScaleModel::kFixed;
  left.termination = Termination::kSolved;
  left.state = SlaveState::kConverged;
  left.message = "planar: fine";
  SlaveCalibration back = left;
  back.name = "back";
  back.scales = {{0, 0.5, 0.01}, {3, 0.6, std::nan("")}};
  back.estimate.scale = 0.5;
  back.scale_model = ScaleModel::kSegments;
  back.state = SlaveState::kInitialising;
  back.termination = Termination::kDegenerate;
  r.slaves = {left, back};
  return r;
}

class ResultFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rigcal_result_file_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Write(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }
  void ExpectSame(const RigCalibration& read, bool json) {
    const RigCalibration expected = MakeResult();
    EXPECT_EQ(read.master, "front");
    ASSERT_EQ(read.slaves.size(), 2u);
    for (size_t i = 0; i < 2; ++i) {
      const SlaveCalibration& a = read.slaves[i];
      const SlaveCalibration& b = expected.slaves[i];
      EXPECT_EQ(a.name, b.name);
      EXPECT_LT(AngleBetween(a.estimate.q, b.estimate.q), 1e-12);
      EXPECT_LT((a.estimate.C - b.estimate.C).norm(), 1e-12);
      EXPECT_DOUBLE_EQ(a.estimate.scale, b.estimate.scale);
      ASSERT_EQ(a.scales.size(), b.scales.size());
      for (size_t k = 0; k < a.scales.size(); ++k) {
        EXPECT_EQ(a.scales[k].segment, b.scales[k].segment);
        EXPECT_DOUBLE_EQ(a.scales[k].scale, b.scales[k].scale);
        EXPECT_EQ(std::isnan(a.scales[k].std), std::isnan(b.scales[k].std));
      }
      EXPECT_DOUBLE_EQ(a.rot_std_deg, b.rot_std_deg);
      EXPECT_DOUBLE_EQ(a.pos_std.x(), b.pos_std.x());
      EXPECT_TRUE(std::isnan(a.pos_std.z()));  // unknown stays unknown
      EXPECT_TRUE(std::isnan(a.axis_offset_std));
      EXPECT_EQ(a.state, b.state);
      EXPECT_EQ(a.termination, b.termination);
      EXPECT_EQ(a.message, b.message);
      EXPECT_EQ(a.motion_model, b.motion_model);
      EXPECT_EQ(a.scale_model, b.scale_model);
      EXPECT_EQ(a.motions.used, b.motions.used);
      EXPECT_EQ(a.motions.rejected(), b.motions.rejected());
      if (!json) {
        EXPECT_EQ(a.motions.small_rotation, b.motions.small_rotation);
      }
    }
    if (!json) {
      EXPECT_EQ(read.pairs_selected, 77);
    }
  }
  std::filesystem::path dir_;
};

TEST_F(ResultFileTest, YamlRoundTrip) {
  const std::string path = (dir_ / "result.yaml").string();
  ASSERT_TRUE(WriteResultYaml(path, MakeResult()).ok());
  auto read = ReadResultFile(path);
  ASSERT_TRUE(read.ok()) << read.error();
  ExpectSame(*read, false);
}

TEST_F(ResultFileTest, JsonRoundTrip) {
  const std::string path = Write("result.json", ResultToJson(MakeResult(), nullptr).dump(2));
  auto read = ReadResultFile(path);
  ASSERT_TRUE(read.ok()) << read.error();
  ExpectSame(*read, true);
}

TEST_F(ResultFileTest, ErrorsNameLineAndField) {
  std::string yaml = ResultToYaml(MakeResult());
  yaml.replace(yaml.find("state: converged"), 16, "state: excellent");
  auto bad_state = ReadResultFile(Write("bad_state.yaml", yaml));
  ASSERT_FALSE(bad_state.ok());
  EXPECT_THAT(bad_state.error(), ::testing::MatchesRegex(".*bad_state.yaml:[0-9]+: left.state: "
                                                         "unknown value 'excellent'.*"));

  nlohmann::json j = ResultToJson(MakeResult(), nullptr);
  j["slaves"][1].erase("motions_used");
  auto missing = ReadResultFile(Write("missing.json", j.dump(2)));
  ASSERT_FALSE(missing.ok());
  EXPECT_THAT(missing.error(), HasSubstr("back.motions_used: missing"));

  auto syntax = ReadResultFile(Write("syntax.json", "{\"master\": \"a\", \"slaves\": [}"));
  ASSERT_FALSE(syntax.ok());
  EXPECT_THAT(syntax.error(), HasSubstr("syntax.json:1"));

  auto empty = ReadResultFile(Write("empty.yaml", "master: front\n"));
  ASSERT_FALSE(empty.ok());
  EXPECT_THAT(empty.error(), HasSubstr("no slave results"));
}

}  // namespace
}  // namespace rigcal::io
