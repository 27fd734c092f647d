// SPDX-License-Identifier: Apache-2.0
#pragma once
// The rig of the live trigger tests: two EuRoC camera folders of kFrames tiny images at 20 Hz
// and a rig config whose `trigger.port` is `port` (cam0 on line 0, cam1 on line 3). Header-only.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

namespace rigcal::testing {

inline constexpr int kFrames = 40;

// Two EuRoC camera folders of kFrames tiny images at 20 Hz and a rig config naming `port`; the
// last frame of each camera stamped `last_frame_late_ns` later than the rate puts it.
inline std::string WriteRig(const std::filesystem::path& dir, const std::string& port,
                            const std::string& options, int64_t last_frame_late_ns = 0) {
  for (const char* cam : {"cam0", "cam1"}) {
    std::filesystem::create_directories(dir / cam / "data");
    std::ofstream csv(dir / cam / "data.csv");
    csv << "#timestamp [ns],filename\n";
    for (int k = 0; k < kFrames; ++k) {
      const int64_t t = 1'403'636'579'763'555'584 + int64_t{k} * 50'000'000 +
                        (k == kFrames - 1 ? last_frame_late_ns : 0);
      const std::string name = std::to_string(t) + ".png";
      cv::imwrite((dir / cam / "data" / name).string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(k)));
      csv << t << "," << name << "\n";
    }
  }
  const std::string camera =
      "    model: pinhole\n    resolution: [64, 48]\n    intrinsics: [50, 50, 32, 24]\n"
      "    distortion: [0, 0, 0, 0]\n";
  const std::filesystem::path path = dir / "rig.yaml";
  std::ofstream(path) << "rig: {master: cam0}\n"
                         "source: {type: image_folders}\n"
                         "trigger: {port: "
                      << port << ", rate_hz: 20, heartbeat_ms: 50, " << options
                      << "}\n"
                         "cameras:\n"
                         "  - name: cam0\n"
                      << camera
                      << "    device: cam0\n"
                         "    trigger: {line: 0}\n"
                         "  - name: cam1\n"
                      << camera
                      << "    device: cam1\n"
                         "    nominal: {q_wxyz: [1, 0, 0, 0], C: [1, 0, 0]}\n"
                         "    trigger: {line: 3}\n";
  return path.string();
}

}  // namespace rigcal::testing
