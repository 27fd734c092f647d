// SPDX-License-Identifier: Apache-2.0
// Rig YAML (truth / result), Kalibr camchain, and the atomic writer underneath them.
#include "rigcal/io/rig_files.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "rigcal/base/quaternion.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/io/result_camchain.h"

namespace rigcal::io {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class RigFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::path(::testing::TempDir()) / "rig_files_XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  std::string Write(const std::string& name, const std::string& contents) {
    std::ofstream(Path(name)) << contents;
    return Path(name);
  }

  std::string ReadRigError(const std::string& name, const std::string& contents) {
    const auto rig = ReadRigYaml(Write(name, contents));
    EXPECT_FALSE(rig.ok()) << name << " was accepted";
    return rig.ok() ? "" : rig.error();
  }

  std::vector<std::string> Listing() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename());
    std::sort(names.begin(), names.end());
    return names;
  }

  fs::path dir_;
};

Similarity MakeRig(const Eigen::Vector3d& axis, double angle_deg, const Eigen::Vector3d& c,
                   double scale) {
  Similarity s;
  s.q = AxisAngle(axis, angle_deg * kRadPerDeg);
  s.C = c;
  s.scale = scale;
  return s;
}

// A result with a converged slave, a slave with three segment scales and an unusable one.
RigCalibration MakeResult() {
  RigCalibration r;
  r.master = "front";
  r.pairs_selected = 321;
  SlaveCalibration left;
  left.name = "left";
  left.estimate = MakeRig({0, 1, 0}, -90, {-0.85, 0.05, -0.6}, 0.5);
  left.scales = {SegmentScale{0, 0.5, 0.001}};
  left.rot_std_deg = 0.02;
  left.pos_std = {0.001, 0.002, 0.003};
  left.motions.total = 300;
  left.motions.used = 290;
  left.motions.small_rotation = 6;
  left.motions.angle_mismatch = 3;
  left.motions.residual_outlier = 1;
  left.glitches.rotation_jump = 1;
  left.glitches.in_slave = 1;
  left.termination = Termination::kSolved;
  left.state = SlaveState::kConverged;
  left.message = "ok";
  SlaveCalibration back;
  back.name = "back";
  back.estimate = MakeRig({0.1, 1, 0}, 177, {0.1, -0.1, -2.2}, 2.0);
  back.scales = {SegmentScale{0, 2.0, 0.01}, SegmentScale{1, 2.5, 0.02},
                 SegmentScale{4, 1.5, 0.03}};
  back.scale_model = ScaleModel::kSegments;
  back.unobservable = {Eigen::Vector3d::UnitY()};
  back.termination = Termination::kNoConvergence;
  back.state = SlaveState::kUsable;
  back.message = "iteration limit";
  SlaveCalibration still;
  still.name = "still";
  still.termination = Termination::kInsufficientMotion;
  still.message = "need >= 2 motions with rotation >= 2 deg, got 0";
  r.slaves = {left, back, still};
  return r;
}

void ExpectRigNear(const Similarity& a, const Similarity& b, double tol) {
  EXPECT_LT((a.q.coeffs() - b.q.coeffs()).norm(), tol);
  EXPECT_LT((a.C - b.C).norm(), tol);
  EXPECT_NEAR(a.scale, b.scale, tol);
}

TEST_F(RigFilesTest, RigYamlRoundTrips) {
  const std::map<std::string, Similarity> rig = {
      {"cam1", MakeRig({1, 2, 3}, 33.3, {0.1, -1.0 / 3.0, 1e-9}, 0.123456789)},
      {"cam2", MakeRig({0, 0, 1}, 180, {-2, 0, 5}, 2.0)}};
  ASSERT_TRUE(WriteRigYaml(Path("truth.yaml"), rig).ok());
  const auto read = ReadRigYaml(Path("truth.yaml"));
  ASSERT_TRUE(read.ok()) << read.error();
  ASSERT_EQ(read->size(), 2u);
  // Shortest round-trip digits: exact up to the re-normalisation of q (a few ulp).
  ExpectRigNear(read->at("cam1"), rig.at("cam1"), 1e-15);
  ExpectRigNear(read->at("cam2"), rig.at("cam2"), 1e-15);
  EXPECT_EQ(read->at("cam1").C, rig.at("cam1").C);
}

TEST_F(RigFilesTest, ReadsHandWrittenFileWithMetadataAndScales) {
  const auto rig =
      ReadRigYaml(Write("hand.yaml",
                        "master: cam0\n"
                        "cam1:\n"
                        "  q_wxyz: [0.7071, 0, 0.7071, 0]   # 4 decimals\n"
                        "  C: [1, 2, 3]\n"
                        "  scale: 0.5\n"
                        "  scales: [{segment: 0, scale: 0.5}, {segment: 1, scale: 0.6}]\n"
                        "cam2: {q_wxyz: [1, 0, 0, 0], C: [0, 0, -1], scale: 2}\n"));
  ASSERT_TRUE(rig.ok()) << rig.error();
  ASSERT_EQ(rig->size(), 2u);
  EXPECT_EQ(rig->count("master"), 0u);
  EXPECT_NEAR(rig->at("cam1").q.norm(), 1.0, 1e-15);
  EXPECT_NEAR(rig->at("cam1").q.y(), std::sqrt(0.5), 1e-12);
  EXPECT_EQ(rig->at("cam2").C, Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(rig->at("cam2").scale, 2.0);
}

// A segment given two scales, and a truth relative to another master: errors naming the file,
// the line and the field.
TEST_F(RigFilesTest, TwoScalesForOneSegmentAndAnotherMasterAreErrors) {
  EXPECT_THAT(ReadRigError("dup.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, 0]\n  scale: 1\n"
                           "  scales:\n  - {segment: 0, scale: 1}\n  - {segment: 0, scale: 2}\n"),
              HasSubstr("dup.yaml:7: cam1.scales[1].segment: segment 0 appears twice"));
  const std::string other = Write("other.yaml",
                                  "master: back\n"
                                  "cam1: {q_wxyz: [1, 0, 0, 0], C: [0, 0, -1], scale: 2}\n");
  const auto rig = ReadRigYaml(other, "front");
  ASSERT_FALSE(rig.ok());
  EXPECT_THAT(rig.error(),
              HasSubstr("other.yaml:1: master: the file is relative to master 'back', the "
                        "rig's master is 'front'"));
  EXPECT_TRUE(ReadRigYaml(other, "back").ok());
  EXPECT_TRUE(ReadRigYaml(other).ok());
  const auto truth = ReadTrueMountings(other, "front");
  ASSERT_FALSE(truth.ok());
  EXPECT_THAT(truth.error(), HasSubstr("other.yaml:1: master:"));
}

// Every rejected rig file: the message names the file, the line and the field.
TEST_F(RigFilesTest, RigYamlMissingFile) {
  const auto rig = ReadRigYaml(Path("absent.yaml"));
  ASSERT_FALSE(rig.ok());
  EXPECT_THAT(rig.error(), HasSubstr(Path("absent.yaml") + ": cannot open"));
}

TEST_F(RigFilesTest, RigYamlSyntaxError) {
  EXPECT_THAT(ReadRigError("syntax.yaml", "cam1:\n  q_wxyz: [1, 0, 0, 0\n  C: [0, 0, 0]\n"),
              ::testing::MatchesRegex(".*syntax.yaml:[0-9]+: YAML syntax error.*"));
}

TEST_F(RigFilesTest, RigYamlSlaveNamesAreText) {
  // Found by fuzzing: a name with bytes that are not UTF-8 was read, but written back by
  // RigToYaml as another name.
  const std::string slave = "\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, 0]\n  scale: 1\n";
  EXPECT_THAT(ReadRigError("bytes.yaml",
                           "master: cam0\n\xff\x01"
                           "cam1:" +
                               slave),
              HasSubstr("bytes.yaml:2: slave name: not UTF-8 text"));
  EXPECT_THAT(ReadRigError("slash.yaml", "a/b:" + slave),
              HasSubstr("slash.yaml:1: slave name: '/' in a camera name"));
  // UTF-8 names are names.
  const std::string path = Write("utf8.yaml", "cam\xc3\xa9ra:" + slave);
  auto rig = ReadRigYaml(path);
  ASSERT_TRUE(rig.ok()) << rig.error();
  EXPECT_EQ(rig->count("cam\xc3\xa9ra"), 1u);
}

TEST_F(RigFilesTest, RigYamlMissingFields) {
  EXPECT_THAT(ReadRigError("noq.yaml", "cam1:\n  C: [0, 0, 0]\n  scale: 1\n"),
              HasSubstr("noq.yaml:2: cam1.q_wxyz: missing"));
  EXPECT_THAT(ReadRigError("noc.yaml", "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  scale: 1\n"),
              HasSubstr("noc.yaml:2: cam1.C: missing"));
  EXPECT_THAT(ReadRigError("nos.yaml",
                           "a: {q_wxyz: [1, 0, 0, 0], C: [0, 0, 0], scale: 1}\n"
                           "cam2:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, 0]\n"),
              HasSubstr("nos.yaml:3: cam2.scale: missing"));
}

TEST_F(RigFilesTest, RigYamlWrongLengths) {
  EXPECT_THAT(ReadRigError("q3.yaml", "cam1:\n  q_wxyz: [1, 0, 0]\n  C: [0, 0, 0]\n  scale: 1\n"),
              HasSubstr("q3.yaml:2: cam1.q_wxyz: expected 4 numbers, got 3"));
  EXPECT_THAT(ReadRigError("c4.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, 0, 1]\n"
                           "  scale: 1\n"),
              HasSubstr("c4.yaml:3: cam1.C: expected 3 numbers, got 4"));
  EXPECT_THAT(ReadRigError("cs.yaml", "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: 5\n  scale: 1\n"),
              HasSubstr("cs.yaml:3: cam1.C: expected a list of 3 numbers"));
}

TEST_F(RigFilesTest, RigYamlNonNumeric) {
  EXPECT_THAT(ReadRigError("nn.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, abc, 0]\n"
                           "  scale: 1\n"),
              HasSubstr("nn.yaml:3: cam1.C[1]: 'abc' is not a number"));
  EXPECT_THAT(ReadRigError("ns.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, 0]\n"
                           "  scale: big\n"),
              HasSubstr("ns.yaml:4: cam1.scale: 'big' is not a number"));
  EXPECT_THAT(ReadRigError("nan.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, nan]\n"
                           "  scale: 1\n"),
              HasSubstr("nan.yaml:3: cam1.C[2]: 'nan' is not finite"));
}

TEST_F(RigFilesTest, RigYamlBadValues) {
  EXPECT_THAT(ReadRigError("s0.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, 0]\n"
                           "  scale: -2\n"),
              HasSubstr("s0.yaml:4: cam1.scale: must be > 0"));
  EXPECT_THAT(ReadRigError("qn.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0.1, 0]\n  C: [0, 0, 0]\n"
                           "  scale: 1\n"),
              HasSubstr("qn.yaml:2: cam1.q_wxyz: norm 1.00499 is not 1"));
  EXPECT_THAT(ReadRigError("sc.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, 0]\n"
                           "  scale: 1\n  scales:\n  - {segment: 0}\n"),
              HasSubstr("sc.yaml:6: cam1.scales[0].scale: missing"));
  EXPECT_THAT(ReadRigError("sid.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, 0]\n"
                           "  scale: 1\n  scales:\n  - {segment: x, scale: 1}\n"),
              HasSubstr("sid.yaml:6: cam1.scales[0].segment: 'x' is not an integer"));
}

TEST_F(RigFilesTest, RigYamlStructure) {
  EXPECT_THAT(ReadRigError("list.yaml", "- 1\n- 2\n"), HasSubstr("list.yaml:1: expected a map"));
  EXPECT_THAT(ReadRigError("empty.yaml", "master: cam0\n"), HasSubstr("empty.yaml: no slave"));
  EXPECT_THAT(ReadRigError("scalar.yaml", "cam1: 5\n"),
              HasSubstr("scalar.yaml:1: cam1: expected a map with q_wxyz, C and scale"));
}

TEST_F(RigFilesTest, RigYamlStrictKeysAndDocuments) {
  EXPECT_THAT(ReadRigError("typo.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, 0]\n"
                           "  scale: 1\n  sclae: 2\n"),
              HasSubstr("typo.yaml:5: cam1.sclae: unknown key"));
  EXPECT_THAT(ReadRigError("segkey.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, 0]\n"
                           "  scale: 1\n  scales:\n  - {segment: 0, scale: 1, "
                           "x: 2}\n"),
              HasSubstr("segkey.yaml:6: cam1.scales[0].x: unknown key"));
  EXPECT_THAT(ReadRigError("dup.yaml",
                           "cam1:\n  q_wxyz: [1, 0, 0, 0]\n  C: [0, 0, 0]\n"
                           "  scale: 1\n  C: [1, 1, 1]\n"),
              HasSubstr("dup.yaml:5: C: duplicate key"));
  EXPECT_THAT(ReadRigError("dupslave.yaml",
                           "cam1: {q_wxyz: [1, 0, 0, 0], C: [0, 0, 0], scale: "
                           "1}\ncam1: {q_wxyz: [1, 0, 0, 0], C: [1, 0, 0], "
                           "scale: 1}\n"),
              HasSubstr("dupslave.yaml:2: cam1: duplicate key"));
  EXPECT_THAT(ReadRigError("docs.yaml",
                           "cam1: {q_wxyz: [1, 0, 0, 0], C: [0, 0, 0], scale: 1}\n"
                           "---\ncam2: {q_wxyz: [1, 0, 0, 0], C: [0, 0, 0], scale: "
                           "1}\n"),
              HasSubstr("docs.yaml:3: a second YAML document"));
}

// yaml-cpp 0.7's LoadAll makes an endless series of documents of these 3 bytes (found by the
// rig_yaml fuzz target as a hang); the reader parses at most two documents.
TEST_F(RigFilesTest, RigYamlMalformedInputIsAnErrorNotAHang) {
  EXPECT_THAT(ReadRigError("comma.yaml", ",\n["), HasSubstr("comma.yaml:"));
  EXPECT_THAT(ReadRigError("comma2.yaml", ",a: [b\n"), HasSubstr("comma2.yaml:"));
}

// Nested aliases ("billion laughs", found by the rig_yaml fuzz target): 9 levels of 10 aliases
// are 10^9 nodes in 0.5 kB. The duplicate-key check visited every one of them (the reader hung
// for hours); it now stops after 100000 nodes and says why.
TEST_F(RigFilesTest, RigYamlNestedAliasesAreRefusedNotExpanded) {
  std::string text = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int level = 1; level <= 8; ++level) {
    const std::string alias = "*a" + std::to_string(level - 1);
    text += "a" + std::to_string(level) + ": &a" + std::to_string(level) + " [";
    for (int k = 0; k < 10; ++k) text += (k ? ", " : "") + alias;
    text += "]\n";
  }
  EXPECT_THAT(ReadRigError("laughs.yaml", text),
              HasSubstr("laughs.yaml: more than 100000 YAML nodes with every alias expanded"));
}

TEST_F(RigFilesTest, ResultYamlRoundTripsThroughReadRigYaml) {
  const RigCalibration result = MakeResult();
  ASSERT_TRUE(WriteResultYaml(Path("result.yaml"), result).ok());
  const auto read = ReadRigYaml(Path("result.yaml"));
  ASSERT_TRUE(read.ok()) << read.error();
  ASSERT_EQ(read->size(), 3u);
  for (const SlaveCalibration& s : result.slaves) {
    ASSERT_EQ(read->count(s.name), 1u) << s.name;
    ExpectRigNear(read->at(s.name), s.estimate, 1e-15);
  }
}

TEST_F(RigFilesTest, ResultYamlHasStatusAndStatistics) {
  const std::string yaml = ResultToYaml(MakeResult());
  for (const char* expected :
       {"master: front",
        "pairs_selected: 321",
        "usable: true",
        "usable: false",
        "state: converged",
        "termination: solved",
        "termination: no_convergence",
        "termination: insufficient_motion",
        "need >= 2 motions with rotation >= 2 deg, got 0",
        "rot_deg: 0.02",
        "pos: [0.001, 0.002, 0.003]",
        "motions: {total: 300, used: 290, rejected: 10, small_rotation: 6, angle_mismatch: 3, "
        "residual_outlier: 1}",
        "glitches: {dropped: 1, position_jump: 0, rotation_jump: 1, angle_mismatch: 0, "
        "in_master: 0, in_slave: 1}",
        "models: {motion: general, scale: segments}",
        "{segment: 4, scale: 1.5, std: 0.03}",
        "unobservable: [[0, 1, 0]]",
        "unobservable: []",
        "unobservable_from_prior: false",
        "axis: .nan",
        "observability:",
        "tilt_snr: 0",
        "mean_axis: [0, 0, 0]",
        "planar: false"}) {
    EXPECT_THAT(yaml, HasSubstr(expected));
  }
  // One scale: no `scales` list for that slave (only `back` has one).
  EXPECT_EQ(yaml.find("scales:"), yaml.rfind("scales:"));
}

// --prior: nominal mountings from a rig YAML, or from a rig config's cameras[].nominal.
TEST_F(RigFilesTest, NominalMountingsFromRigYamlOrRigConfig) {
  const std::map<std::string, Similarity> rig = {
      {"left", MakeRig({0, 1, 0}, -90, {-0.9, 0.3, -1.5}, 1.0)}};
  ASSERT_TRUE(WriteRigYaml(Path("nominal.yaml"), rig).ok());
  const auto from_rig = ReadNominalMountings(Path("nominal.yaml"));
  ASSERT_TRUE(from_rig.ok()) << from_rig.error();
  ASSERT_EQ(from_rig->count("left"), 1u);
  ExpectRigNear(from_rig->at("left"), rig.at("left"), 1e-15);

  const std::string config = Write("rig.yaml",
                                   "rig: {name: car, master: front}\n"
                                   "cameras:\n"
                                   "  - name: front\n"
                                   "  - name: left\n"
                                   "    nominal: {q_wxyz: [0.7071068, 0, -0.7071068, 0], "
                                   "C: [-0.9, 0.3, -1.5]}\n"
                                   "  - name: rear\n");
  const auto from_config = ReadNominalMountings(config);
  ASSERT_TRUE(from_config.ok()) << from_config.error();
  ASSERT_EQ(from_config->size(), 1u);  // the cameras without a nominal are not listed
  EXPECT_EQ(from_config->at("left").C, Eigen::Vector3d(-0.9, 0.3, -1.5));

  const std::string none = Write("none.yaml",
                                 "rig: {name: car, master: front}\n"
                                 "cameras:\n  - name: front\n  - name: left\n");
  const auto empty = ReadNominalMountings(none);
  ASSERT_FALSE(empty.ok());
  EXPECT_THAT(empty.error(), HasSubstr("no camera has a `nominal` mounting"));
  const auto bad = ReadNominalMountings(Write("bad.yaml", "left: {q_wxyz: [1, 0, 0]}\n"));
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(bad.error(), HasSubstr("left.q_wxyz"));
}

CamchainOptions Cameras(std::vector<std::string> order) {
  CamchainOptions options;
  options.camera_order = std::move(order);
  return options;
}

// Independent check of T_cn_cnm1: it must take a point from camera n-1 to camera n, where
// p_master = R_n p_cam_n + C_n.
TEST_F(RigFilesTest, CamchainTransformsPointsBetweenNeighbours) {
  const RigCalibration result = MakeResult();
  ASSERT_TRUE(
      WriteCamchain(Path("camchain.yaml"), result, Cameras({"front", "back", "left"})).ok());
  const auto chain = ReadCamchain(Path("camchain.yaml"));
  ASSERT_TRUE(chain.ok()) << chain.error();
  ASSERT_EQ(chain->size(), 3u);
  EXPECT_EQ((*chain)[0].name, "front");
  EXPECT_EQ((*chain)[1].name, "back");
  EXPECT_EQ((*chain)[2].name, "left");
  EXPECT_EQ((*chain)[0].cn_from_cnm1, Eigen::Matrix4d::Identity());

  auto cam_from_master = [](const Similarity& s, const Eigen::Vector3d& p) -> Eigen::Vector3d {
    return s.q.toRotationMatrix().transpose() * (p - s.C);
  };
  const Similarity& back = result.slaves[1].estimate;
  const Similarity& left = result.slaves[0].estimate;
  for (const Eigen::Vector3d& p_master :
       {Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(-4, 0.5, 10), Eigen::Vector3d(0, 0, 0)}) {
    const Eigen::Vector3d p_back = cam_from_master(back, p_master);
    const Eigen::Vector3d p_left = cam_from_master(left, p_master);
    const Eigen::Vector4d in_back = (*chain)[1].cn_from_cnm1 * p_master.homogeneous();
    const Eigen::Vector4d in_left = (*chain)[2].cn_from_cnm1 * p_back.homogeneous();
    // 1e-12: a few double roundings of numbers of order 10.
    EXPECT_LT((in_back.head<3>() - p_back).norm(), 1e-12);
    EXPECT_LT((in_left.head<3>() - p_left).norm(), 1e-12);
  }
}

TEST_F(RigFilesTest, CamchainDefaultOrderSkipsUnusableSlaves) {
  ASSERT_TRUE(WriteCamchain(Path("c.yaml"), MakeResult()).ok());
  const auto chain = ReadCamchain(Path("c.yaml"));
  ASSERT_TRUE(chain.ok()) << chain.error();
  ASSERT_EQ(chain->size(), 3u);
  EXPECT_EQ((*chain)[1].name, "left");
  EXPECT_EQ((*chain)[2].name, "back");
  std::ifstream in(Path("c.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_THAT(text.str(), HasSubstr("# Kalibr camchain written by rigcal"));
  // Neither intrinsics nor a unit known: extrinsics only, in master units, and said so.
  EXPECT_THAT(text.str(), HasSubstr("No intrinsics in the rig config for front, left, back"));
  EXPECT_THAT(text.str(), HasSubstr("rigcal_translation_unit: master_odometry_unit"));
  EXPECT_THAT(text.str(), ::testing::Not(HasSubstr("camera_model")));
  EXPECT_THAT(text.str(), ::testing::Not(HasSubstr("still")));
}

// With the intrinsics of the rig config and a known unit: complete Kalibr entries, translations
// in metres.
TEST_F(RigFilesTest, CamchainInMetresWithIntrinsics) {
  const RigCalibration result = MakeResult();
  CamchainOptions options;
  options.metres_per_unit = 2.0;
  options.unit_source = "test unit";
  camera::CameraSpec spec;
  spec.width = 640;
  spec.height = 480;
  spec.intrinsics = {500, 501, 320, 240};
  spec.distortion = {0.1, -0.01, 0.001, 0.002};
  options.intrinsics["front"] = spec;
  options.intrinsics["left"] = spec;
  const auto written = WriteCamchain(Path("m.yaml"), result, options);
  ASSERT_TRUE(written.ok()) << written.error();
  EXPECT_TRUE(written->metric);
  EXPECT_EQ(written->no_intrinsics, std::vector<std::string>({"back"}));
  const auto chain = ReadCamchain(Path("m.yaml"));
  ASSERT_TRUE(chain.ok()) << chain.error();
  // cam1 = left: T_cn_cnm1 = left_from_front, its translation -R^T C in metres.
  const Similarity& left = result.slaves[0].estimate;
  const Eigen::Vector3d t = -(left.q.toRotationMatrix().transpose() * left.C) * 2.0;
  EXPECT_LT(((*chain)[1].cn_from_cnm1.topRightCorner<3, 1>() - t).norm(), 1e-12);
  std::ifstream in(Path("m.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_THAT(text.str(), HasSubstr("rigcal_translation_unit: m\n"));
  EXPECT_THAT(text.str(), HasSubstr("camera_model: pinhole"));
  EXPECT_THAT(text.str(), HasSubstr("distortion_model: radtan"));
  EXPECT_THAT(text.str(), HasSubstr("resolution: [640, 480]"));
  EXPECT_THAT(text.str(), HasSubstr("No intrinsics in the rig config for back"));
}

TEST_F(RigFilesTest, CamchainOrderErrors) {
  const RigCalibration result = MakeResult();
  EXPECT_THAT(WriteCamchain(Path("c.yaml"), result, Cameras({"left", "front"})).error(),
              HasSubstr("the first camera must be the master 'front'"));
  EXPECT_THAT(WriteCamchain(Path("c.yaml"), result, Cameras({"front", "right"})).error(),
              HasSubstr("unknown camera 'right'"));
  EXPECT_THAT(WriteCamchain(Path("c.yaml"), result, Cameras({"front", "still"})).error(),
              HasSubstr("camera 'still' has no usable estimate (insufficient_motion)"));
  EXPECT_FALSE(fs::exists(Path("c.yaml")));
}

TEST_F(RigFilesTest, CamchainReaderErrors) {
  auto error = [&](const std::string& name, const std::string& text) {
    const auto chain = ReadCamchain(Write(name, text));
    EXPECT_FALSE(chain.ok()) << name;
    return chain.ok() ? std::string() : chain.error();
  };
  EXPECT_THAT(error("a.yaml", "cam0: {}\ncam1:\n  rigcal_name: x\n"),
              HasSubstr("a.yaml:3: cam1.T_cn_cnm1: missing"));
  EXPECT_THAT(error("b.yaml", "cam0: {}\ncam1:\n  T_cn_cnm1:\n  - [1, 0, 0, 0]\n"),
              HasSubstr("b.yaml:4: cam1.T_cn_cnm1: expected 4 rows"));
  EXPECT_THAT(error("c.yaml",
                    "cam0: {}\ncam1:\n  T_cn_cnm1:\n  - [1, 0, 0, 0]\n"
                    "  - [0, 1, 0, 0]\n  - [0, 0, 1]\n  - [0, 0, 0, 1]\n"),
              HasSubstr("c.yaml:6: cam1.T_cn_cnm1[2]: expected 4 numbers, got 3"));
  EXPECT_THAT(error("d.yaml",
                    "cam0: {}\ncam1:\n  T_cn_cnm1:\n  - [2, 0, 0, 0]\n"
                    "  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n  - [0, 0, 0, 1]\n"),
              HasSubstr("d.yaml:4: cam1.T_cn_cnm1: rotation block is not a rotation matrix"));
  EXPECT_THAT(error("e.yaml", "cam1: {}\n"), HasSubstr("e.yaml:1: expected a map with cam0"));
}

// --- WriteFileAtomically -------------------------------------------------------------------

TEST_F(RigFilesTest, AtomicWriteReplacesAndLeavesNoTemporaryFile) {
  const std::string path = Path("out.txt");
  ASSERT_TRUE(WriteFileAtomically(path, "first\n").ok());
  ASSERT_TRUE(WriteFileAtomically(path, "second\n").ok());
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), "second\n");
  EXPECT_EQ(Listing(), std::vector<std::string>({"out.txt"}));
  EXPECT_EQ(fs::status(path).permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                fs::perms::others_read);
}

TEST_F(RigFilesTest, AtomicWriteErrorNamesPathAndErrno) {
  const std::string path = Path("no_such_dir/out.txt");
  const std::string error = WriteFileAtomically(path, "x").message();
  EXPECT_THAT(error, HasSubstr(path));
  EXPECT_THAT(error, HasSubstr("No such file or directory"));
  // A directory is refused before anything is written (output_file_fault_test: the others).
  fs::create_directory(Path("a_dir"));
  const std::string over_dir = WriteFileAtomically(Path("a_dir"), "x").message();
  EXPECT_THAT(over_dir, HasSubstr(Path("a_dir")));
  EXPECT_THAT(over_dir, HasSubstr("it is a directory, not a regular file"));
  EXPECT_EQ(Listing(), std::vector<std::string>({"a_dir"}));
}

}  // namespace
}  // namespace rigcal::io
