// SPDX-License-Identifier: Apache-2.0
#pragma once
// Externally triggered cameras: a capture source whose frames are exposed by the trigger
// generator's pulses gets, for every frame, the pulse's sequence number and its mapped,
// exposure-centred time (TriggerMatcher), so the SyncBuffer can match sets by trigger
// sequence (sync.match_by_trigger_seq) and every camera carries the same time for one pulse.
//
// Hooking up a capture source (V4L2, libcamera): wrap its CameraDevice in a TriggeredCamera,
// or call the matcher directly from the capture thread:
//     TriggerMatch m;
//     if (matcher.WaitMatch(spec, frame.t_ns, wait_ns, &m) == MatchOutcome::kMatched) {
//       frame.seq = m.seq;  frame.t_ns = m.centre_ns;
//     }
// with `spec` = {trigger line of the camera, that line's phase offset, where the driver stamps
// the frame relative to the exposure centre: e.g. +exposure/2 for a V4L2 end-of-frame stamp}.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/capture/capture_device.h"
#include "rigcal/trigger/trigger_matcher.h"
#include "rigcal/trigger/trigger_timeline.h"

namespace rigcal::trigger {

// A CameraDevice whose frames get their trigger pulse: seq = the pulse's continuous sequence
// number, t_ns = the mapped exposure centre (plus the line's phase offset). A frame without a
// pulse within the matcher's tolerance (or whose pulse did not arrive within `wait_ns`) keeps
// its stamp and gets seq -1 (counted by unmatched()). Of those, late_reports() counts the frames
// whose pulse report had not arrived `wait_ns` after the frame (no later pulse was known either:
// a busy host or a slow link, not a spurious frame), unsynced() those that came while the clock
// map had too few samples to map a pulse (after the start, an MCU reset or a map restart).
// Threads: as the wrapped device (one capture thread; Interrupt from any thread).
class TriggeredCamera final : public capture::CameraDevice {
 public:
  TriggeredCamera(std::unique_ptr<capture::CameraDevice> device,
                  std::shared_ptr<TriggerTimeline> trigger, CameraTriggerSpec spec,
                  int64_t wait_ns = 50'000'000);

  const std::string& name() const override { return device_->name(); }
  double frame_rate_hz() const override { return device_->frame_rate_hz(); }
  Expected<std::optional<capture::Frame>> Grab() override;
  void Interrupt() override { device_->Interrupt(); }

  int64_t matched() const { return matched_.load(); }
  int64_t unmatched() const { return unmatched_.load(); }
  int64_t late_reports() const { return late_reports_.load(); }
  int64_t unsynced() const { return unsynced_.load(); }
  int64_t wait_ns() const { return wait_ns_; }

 private:
  std::unique_ptr<capture::CameraDevice> device_;
  std::shared_ptr<TriggerTimeline> trigger_;
  CameraTriggerSpec spec_;
  int64_t wait_ns_;
  std::atomic<int64_t> matched_{0};
  std::atomic<int64_t> unmatched_{0};
  std::atomic<int64_t> late_reports_{0};
  std::atomic<int64_t> unsynced_{0};
};

}  // namespace rigcal::trigger
