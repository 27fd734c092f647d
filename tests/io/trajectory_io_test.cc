// SPDX-License-Identifier: Apache-2.0
// Trajectory files in TUM, EuRoC CSV and native format: format detection, reading and writing
// (exact stamps, round trips), and every rejected input.
#include "rigcal/io/trajectory_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/trajectory_fixtures.h"
#include "rigcal/base/logging.h"
#include "support/skip.h"

namespace rigcal::io::trajectory_test {
namespace {

TEST_F(TrajectoryIoTest, ReadsTum) {
  TrajectoryFormat format = TrajectoryFormat::kNative;
  const auto t = ReadTrajectory(Write("front.txt",
                                      "# timestamp tx ty tz qx qy qz qw\n"
                                      "\n"
                                      "1305031102.175304 1.5 -2 3e-1 0 0 0 1\n"
                                      "  1305031102.2 1 2 3 0.5 0.5 0.5 0.5  \r\n"),
                                {}, &format);
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(format, TrajectoryFormat::kTum);
  EXPECT_EQ(t->name, "front");
  ASSERT_EQ(t->size(), 2u);
  EXPECT_EQ(t->t_ns[0], 1305031102175304000LL);
  EXPECT_EQ(t->t_ns[1], 1305031102200000000LL);
  EXPECT_EQ(t->poses[0].C, Eigen::Vector3d(1.5, -2, 0.3));
  EXPECT_EQ(t->poses[1].q.coeffs(), Eigen::Vector4d(0.5, 0.5, 0.5, 0.5));  // x y z w
  EXPECT_EQ(t->segment, std::vector<int>({0, 0}));
}

TEST_F(TrajectoryIoTest, TumQuaternionOrderIsXyzw) {
  // 90 degrees about z: qz = qw = sqrt(1/2); TUM lists qx qy qz qw.
  const double h = std::sqrt(0.5);
  std::ostringstream s;
  s.precision(17);
  s << "0 0 0 0 0 0 0 1\n1 0 0 0 0 0 " << h << " " << h << "\n";
  const auto t = ReadTrajectory(Write("z90.txt", s.str()));
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_TRUE((t->poses[1].R() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY()));
}

TEST_F(TrajectoryIoTest, ReadsTumSegmentColumn) {
  const auto t = ReadTrajectory(Write("seg.txt",
                                      "0.0 0 0 0 0 0 0 1 0\n"
                                      "0.1 0 0 0 0 0 0 1 0\n"
                                      "0.2 0 0 0 0 0 0 1 3\n"));
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(t->segment, std::vector<int>({0, 0, 3}));
}

TEST_F(TrajectoryIoTest, ReadsEurocCsvAndIgnoresExtraColumns) {
  TrajectoryFormat format = TrajectoryFormat::kTum;
  const auto t = ReadTrajectory(
      Write("state_groundtruth_estimate0.csv",
            "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], "
            "q_RS_y [], q_RS_z [], v_x\n"
            "1403715524907143168,0.5,1.9,0.9,1,0,0,0,-0.002\n"
            "1403715524912143104, 0.6, 2.0, 1.0, 0, 1, 0, 0, 0.1\n"),
      {}, &format);
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(format, TrajectoryFormat::kEurocCsv);
  EXPECT_EQ(t->name, "state_groundtruth_estimate0");
  ASSERT_EQ(t->size(), 2u);
  EXPECT_EQ(t->t_ns[0], 1403715524907143168LL);
  EXPECT_EQ(t->t_ns[1], 1403715524912143104LL);
  EXPECT_EQ(t->poses[1].C, Eigen::Vector3d(0.6, 2.0, 1.0));
  EXPECT_EQ(t->poses[1].q.w(), 0.0);
  EXPECT_EQ(t->poses[1].q.x(), 1.0);  // q_w first in EuRoC
}

TEST_F(TrajectoryIoTest, ReadsNativeWithHeader) {
  TrajectoryFormat format = TrajectoryFormat::kTum;
  const auto t = ReadTrajectory(Write("cam2.poses",
                                      "# rigcal poses\n"
                                      "0 1 0 0 0 1 2 3 0\n"
                                      "50000000 0 0 1 0 4 5 6 1\n"),
                                {}, &format);
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(format, TrajectoryFormat::kNative);
  EXPECT_EQ(t->t_ns, std::vector<int64_t>({0, 50000000}));
  EXPECT_EQ(t->poses[1].C, Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(t->poses[1].q.y(), 1.0);  // qw qx qy qz order
  EXPECT_EQ(t->segment, std::vector<int>({0, 1}));
}

TEST_F(TrajectoryIoTest, DetectsNativeByLargeIntegerStampAndTumOtherwise) {
  TrajectoryFormat format = TrajectoryFormat::kTum;
  auto t = ReadTrajectory(Write("a.txt", "1700000000000000000 1 0 0 0 1 2 3\n"), {}, &format);
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(format, TrajectoryFormat::kNative);
  EXPECT_EQ(t->poses[0].C, Eigen::Vector3d(1, 2, 3));
  // Small integer stamps without the header are TUM seconds.
  t = ReadTrajectory(Write("b.txt", "17 1 2 3 0 0 0 1\n"), {}, &format);
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(format, TrajectoryFormat::kTum);
  EXPECT_EQ(t->t_ns[0], 17000000000LL);
}

TEST_F(TrajectoryIoTest, TumAndNativeWritersRoundTripExactly) {
  const TimedTrajectory original =
      MakeTrajectory("cam7", {-5, 0, 1403715524907143168LL, 1403715524907143169LL,
                              1403715525000000000LL, 1403715526000000001LL});
  for (const bool native : {false, true}) {
    const std::string path = (dir_ / (native ? "cam7.poses" : "cam7.txt")).string();
    const std::string error =
        (native ? WriteTrajectoryNative(path, original) : WriteTrajectoryTum(path, original))
            .message();
    ASSERT_EQ(error, "");
    TrajectoryFormat format = TrajectoryFormat::kEurocCsv;
    const auto read = ReadTrajectory(path, {}, &format);
    ASSERT_TRUE(read.ok()) << read.error();
    EXPECT_EQ(format, native ? TrajectoryFormat::kNative : TrajectoryFormat::kTum);
    EXPECT_EQ(read->name, "cam7");
    EXPECT_EQ(read->t_ns, original.t_ns);
    EXPECT_EQ(read->segment, original.segment);
    for (size_t k = 0; k < original.size(); ++k) {
      // Shortest round-trip digits: positions are exact, quaternions differ only by the
      // re-normalisation on reading (a few ulp).
      EXPECT_EQ(read->poses[k].C, original.poses[k].C) << k;
      EXPECT_LT((read->poses[k].q.coeffs() - original.poses[k].q.coeffs()).norm(), 1e-15) << k;
    }
  }
}

TEST_F(TrajectoryIoTest, TumWriterOmitsSegmentColumnWhenAllZero) {
  TimedTrajectory t = MakeTrajectory("x", {0, 1, 2});
  t.segment.assign(3, 0);
  const std::string path = (dir_ / "x.txt").string();
  const Status written = WriteTrajectoryTum(path, t);
  ASSERT_TRUE(written.ok()) << written.message();
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header comment
  std::getline(in, line);
  std::istringstream fields(line);
  int count = 0;
  for (std::string f; fields >> f;) ++count;
  EXPECT_EQ(count, 8) << line;
}

TEST_F(TrajectoryIoTest, NormalisesNearUnitQuaternionsWithOneWarning) {
  std::ostringstream log;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
  ASSERT_TRUE(SetLogLevel("info"));
  auto logger = ModuleLogger("tools");
  logger->sinks().push_back(sink);
  const auto t = ReadTrajectory(Write("near.txt",
                                      "0 0 0 0 0 0 0 1.0000005\n"
                                      "1 0 0 0 0 0 0 0.9999996\n"
                                      "2 0 0 0 0 0 0 1\n"));
  logger->sinks().pop_back();
  ASSERT_TRUE(t.ok()) << t.error();
  for (const Pose& p : t->poses) EXPECT_NEAR(p.q.norm(), 1.0, 1e-15);
  const std::string text = log.str();
  EXPECT_THAT(text, HasSubstr("near.txt"));
  EXPECT_THAT(text, HasSubstr("normalised 2 of 3"));
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
}

TEST_F(TrajectoryIoTest, QuaternionToleranceIsAnOption) {
  const std::string contents = "0 0 0 0 0 0 0 1.005\n";
  EXPECT_FALSE(ReadTrajectory(Write("q.txt", contents)).ok());
  TrajectoryReadOptions loose;
  loose.max_quaternion_norm_error = 1e-2;
  EXPECT_TRUE(ReadTrajectory(Write("q.txt", contents), loose).ok());
}

// Beyond the tolerance but within what the printed digits explain: 2 decimals round each
// component by up to 0.005 (0.0071 for two), so |q| of "0.71 0 0 0.71" (1.0041) is a unit
// quaternion printed; "0 0 0 1.01" is not (one rounded component, 0.005).
TEST_F(TrajectoryIoTest, PrintedDigitsBoundTheNormError) {
  TrajectoryReadOptions strict;
  strict.max_quaternion_norm_error = 1e-6;
  EXPECT_TRUE(ReadTrajectory(Write("two.txt", "0 0 0 0 0.71 0 0 0.71\n"), strict).ok());
  EXPECT_FALSE(ReadTrajectory(Write("one.txt", "0 0 0 0 0 0 0 1.01\n"), strict).ok());
  // The same norm error with 9 printed decimals is not rounding.
  const auto nine =
      ReadTrajectory(Write("nine.txt", "0 0 0 0 0.710000000 0 0 0.710000000\n"), strict);
  ASSERT_FALSE(nine.ok());
  EXPECT_THAT(nine.error(), HasSubstr("the rounding of its printed digits"));
}

// Every rejected input: the message names the file, the line and what is wrong.
TEST_F(TrajectoryIoTest, MissingFile) {
  const std::string path = (dir_ / "nope.txt").string();
  const auto t = ReadTrajectory(path);
  ASSERT_FALSE(t.ok());
  EXPECT_THAT(t.error(), HasSubstr(path));
  EXPECT_THAT(t.error(), HasSubstr("No such file"));
}

TEST_F(TrajectoryIoTest, Directory) {
  const auto t = ReadTrajectory(dir_.string());
  ASSERT_FALSE(t.ok());
  EXPECT_THAT(t.error(), HasSubstr("is a directory"));
}

TEST_F(TrajectoryIoTest, EmptyFileAndOnlyComments) {
  EXPECT_THAT(ErrorOf("empty.txt", ""), HasSubstr("empty.txt: no poses"));
  EXPECT_THAT(ErrorOf("comments.txt", "# a\n\n# b\n"), HasSubstr("comments.txt: no poses"));
}

TEST_F(TrajectoryIoTest, UnparsableColumn) {
  const std::string e = ErrorOf("bad.txt", "# h\n0 0 0 0 0 0 0 1\n0.1 0 0 zero 0 0 0 1\n");
  EXPECT_THAT(e, HasSubstr("bad.txt:3:"));
  EXPECT_THAT(e, HasSubstr("column 4 (tz)"));
  EXPECT_THAT(e, HasSubstr("'zero' is not a number"));
}

TEST_F(TrajectoryIoTest, UnparsableStamps) {
  EXPECT_THAT(ErrorOf("t.txt", "12s 0 0 0 0 0 0 1\n"),
              HasSubstr("t.txt:1: column 1 (t [s]): '12s' is not a time in seconds"));
  EXPECT_THAT(ErrorOf("t.csv", "#h\n1403715524.9,0,0,0,1,0,0,0\n"),
              HasSubstr("t.csv:2: column 1 (timestamp [ns]): '1403715524.9' is not an integer"));
}

TEST_F(TrajectoryIoTest, NanAndInf) {
  EXPECT_THAT(ErrorOf("nan.txt", "0 0 0 0 0 0 0 1\n1 nan 0 0 0 0 0 1\n"),
              HasSubstr("nan.txt:2: column 2 (tx) is not finite"));
  EXPECT_THAT(ErrorOf("inf.csv", "#h\n1,0,0,0,1,0,0,-inf\n"),
              HasSubstr("inf.csv:2: column 8 (q_z) is not finite"));
}

TEST_F(TrajectoryIoTest, NonUnitQuaternion) {
  const std::string e = ErrorOf("q.txt", "0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1.01\n");
  EXPECT_THAT(e, HasSubstr("q.txt:2:"));
  EXPECT_THAT(e, HasSubstr("has norm 1.01"));
  // Just beyond the 1e-3 tolerance (and the 2e-7 rounding of 7 decimals).
  EXPECT_THAT(ErrorOf("q2.txt", "0 0 0 0 0 0 0 1.0010011\n"), HasSubstr("q2.txt:1:"));
  EXPECT_THAT(ErrorOf("zero.txt", "0 0 0 0 0 0 0 0\n"), HasSubstr("zero.txt:1:"));
}

TEST_F(TrajectoryIoTest, TimeGoingBackwards) {
  const std::string e =
      ErrorOf("back.txt", "0 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n# c\n1.5 0 0 0 0 0 0 1\n");
  EXPECT_THAT(e, HasSubstr("back.txt:4: time goes backwards"));
  EXPECT_THAT(e, HasSubstr("on line 2"));
}

TEST_F(TrajectoryIoTest, DuplicateStamp) {
  const std::string e = ErrorOf("dup.csv", "#h\n5,0,0,0,1,0,0,0\n5,1,0,0,1,0,0,0\n");
  EXPECT_THAT(e, HasSubstr("dup.csv:3: duplicate time stamp"));
  EXPECT_THAT(e, HasSubstr("line 2"));
}

TEST_F(TrajectoryIoTest, WrongColumnCounts) {
  EXPECT_THAT(ErrorOf("seven.txt", "0 0 0 0 0 0 1\n"),
              HasSubstr("seven.txt:1: expected 8 or 9 columns"));
  EXPECT_THAT(ErrorOf("ten.txt", "0 0 0 0 0 0 0 1 0 0\n"), HasSubstr("ten.txt:1:"));
  EXPECT_THAT(ErrorOf("mixed.txt", "0 0 0 0 0 0 0 1 0\n1 0 0 0 0 0 0 1\n"),
              HasSubstr("mixed.txt:2: expected 9 columns like line 1, got 8"));
  EXPECT_THAT(ErrorOf("short.csv", "#h\n1,0,0,0,1,0,0\n"),
              HasSubstr("short.csv:2: expected at least 8 comma-separated columns"));
}

TEST_F(TrajectoryIoTest, BadSegment) {
  EXPECT_THAT(ErrorOf("seg.txt", "0 0 0 0 0 0 0 1 1.5\n"),
              HasSubstr("seg.txt:1: column 9 (segment): '1.5' is not an integer segment id"));
}

TEST_F(TrajectoryIoTest, WriterReportsUnwritablePath) {
  const std::string path = (dir_ / "missing_dir" / "x.txt").string();
  const std::string error = WriteTrajectoryTum(path, MakeTrajectory("x", {0, 1})).message();
  EXPECT_THAT(error, HasSubstr(path));
  EXPECT_THAT(error, HasSubstr("No such file or directory"));
}

// Real EuRoC ground truth prints quaternions whose norms are off by up to 1.5e-4 (more than
// the rounding of its 6 decimals): read at the default tolerance (1e-3), rejected at a strict
// one naming the line.
TEST(TrajectoryIoDataTest, EurocGroundTruth) {
  const fs::path path = fs::path(RIGCAL_SHARED_DATA_DIR) / "trajectories" / "V102_groundtruth.csv";
  if (!fs::exists(path)) RIGCAL_SKIP_MISSING() << path << " not present";
  TrajectoryReadOptions strict;
  strict.max_quaternion_norm_error = 1e-6;
  const auto rejected = ReadTrajectory(path.string(), strict);
  ASSERT_FALSE(rejected.ok());
  EXPECT_THAT(rejected.error(), ::testing::MatchesRegex(".*V102_groundtruth.csv:[0-9]+: .*norm.*"));
  const auto t = ReadTrajectory(path.string());
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(t->size(), 16702u);
  EXPECT_EQ(t->t_ns.front(), 1403715524907143168LL);
}
}  // namespace
}  // namespace rigcal::io::trajectory_test
