// SPDX-License-Identifier: Apache-2.0
#pragma once
// The sparse map of one VO segment: keyframes (poses and the bearings they observed) and
// landmarks (3D points with their observations). Ids are never reused within a segment.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <memory>
#include <unordered_map>
#include <vector>

#include "affine_patch.h"
#include "map_descriptors.h"

namespace rigcal::vo {

struct Keyframe {
  int id = -1;
  int64_t t_ns = 0;
  // world_from_cam rotation (Eigen storage x, y, z, w is the Ceres parameter block) and centre.
  Eigen::Quaterniond q_world_from_cam = Eigen::Quaterniond::Identity();
  Eigen::Vector3d C = Eigen::Vector3d::Zero();

  Eigen::Matrix3d R() const { return q_world_from_cam.toRotationMatrix(); }
};

struct Observation {
  int keyframe_id = -1;
  Eigen::Vector3d bearing = Eigen::Vector3d::UnitZ();  // unit, camera frame
};

struct Landmark {
  // At most this many descriptors: the first keyframe's and the newest ones.
  static constexpr size_t kMaxDescriptors = 4;

  int id = -1;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // world (segment reference) frame
  std::vector<Observation> observations;
  // Its appearance at the keyframes that observed it, for relocalisation: descriptors to find
  // it, and the reference patch of the track that observed it at the newest of them with the
  // warp into that keyframe, to place it to a fraction of a pixel once found.
  std::vector<Descriptor> descriptors;
  std::shared_ptr<const PatchTemplate> patch;
  Eigen::Matrix2d warp = Eigen::Matrix2d::Identity();

  // Keeps the first descriptor and the newest ones.
  void AddDescriptor(const Descriptor& descriptor);
};

class VoMap {
 public:
  void Clear();

  // Adds a keyframe and returns its id.
  int AddKeyframe(int64_t t_ns, const Eigen::Quaterniond& q_world_from_cam,
                  const Eigen::Vector3d& C);
  // Adds a landmark and returns its id.
  int AddLandmark(const Eigen::Vector3d& point);
  void AddObservation(int landmark_id, int keyframe_id, const Eigen::Vector3d& bearing);
  void RemoveLandmark(int landmark_id);

  Keyframe* keyframe(int id);
  const Keyframe* keyframe(int id) const;
  Landmark* landmark(int id);
  const Landmark* landmark(int id) const;

  // Keyframes by increasing id (= time).
  std::map<int, Keyframe>& keyframes() { return keyframes_; }
  const std::map<int, Keyframe>& keyframes() const { return keyframes_; }
  std::unordered_map<int, Landmark>& landmarks() { return landmarks_; }
  const std::unordered_map<int, Landmark>& landmarks() const { return landmarks_; }

  // The ids of the newest `count` keyframes, oldest first.
  std::vector<int> NewestKeyframes(int count) const;

  // Drops all but the newest `keep` keyframes, their observations, and the landmarks left
  // without observations unless `is_alive(landmark_id)` (a live track still uses it).
  template <typename IsAlive>
  void PruneKeyframes(int keep, IsAlive is_alive);

 private:
  std::map<int, Keyframe> keyframes_;
  std::unordered_map<int, Landmark> landmarks_;
  int next_keyframe_id_ = 0;
  int next_landmark_id_ = 0;
};

template <typename IsAlive>
void VoMap::PruneKeyframes(int keep, IsAlive is_alive) {
  if (static_cast<int>(keyframes_.size()) <= keep) return;
  const std::vector<int> kept = NewestKeyframes(keep);
  const int oldest_kept = kept.front();
  keyframes_.erase(keyframes_.begin(), keyframes_.find(oldest_kept));
  for (auto it = landmarks_.begin(); it != landmarks_.end();) {
    auto& obs = it->second.observations;
    obs.erase(std::remove_if(obs.begin(), obs.end(),
                             [&](const Observation& o) { return o.keyframe_id < oldest_kept; }),
              obs.end());
    if (obs.empty() && !is_alive(it->first)) {
      it = landmarks_.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace rigcal::vo
