// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger/trigger_clock_map.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace rigcal::trigger {

Status TriggerClockMapOptions::Check() const {
  if (window_samples < 8 || window_samples > 100'000) {
    return Error{"window_samples: must be in [8, 100000]"};
  }
  if (window_span_us <= 0 || window_span_us > 3'600'000'000) {
    return Error{"window_span_us: must be in (0, 1 h]"};
  }
  if (min_span_us < 0 || min_span_us > window_span_us) {
    return Error{"min_span_us: must be in [0, window_span_us]"};
  }
  if (prior_span_us < min_span_us || prior_span_us > window_span_us) {
    return Error{"prior_span_us: must be in [min_span_us, window_span_us]"};
  }
  if (min_samples < 1 || min_samples > window_samples) {
    return Error{"min_samples: must be in [1, window_samples]"};
  }
  if (!(max_drift_ppm > 0.0 && max_drift_ppm <= 10'000.0)) {
    return Error{"max_drift_ppm: must be in (0, 10000]"};
  }
  if (max_early_us <= 0) return Error{"max_early_us: must be > 0"};
  if (reset_after_early < 1) return Error{"reset_after_early: must be >= 1"};
  return Status::Ok();
}

TriggerClockMap::TriggerClockMap(TriggerClockMapOptions options) : options_(options) {
  RequireValid(options_.Check(), "TriggerClockMapOptions");
}

void TriggerClockMap::Reset() {
  // The crystal is the same after a reboot: its drift is a good slope until the new window
  // is long enough to fit its own.
  if (drift_fitted_) prior_b_ = slope_ - 1000.0;
  window_.clear();
  early_run_ = 0;
  drift_fitted_ = false;
  ++resets_;
}

bool TriggerClockMap::synced() const {
  return static_cast<int>(window_.size()) >= options_.min_samples;
}

TriggerClockMap::SampleResult TriggerClockMap::Add(uint64_t mcu_us, int64_t host_ns) {
  SampleResult result = SampleResult::kAdded;
  if (!window_.empty() && mcu_us < window_.back().mcu_us) {
    Reset();  // the MCU restarted (its clock went back)
    result = SampleResult::kRestarted;
  }
  if (synced()) {
    const double below_ns = static_cast<double>(*ToHostNs(mcu_us) - host_ns);
    if (below_ns > 1000.0 * static_cast<double>(options_.max_early_us)) {
      if (++early_run_ < options_.reset_after_early) {
        ++rejected_;
        return SampleResult::kRejectedEarly;
      }
      Reset();  // the MCU clock jumped: start over from this sample
      result = SampleResult::kRestarted;
    }
  }
  early_run_ = 0;
  window_.push_back({mcu_us, host_ns});
  while (static_cast<int>(window_.size()) > options_.window_samples ||
         window_.back().mcu_us - window_.front().mcu_us >
             static_cast<uint64_t>(options_.window_span_us)) {
    window_.pop_front();
  }
  Fit();
  return result;
}

void TriggerClockMap::Fit() {
  // Relative coordinates: x in µs from the first sample, y in ns minus the nominal slope, so
  // doubles keep sub-ns resolution.
  ref_mcu_us_ = window_.front().mcu_us;
  ref_host_ns_ = window_.front().host_ns;
  const size_t n = window_.size();
  std::vector<double> xs(n), ys(n);
  double mean_x = 0.0;
  for (size_t i = 0; i < n; ++i) {
    xs[i] = static_cast<double>(window_[i].mcu_us - ref_mcu_us_);
    ys[i] = static_cast<double>(window_[i].host_ns - ref_host_ns_) - 1000.0 * xs[i];
    mean_x += xs[i];
  }
  mean_x /= static_cast<double>(n);
  const double span = xs.back();
  double a = 0.0;  // residual line y = a + b x (b: ns per µs beyond nominal)
  double b = 0.0;
  const double needed =
      static_cast<double>(prior_b_ ? options_.prior_span_us : options_.min_span_us);
  drift_fitted_ = span >= needed && n >= 2;
  if (drift_fitted_) {
    // Lower convex hull (monotone chain; x is non-decreasing).
    std::vector<size_t> hull;
    for (size_t i = 0; i < n; ++i) {
      if (!hull.empty() && xs[i] == xs[hull.back()]) {
        if (ys[i] >= ys[hull.back()]) continue;
        hull.pop_back();
      }
      while (hull.size() >= 2) {
        const size_t p = hull[hull.size() - 2], q = hull.back();
        const double cross = (xs[q] - xs[p]) * (ys[i] - ys[p]) - (ys[q] - ys[p]) * (xs[i] - xs[p]);
        if (cross > 0.0) break;  // left turn: q stays on the lower hull
        hull.pop_back();
      }
      hull.push_back(i);
    }
    // The hull edge spanning the mean x minimises the summed height above the line.
    size_t k = 0;
    while (k + 2 < hull.size() && xs[hull[k + 1]] < mean_x) ++k;
    if (hull.size() >= 2) {
      const size_t p = hull[k], q = hull[k + 1];
      b = (ys[q] - ys[p]) / (xs[q] - xs[p]);
      const double max_b = 1000.0 * options_.max_drift_ppm * 1e-6;
      b = std::clamp(b, -max_b, max_b);
      a = ys[p] - b * xs[p];
      // After clamping the line may cut a sample: lower it onto the hull.
      for (size_t i : hull) a = std::min(a, ys[i] - b * xs[i]);
    } else {
      drift_fitted_ = false;
    }
  }
  if (!drift_fitted_) {
    b = prior_b_.value_or(0.0);
    a = ys[0];
    for (size_t i = 0; i < n; ++i) a = std::min(a, ys[i] - b * xs[i]);
  }
  intercept_ns_ = a;
  slope_ = 1000.0 + b;
  drift_ppm_ = (1000.0 / slope_ - 1.0) * 1e6;  // MCU rate error: fast = positive
}

std::optional<int64_t> TriggerClockMap::ToHostNs(uint64_t mcu_us) const {
  if (!synced()) return std::nullopt;
  const double dx = mcu_us >= ref_mcu_us_ ? static_cast<double>(mcu_us - ref_mcu_us_)
                                          : -static_cast<double>(ref_mcu_us_ - mcu_us);
  return ref_host_ns_ + static_cast<int64_t>(std::llround(intercept_ns_ + slope_ * dx));
}

}  // namespace rigcal::trigger
