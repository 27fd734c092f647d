// SPDX-License-Identifier: Apache-2.0
// A pose log with glitched stamps through `rigcal replay` and `rigcal calib --log`: one pose
// stamped INT64_MAX, or ten at 4e18 ns, in the middle of a drive. They are rejected, move no
// clock (the publications go on at the log's rate after them) and no schedule walks towards
// them: the run ends in seconds with the drive's result.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include "cli/command_test.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/lcm/pose_log.h"

namespace rigcal {
namespace {

namespace fs = std::filesystem;

using cli_test::Slurp;
using cli_test::Spawn;
using cli_test::WaitExit;

const Similarity kLeft{Eigen::Quaterniond(0.9238795, 0, 0.3826834, 0).normalized(),
                       Eigen::Vector3d(0.3, 0.05, -0.2), 1.0};

class ReplayClockGlitchFault : public cli_test::CommandTest {
 protected:
  void SetUp() override {
    CommandTest::SetUp();
    if (HasFatalFailure()) return;
    std::ofstream(Path("rig.yaml")) << "rig: {name: test, master: front}\n"
                                       "cameras:\n"
                                       "  - name: front\n"
                                       "  - name: left\n"
                                       "publish: {extrinsics_rate_hz: 2, status_rate_hz: 1}\n"
                                       "state: {save_interval_s: 1}\n";
  }

  // A 40 s drive at 20 Hz with `glitches` master poses stamped `glitch_ns` in its middle (in
  // file order), one after each of as many consecutive frames, with stamps stepping back by 1 ns;
  // or, `back_to_back`, as many consecutive events after the middle frame stepping on at the
  // drive's rate (a timeline of their own that no other camera shares): the drive's pieces and
  // the glitches written one after the other (an LCM log is its events in file order).
  void WriteGlitchedLog(const std::string& name, int64_t glitch_ns, int glitches,
                        bool back_to_back = false) const {
    DriveOptions d;
    d.num_frames = 800;
    d.rotation_noise_deg = 0.05;
    d.position_noise = 0.002;
    const SyntheticDrive drive = GenerateDrive({"front", "left"}, {kLeft}, d);
    const RigRecording& rec = drive.recording;
    const lcm::CameraNames names = {"front", "left"};
    std::vector<std::vector<CameraPose>> pieces(1);
    const size_t mid = rec.size() / 2;
    for (size_t k = 0; k < rec.size(); ++k) {
      for (int camera = 0; camera < 2; ++camera) pieces.back().push_back(rec.PoseAt(camera, k));
      if (back_to_back && k == mid) {
        pieces.emplace_back();
        for (int i = 0; i < glitches; ++i) {
          CameraPose glitch = rec.PoseAt(0, k);
          glitch.t_ns = glitch_ns + i * 50'000'000;  // 20 Hz
          pieces.back().push_back(glitch);
        }
        pieces.emplace_back();
      } else if (!back_to_back && k >= mid && k < mid + static_cast<size_t>(glitches)) {
        CameraPose glitch = rec.PoseAt(0, k);
        glitch.t_ns = glitch_ns - static_cast<int64_t>(k - mid);
        pieces.push_back({glitch});
        pieces.emplace_back();
      }
    }
    std::ofstream out(Path(name), std::ios::binary);
    for (const std::vector<CameraPose>& piece : pieces) {
      ASSERT_TRUE(lcm::WritePoseEvents(Path("piece.lcmlog"), names, piece).ok());
      out << Slurp(Path("piece.lcmlog"));
    }
  }

  // `rigcal <args>` in the background; its exit code, -1 when it ran longer than 60 s (killed).
  int RunBounded(const std::vector<std::string>& args, const std::string& err) const {
    const pid_t pid = Spawn(binary_, args, Path(err));
    EXPECT_GT(pid, 0);
    return pid > 0 ? WaitExit(pid, std::chrono::seconds(60)) : -1;
  }
};

TEST_F(ReplayClockGlitchFault, GlitchedStampsNeitherHangNorMoveTheClock) {
  struct Case {
    const char* name;
    int64_t stamp_ns;
    int count;
    bool back_to_back;
  };
  const std::vector<Case> cases = {
      {"one at INT64_MAX", std::numeric_limits<int64_t>::max(), 1, false},
      {"ten at 4e18", 4'000'000'000'000'000'000, 10, false},
      {"ten at 4e18 back to back", 4'000'000'000'000'000'000, 10, true}};
  for (const Case& c : cases) {
    WriteGlitchedLog("g.lcmlog", c.stamp_ns, c.count, c.back_to_back);
    for (const std::string command : {"replay", "calib"}) {
      const std::string out = Path("out.lcmlog");
      std::vector<std::string> args = {command};
      if (command == "calib") args.push_back("--log");
      for (const std::string& a :
           {Path("g.lcmlog"), std::string("--config"), Path("rig.yaml"), std::string("--out"),
            Path("r.yaml"), std::string("--state"), Path("s.state"), std::string("--publish-lcm"),
            "file://" + out + "?mode=w"}) {
        args.push_back(a);
      }
      if (command == "replay") args.push_back("--no-progress");
      const int code = RunBounded(args, "err.txt");
      const std::string err = Slurp(Path("err.txt"));
      ASSERT_NE(code, -1) << c.name << ", " << command << ": still running after 60 s\n"
                          << err.substr(0, 4000);
      EXPECT_EQ(code, 0) << c.name << ", " << command << "\n" << err.substr(0, 4000);
      EXPECT_NE(Slurp(Path("r.yaml")).find("usable: true"), std::string::npos) << c.name;
      // 40 s of log at 2 Hz: about 80 RIGCAL_EXTRINSICS (the clock went on after the glitch).
      const std::string log = Slurp(out);
      int published = 0;
      for (size_t at = log.find("RIGCAL_EXTRINSICS"); at != std::string::npos;
           at = log.find("RIGCAL_EXTRINSICS", at + 1)) {
        ++published;
      }
      EXPECT_GE(published, 75) << c.name << ", " << command;
      EXPECT_LE(published, 85) << c.name << ", " << command;
      fs::remove(out);
      fs::remove(Path("r.yaml"));
      fs::remove(Path("s.state"));
    }
  }
}

// `replay --speed 20` of the same logs: the glitched stamps are not waited for (a wait towards
// 4e18 ns of log time never ended, and INT64_MAX at --speed 0.5 overflowed the due time), the
// 40 s drive is paced in about 2 s, and the glitch is named.
TEST_F(ReplayClockGlitchFault, PacingSkipsGlitchedStamps) {
  struct Case {
    const char* name;
    int64_t stamp_ns;
    int count;
    bool back_to_back;
    const char* speed;
  };
  const std::vector<Case> cases = {
      {"one at INT64_MAX", std::numeric_limits<int64_t>::max(), 1, false, "20"},
      {"ten at 4e18 back to back", 4'000'000'000'000'000'000, 10, true, "20"},
      {"one at INT64_MAX, half speed", std::numeric_limits<int64_t>::max(), 1, false, "0.5"}};
  for (const Case& c : cases) {
    WriteGlitchedLog("g.lcmlog", c.stamp_ns, c.count, c.back_to_back);
    std::vector<std::string> args = {"replay",         Path("g.lcmlog"), "--config",
                                     Path("rig.yaml"), "--out",          Path("r.yaml"),
                                     "--no-progress",  "--speed",        c.speed};
    // At half speed the 40 s drive would take 80 s: the 4 s around the glitch (8 s) do.
    const bool half = std::string(c.speed) == "0.5";
    if (half) args.insert(args.end(), {"--from", "18", "--to", "22"});
    const auto start = std::chrono::steady_clock::now();
    const int code = RunBounded(args, "err.txt");
    const double took_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::string err = Slurp(Path("err.txt"));
    ASSERT_NE(code, -1) << c.name << ": still pacing after 60 s\n" << err.substr(0, 4000);
    // 4 s of drive may not determine the rig (exit 3); the whole drive does.
    EXPECT_TRUE(code == 0 || (half && code == 3)) << c.name << ": exit " << code << "\n"
                                                  << err.substr(0, 4000);
    EXPECT_NE(err.find("not paced and moves no clock"), std::string::npos) << c.name << "\n"
                                                                           << err.substr(0, 4000);
    std::cout << c.name << " at --speed " << c.speed << ": " << took_s << " s\n";
    fs::remove(Path("r.yaml"));
  }
}

}  // namespace
}  // namespace rigcal
