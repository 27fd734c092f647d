// SPDX-License-Identifier: Apache-2.0
#include "paced_replay_device.h"

#include <algorithm>
#include <chrono>
#include <thread>

#include "rigcal/capture/v4l2_timestamp.h"

namespace rigcal::pipeline {

int64_t ReplayClock::HostNs(int64_t t_ns) {
  MutexLock lock(mutex_);
  if (!origin_ns_) origin_ns_ = t_ns;
  return epoch_ns_ + (t_ns - *origin_ns_);
}

Expected<std::optional<capture::Frame>> PacedReplayDevice::Grab() {
  Expected<std::optional<capture::Frame>> grabbed = device_->Grab();
  if (!grabbed || !grabbed->has_value()) return grabbed;
  capture::Frame& frame = **grabbed;
  frame.t_ns = clock_->HostNs(frame.t_ns);
  // Wait for the frame's time in short steps, so Interrupt is prompt.
  while (!interrupted_.load()) {
    const int64_t left = frame.t_ns - capture::MonotonicNowNs();
    if (left <= 0) break;
    std::this_thread::sleep_for(std::chrono::nanoseconds(std::min<int64_t>(left, 20'000'000)));
  }
  if (interrupted_.load()) return std::optional<capture::Frame>();
  return grabbed;
}

void PacedReplayDevice::Interrupt() {
  interrupted_ = true;
  device_->Interrupt();
}

}  // namespace rigcal::pipeline
