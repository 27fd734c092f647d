#pragma once
// PacedReplayDevice: replays a recording (an image folder) in real time on the host clock, so a
// live trigger generator can expose it: the recording's time runs from `epoch_ns` (CLOCK_MONOTONIC,
// e.g. the next trigger pulse), each frame is stamped epoch + (its recorded stamp - the first
// recorded stamp of any camera of the replay) and Grab returns it at that time.
//
// Threads: as the wrapped device (one capture thread per device; Interrupt from any thread).
// The cameras of one replay share a ReplayClock.

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "rigcal/drivers/capture_device.h"
#include "rigcal/drivers/v4l2_timestamp.h"

namespace rigcal::tools {

class ReplayClock {
 public:
  explicit ReplayClock(int64_t epoch_ns) : epoch_ns_(epoch_ns) {}
  // Host time of recorded stamp `t_ns`; the first call fixes the recording's origin.
  int64_t HostNs(int64_t t_ns) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!origin_ns_) origin_ns_ = t_ns;
    return epoch_ns_ + (t_ns - *origin_ns_);
  }

 private:
  const int64_t epoch_ns_;
  std::mutex mutex_;
  std::optional<int64_t> origin_ns_;
};

class PacedReplayDevice final : public drivers::CameraDevice {
 public:
  PacedReplayDevice(std::unique_ptr<drivers::CameraDevice> device,
                    std::shared_ptr<ReplayClock> clock)
      : device_(std::move(device)), clock_(std::move(clock)) {}

  const std::string& name() const override { return device_->name(); }
  double frame_rate_hz() const override { return device_->frame_rate_hz(); }
  Expected<std::optional<drivers::Frame>> Grab() override {
    Expected<std::optional<drivers::Frame>> grabbed = device_->Grab();
    if (!grabbed || !grabbed->has_value()) return grabbed;
    drivers::Frame& frame = **grabbed;
    frame.t_ns = clock_->HostNs(frame.t_ns);
    // Wait for the frame's time in short steps, so Interrupt is prompt.
    while (!interrupted_.load()) {
      const int64_t left = frame.t_ns - drivers::MonotonicNowNs();
      if (left <= 0) break;
      std::this_thread::sleep_for(std::chrono::nanoseconds(std::min<int64_t>(left, 20'000'000)));
    }
    if (interrupted_.load()) return std::optional<drivers::Frame>();
    return grabbed;
  }
  void Interrupt() override {
    interrupted_ = true;
    device_->Interrupt();
  }

 private:
  std::unique_ptr<drivers::CameraDevice> device_;
  std::shared_ptr<ReplayClock> clock_;
  std::atomic<bool> interrupted_{false};
};

}  // namespace rigcal::tools
