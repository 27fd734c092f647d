// SPDX-License-Identifier: Apache-2.0
#pragma once
// TriggerMatcher: gives a frame of an externally triggered camera the trigger pulse that
// exposed it: its sequence number and its exposure-centred time on the host clock.
//
// It is fed with the trigger link's messages (OnMessage, from the link's thread): pulse reports
// (seq, T_k in MCU µs), heartbeats and Hellos. Every message is a clock sample for its
// TriggerClockMap (MCU µs -> host CLOCK_MONOTONIC ns). MCU time or seq going back (the Hello
// of a reboot does) is an MCU reset: the map restarts and the sequence continues, so `trigger_seq`
// never repeats or goes back (seq = the MCU's number + a base that jumps past every earlier
// number).
//
// Exposure feedback: for a line whose camera reports its exposure (TriggerLineSettings::
// exposure_input), the generator sends an ExposureReport {seq, line, measured start, duration}
// after each exposure. The matcher then uses the measured exposure centre instead of the
// scheduled one (T_k + phase offset): a camera that exposed late or for less than configured
// (auto exposure) gets the time it really exposed at. A camera with
// CameraTriggerSpec::exposure_feedback waits (kNotYet) for its pulse's measurement until a later
// pulse has arrived; then it takes the scheduled centre (counted: exposure_missing).
//
// A capture source asks Match(camera, stamp_ns) for each frame (any thread): the pulse whose
// expected stamp, mapped(T_k) + the line's phase offset + the camera's stamp offset (where in
// its exposure the driver stamps a frame: 0 for the middle, +exposure/2 for the end, plus any
// fixed latency), is nearest to `stamp_ns`, within `tolerance_ns`. The answer uses the map as it
// is at the time of the call (later samples refine it; pulses of an earlier MCU boot keep the
// time mapped when they arrived). A pulse report may arrive after the frame (serial and USB
// delay): Match then says kNotYet, and WaitMatch waits for it.
//
// Memory: a ring of `capacity` pulses. Thread-safe: every method locks.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/trigger/trigger_clock_map.h"
#include "rigcal/trigger_protocol/messages.h"

namespace rigcal::trigger {

struct TriggerMatcherOptions {
  int capacity = 512;                // pulses kept, [2, 1e6]
  int64_t tolerance_ns = 5'000'000;  // largest |stamp - expected stamp|, (0, 1 s]
  // true: a pulse's time is mapped once, with the map as it is when the pulse arrives, so a
  // frame's answer does not depend on how much later data has come in (deterministic runs on a
  // simulated link). false: with the newest map (more accurate for a live link).
  bool map_at_arrival = false;
  TriggerClockMapOptions clock;
  Status Check() const;
};

// How camera frames relate to the trigger.
struct CameraTriggerSpec {
  int line = 0;                 // the trigger line the camera hangs on, [0, 8)
  int64_t phase_offset_ns = 0;  // that line's phase offset (exposure centre - T_k)
  int64_t stamp_offset_ns = 0;  // frame stamp - exposure centre, as the driver stamps
  // The line reports the camera's measured exposure: wait for it (see the class comment).
  bool exposure_feedback = false;
};

struct TriggerMatch {
  int64_t seq = -1;         // continuous across MCU resets (see the class comment)
  int64_t centre_ns = 0;    // mapped exposure centre: mapped(T_k) + phase offset, host ns
  int64_t residual_ns = 0;  // stamp - expected stamp
  bool measured = false;    // centre_ns is the measured exposure centre (ExposureReport)
};

enum class MatchOutcome {
  kMatched,
  kNotYet,     // no pulse reported yet at or after the stamp: it may still arrive
  kNoPulse,    // pulses around the stamp are known, none within tolerance (a spurious frame)
  kNotSynced,  // the clock map has too few samples (after start or an MCU reset)
};

struct TriggerMatcherStats {
  int64_t pulses = 0;
  int64_t heartbeats = 0;
  int64_t mcu_resets = 0;  // MCU reboots: its clock or seq went back
  // The clock map started over on a run of samples earlier than it allows: a map fitted on
  // arrivals that were all late (a loaded host at the start), or an MCU clock that jumped ahead.
  int64_t map_restarts = 0;
  int64_t seq_gaps = 0;  // pulses missing between consecutive reports
  int64_t matched = 0;
  int64_t unmatched = 0;           // kNoPulse answers
  int64_t exposures = 0;           // ExposureReports that found their pulse
  int64_t exposures_orphaned = 0;  // ExposureReports whose pulse was not (or no longer) known
  int64_t measured_matches = 0;    // matches that used a measured exposure centre
  int64_t exposure_missing = 0;    // exposure_feedback matches that fell back to the schedule
  double drift_ppm = 0.0;          // current clock-map estimate
  bool synced = false;
};

class TriggerMatcher {
 public:
  explicit TriggerMatcher(TriggerMatcherOptions options = {});

  // One message from the link with its host receive time.
  void OnMessage(const trigger_protocol::Message& message, int64_t rx_ns) RIGCAL_EXCLUDES(mutex_);

  // The pulse of a frame stamped `stamp_ns` (host ns) of a camera on `camera`'s line.
  MatchOutcome Match(const CameraTriggerSpec& camera, int64_t stamp_ns, TriggerMatch* match) const
      RIGCAL_EXCLUDES(mutex_);
  // Match, waiting up to `timeout_ns` of steady time while the answer is kNotYet or kNotSynced.
  MatchOutcome WaitMatch(const CameraTriggerSpec& camera, int64_t stamp_ns, int64_t timeout_ns,
                         TriggerMatch* match) const RIGCAL_EXCLUDES(mutex_);

  // The mapped host time of MCU time `mcu_us` (nullopt before sync).
  std::optional<int64_t> MapMcuTime(uint64_t mcu_us) const RIGCAL_EXCLUDES(mutex_);
  TriggerMatcherStats stats() const RIGCAL_EXCLUDES(mutex_);

 private:
  struct Pulse {
    int64_t seq;
    uint64_t mcu_us;
    uint8_t line_mask;
    int boot;                   // MCU boot it belongs to
    int64_t mapped_ns;          // when it arrived (used once its boot is over), or -1
    uint8_t measured_mask = 0;  // lines with a measured exposure centre
    uint64_t centre_us[trigger_protocol::kMaxLines] = {};
  };
  void Restart() RIGCAL_REQUIRES(mutex_);
  void OnExposure(const trigger_protocol::ExposureReport& e) RIGCAL_REQUIRES(mutex_);
  // Host time of MCU time `mcu_us` as pulse `p` maps it (its boot's map or its arrival mapping).
  int64_t PulseTimeNs(const Pulse& p, uint64_t mcu_us) const RIGCAL_REQUIRES(mutex_);
  MatchOutcome MatchLocked(const CameraTriggerSpec& camera, int64_t stamp_ns,
                           TriggerMatch* match) const RIGCAL_REQUIRES(mutex_);

  const TriggerMatcherOptions options_;
  mutable Mutex mutex_;
  mutable std::condition_variable changed_;
  TriggerClockMap map_ RIGCAL_GUARDED_BY(mutex_);
  std::deque<Pulse> pulses_ RIGCAL_GUARDED_BY(mutex_);
  int boot_ RIGCAL_GUARDED_BY(mutex_) = 0;
  int64_t seq_base_ RIGCAL_GUARDED_BY(mutex_) = 0;   // added to the MCU's seq
  int64_t last_seq_ RIGCAL_GUARDED_BY(mutex_) = -1;  // continuous seq of the newest pulse
  int64_t last_mcu_seq_ RIGCAL_GUARDED_BY(mutex_) = -1;
  uint64_t last_mcu_us_ RIGCAL_GUARDED_BY(mutex_) = 0;
  mutable TriggerMatcherStats stats_ RIGCAL_GUARDED_BY(mutex_);
};

}  // namespace rigcal::trigger
