// Trajectory files: format detection, exact stamps, every rejected input, and matching.
#include "rigcal/io/trajectory_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rigcal/calib/logging.h"

namespace rigcal::tools {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class TrajectoryIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::path(::testing::TempDir()) / "trajectory_io_XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::string Write(const std::string& name, const std::string& contents) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << contents;
    return path;
  }

  // Reads a file expected to be rejected and returns the error message.
  std::string ErrorOf(const std::string& name, const std::string& contents,
                      const TrajectoryReadOptions& options = {}) {
    const auto result = ReadTrajectory(Write(name, contents), options);
    EXPECT_FALSE(result.ok()) << name << " was accepted";
    return result.ok() ? "" : result.error();
  }

  fs::path dir_;
};

TimedTrajectory MakeTrajectory(const std::string& name, const std::vector<int64_t>& stamps) {
  TimedTrajectory t;
  t.name = name;
  t.t_ns = stamps;
  for (size_t k = 0; k < stamps.size(); ++k) {
    Pose p;
    p.q = Eigen::Quaterniond(
        Eigen::AngleAxisd(0.01 * static_cast<double>(k), Eigen::Vector3d(1, 2, 3).normalized()));
    p.C = Eigen::Vector3d(0.1 * static_cast<double>(k), -0.2, 0.3);
    t.poses.push_back(p);
    t.segment.push_back(static_cast<int>(k / 4));
  }
  return t;
}

TEST(ParseSecondsToNsTest, ExactDecimalConversion) {
  EXPECT_EQ(ParseSecondsToNs("1305031102.175304"), 1305031102175304000LL);
  // 1403715524.907143168 is not representable as a double; the string path keeps every digit.
  EXPECT_EQ(ParseSecondsToNs("1403715524.907143168"), 1403715524907143168LL);
  EXPECT_EQ(ParseSecondsToNs("0"), 0);
  EXPECT_EQ(ParseSecondsToNs("-0.5"), -500000000LL);
  EXPECT_EQ(ParseSecondsToNs("+2"), 2000000000LL);
  EXPECT_EQ(ParseSecondsToNs(".25"), 250000000LL);
  EXPECT_EQ(ParseSecondsToNs("7."), 7000000000LL);
  EXPECT_EQ(ParseSecondsToNs("1.037359e-01"), 103735900LL);
  EXPECT_EQ(ParseSecondsToNs("1.5E3"), 1500000000000LL);
  EXPECT_EQ(ParseSecondsToNs("0.000000001"), 1);
  EXPECT_EQ(ParseSecondsToNs("1.00000000000000000000"), 1000000000LL);
  // Below the nanosecond: round half away from zero.
  EXPECT_EQ(ParseSecondsToNs("1.0000000005"), 1000000001LL);
  EXPECT_EQ(ParseSecondsToNs("1.0000000004999"), 1000000000LL);
  EXPECT_EQ(ParseSecondsToNs("-1.0000000005"), -1000000001LL);
  EXPECT_EQ(ParseSecondsToNs("4e-10"), 0);
  EXPECT_EQ(ParseSecondsToNs("9223372036.854775807"), INT64_MAX);
}

TEST(ParseSecondsToNsTest, RejectsNonNumbersAndOverflow) {
  for (const char* bad : {"", "-", ".", "abc", "1.2.3", "1e", "1e+", "12s", "nan", "inf", "0x10",
                          "1 2", "9223372036.854775808", "1e30", "99999999999999999999"}) {
    EXPECT_FALSE(ParseSecondsToNs(bad).has_value()) << "'" << bad << "'";
  }
}

// The exact text of FormatNsAsSeconds is tested in tests/calib/time_format_test.cc.
TEST(FormatNsAsSecondsTest, RoundTrips) {
  for (const int64_t t : std::vector<int64_t>{INT64_MIN + 1, -1234567890123LL, 42, INT64_MAX}) {
    EXPECT_EQ(ParseSecondsToNs(FormatNsAsSeconds(t)), t);
  }
}

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
  const std::string contents = "0 0 0 0 0 0 0 1.0005\n";
  EXPECT_FALSE(ReadTrajectory(Write("q.txt", contents)).ok());
  TrajectoryReadOptions loose;
  loose.max_quaternion_norm_error = 1e-3;
  EXPECT_TRUE(ReadTrajectory(Write("q.txt", contents), loose).ok());
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
  // Just beyond the 1e-6 tolerance.
  EXPECT_THAT(ErrorOf("q2.txt", "0 0 0 0 0 0 0 1.0000011\n"), HasSubstr("q2.txt:1:"));
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

// Real EuRoC ground truth prints quaternions whose norms are off by up to 1.5e-4: rejected at
// the default tolerance (naming the line), read with a loose one.
TEST(TrajectoryIoDataTest, EurocGroundTruth) {
  const fs::path path = fs::path(RIGCAL_SHARED_DATA_DIR) / "trajectories" / "V102_groundtruth.csv";
  if (!fs::exists(path)) GTEST_SKIP() << path << " not present";
  const auto strict = ReadTrajectory(path.string());
  ASSERT_FALSE(strict.ok());
  EXPECT_THAT(strict.error(), ::testing::MatchesRegex(".*V102_groundtruth.csv:[0-9]+: .*norm.*"));
  TrajectoryReadOptions loose;
  loose.max_quaternion_norm_error = 1e-3;
  const auto t = ReadTrajectory(path.string(), loose);
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(t->size(), 16702u);
  EXPECT_EQ(t->t_ns.front(), 1403715524907143168LL);
}

// --- KITTI odometry poses ----------------------------------------------------------------

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
  if (!fs::exists(dir / "KITTI_00_gt.txt")) GTEST_SKIP() << dir << " has no KITTI_00_gt.txt";
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

// --- Matching ---------------------------------------------------------------------------

std::vector<int64_t> Stamps(int64_t start, int64_t step, int count) {
  std::vector<int64_t> t;
  for (int k = 0; k < count; ++k) t.push_back(start + step * k);
  return t;
}

TEST(MatchTrajectoriesTest, SameStampsMatchEverything) {
  const auto master = MakeTrajectory("m", Stamps(0, 50'000'000, 10));
  const auto slave = MakeTrajectory("s", Stamps(0, 50'000'000, 10));
  const auto rec = MatchTrajectories(master, {slave}, 5'000'000);
  ASSERT_TRUE(rec.ok()) << rec.error();
  EXPECT_TRUE(rec->Check().ok()) << rec->Check().message();
  EXPECT_EQ(rec->t_ns, master.t_ns);
  EXPECT_EQ(rec->master.name, "m");
  ASSERT_EQ(rec->slaves.size(), 1u);
  EXPECT_EQ(rec->slaves[0].name, "s");
  EXPECT_EQ(rec->slaves[0].segment, slave.segment);
}

TEST(MatchTrajectoriesTest, OffsetWithinToleranceAndKeepsOnlyStampsInAllSlaves) {
  const auto master = MakeTrajectory("m", Stamps(0, 50'000'000, 10));
  const auto early = MakeTrajectory("early", Stamps(-3'000'000, 50'000'000, 10));
  auto gappy = MakeTrajectory("gappy", Stamps(1'000'000, 50'000'000, 10));
  // Remove master stamp 4's partner from the second slave.
  gappy.t_ns.erase(gappy.t_ns.begin() + 4);
  gappy.poses.erase(gappy.poses.begin() + 4);
  gappy.segment.erase(gappy.segment.begin() + 4);
  const auto rec = MatchTrajectories(master, {early, gappy}, 5'000'000);
  ASSERT_TRUE(rec.ok()) << rec.error();
  ASSERT_EQ(rec->size(), 9u);
  EXPECT_EQ(rec->t_ns[4], master.t_ns[5]);
  // Poses travel with their stamps (after the erase, gappy's index 4 is stamped 251 ms).
  EXPECT_EQ(rec->slaves[1].poses[4].C, gappy.poses[4].C);
  EXPECT_EQ(rec->slaves[0].poses[4].C, early.poses[5].C);
  EXPECT_EQ(rec->master.poses[4].C, master.poses[5].C);
}

TEST(MatchTrajectoriesTest, OffsetBeyondToleranceMatchesNothing) {
  const auto master = MakeTrajectory("m", Stamps(0, 50'000'000, 10));
  const auto late = MakeTrajectory("late", Stamps(7'000'000, 50'000'000, 10));
  const auto rec = MatchTrajectories(master, {late}, 5'000'000);
  ASSERT_FALSE(rec.ok());
  EXPECT_THAT(rec.error(), HasSubstr("late matched 0 of 10"));
}

TEST(MatchTrajectoriesTest, FastMasterUsesEverySlavePoseOnce) {
  // Master at 200 Hz, slave at 20 Hz: within 5 ms up to two master stamps are near one slave
  // stamp; only the mutually nearest pair is kept.
  const auto master = MakeTrajectory("m", Stamps(0, 5'000'000, 200));
  const auto slave = MakeTrajectory("s", Stamps(2'000'000, 50'000'000, 20));
  const auto rec = MatchTrajectories(master, {slave}, 5'000'000);
  ASSERT_TRUE(rec.ok()) << rec.error();
  ASSERT_EQ(rec->size(), 20u);
  for (size_t k = 0; k < rec->size(); ++k) {
    EXPECT_EQ(rec->t_ns[k], static_cast<int64_t>(k) * 50'000'000) << k;
    EXPECT_EQ(rec->slaves[0].poses[k].C, slave.poses[k].C) << k;
  }
}

TEST(MatchTrajectoriesTest, SlowMasterTakesNearestSlavePose) {
  const auto master = MakeTrajectory("m", Stamps(0, 50'000'000, 20));
  const auto slave = MakeTrajectory("s", Stamps(-1'000'000, 5'000'000, 200));
  const auto rec = MatchTrajectories(master, {slave}, 5'000'000);
  ASSERT_TRUE(rec.ok()) << rec.error();
  ASSERT_EQ(rec->size(), 20u);
  // Around master stamp k, slave index 10 k is 1 ms early and 10 k + 1 is 4 ms late.
  for (size_t k = 0; k < rec->size(); ++k) {
    EXPECT_EQ(rec->slaves[0].poses[k].C, slave.poses[10 * k].C) << k;
  }
}

TEST(MatchTrajectoriesTest, NoOverlapNamesRanges) {
  const auto master = MakeTrajectory("master_cam", Stamps(0, 1'000'000'000, 10));
  const auto slave = MakeTrajectory("cam1", Stamps(100'000'000'000, 1'000'000'000, 10));
  const auto rec = MatchTrajectories(master, {slave}, 5'000'000);
  ASSERT_FALSE(rec.ok());
  EXPECT_THAT(rec.error(), HasSubstr("no overlapping time range: master master_cam 0.000..9.000 s, "
                                     "cam1 100.000..109.000 s"));
}

TEST(MatchTrajectoriesTest, FewerThanTwoMatchesNamesTheSlave) {
  const auto master = MakeTrajectory("m", Stamps(0, 50'000'000, 10));
  const auto good = MakeTrajectory("good", Stamps(0, 50'000'000, 10));
  const auto one = MakeTrajectory("one", {450'000'000, 460'000'000});
  const auto rec = MatchTrajectories(master, {good, one}, 5'000'000);
  ASSERT_FALSE(rec.ok());
  EXPECT_THAT(rec.error(), HasSubstr("only 1 master stamps"));
  EXPECT_THAT(rec.error(), HasSubstr("good matched 10 of 10"));
  EXPECT_THAT(rec.error(), HasSubstr("one matched 1 of 10"));
}

TEST(MatchTrajectoriesTest, DuplicateNamesAreRejected) {
  const auto master = MakeTrajectory("cam", Stamps(0, 50'000'000, 10));
  const auto slave = MakeTrajectory("cam", Stamps(0, 50'000'000, 10));
  const auto rec = MatchTrajectories(master, {slave}, 5'000'000);
  ASSERT_FALSE(rec.ok());
  EXPECT_THAT(rec.error(), HasSubstr("two cameras are named 'cam'"));
}

}  // namespace
}  // namespace rigcal::tools
