// SPDX-License-Identifier: Apache-2.0
// TriggeredCamera: a capture device's frames with their trigger pulse. Its counters matched_,
// unmatched_, late_reports_ and unsynced_ are std::atomic: the capture thread counts, any thread
// reads.
#include "rigcal/trigger/triggered_camera.h"

#include <algorithm>

#include "rigcal/base/logging.h"

namespace rigcal::trigger {

TriggeredCamera::TriggeredCamera(std::unique_ptr<capture::CameraDevice> device,
                                 std::shared_ptr<TriggerTimeline> trigger, CameraTriggerSpec spec,
                                 int64_t wait_ns)
    : device_(std::move(device)), trigger_(std::move(trigger)), spec_(spec), wait_ns_(wait_ns) {}

Expected<std::optional<capture::Frame>> TriggeredCamera::Grab() {
  Expected<std::optional<capture::Frame>> grabbed = device_->Grab();
  if (!grabbed || !grabbed->has_value()) return grabbed;
  capture::Frame& frame = **grabbed;
  // Reports arrive after their pulse: let the link catch up past the frame's stamp.
  trigger_->AdvanceTo(frame.t_ns + wait_ns_);
  TriggerMatch m;
  const MatchOutcome outcome = trigger_->matcher().WaitMatch(spec_, frame.t_ns, wait_ns_, &m);
  if (outcome == MatchOutcome::kMatched) {
    frame.seq = m.seq;
    frame.t_ns = m.centre_ns;
    ++matched_;
  } else {
    frame.seq = -1;
    if (outcome == MatchOutcome::kNotYet) ++late_reports_;
    if (outcome == MatchOutcome::kNotSynced) ++unsynced_;
    if (++unmatched_ == 1 || unmatched_ % 100 == 0) {
      ModuleLogger("trigger")->warn(
          "{}: {} frames without a trigger pulse ({} because the pulse report came more than {} "
          "ms after the frame, {} while the clock map was not synced)",
          name(), unmatched_.load(), late_reports_.load(), wait_ns_ / 1'000'000, unsynced_.load());
    }
  }
  return grabbed;
}

}  // namespace rigcal::trigger
