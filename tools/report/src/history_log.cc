// SPDX-License-Identifier: Apache-2.0
#include "history_log.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>

#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/lcm/status_message.h"

namespace rigcal::report::internal {
namespace {

constexpr unsigned char kLcmSyncWord[4] = {0xED, 0xA1, 0xDA, 0x01};  // big-endian 0xEDA1DA01

template <typename Message>
void Collect(lcm::MessageValidator* validator, const ::lcm::LogEvent& event, std::vector<Message>* out,
             LogContents* contents) {
  Expected<Message> msg = validator->Decode<Message>(event.channel, event.data, event.datalen);
  if (!msg) {
    if (contents->rejected++ == 0) contents->first_rejection = msg.error();
    return;
  }
  out->push_back(std::move(msg).value());
}

}  // namespace

bool IsLcmLog(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char head[4] = {};
  if (!in.read(reinterpret_cast<char*>(head), 4)) return false;
  return std::equal(head, head + 4, kLcmSyncWord);
}

Expected<LogContents> ReadLogContents(const std::string& path) {
  ::lcm::LogFile log(path, "r");
  if (!log.good()) return Error{path + ": cannot open the LCM log"};
  LogContents contents;
  lcm::MessageValidator validator;  // any camera names: the rig is known from the messages
  const std::string pose_prefix = lcm::PoseChannel("");
  int64_t good_end = 0;
  while (const ::lcm::LogEvent* event = log.readNextEvent()) {
    ++contents.events;
    if (FILE* file = log.getFilePtr()) good_end = std::ftell(file);
    if (event->channel == lcm::kExtrinsicsChannel) {
      Collect(&validator, *event, &contents.extrinsics, &contents);
    } else if (event->channel == lcm::kStatusChannel) {
      Collect(&validator, *event, &contents.status, &contents);
    } else if (event->channel.rfind(pose_prefix, 0) == 0) {
      std::vector<camera_pose_t> pose;
      Collect(&validator, *event, &pose, &contents);
      if (pose.empty()) continue;
      const camera_pose_t& p = pose.front();
      CameraPoses& camera = contents.poses[p.camera];
      camera.t_ns.push_back(p.t_ns);
      Pose value;
      value.q = Eigen::Quaterniond(p.q[0], p.q[1], p.q[2], p.q[3]);
      value.C = Eigen::Vector3d(p.C[0], p.C[1], p.C[2]);
      camera.poses.push_back(value);
      camera.segment.push_back(p.segment);
    }
  }
  // LCM reports a clean end and a damaged tail alike: compare where the last complete event
  // ended with the file size.
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && static_cast<uintmax_t>(good_end) < size) {
    contents.damage = path + ": truncated or corrupt event after byte " + std::to_string(good_end) +
                      " of " + std::to_string(size) + "; the events before it are used";
  }
  return contents;
}

}  // namespace rigcal::report::internal
