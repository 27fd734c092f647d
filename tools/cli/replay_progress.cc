// SPDX-License-Identifier: Apache-2.0
#include "replay_progress.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rigcal::cli {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kBarWidth = 30;
constexpr auto kLinePeriod = std::chrono::seconds(5);

}  // namespace

std::string ClockText(double seconds) {
  const auto s = static_cast<long long>(std::llround(std::max(0.0, seconds)));
  char text[32];
  if (s >= 3600) {
    std::snprintf(text, sizeof(text), "%lld:%02lld:%02lld", s / 3600, s / 60 % 60, s % 60);
  } else {
    std::snprintf(text, sizeof(text), "%lld:%02lld", s / 60, s % 60);
  }
  return text;
}

ReplayProgressDisplay::ReplayProgressDisplay(std::string label)
    : label_(std::move(label)), start_(Clock::now()), next_line_(start_ + kLinePeriod) {}

void ReplayProgressDisplay::Update(const pipeline::ReplayProgress& p) {
  const double fraction =
      p.log_bytes > 0 ? std::clamp(static_cast<double>(p.bytes_read) / p.log_bytes, 0.0, 1.0) : 1.0;
  const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
  // Too early to extrapolate below 1 % or within the first second.
  std::string eta = "ETA ?";
  if (p.done) {
    eta = "done";
  } else if (fraction >= 0.01 && elapsed >= 1.0) {
    eta = "ETA " + ClockText(elapsed * (1.0 - fraction) / fraction);
  }
  char figures[160];
  std::snprintf(figures, sizeof(figures), "%3.0f%% %.1f/%.1f MB  log %s  %llu sets  %s  %s",
                100.0 * fraction, p.bytes_read / 1e6, p.log_bytes / 1e6,
                ClockText(p.log_time_s).c_str(), static_cast<unsigned long long>(p.sets),
                ClockText(elapsed).c_str(), eta.c_str());
  if (line_.tty()) {
    const int filled = static_cast<int>(fraction * kBarWidth);
    std::string bar(static_cast<size_t>(filled), '#');
    bar.resize(kBarWidth, '.');
    line_.Show(label_ + " [" + bar + "] " + figures, p.done);
    return;
  }
  if (p.done || Clock::now() >= next_line_) {
    line_.Show(label_ + ": " + figures, p.done);
    next_line_ = Clock::now() + kLinePeriod;
  }
}

}  // namespace rigcal::cli
