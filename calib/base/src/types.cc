// SPDX-License-Identifier: Apache-2.0
#include "rigcal/base/types.h"

#include <sstream>

namespace rigcal {

Pose Pose::Inverse() const {
  Pose inv;
  inv.q = q.conjugate();
  inv.C = -(inv.q * C);
  return inv;
}

Pose Pose::operator*(const Pose& other) const {
  Pose out;
  out.q = (q * other.q).normalized();
  out.C = q * other.C + C;
  return out;
}

Pose Pose::Between(const Pose& other) const { return Inverse() * other; }

CameraPose RigRecording::PoseAt(int camera, size_t k) const {
  const CameraTrack& track = camera == 0 ? master : slaves.at(camera - 1);
  CameraPose p;
  p.camera = camera;
  p.t_ns = t_ns.at(k);
  p.segment = track.segment.empty() ? 0 : track.segment.at(k);
  p.pose = track.poses.at(k);
  return p;
}

std::vector<std::optional<CameraPose>> RigRecording::SetAt(size_t k) const {
  std::vector<std::optional<CameraPose>> set;
  for (int camera = 0; camera <= static_cast<int>(slaves.size()); ++camera) {
    set.emplace_back(PoseAt(camera, k));
  }
  return set;
}

Status RigRecording::Check() const {
  std::ostringstream err;
  auto check = [&](const CameraTrack& track) {
    if (track.poses.size() != t_ns.size()) {
      err << "camera '" << track.name << "' has " << track.poses.size() << " poses for "
          << t_ns.size() << " stamps";
      return false;
    }
    if (!track.segment.empty() && track.segment.size() != t_ns.size()) {
      err << "camera '" << track.name << "' has " << track.segment.size() << " segment ids for "
          << t_ns.size() << " stamps";
      return false;
    }
    return true;
  };
  if (!check(master)) return Error{err.str()};
  for (const auto& s : slaves) {
    if (!check(s)) return Error{err.str()};
  }
  for (size_t k = 1; k < t_ns.size(); ++k) {
    if (t_ns[k] <= t_ns[k - 1]) {
      err << "stamps not increasing at index " << k;
      return Error{err.str()};
    }
  }
  return Status::Ok();
}

}  // namespace rigcal
