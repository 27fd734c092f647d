#include "rigcal/lcm/pose_log.h"

#include <unistd.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <vector>

#include "rigcal/io/atomic_file.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/pose_message.h"

namespace rigcal::tools {

Status WritePoseLog(const std::string& path, const RigRecording& recording) {
  if (const Status status = recording.Check(); !status.ok()) return status.Prefixed(path);
  CameraNames names = {recording.master.name};
  for (const CameraTrack& slave : recording.slaves) names.push_back(slave.name);
  Expected<AtomicFile> file = AtomicFile::Create(path);
  if (!file.ok()) return file.status();
  const std::string& temp = file->temp_path();
  {
    lcm::LogFile log(temp, "w");
    if (!log.good()) return Error{temp + ": cannot create the log file"};
    int64_t event_number = 0;
    for (size_t k = 0; k < recording.size(); ++k) {
      for (size_t cam = 0; cam < names.size(); ++cam) {
        const CameraTrack& track = cam == 0 ? recording.master : recording.slaves[cam - 1];
        CameraPose pose;
        pose.camera = static_cast<int>(cam);
        pose.t_ns = recording.t_ns[k];
        pose.pose = track.poses[k];
        pose.segment = track.segment.empty() ? 0 : track.segment[k];
        const int64_t utime = recording.t_ns[k] / 1000;
        auto msg = CameraPoseToLcm(pose, names, utime);
        if (!msg) {
          return Error{path + ": pose " + std::to_string(k) + " of " + names[cam] + ": " +
                       msg.error()};
        }
        const std::string channel = PoseChannel(names[cam]);
        auto bytes = EncodeMessage(channel, names, *msg);
        if (!bytes) return Error{path + ": " + bytes.error()};
        lcm::LogEvent event;
        event.eventnum = event_number++;
        event.timestamp = utime;
        event.channel = channel;
        event.datalen = static_cast<int32_t>(bytes->size());
        event.data = bytes->data();
        if (log.writeEvent(&event) != 0) return Error{temp + ": write failed"};
      }
    }
  }
  return file->Commit();
}

}  // namespace rigcal::tools
