// SPDX-License-Identifier: Apache-2.0
#include "vo_map.h"

#include <algorithm>

namespace rigcal::vo {

void Landmark::AddDescriptor(const Descriptor& descriptor) {
  if (descriptors.size() >= kMaxDescriptors) descriptors.erase(descriptors.begin() + 1);
  descriptors.push_back(descriptor);
}

void VoMap::Clear() {
  keyframes_.clear();
  landmarks_.clear();
}

int VoMap::AddKeyframe(int64_t t_ns, const Eigen::Quaterniond& q_world_from_cam,
                       const Eigen::Vector3d& C) {
  Keyframe kf;
  kf.id = next_keyframe_id_++;
  kf.t_ns = t_ns;
  kf.q_world_from_cam = q_world_from_cam.normalized();
  kf.C = C;
  keyframes_.emplace(kf.id, kf);
  return kf.id;
}

int VoMap::AddLandmark(const Eigen::Vector3d& point) {
  Landmark lm;
  lm.id = next_landmark_id_++;
  lm.point = point;
  landmarks_.emplace(lm.id, std::move(lm));
  return next_landmark_id_ - 1;
}

void VoMap::AddObservation(int landmark_id, int keyframe_id, const Eigen::Vector3d& bearing) {
  Landmark* lm = landmark(landmark_id);
  if (lm == nullptr || keyframe(keyframe_id) == nullptr) return;
  lm->observations.push_back({keyframe_id, bearing});
}

void VoMap::RemoveLandmark(int landmark_id) { landmarks_.erase(landmark_id); }

Keyframe* VoMap::keyframe(int id) {
  auto it = keyframes_.find(id);
  return it == keyframes_.end() ? nullptr : &it->second;
}

const Keyframe* VoMap::keyframe(int id) const {
  auto it = keyframes_.find(id);
  return it == keyframes_.end() ? nullptr : &it->second;
}

Landmark* VoMap::landmark(int id) {
  auto it = landmarks_.find(id);
  return it == landmarks_.end() ? nullptr : &it->second;
}

const Landmark* VoMap::landmark(int id) const {
  auto it = landmarks_.find(id);
  return it == landmarks_.end() ? nullptr : &it->second;
}

std::vector<int> VoMap::NewestKeyframes(int count) const {
  std::vector<int> ids;
  for (auto it = keyframes_.rbegin();
       it != keyframes_.rend() && static_cast<int>(ids.size()) < count; ++it) {
    ids.push_back(it->first);
  }
  std::reverse(ids.begin(), ids.end());
  return ids;
}

}  // namespace rigcal::vo
