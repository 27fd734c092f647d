// SPDX-License-Identifier: Apache-2.0
// `rigcal record` through the built binary on small simulated rigs: every frame in the log as
// image_t (raw, PNG, JPEG), the progress line, splitting by size, no silent overwrite, VO poses and
// extrinsics when VO runs, and a recording cut inside an event (power loss) that still replays up
// to its last complete event.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "cli/command_test.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/lcm/log_writer.h"
#include "rigcal/pipeline/image_codec.h"
#include "support/command_runner.h"
#include "support/lcm_log_events.h"
#include "support/simulated_rig_config.h"

namespace rigcal {
namespace {

namespace fs = std::filesystem;
using cli_test::Quote;

struct LogSummary {
  std::map<std::string, int> events;  // per channel
  std::vector<image_t> images;
  int bad_images = 0;
};

LogSummary ReadLog(const std::string& path) {
  LogSummary summary;
  lcm::MessageValidator validator;
  for (const support::LoggedEvent& e : support::ReadLcmLog(path)) {
    ++summary.events[e.channel];
    if (e.channel.rfind("RIGCAL_IMAGE_", 0) != 0) continue;
    auto image = validator.Decode<image_t>(e.channel, e.data.data(), e.data.size());
    if (image) {
      summary.images.push_back(*image);
    } else {
      ++summary.bad_images;
    }
  }
  return summary;
}

class RecordCommandTest : public cli_test::CommandTest {
 protected:
  std::string WriteConfig(int width, int height, int frames) {
    const std::string path = (dir_ / "rig.yaml").string();
    std::ofstream(path) << support::SimulatedRigConfig(width, height, frames);
    return path;
  }
};

TEST_F(RecordCommandTest, RecordsEveryFrameWithProgress) {
  const std::string config = WriteConfig(160, 120, 30);
  const std::string log = (dir_ / "drive.lcmlog").string();
  const auto r = Run("record --config " + Quote(config) + " -o " + Quote(log) +
                     " --no-vo --fast --image-encoding png");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const LogSummary summary = ReadLog(log);
  EXPECT_EQ(summary.events.at("RIGCAL_IMAGE_cam0"), 30);
  EXPECT_EQ(summary.events.at("RIGCAL_IMAGE_cam1"), 30);
  EXPECT_EQ(summary.events.size(), 2u);  // no VO: images only
  EXPECT_EQ(summary.bad_images, 0);
  for (const image_t& msg : summary.images) {
    EXPECT_EQ(msg.encoding, image_t::ENCODING_PNG);
    auto image = pipeline::FrameFromImage(msg, 0);
    ASSERT_TRUE(image.ok()) << image.error();
    EXPECT_EQ(image->image.cols, 160);
    EXPECT_GT(cv::norm(image->image, cv::NORM_L1), 0.0);  // rendered, not blank
  }
  // Not a terminal: plain progress lines, the last with every frame; the summary with figures.
  EXPECT_EQ(r.err.find('\r'), std::string::npos);
  EXPECT_NE(r.err.find("| frames 30 30 | drops 0 |"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" MB ("), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("recorded 60 frames"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("MB/s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("CPU"), std::string::npos) << r.out;

  // An existing log is replaced (output_files.h), with or without the --force of older scripts.
  const auto again = Run("record --config " + Quote(config) + " -o " + Quote(log) +
                         " --no-vo --fast --image-encoding jpeg");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  const auto forced = Run("record --config " + Quote(config) + " -o " + Quote(log) +
                          " --no-vo --fast --image-encoding jpeg --force");
  ASSERT_EQ(forced.exit_code, 0) << forced.err;
  const LogSummary jpeg = ReadLog(log);
  ASSERT_EQ(jpeg.images.size(), 60u);
  EXPECT_EQ(jpeg.images[0].encoding, image_t::ENCODING_JPEG);
}

// On a terminal the progress line is rewritten in place (\r, erase to the end of the line).
TEST_F(RecordCommandTest, ProgressInPlaceOnATerminal) {
  if (support::RunShell("command -v script", dir_).exit_code != 0) {
    RIGCAL_SKIP_UNLESS_CI("`script` (util-linux) not found: no pseudo-terminal to test with");
  }
  const std::string config = WriteConfig(160, 120, 200);
  const std::string command = Quote(binary_) + " record --config " + Quote(config) + " -o " +
                              Quote(Path("tty.lcmlog")) + " --no-vo --duration 1.5";
  // script runs the command on a pseudo-terminal and copies what it printed to stdout.
  const auto r = support::RunShell("script -qec " + Quote(command) + " /dev/null", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("\rrigcal record: "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\033[K"), std::string::npos) << r.out;
}

TEST_F(RecordCommandTest, MissingConfigIsBadInput) {
  const auto r =
      Run("record --config " + Quote(Path("none.yaml")) + " -o " + Quote(Path("x.lcmlog")));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(Path("none.yaml")), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(Path("x.lcmlog")));
}

TEST_F(RecordCommandTest, SplitsBySize) {
  const std::string config = WriteConfig(160, 120, 40);
  const std::string log = (dir_ / "split.lcmlog").string();
  // Raw frames of 19.2 kB: 5 per 100 kB part.
  const auto r = Run("record --config " + Quote(config) + " -o " + Quote(log) +
                     " --no-vo --fast --split-mb 0.1");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_FALSE(fs::exists(log));
  int frames = 0;
  int parts = 0;
  for (;; ++parts) {
    const std::string part = lcm::LogPartPath(log, parts);
    if (!fs::exists(part)) break;
    EXPECT_LE(fs::file_size(part), 100'000u) << part;
    const LogSummary summary = ReadLog(part);
    EXPECT_EQ(summary.bad_images, 0) << part;
    frames += static_cast<int>(summary.images.size());
  }
  EXPECT_EQ(frames, 80);
  EXPECT_GE(parts, 16);
  EXPECT_NE(r.out.find(log + ".00"), std::string::npos) << r.out;
}

// With VO: poses of both cameras and extrinsics beside the images; then the log is cut inside its
// last event, as a power loss leaves it, and still reads and replays up to the cut.
TEST_F(RecordCommandTest, RecordsVoPosesAndSurvivesACut) {
  const std::string config = WriteConfig(376, 240, 160);
  const std::string log = (dir_ / "vo.lcmlog").string();
  const auto r = Run("record --config " + Quote(config) + " -o " + Quote(log) + " --fast");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  LogSummary summary = ReadLog(log);
  EXPECT_EQ(summary.events.at("RIGCAL_IMAGE_cam0"), 160);
  EXPECT_EQ(summary.events.at("RIGCAL_IMAGE_cam1"), 160);
  EXPECT_GT(summary.events["RIGCAL_POSE_cam0"], 100) << r.err;
  EXPECT_GT(summary.events["RIGCAL_POSE_cam1"], 100) << r.err;
  EXPECT_GE(summary.events["RIGCAL_EXTRINSICS"], 1) << r.err;

  int total = 0;
  for (const auto& [channel, n] : summary.events) total += n;
  const uintmax_t size = fs::file_size(log);
  fs::resize_file(log, size - 100);  // inside the last event (an extrinsics message > 100 bytes)
  const LogSummary cut = ReadLog(log);
  int cut_total = 0;
  for (const auto& [channel, n] : cut.events) cut_total += n;
  EXPECT_EQ(cut_total, total - 1);
  // The log replays: the node reads up to the cut and says at which byte the log is damaged.
  const auto replay = Run("calib --config " + Quote(config) + " --log " + Quote(log) + " --out " +
                          Quote((dir_ / "result.yaml").string()));
  EXPECT_NE(replay.exit_code, 1) << replay.err;
  EXPECT_NE(replay.err.find("truncated"), std::string::npos) << replay.err;
  EXPECT_NE(replay.err.find("byte "), std::string::npos) << replay.err;
}

}  // namespace
}  // namespace rigcal
