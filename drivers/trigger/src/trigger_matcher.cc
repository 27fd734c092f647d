// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger/trigger_matcher.h"

#include <chrono>
#include <cstdlib>

#include "rigcal/base/logging.h"

namespace rigcal::trigger {

using trigger_protocol::MessageType;

Status TriggerMatcherOptions::Check() const {
  if (capacity < 2 || capacity > 1'000'000) return Error{"capacity: must be in [2, 1000000]"};
  if (tolerance_ns <= 0 || tolerance_ns > 1'000'000'000) {
    return Error{"tolerance_ns: must be in (0, 1 s]"};
  }
  return clock.Check().Prefixed("clock");
}

TriggerMatcher::TriggerMatcher(TriggerMatcherOptions options)
    : options_(std::move(options)),
      map_((RequireValid(options_.Check(), "TriggerMatcherOptions"), options_.clock)) {}

void TriggerMatcher::Restart() {
  // Pulses of the ending boot keep the best mapping there will ever be for them.
  for (Pulse& p : pulses_) {
    if (p.boot == boot_) {
      if (std::optional<int64_t> t = map_.ToHostNs(p.mcu_us)) p.mapped_ns = *t;
    }
  }
  ++boot_;
  map_.Reset();
  seq_base_ = last_seq_ + 1;
  last_mcu_seq_ = -1;
  last_mcu_us_ = 0;
  ++stats_.mcu_resets;
  ModuleLogger("trigger")->warn(
      "trigger: the MCU restarted; clock mapping restarts, sequence "
      "continues at {}",
      seq_base_);
}

void TriggerMatcher::OnMessage(const trigger_protocol::Message& m, int64_t rx_ns) {
  if (m.type == MessageType::kExposureReport) {  // no clock sample: it carries no send time
    {
      MutexLock lock(mutex_);
      OnExposure(m.exposure);
    }
    changed_.notify_all();
    return;
  }
  {
    MutexLock lock(mutex_);
    uint64_t mcu_us = 0;
    switch (m.type) {
      case MessageType::kHello:
        mcu_us = m.hello.mcu_time_us;
        break;
      case MessageType::kPulseReport:
        mcu_us = m.pulse.mcu_time_us;
        break;
      case MessageType::kHeartbeat:
        mcu_us = m.heartbeat.mcu_time_us;
        ++stats_.heartbeats;
        break;
      default:
        return;  // answers carry no time
    }
    const bool went_back =
        mcu_us < last_mcu_us_ ||
        (m.type == MessageType::kPulseReport && last_mcu_seq_ >= 0 && m.pulse.seq <= last_mcu_seq_);
    if (went_back) Restart();  // a Hello after a reboot always goes back in MCU time
    last_mcu_us_ = mcu_us;
    if (map_.Add(mcu_us, rx_ns) == TriggerClockMap::SampleResult::kRestarted && !went_back) {
      ++boot_;  // the map started over: later pulses belong to a new epoch
      ++stats_.map_restarts;
    }
    if (m.type == MessageType::kPulseReport) {
      if (last_mcu_seq_ >= 0 && m.pulse.seq > last_mcu_seq_ + 1) {
        stats_.seq_gaps += m.pulse.seq - last_mcu_seq_ - 1;
      }
      last_mcu_seq_ = m.pulse.seq;
      last_seq_ = seq_base_ + m.pulse.seq;
      const std::optional<int64_t> mapped = map_.ToHostNs(mcu_us);
      pulses_.push_back({last_seq_, mcu_us, m.pulse.line_mask, boot_, mapped ? *mapped : -1});
      while (static_cast<int>(pulses_.size()) > options_.capacity) pulses_.pop_front();
      ++stats_.pulses;
    }
  }
  changed_.notify_all();
}

void TriggerMatcher::OnExposure(const trigger_protocol::ExposureReport& e) {
  if (e.line >= trigger_protocol::kMaxLines) return;
  const int64_t seq = seq_base_ + e.seq;  // the report follows its pulse within one boot
  for (auto it = pulses_.rbegin(); it != pulses_.rend(); ++it) {
    if (it->seq < seq || it->boot != boot_) break;
    if (it->seq == seq) {
      it->measured_mask = static_cast<uint8_t>(it->measured_mask | (1u << e.line));
      it->centre_us[e.line] = e.CentreUs();
      ++stats_.exposures;
      return;
    }
  }
  ++stats_.exposures_orphaned;
}

int64_t TriggerMatcher::PulseTimeNs(const Pulse& p, uint64_t mcu_us) const {
  if (p.boot == boot_ && !options_.map_at_arrival) {
    if (std::optional<int64_t> t = map_.ToHostNs(mcu_us)) return *t;
    return -1;
  }
  if (p.mapped_ns < 0) return -1;
  // Near the pulse, the nominal slope (1000 ns per µs) is off by the drift only (< 0.1 µs).
  return p.mapped_ns + (static_cast<int64_t>(mcu_us) - static_cast<int64_t>(p.mcu_us)) * 1000;
}

MatchOutcome TriggerMatcher::MatchLocked(const CameraTriggerSpec& camera, int64_t stamp_ns,
                                         TriggerMatch* match) const {
  const Pulse* best = nullptr;
  const Pulse* newest = nullptr;
  int64_t best_distance = INT64_MAX;
  int64_t best_expected = 0;
  bool best_measured = false;
  int64_t newest_expected = INT64_MIN;
  bool any_mapped = false;
  const uint8_t bit = static_cast<uint8_t>(1u << camera.line);
  for (auto it = pulses_.rbegin(); it != pulses_.rend(); ++it) {
    const Pulse& p = *it;
    if ((p.line_mask & bit) == 0) continue;
    if (newest == nullptr) newest = &p;
    const bool measured = (p.measured_mask & bit) != 0;
    // The measured exposure centre when the generator reported one, else the scheduled one.
    const int64_t t =
        measured ? PulseTimeNs(p, p.centre_us[camera.line]) : PulseTimeNs(p, p.mcu_us);
    if (t < 0) continue;
    any_mapped = true;
    const int64_t expected = t + (measured ? 0 : camera.phase_offset_ns) + camera.stamp_offset_ns;
    newest_expected = std::max(newest_expected, expected);
    const int64_t distance = std::llabs(stamp_ns - expected);
    if (distance < best_distance) {
      best = &p;
      best_distance = distance;
      best_expected = expected;
      best_measured = measured;
    }
    if (expected < stamp_ns - options_.tolerance_ns && best_distance <= options_.tolerance_ns) {
      break;  // older pulses are further away
    }
  }
  if (!any_mapped) return map_.synced() ? MatchOutcome::kNotYet : MatchOutcome::kNotSynced;
  if (best != nullptr && best_distance <= options_.tolerance_ns) {
    if (camera.exposure_feedback && !best_measured) {
      // Its measurement may still come, until a later pulse of the line has arrived.
      if (best == newest) return MatchOutcome::kNotYet;
      ++stats_.exposure_missing;
    }
    if (best_measured) ++stats_.measured_matches;
    match->seq = best->seq;
    match->centre_ns = best_expected - camera.stamp_offset_ns;
    match->residual_ns = stamp_ns - best_expected;
    match->measured = best_measured;
    return MatchOutcome::kMatched;
  }
  if (newest_expected < stamp_ns + options_.tolerance_ns) return MatchOutcome::kNotYet;
  return MatchOutcome::kNoPulse;
}

MatchOutcome TriggerMatcher::Match(const CameraTriggerSpec& camera, int64_t stamp_ns,
                                   TriggerMatch* match) const {
  MutexLock lock(mutex_);
  const MatchOutcome outcome = MatchLocked(camera, stamp_ns, match);
  if (outcome == MatchOutcome::kMatched) ++stats_.matched;
  if (outcome == MatchOutcome::kNoPulse) ++stats_.unmatched;
  return outcome;
}

MatchOutcome TriggerMatcher::WaitMatch(const CameraTriggerSpec& camera, int64_t stamp_ns,
                                       int64_t timeout_ns, TriggerMatch* match) const {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::nanoseconds(timeout_ns);
  MutexLock lock(mutex_);
  while (true) {
    const MatchOutcome outcome = MatchLocked(camera, stamp_ns, match);
    if (outcome == MatchOutcome::kMatched || outcome == MatchOutcome::kNoPulse ||
        lock.WaitUntil(changed_, deadline) == std::cv_status::timeout) {
      const MatchOutcome final_outcome =
          outcome == MatchOutcome::kMatched || outcome == MatchOutcome::kNoPulse
              ? outcome
              : MatchLocked(camera, stamp_ns, match);
      if (final_outcome == MatchOutcome::kMatched) ++stats_.matched;
      if (final_outcome == MatchOutcome::kNoPulse) ++stats_.unmatched;
      return final_outcome;
    }
  }
}

std::optional<int64_t> TriggerMatcher::MapMcuTime(uint64_t mcu_us) const {
  MutexLock lock(mutex_);
  return map_.ToHostNs(mcu_us);
}

TriggerMatcherStats TriggerMatcher::stats() const {
  MutexLock lock(mutex_);
  TriggerMatcherStats s = stats_;
  s.drift_ppm = map_.drift_ppm();
  s.synced = map_.synced();
  return s;
}

}  // namespace rigcal::trigger
