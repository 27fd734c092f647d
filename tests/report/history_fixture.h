// SPDX-License-Identifier: Apache-2.0
#pragma once
// A calibration history as `rigcal report` reads it, made by the real online estimator: a
// synthetic 3-camera drive (DemoRig) is fed set by set to a RigEstimator, and every half second
// its estimate becomes a RIGCAL_EXTRINSICS (EstimateToLcm) and the cameras' health a
// RIGCAL_STATUS (MakeRigStatus), written to an LCM log; the drive's poses go to a pose log
// (WritePoseLog) and its truth to a rig YAML.

#include <unistd.h>

#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <string>
#include <vector>

#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/pose_log.h"
#include "rigcal/lcm/status_message.h"
#include "rigcal/lcm/extrinsics_message.h"

namespace rigcal::report::report_test {

struct HistoryFiles {
  std::filesystem::path dir;
  std::string history_log;  // RIGCAL_EXTRINSICS + RIGCAL_STATUS
  std::string pose_log;     // RIGCAL_POSE_<camera>
  std::string truth;        // rig YAML
  int extrinsics = 0;       // messages written
  int status = 0;
  std::vector<std::string> names;  // master first
  std::map<std::string, Similarity> truth_rig;
};

// How often `needle` occurs in `text` (plots, ids, attributes of a page).
inline int CountOf(const std::string& text, const std::string& needle) {
  int n = 0;
  for (size_t pos = text.find(needle); pos != std::string::npos;
       pos = text.find(needle, pos + needle.size())) {
    ++n;
  }
  return n;
}

// Appends one checked message to `log` as an event at `utime`; false when it fails.
template <typename Message>
bool WriteEvent(::lcm::LogFile* log, const std::string& channel, const Message& msg, int64_t utime,
                int64_t* event_number) {
  auto bytes = lcm::EncodeMessage(channel, lcm::CameraNames{}, msg);
  if (!bytes) return false;
  ::lcm::LogEvent event;
  event.eventnum = (*event_number)++;
  event.timestamp = utime;
  event.channel = channel;
  event.datalen = static_cast<int32_t>(bytes->size());
  event.data = bytes->data();
  return log->writeEvent(&event) == 0;
}

// Writes the files into a fresh directory under the temp dir named after `tag` (and the process
// id unless `per_process` is false: then a later run replaces it). `frames` poses per camera at
// 20 Hz.
inline HistoryFiles MakeHistory(const std::string& tag, int frames = 600, bool per_process = true) {
  HistoryFiles files;
  files.dir =
      std::filesystem::temp_directory_path() /
      ("rigcal_report_" + tag + (per_process ? "_" + std::to_string(::getpid()) : std::string()));
  std::filesystem::remove_all(files.dir);
  std::filesystem::create_directories(files.dir);
  files.history_log = (files.dir / "history.lcmlog").string();
  files.pose_log = (files.dir / "poses.lcmlog").string();
  files.truth = (files.dir / "truth.yaml").string();
  files.names = {"cam0", "cam1", "cam2"};

  const std::vector<Similarity> rigs = DemoRig();
  DriveOptions drive;
  drive.num_frames = frames;
  drive.rotation_noise_deg = 0.02;
  drive.position_noise = 0.001;
  const SyntheticDrive synthetic = GenerateDrive(files.names, rigs, drive);
  for (size_t i = 0; i < rigs.size(); ++i) files.truth_rig[files.names[i + 1]] = rigs[i];
  if (!io::WriteRigYaml(files.truth, files.truth_rig).ok()) return files;
  if (!lcm::WritePoseLog(files.pose_log, synthetic.recording).ok()) return files;

  RigEstimator estimator(files.names, RigEstimatorOptions{});
  ::lcm::LogFile log(files.history_log, "w");
  int64_t event_number = 0;
  const RigRecording& rec = synthetic.recording;
  for (size_t k = 0; k < rec.size(); ++k) {
    estimator.AddSet(rec.t_ns[k], rec.SetAt(k));
    if (k % 10 != 9) continue;
    const int64_t utime = rec.t_ns[k] / 1000;
    auto extrinsics = lcm::EstimateToLcm(estimator.Estimate(), utime);
    if (extrinsics && WriteEvent(&log, lcm::kExtrinsicsChannel, *extrinsics, utime, &event_number)) {
      ++files.extrinsics;
    }
    std::vector<lcm::CameraStatusInput> cameras;
    for (const std::string& name : files.names) {
      lcm::CameraStatusInput c;
      c.name = name;
      c.fps = 20.0;
      c.frames_received = static_cast<int64_t>(k + 1);
      // Some life in the health plots: cam2 rejects a pose now and then, cam1 loses
      // tracking for two seconds.
      c.dropped_invalid = name == "cam2" ? static_cast<int64_t>(k / 100) : 0;
      const bool lost = name == "cam1" && k >= 300 && k < 340;
      c.vo_state = lost ? camera_status_t::VO_LOST : camera_status_t::VO_TRACKING;
      c.fps = lost ? 12.0 : 20.0;
      c.last_pose_age_ms = lost ? 400 : 20;
      cameras.push_back(c);
    }
    // cam1 runs free: its clock offset, 40 ms until its clock restarts at frame 400 (a jump),
    // being re-estimated for 100 frames, then -2.5 s.
    RigEstimate estimate = estimator.Estimate();
    SlaveOnlineState& clock = estimate.online[0];
    clock.clock_offset_estimated = true;
    clock.clock_offset_known = k < 400 || k >= 500;
    clock.clock_jumps = k < 400 ? 0 : 1;
    estimate.rig.slaves[0].time_offset_s = k < 400 ? 0.040 : -2.5;
    estimate.rig.slaves[0].time_offset_std_s = 1e-4;
    const rig_status_t status = lcm::MakeRigStatus(cameras, SyncStats{}, 64, estimate, 42.0, utime);
    if (WriteEvent(&log, lcm::kStatusChannel, status, utime, &event_number)) ++files.status;
  }
  return files;
}

}  // namespace rigcal::report::report_test
