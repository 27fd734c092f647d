#include "rigcal/lcm/pose_log.h"

#include <unistd.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <vector>

#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/pose_message.h"

namespace rigcal::tools {

std::string WritePoseLog(const std::string& path, const RigRecording& recording) {
  if (std::string error = recording.Validate(); !error.empty()) return path + ": " + error;
  CameraNames names = {recording.master.name};
  for (const CameraTrack& slave : recording.slaves) names.push_back(slave.name);
  const std::string temp = path + ".tmp." + std::to_string(getpid());
  {
    lcm::LogFile log(temp, "w");
    if (!log.good()) return temp + ": cannot create the log file";
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
          std::remove(temp.c_str());
          return path + ": pose " + std::to_string(k) + " of " + names[cam] + ": " + msg.error();
        }
        const std::string channel = PoseChannel(names[cam]);
        auto bytes = EncodeMessage(channel, names, *msg);
        if (!bytes) {
          std::remove(temp.c_str());
          return path + ": " + bytes.error();
        }
        lcm::LogEvent event;
        event.eventnum = event_number++;
        event.timestamp = utime;
        event.channel = channel;
        event.datalen = static_cast<int32_t>(bytes->size());
        event.data = bytes->data();
        if (log.writeEvent(&event) != 0) {
          std::remove(temp.c_str());
          return temp + ": write failed";
        }
      }
    }
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    std::remove(temp.c_str());
    return path + ": cannot rename the finished log into place";
  }
  return "";
}

}  // namespace rigcal::tools
