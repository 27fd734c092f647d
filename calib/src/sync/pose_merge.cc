// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/pose_merge.h"

#include <limits>

namespace rigcal {
namespace {
constexpr int64_t kNotStarted = std::numeric_limits<int64_t>::min();
}  // namespace

PoseMerge::PoseMerge(int num_cameras, int64_t lead_ns, Sink sink)
    : lead_ns_(lead_ns),
      sink_(std::move(sink)),
      progress_(static_cast<size_t>(num_cameras), kNotStarted),
      ended_(static_cast<size_t>(num_cameras), false),
      held_(static_cast<size_t>(num_cameras)) {}

void PoseMerge::Deliver(int camera, int64_t frame_t_ns, std::vector<CameraPose> poses) {
  MutexLock lock(mutex_);
  const auto c = static_cast<size_t>(camera);
  for (CameraPose& pose : poses) held_[c].push_back({frame_t_ns, std::move(pose)});
  progress_[c] = frame_t_ns;
  ReleaseSafe();
  changed_.notify_all();
  while (!stopped_ && Lagging(camera, frame_t_ns)) lock.Wait(changed_);
}

void PoseMerge::End(int camera) {
  MutexLock lock(mutex_);
  ended_[static_cast<size_t>(camera)] = true;
  ReleaseSafe();
  changed_.notify_all();
}

void PoseMerge::Stop() {
  MutexLock lock(mutex_);
  stopped_ = true;
  changed_.notify_all();
}

bool PoseMerge::Lagging(int camera, int64_t t_ns) const {
  for (size_t j = 0; j < progress_.size(); ++j) {
    if (static_cast<int>(j) == camera || ended_[j]) continue;
    if (progress_[j] == kNotStarted || progress_[j] < t_ns - lead_ns_) return true;
  }
  return false;
}

void PoseMerge::ReleaseSafe() {
  while (true) {
    // The held pose first in (frame stamp, camera) order.
    size_t best = held_.size();
    for (size_t c = 0; c < held_.size(); ++c) {
      if (held_[c].empty()) continue;
      if (best == held_.size() || held_[c].front().frame_t_ns < held_[best].front().frame_t_ns) {
        best = c;
      }
    }
    if (best == held_.size()) return;
    // Safe when no streaming camera can still deliver a frame stamped at or before it: each
    // has processed a frame at least as late (ties among held poses went to the lower index).
    const int64_t t = held_[best].front().frame_t_ns;
    for (size_t j = 0; j < progress_.size(); ++j) {
      if (j == best || ended_[j]) continue;
      if (progress_[j] == kNotStarted || progress_[j] < t) return;
    }
    sink_(held_[best].front().pose);
    held_[best].pop_front();
  }
}

}  // namespace rigcal
