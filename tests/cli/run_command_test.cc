// SPDX-License-Identifier: Apache-2.0
// `rigcal run` end to end through the built binary: the real static EuRoC frames (the drone
// stands still: the run must say "insufficient motion" and list the missing images, not
// crash), and the thesis virtual scene config with --eval.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli/command_test.h"
#include "support/skip.h"

namespace {

namespace fs = std::filesystem;

using RunCommandTest = rigcal::cli_test::CommandTest;
using rigcal::cli_test::RunResult;
using rigcal::cli_test::Slurp;

TEST_F(RunCommandTest, StaticEurocFramesGiveInsufficientMotion) {
  const fs::path mav0 = fs::path(RIGCAL_SHARED_DATA_DIR) / "euroc_v101_static" / "mav0";
  if (!fs::exists(mav0)) RIGCAL_SKIP_MISSING() << mav0 << " not found";
  const std::string config = (dir_ / "euroc.yaml").string();
  std::ofstream(config)
      << "rig: {name: euroc_static, master: cam0}\n"
         "cameras:\n"
         "  - name: cam0\n"
         "    model: pinhole\n"
         "    resolution: [752, 480]\n"
         "    intrinsics: [458.654, 457.296, 367.215, 248.375]\n"
         "    distortion: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n"
         "    device: "
      << (mav0 / "cam0").string()
      << "\n"
         "  - name: cam1\n"
         "    model: pinhole\n"
         "    resolution: [752, 480]\n"
         "    intrinsics: [457.587, 456.134, 379.999, 255.238]\n"
         "    distortion: [-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05]\n"
         "    device: "
      << (mav0 / "cam1").string()
      << "\n"
         "source: {type: image_folders}\n";
  const RunResult r =
      Run("run --config '" + config + "' --out '" + (dir_ / "result.yaml").string() + "'");
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;  // no slave calibrated
  EXPECT_NE(r.out.find("insufficient motion"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("4 listed images missing or unreadable"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1403715278012143104"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "result.yaml"));  // the (unusable) result is still written
}

// A slave camera dies mid-run: the run names it, the other slave still calibrates, and the
// result is written.
TEST_F(RunCommandTest, DeadCameraIsNamedAndTheOthersCalibrate) {
  const std::string config = (dir_ / "rig.yaml").string();
  std::ofstream(config)
      << "rig: {name: dying, master: cam0}\n"
         "cameras:\n"
         "  - {name: cam0, model: pinhole, resolution: [480, 320], "
         "intrinsics: [300, 300, 239.5, 159.5]}\n"
         "  - name: cam1\n"
         "    model: pinhole\n"
         "    resolution: [480, 320]\n"
         "    intrinsics: [300, 300, 239.5, 159.5]\n"
         "    truth: {q_wxyz: [0.70710678118654752, 0, 0.70710678118654752, 0], C: [0.5, 0, 0]}\n"
         "  - name: cam2\n"
         "    model: pinhole\n"
         "    resolution: [480, 320]\n"
         "    intrinsics: [300, 300, 239.5, 159.5]\n"
         "    truth: {q_wxyz: [0.70710678118654752, 0.70710678118654752, 0, 0], C: [0, 0.3, 0]}\n"
         "source:\n"
         "  type: simulated\n"
         "  frame_rate_hz: 20\n"
         "  num_frames: 240\n"
         "  seed: 3\n"
         "  fail_after_s: {cam2: 3}\n"
         "  scene: {type: room, size: [20, 16, 6], boxes: 10}\n"
         "  trajectory:\n"
         "    waypoint_interval_s: 2\n"
         "    waypoints:\n"
         "      - {p: [-3.0, 0.0, 3.0], ypr_deg: [0, 0, 0]}\n"
         "      - {p: [-2.3, 0.8, 3.2], ypr_deg: [20, -10, 8]}\n"
         "      - {p: [-1.4, 1.5, 3.0], ypr_deg: [38, 5, -6]}\n"
         "      - {p: [-0.4, 1.2, 2.8], ypr_deg: [15, 15, -15]}\n"
         "      - {p: [0.5, 0.4, 3.1], ypr_deg: [-10, 0, 5]}\n"
         "      - {p: [1.2, -0.6, 3.4], ypr_deg: [-35, -15, 12]}\n"
         "      - {p: [0.8, -1.6, 3.1], ypr_deg: [-20, 8, 18]}\n";
  const std::string result = (dir_ / "result.yaml").string();
  const RunResult r =
      Run("run --config '" + config + "' --fast --status-every 0 --out '" + result + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("camera 'cam2' died"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("camera 'cam1' died"), std::string::npos) << r.err;
  const std::string written = Slurp(result);
  EXPECT_NE(written.find("cam1"), std::string::npos) << written;
  // cam1 converged; cam2 has an estimate from its first 3 s or none, but is listed.
  EXPECT_NE(r.out.find("cam1: converged"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("cam2"), std::string::npos) << r.out;
}

TEST_F(RunCommandTest, MissingSourceIsAClearError) {
  const std::string config = (dir_ / "rig.yaml").string();
  std::ofstream(config) << "rig: {master: a}\ncameras:\n  - name: a\n  - name: b\n";
  const RunResult r = Run("run --config '" + config + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no `source:` section"), std::string::npos) << r.err;
}

}  // namespace
