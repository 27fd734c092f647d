// SPDX-License-Identifier: Apache-2.0
#pragma once
// The simulated trigger generator as the TriggerTimeline of externally triggered cameras
// (rigcal/trigger/triggered_camera.h): a SimulatedTriggerStream (the firmware core, drift, delay
// jitter) driven in simulated time up to each frame's stamp, so simulated runs stay
// deterministic and need no thread.

#include <cstdint>
#include <memory>

#include "rigcal/base/status.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/sim/simulated_rig_spec.h"
#include "rigcal/sim/simulated_trigger.h"
#include "rigcal/trigger/trigger_link.h"
#include "rigcal/trigger/trigger_matcher.h"
#include "rigcal/trigger/trigger_receiver.h"
#include "rigcal/trigger/trigger_timeline.h"

namespace rigcal::sim {

// Create() applies the settings and runs until the first pulse (seq 0), whose true host time
// first_tick_ns() is tick 0: a simulated rig whose frame k is stamped first_tick_ns() + k / rate
// gets pulse seq k.
class SimulatedTriggerTimeline final : public trigger::TriggerTimeline {
 public:
  static Expected<std::unique_ptr<SimulatedTriggerTimeline>> Create(
      const trigger::TriggerSettings& settings, const SimulatedTriggerOptions& options,
      trigger::TriggerMatcherOptions matcher_options = {});

  void AdvanceTo(int64_t t_ns) override RIGCAL_EXCLUDES(mutex_);
  const trigger::TriggerMatcher& matcher() const override { return matcher_; }
  int64_t first_tick_ns() const { return first_tick_ns_; }

 private:
  explicit SimulatedTriggerTimeline(trigger::TriggerMatcherOptions matcher_options)
      : matcher_(matcher_options) {}
  trigger::TriggerMatcher matcher_;
  mutable Mutex mutex_;
  std::unique_ptr<trigger::TriggerSession> session_ RIGCAL_GUARDED_BY(mutex_);
  SimulatedTriggerStream* stream_ = nullptr;  // owned by the session
  int64_t first_tick_ns_ = 0;
};

// The trigger generator of a simulated rig with `source.trigger` (SimulatedRigSpec::Trigger):
// camera i on line i, at the rig's frame rate, the MCU booting at `start_host_ns`. Its
// first_tick_ns() is where the rig's frame 0 belongs (start_time_ns, or StartAt in realtime).
Expected<std::unique_ptr<SimulatedTriggerTimeline>> MakeSimulatedRigTrigger(
    const SimulatedRigSpec& spec, int64_t start_host_ns);

}  // namespace rigcal::sim
