// SPDX-License-Identifier: Apache-2.0
#pragma once
// PacedReplayDevice: replays a recording (an image folder) in real time on the host clock, so a
// live trigger generator can expose it: each frame is stamped at the ReplayClock's host time of
// (its recorded stamp - the first recorded stamp any camera of the replay grabbed) and Grab
// returns it at that time. The clock is the trigger generator's from a tick (trigger::TickClock:
// the frames move with the pulses when the clock map moves).
//
// A frame stamped more than MaxGapNs() after the previous one of its camera is not waited for:
// Grab returns an error naming the gap (a glitched stamp, e.g. 4e18 ns, would otherwise be waited
// for until a signal), and the capture loop reports the camera as dead.
//
// Threads: as the wrapped device (one capture thread per device; Interrupt from any thread).
// The cameras of one replay share a ReplayClock (thread-safe).

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

#include "rigcal/base/status.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/capture/capture_device.h"

namespace rigcal::pipeline {

class ReplayClock {
 public:
  // The host time of a time since the recording's origin (e.g. a trigger::TickClock's).
  using HostNsSince = std::function<int64_t(int64_t since_origin_ns)>;

  // The recording's time runs on `host_ns_since`, asked at every frame.
  explicit ReplayClock(HostNsSince host_ns_since) : host_ns_since_(std::move(host_ns_since)) {}

  // Host time of recorded stamp `t_ns`; the first call fixes the recording's origin.
  int64_t HostNs(int64_t t_ns) RIGCAL_EXCLUDES(mutex_);

 private:
  const HostNsSince host_ns_since_;
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

  // The longest gap between two consecutive frames that the replay waits through: 100 frame
  // periods, at least 10 s (a recording paused for a while is replayed as it was; a stamp
  // further ahead is taken for a glitch).
  int64_t MaxGapNs() const;

 private:
  // Error when `t_ns` (recorded) lies more than MaxGapNs() after the previous frame's stamp.
  Status CheckGap(int64_t t_ns) const;

  std::unique_ptr<capture::CameraDevice> device_;
  std::shared_ptr<ReplayClock> clock_;
  std::atomic<bool> interrupted_{false};
  int64_t frames_ = 0;                           // frames grabbed (the capture thread only)
  std::optional<int64_t> previous_recorded_ns_;  // the previous frame's recorded stamp
};

}  // namespace rigcal::pipeline
