// SPDX-License-Identifier: Apache-2.0
#pragma once
// FlowWatch: whether a live capture is healthy, for the service watchdog (rigcal-run.service):
// every camera delivered a frame through its VO within the last `timeout_ns` (wall clock), and
// the estimator took a set within it or had none waiting. Sets wait only once every VO tracks:
// while a VO initialises (a parked vehicle, a slow start) frames flow and nothing is owed to the
// estimator, so the watchdog is fed. Until the first timeout has passed since the start, the
// flow is healthy (the cameras open). A stalled camera or an estimator that stopped consuming
// the sets it is given starves the watchdog, so systemd restarts the service.
//
// Not thread-safe: the capture loop's thread owns it.

#include <cstdint>
#include <string>
#include <vector>

namespace rigcal::pipeline {

class FlowWatch {
 public:
  FlowWatch(std::vector<std::string> names, int64_t start_ns, int64_t timeout_ns)
      : names_(std::move(names)),
        timeout_ns_(timeout_ns),
        frames_(names_.size(), -1),
        frame_progress_ns_(names_.size(), start_ns),
        sets_progress_ns_(start_ns) {}

  // The counters now: frames through each camera's VO, sets the estimator consumed, sets matched
  // and not consumed yet (waiting). Returns whether the flow is healthy.
  bool Update(int64_t now_ns, const std::vector<int64_t>& frames, uint64_t sets, uint64_t waiting) {
    for (size_t i = 0; i < frames_.size() && i < frames.size(); ++i) {
      if (frames[i] != frames_[i]) {
        frames_[i] = frames[i];
        frame_progress_ns_[i] = now_ns;
      }
    }
    if (sets != sets_ || waiting == 0) {
      sets_ = sets;
      sets_progress_ns_ = now_ns;
    }
    problem_.clear();
    for (size_t i = 0; i < frames_.size(); ++i) {
      if (now_ns - frame_progress_ns_[i] > timeout_ns_) {
        problem_ += (problem_.empty() ? "" : ", ") + ("camera '" + names_[i] + "' stalled");
      }
    }
    if (now_ns - sets_progress_ns_ > timeout_ns_) {
      problem_ += (problem_.empty() ? "" : ", ") +
                  std::string("the estimator takes none of the sets waiting");
    }
    return problem_.empty();
  }

  // What is wrong after the last Update ("camera 'cam1' stalled"); empty when healthy.
  const std::string& problem() const { return problem_; }

 private:
  std::vector<std::string> names_;
  int64_t timeout_ns_;
  std::vector<int64_t> frames_;
  std::vector<int64_t> frame_progress_ns_;
  uint64_t sets_ = 0;
  int64_t sets_progress_ns_;
  std::string problem_;
};

}  // namespace rigcal::pipeline
