// SPDX-License-Identifier: Apache-2.0
#pragma once
// TriggerClockMap: maps the trigger MCU's clock (µs since its boot) to the host's
// CLOCK_MONOTONIC (ns) from (MCU send time, host receive time) samples: every pulse report and
// heartbeat carries the MCU time at which it was sent (never earlier, messages.h) and the link
// stamps its arrival.
//
// Model: host_ns = offset + slope * mcu_us, slope = 1000 * (1 + drift). The transport delay
// (UART, USB polling, scheduling) is one-sided: arrival = true host time + delay, delay >= 0.
// So the true line lies BELOW every sample, and the best estimate is the lower envelope:
// the line minimising the summed height of the samples above it subject to lying below all of
// them (Moon, Skelly & Towsley, "Estimation and removal of clock skew from network delay
// measurements", 1999). Its solution is the edge of the samples' lower convex hull that spans
// their mean MCU time: linear in the window size, no tuning, and immune to any number of late
// (delayed) samples: outliers above the line never touch it.
//
// Window: the last `window_samples` samples within `window_span_us` of MCU time (drift wanders
// with temperature). Below `min_span_us` of data the slope is not fitted: the nominal slope
// (drift 0) through the lowest sample is used, whose error grows by drift x span. After an MCU
// reboot the previous fit's drift is used instead until `prior_span_us`: re-sync then needs only
// the offset, i.e. a few of the smallest delays.
//
// Early samples (below the line) cannot come from delay. One more than `max_early_us` below
// the current fit is rejected (a host stamp from the wrong clock, a corrupt message that passed
// the CRC); `reset_after_early` consecutive ones mean the MCU clock jumped: the window restarts.
// An MCU reset (its time goes backwards, or Reset() on its Hello) restarts the window too
// (resets() counts them).
//
// Not thread-safe: one owner (TriggerMatcher locks around it).

#include <cstdint>
#include <deque>
#include <optional>

#include "rigcal/base/status.h"

namespace rigcal::trigger {

struct TriggerClockMapOptions {
  int window_samples = 4000;            // [8, 100000]
  int64_t window_span_us = 60'000'000;  // (0, 1 h]
  int64_t min_span_us = 2'000'000;      // [0, window_span_us]: below, slope fixed at nominal
  // After an MCU reboot the drift fitted before it is kept until the new window spans this
  // (the crystal is the same): [min_span_us, window_span_us].
  int64_t prior_span_us = 20'000'000;
  int min_samples = 4;            // [1, window_samples]: mapping available from here
  double max_drift_ppm = 1000.0;  // (0, 10000]: a fitted slope is clamped to this
  int64_t max_early_us = 1000;    // > 0
  int reset_after_early = 3;      // >= 1
  Status Check() const;
};

class TriggerClockMap {
 public:
  enum class SampleResult { kAdded, kRejectedEarly, kRestarted };

  explicit TriggerClockMap(TriggerClockMapOptions options = {});

  // One sample: MCU time (µs) and host receive time (ns). MCU times must increase within an
  // MCU boot; a smaller one restarts the window (kRestarted).
  SampleResult Add(uint64_t mcu_us, int64_t host_ns);
  // Forgets every sample (the MCU restarted: its Hello). Counts a reset.
  void Reset();

  // Enough samples (min_samples) since the last reset.
  bool synced() const;
  // Host CLOCK_MONOTONIC ns of MCU time `mcu_us` (extrapolated when outside the window);
  // nullopt before synced().
  std::optional<int64_t> ToHostNs(uint64_t mcu_us) const;
  // The fitted drift of the MCU clock against the host, ppm (MCU fast = positive), and whether
  // it was fitted (span >= min_span_us) or assumed 0.
  double drift_ppm() const { return drift_ppm_; }
  bool drift_fitted() const { return drift_fitted_; }
  size_t samples() const { return window_.size(); }
  int resets() const { return resets_; }
  int64_t rejected() const { return rejected_; }

 private:
  struct Sample {
    uint64_t mcu_us;
    int64_t host_ns;
  };
  void Fit();

  TriggerClockMapOptions options_;
  std::deque<Sample> window_;
  // host_ns = ref_host_ns_ + intercept_ns_ + slope_ * (mcu_us - ref_mcu_us_)
  uint64_t ref_mcu_us_ = 0;
  int64_t ref_host_ns_ = 0;
  double intercept_ns_ = 0.0;
  double slope_ = 1000.0;  // ns per µs
  double drift_ppm_ = 0.0;
  bool drift_fitted_ = false;
  std::optional<double> prior_b_;  // slope - 1000 fitted before the last reset
  int early_run_ = 0;
  int resets_ = 0;
  int64_t rejected_ = 0;
};

}  // namespace rigcal::trigger
