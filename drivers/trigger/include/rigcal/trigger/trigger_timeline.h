// SPDX-License-Identifier: Apache-2.0
#pragma once
// TriggerTimeline: where the trigger messages of externally triggered cameras come from. A live
// link (LiveTriggerTimeline: TriggerReceiver's thread) delivers them by itself; a simulated link
// (rigcal/sim/simulated_trigger_timeline.h) is advanced on demand to the frame's time, so
// simulated runs stay deterministic and need no thread.

#include <cstdint>

#include "rigcal/trigger/trigger_matcher.h"

namespace rigcal::trigger {

class TriggerTimeline {
 public:
  virtual ~TriggerTimeline() = default;
  // Delivers every trigger message the host will have received by host time `t_ns` to the
  // matcher (a no-op for a live link, whose thread does it). Thread-safe.
  virtual void AdvanceTo(int64_t t_ns) = 0;
  virtual const TriggerMatcher& matcher() const = 0;
};

}  // namespace rigcal::trigger
