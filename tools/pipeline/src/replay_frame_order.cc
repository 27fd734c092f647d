// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/replay_frame_order.h"

#include <algorithm>
#include <limits>

namespace rigcal::pipeline {
namespace {
constexpr int64_t kNothingYet = std::numeric_limits<int64_t>::min();

int64_t ImageBytes(const capture::Frame& frame) {
  return static_cast<int64_t>(frame.image.total() * frame.image.elemSize());
}
}  // namespace

ReplayFrameOrder::ReplayFrameOrder(int num_cameras, int64_t max_bytes)
    : held_(static_cast<size_t>(num_cameras)),
      released_ns_(static_cast<size_t>(num_cameras), kNothingYet),
      marked_(static_cast<size_t>(num_cameras), false),
      max_bytes_(max_bytes) {}

bool ReplayFrameOrder::Add(capture::Frame frame) {
  const auto c = static_cast<size_t>(frame.camera);
  // A mark at t says nothing of the camera comes at or before t.
  if (frame.t_ns < released_ns_[c] || (marked_[c] && frame.t_ns == released_ns_[c])) {
    ++late_frames_;
    return false;
  }
  // Each camera's frames come in capture order; one out of order is put in its place.
  auto& queue = held_[c];
  auto at =
      std::upper_bound(queue.begin(), queue.end(), frame.t_ns,
                       [](int64_t t_ns, const capture::Frame& held) { return t_ns < held.t_ns; });
  held_bytes_ += ImageBytes(frame);
  queue.insert(at, std::move(frame));
  return true;
}

void ReplayFrameOrder::TakeReady(std::vector<capture::Frame>* out) {
  for (int c = Earliest(); c >= 0; c = Earliest()) {
    const int64_t t_ns = held_[static_cast<size_t>(c)].front().t_ns;
    if (EveryCameraHolds()) {
      Release(c, out);
    } else if (held_bytes_ > max_bytes_) {
      Release(c, out);
      MarkIdleCameras(t_ns, out);
    } else {
      return;
    }
  }
}

void ReplayFrameOrder::TakeAll(std::vector<capture::Frame>* out) {
  for (int c = Earliest(); c >= 0; c = Earliest()) Release(c, out);
}

int ReplayFrameOrder::Earliest() const {
  int best = -1;
  for (size_t c = 0; c < held_.size(); ++c) {
    if (held_[c].empty()) continue;
    if (best < 0 || held_[c].front().t_ns < held_[static_cast<size_t>(best)].front().t_ns) {
      best = static_cast<int>(c);
    }
  }
  return best;
}

bool ReplayFrameOrder::EveryCameraHolds() const {
  return std::none_of(held_.begin(), held_.end(), [](const auto& queue) { return queue.empty(); });
}

void ReplayFrameOrder::Release(int camera, std::vector<capture::Frame>* out) {
  auto& queue = held_[static_cast<size_t>(camera)];
  released_ns_[static_cast<size_t>(camera)] = queue.front().t_ns;
  marked_[static_cast<size_t>(camera)] = false;
  held_bytes_ -= ImageBytes(queue.front());
  out->push_back(std::move(queue.front()));
  queue.pop_front();
}

void ReplayFrameOrder::MarkIdleCameras(int64_t t_ns, std::vector<capture::Frame>* out) {
  for (size_t c = 0; c < held_.size(); ++c) {
    if (!held_[c].empty() || released_ns_[c] >= t_ns) continue;
    capture::Frame mark;
    mark.camera = static_cast<int>(c);
    mark.t_ns = t_ns;
    mark.progress_mark = true;
    released_ns_[c] = t_ns;
    marked_[c] = true;
    out->push_back(std::move(mark));
  }
}

}  // namespace rigcal::pipeline
