// SPDX-License-Identifier: Apache-2.0
#include "paced_replay_device.h"

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <sstream>
#include <thread>

#include "rigcal/capture/v4l2_timestamp.h"

namespace rigcal::pipeline {

int64_t ReplayClock::HostNs(int64_t t_ns) {
  int64_t since_origin_ns = 0;
  {
    MutexLock lock(mutex_);
    if (!origin_ns_) origin_ns_ = t_ns;
    since_origin_ns = t_ns - *origin_ns_;
  }
  return host_ns_since_(since_origin_ns);
}

Expected<std::optional<capture::Frame>> PacedReplayDevice::Grab() {
  Expected<std::optional<capture::Frame>> grabbed = device_->Grab();
  if (!grabbed || !grabbed->has_value()) return grabbed;
  capture::Frame& frame = **grabbed;
  if (Status gap = CheckGap(frame.t_ns); !gap.ok()) return Error{gap.message()};
  previous_recorded_ns_ = frame.t_ns;
  ++frames_;
  const int64_t recorded_ns = frame.t_ns;
  // Wait for the frame's time in short steps, so Interrupt is prompt; the time is asked again at
  // each step (a clock on the trigger's pulses moves with the clock map).
  while (true) {
    frame.t_ns = clock_->HostNs(recorded_ns);
    const int64_t left = frame.t_ns - capture::MonotonicNowNs();
    if (left <= 0 || interrupted_.load()) break;
    std::this_thread::sleep_for(std::chrono::nanoseconds(std::min<int64_t>(left, 20'000'000)));
  }
  if (interrupted_.load()) return std::optional<capture::Frame>();
  return grabbed;
}

int64_t PacedReplayDevice::MaxGapNs() const {
  const double rate_hz = device_->frame_rate_hz();
  const double hundred_periods_ns = rate_hz > 0.0 ? 100.0 * 1e9 / rate_hz : 0.0;
  return static_cast<int64_t>(std::max(10e9, std::min(hundred_periods_ns, 1e12)));
}

Status PacedReplayDevice::CheckGap(int64_t t_ns) const {
  if (!previous_recorded_ns_ || t_ns <= *previous_recorded_ns_) return {};
  // Unsigned: the difference of two int64 stamps may not fit an int64.
  const uint64_t gap_ns =
      static_cast<uint64_t>(t_ns) - static_cast<uint64_t>(*previous_recorded_ns_);
  if (gap_ns <= static_cast<uint64_t>(MaxGapNs())) return {};
  std::ostringstream message;
  message << "frame " << frames_ << " is stamped " << std::setprecision(4)
          << static_cast<double>(gap_ns) * 1e-9 << " s after the previous one (" << t_ns
          << " ns); a paced replay waits at most " << static_cast<double>(MaxGapNs()) * 1e-9
          << " s between frames: a glitched stamp?";
  return Error{message.str()};
}

void PacedReplayDevice::Interrupt() {
  interrupted_ = true;
  device_->Interrupt();
}

}  // namespace rigcal::pipeline
