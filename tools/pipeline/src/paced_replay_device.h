// SPDX-License-Identifier: Apache-2.0
#pragma once
// PacedReplayDevice: replays a recording (an image folder) in real time on the host clock, so a
// live trigger generator can expose it: the recording's time runs from `epoch_ns`
// (CLOCK_MONOTONIC, e.g. the next trigger pulse), each frame is stamped epoch + (its recorded
// stamp - the first recorded stamp any camera of the replay grabbed) and Grab returns it at that
// time.
//
// Threads: as the wrapped device (one capture thread per device; Interrupt from any thread).
// The cameras of one replay share a ReplayClock (thread-safe).

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

#include "rigcal/base/thread_annotations.h"
#include "rigcal/capture/capture_device.h"

namespace rigcal::pipeline {

class ReplayClock {
 public:
  explicit ReplayClock(int64_t epoch_ns) : epoch_ns_(epoch_ns) {}
  // Host time of recorded stamp `t_ns`; the first call fixes the recording's origin.
  int64_t HostNs(int64_t t_ns) RIGCAL_EXCLUDES(mutex_);

 private:
  const int64_t epoch_ns_;
  Mutex mutex_;
  std::optional<int64_t> origin_ns_ RIGCAL_GUARDED_BY(mutex_);
};

class PacedReplayDevice final : public capture::CameraDevice {
 public:
  PacedReplayDevice(std::unique_ptr<capture::CameraDevice> device,
                    std::shared_ptr<ReplayClock> clock)
      : device_(std::move(device)), clock_(std::move(clock)) {}

  const std::string& name() const override { return device_->name(); }
  double frame_rate_hz() const override { return device_->frame_rate_hz(); }
  Expected<std::optional<capture::Frame>> Grab() override;
  void Interrupt() override;

 private:
  std::unique_ptr<capture::CameraDevice> device_;
  std::shared_ptr<ReplayClock> clock_;
  std::atomic<bool> interrupted_{false};
};

}  // namespace rigcal::pipeline
