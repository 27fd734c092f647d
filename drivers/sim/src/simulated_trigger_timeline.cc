// SPDX-License-Identifier: Apache-2.0
// SimulatedTriggerTimeline: the simulated trigger generator driven up to each frame's stamp, and
// the generator of a simulated rig.
#include "rigcal/sim/simulated_trigger_timeline.h"

#include <algorithm>

#include "rigcal/base/logging.h"

namespace rigcal::sim {

Expected<std::unique_ptr<SimulatedTriggerTimeline>> SimulatedTriggerTimeline::Create(
    const trigger::TriggerSettings& settings, const SimulatedTriggerOptions& options,
    trigger::TriggerMatcherOptions matcher_options) {
  if (Status s = options.Check(); !s.ok()) return Error{"simulated trigger: " + s.message()};
  if (Status s = matcher_options.Check(); !s.ok()) return Error{"trigger matcher: " + s.message()};
  std::unique_ptr<SimulatedTriggerTimeline> t(new SimulatedTriggerTimeline(matcher_options));
  auto stream = std::make_unique<SimulatedTriggerStream>(options);
  t->stream_ = stream.get();
  MutexLock lock(t->mutex_);
  t->session_ =
      std::make_unique<trigger::TriggerSession>(std::move(stream), settings, &t->matcher_);
  bool first = false;
  uint64_t first_mcu_us = 0;
  t->session_->set_observer([&](const trigger::TriggerEvent& e) {
    if (!first && e.message.type == trigger_protocol::MessageType::kPulseReport) {
      first = true;
      // Tick 0's time, even if the first reports were lost: T_k = T_0 + floor(k * 1e9 / mHz).
      first_mcu_us = e.message.pulse.mcu_time_us -
                     uint64_t{e.message.pulse.seq} * 1'000'000'000ull / settings.RateMilliHz();
    }
  });
  if (Status s = t->session_->Start(); !s.ok()) return Error{"simulated trigger: " + s.message()};
  const int64_t give_up = t->stream_->NowNs() + 20'000'000'000;
  while (!first && t->stream_->NowNs() < give_up) {
    if (Status s = t->session_->Pump(100); !s.ok()) {
      return Error{"simulated trigger: " + s.message()};
    }
  }
  if (!first) return Error{"simulated trigger: no pulse within 20 s"};
  t->session_->set_observer(nullptr);
  t->first_tick_ns_ = t->stream_->TrueHostNs(t->stream_->boot(), first_mcu_us);
  return t;
}

void SimulatedTriggerTimeline::AdvanceTo(int64_t t_ns) {
  MutexLock lock(mutex_);
  while (stream_->NowNs() < t_ns) {
    const int64_t left_ms = (t_ns - stream_->NowNs() + 999'999) / 1'000'000;
    if (Status s = session_->Pump(static_cast<int>(std::min<int64_t>(left_ms, 100))); !s.ok()) {
      ModuleLogger("sim")->error("simulated trigger: {}", s.message());
      return;
    }
  }
}

Expected<std::unique_ptr<SimulatedTriggerTimeline>> MakeSimulatedRigTrigger(
    const SimulatedRigSpec& spec, int64_t start_host_ns) {
  trigger::TriggerSettings settings;
  settings.rate_hz = spec.frame_rate_hz;
  const int64_t period_us = static_cast<int64_t>(1e6 / spec.frame_rate_hz);
  for (size_t i = 0; i < spec.names.size(); ++i) {
    settings.lines.push_back({static_cast<int>(i), std::min<int64_t>(1000, period_us / 2), 0,
                              static_cast<int64_t>(spec.trigger.exposure_ms * 1000.0)});
  }
  SimulatedTriggerOptions link;
  link.start_host_ns = link.boot_host_ns = start_host_ns;
  link.drift_ppm = spec.trigger.drift_ppm;
  link.delay_jitter_ns = static_cast<int64_t>(spec.trigger.link_jitter_ms * 1e6);
  link.corrupt_probability = spec.trigger.corrupt_probability;
  link.seed = spec.seed;
  trigger::TriggerMatcherOptions matcher;
  matcher.map_at_arrival = true;  // capture threads race: keep lossless runs deterministic
  return SimulatedTriggerTimeline::Create(settings, link, matcher);
}

}  // namespace rigcal::sim
