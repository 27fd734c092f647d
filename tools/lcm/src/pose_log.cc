// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/pose_log.h"

#include <algorithm>
#include <memory>
#include <vector>

#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/log_writer.h"
#include "rigcal/lcm/pose_message.h"

namespace rigcal::lcm {

Status WritePoseLog(const std::string& path, const RigRecording& recording) {
  if (const Status status = recording.Check(); !status.ok()) return status.Prefixed(path);
  CameraNames names = {recording.master.name};
  for (const CameraTrack& slave : recording.slaves) names.push_back(slave.name);
  std::vector<CameraPose> poses;
  poses.reserve(recording.size() * names.size());
  for (size_t k = 0; k < recording.size(); ++k) {
    for (size_t cam = 0; cam < names.size(); ++cam) {
      const CameraTrack& track = cam == 0 ? recording.master : recording.slaves[cam - 1];
      CameraPose pose;
      pose.camera = static_cast<int>(cam);
      pose.t_ns = recording.t_ns[k];
      pose.pose = track.poses[k];
      pose.segment = track.segment.empty() ? 0 : track.segment[k];
      poses.push_back(pose);
    }
  }
  return WritePoseEvents(path, names, std::move(poses));
}

Status WritePoseEvents(const std::string& path, const CameraNames& names,
                       std::vector<CameraPose> poses) {
  std::stable_sort(poses.begin(), poses.end(), [](const CameraPose& a, const CameraPose& b) {
    return a.t_ns != b.t_ns ? a.t_ns < b.t_ns : a.camera < b.camera;
  });
  LogWriterOptions options;
  options.atomic = true;
  options.overwrite = true;
  auto log = LogWriter::Open(path, options);
  if (!log) return log.status();
  for (const CameraPose& pose : poses) {
    const int64_t utime = pose.t_ns / 1000;
    const std::string name = pose.camera >= 0 && static_cast<size_t>(pose.camera) < names.size()
                                 ? names[static_cast<size_t>(pose.camera)]
                                 : "camera " + std::to_string(pose.camera);
    auto msg = CameraPoseToLcm(pose, names, utime);
    if (!msg) {
      return Error{path + ": pose at t_ns " + std::to_string(pose.t_ns) + " of " + name + ": " +
                   msg.error()};
    }
    const std::string channel = PoseChannel(name);
    auto bytes = EncodeMessage(channel, names, *msg);
    if (!bytes) return Error{path + ": " + bytes.error()};
    if (Status status = (*log)->Write(channel, utime, bytes->data(), bytes->size()); !status.ok()) {
      return status;
    }
  }
  return (*log)->Close();
}

}  // namespace rigcal::lcm
