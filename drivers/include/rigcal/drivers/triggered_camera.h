#pragma once
// Externally triggered cameras: a capture source whose frames are exposed by the trigger
// generator's pulses gets, for every frame, the pulse's sequence number and its mapped,
// exposure-centred time (TriggerMatcher), so the SyncBuffer can match sets by trigger
// sequence (sync.match_by_trigger_seq) and every camera carries the same time for one pulse.
//
// TriggerTimeline: where the trigger messages come from. A live link (TriggerReceiver's
// thread) delivers them by itself; a simulated link (SimulatedTriggerTimeline) is advanced on
// demand to the frame's time, so simulated runs stay deterministic and need no thread.
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
#include "rigcal/base/thread_annotations.h"
#include "rigcal/drivers/capture_device.h"
#include "rigcal/drivers/simulated_rig_spec.h"
#include "rigcal/drivers/simulated_trigger.h"
#include "rigcal/drivers/trigger_matcher.h"
#include "rigcal/drivers/trigger_receiver.h"

namespace rigcal::drivers {

class TriggerTimeline {
 public:
  virtual ~TriggerTimeline() = default;
  // Delivers every trigger message the host will have received by host time `t_ns` to the
  // matcher (a no-op for a live link, whose thread does it). Thread-safe.
  virtual void AdvanceTo(int64_t t_ns) = 0;
  virtual const TriggerMatcher& matcher() const = 0;
};

// A simulated trigger generator (SimulatedTriggerStream: the firmware core, drift, delay
// jitter) driven in simulated time up to each frame's stamp. Create() applies the settings and
// runs until the first pulse (seq 0), whose true host time first_tick_ns() is tick 0: a
// simulated rig whose frame k is stamped first_tick_ns() + k / rate gets pulse seq k.
class SimulatedTriggerTimeline final : public TriggerTimeline {
 public:
  static Expected<std::unique_ptr<SimulatedTriggerTimeline>> Create(
      const TriggerSettings& settings, const SimulatedTriggerOptions& options,
      TriggerMatcherOptions matcher_options = {});

  void AdvanceTo(int64_t t_ns) override RIGCAL_EXCLUDES(mutex_);
  const TriggerMatcher& matcher() const override { return matcher_; }
  int64_t first_tick_ns() const { return first_tick_ns_; }

 private:
  explicit SimulatedTriggerTimeline(TriggerMatcherOptions matcher_options)
      : matcher_(std::move(matcher_options)) {}
  TriggerMatcher matcher_;
  mutable Mutex mutex_;
  std::unique_ptr<TriggerSession> session_ RIGCAL_GUARDED_BY(mutex_);
  SimulatedTriggerStream* stream_ = nullptr;  // owned by the session
  int64_t first_tick_ns_ = 0;
};

// The trigger generator of a simulated rig with `source.trigger` (SimulatedRigSpec::Trigger):
// camera i on line i, at the rig's frame rate, the MCU booting at `start_host_ns`. Its
// first_tick_ns() is where the rig's frame 0 belongs (start_time_ns, or StartAt in realtime).
Expected<std::unique_ptr<SimulatedTriggerTimeline>> MakeSimulatedRigTrigger(
    const SimulatedRigSpec& spec, int64_t start_host_ns);

// A CameraDevice whose frames get their trigger pulse: seq = the pulse's continuous sequence
// number, t_ns = the mapped exposure centre (plus the line's phase offset). A frame without a
// pulse within the matcher's tolerance (or whose pulse did not arrive within `wait_ns`) keeps
// its stamp and gets seq -1 (counted by unmatched()).
// Threads: as the wrapped device (one capture thread; Interrupt from any thread).
class TriggeredCamera final : public CameraDevice {
 public:
  TriggeredCamera(std::unique_ptr<CameraDevice> device, std::shared_ptr<TriggerTimeline> trigger,
                  CameraTriggerSpec spec, int64_t wait_ns = 50'000'000);

  const std::string& name() const override { return device_->name(); }
  double frame_rate_hz() const override { return device_->frame_rate_hz(); }
  Expected<std::optional<Frame>> Grab() override;
  void Interrupt() override { device_->Interrupt(); }

  int64_t matched() const { return matched_.load(); }
  int64_t unmatched() const { return unmatched_.load(); }

 private:
  std::unique_ptr<CameraDevice> device_;
  std::shared_ptr<TriggerTimeline> trigger_;
  CameraTriggerSpec spec_;
  int64_t wait_ns_;
  std::atomic<int64_t> matched_{0};
  std::atomic<int64_t> unmatched_{0};
};

}  // namespace rigcal::drivers
