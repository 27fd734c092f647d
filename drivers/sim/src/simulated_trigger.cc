// SPDX-License-Identifier: Apache-2.0
#include "rigcal/sim/simulated_trigger.h"

#include <algorithm>
#include <cmath>

#include "rigcal/trigger_core/ideal_line_timers.h"
#include "rigcal/trigger_core/trigger_app.h"

namespace rigcal::sim {

Status SimulatedTriggerOptions::Check() const {
  if (boot_host_ns < start_host_ns) return Error{"boot_host_ns: must be >= start_host_ns"};
  if (!(std::abs(drift_ppm) <= 10'000.0)) return Error{"drift_ppm: |drift| must be <= 10000"};
  if (delay_min_ns < 0) return Error{"delay_min_ns: must be >= 0"};
  if (delay_jitter_ns < 0) return Error{"delay_jitter_ns: must be >= 0"};
  if (!(corrupt_probability >= 0.0 && corrupt_probability < 1.0)) {
    return Error{"corrupt_probability: must be in [0, 1)"};
  }
  for (size_t i = 0; i < reset_host_ns.size(); ++i) {
    const int64_t before = i == 0 ? boot_host_ns : reset_host_ns[i - 1];
    if (reset_host_ns[i] <= before) {
      return Error{"reset_host_ns: must increase after boot_host_ns"};
    }
  }
  return Status::Ok();
}

SimulatedTriggerStream::SimulatedTriggerStream(SimulatedTriggerOptions options)
    : options_(std::move(options)),
      rng_(options_.seed),
      now_ns_(options_.start_host_ns),
      mcu_time_ns_(options_.start_host_ns) {
  RequireValid(options_.Check(), "SimulatedTriggerOptions");
  if (options_.boot_host_ns == now_ns_) Boot(now_ns_);  // else AdvanceMcu boots it on time
}

SimulatedTriggerStream::~SimulatedTriggerStream() = default;

uint64_t SimulatedTriggerStream::McuUs(int64_t host_ns) const {
  const double elapsed = static_cast<double>(host_ns - boots_.back());
  return static_cast<uint64_t>(std::floor(elapsed * (1.0 + options_.drift_ppm * 1e-6) / 1000.0));
}

int64_t SimulatedTriggerStream::HostNs(uint64_t mcu_us) const { return TrueHostNs(boot(), mcu_us); }

int64_t SimulatedTriggerStream::TrueHostNs(int boot, uint64_t mcu_us) const {
  return boots_[static_cast<size_t>(boot)] +
         static_cast<int64_t>(
             std::ceil(static_cast<double>(mcu_us) * 1000.0 / (1.0 + options_.drift_ppm * 1e-6)));
}

void SimulatedTriggerStream::Boot(int64_t host_ns) {
  boots_.push_back(host_ns);
  app_.reset();
  timers_ = std::make_unique<trigger_core::IdealLineTimers>();  // a reset restarts the timers
  app_ = std::make_unique<trigger_core::TriggerApp>(timers_.get());
  app_->Boot(0);
}

void SimulatedTriggerStream::AdvanceMcu(int64_t to_ns) {
  while (mcu_time_ns_ < to_ns) {
    // The next instant the MCU does something: boot, reset, an edge of its timers, a queued
    // report's time, or 1 ms on (the main loop's SysTick wake-up: heartbeats).
    int64_t next = to_ns;
    if (boots_.empty()) {
      next = std::min(next, options_.boot_host_ns);
    } else {
      const uint64_t now_us = McuUs(mcu_time_ns_);
      const uint64_t event_us =
          std::min({timers_->NextEdgeUs(), app_->scheduler().NextReportUs(), now_us + 1000});
      next = std::min(next, std::max(HostNs(event_us), mcu_time_ns_ + 1));
      if (next_reset_ < options_.reset_host_ns.size()) {
        next = std::min(next, options_.reset_host_ns[next_reset_]);
      }
    }
    mcu_time_ns_ = next;
    if (boots_.empty()) {
      if (mcu_time_ns_ < options_.boot_host_ns) continue;
      Boot(mcu_time_ns_);
    } else if (next_reset_ < options_.reset_host_ns.size() &&
               mcu_time_ns_ >= options_.reset_host_ns[next_reset_]) {
      ++next_reset_;
      Boot(mcu_time_ns_);
    } else {
      timers_->RunUntil(McuUs(mcu_time_ns_), app_.get());
      app_->Poll(McuUs(mcu_time_ns_));
    }
    // Frames leave whole; each arrives after its delay, not before the previous one.
    std::vector<uint8_t> frame;
    uint8_t byte;
    while (app_->PopTx(&byte)) {
      frame.push_back(byte);
      if (byte != 0) continue;
      int64_t delay = options_.delay_min_ns;
      if (options_.delay_jitter_ns > 0) {
        delay += static_cast<int64_t>(rng_() % static_cast<uint64_t>(options_.delay_jitter_ns + 1));
      }
      const int64_t arrival = std::max(last_arrival_ns_, mcu_time_ns_ + delay);
      last_arrival_ns_ = arrival;
      for (uint8_t b : frame) {
        if (options_.corrupt_probability > 0.0 &&
            std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < options_.corrupt_probability) {
          b = static_cast<uint8_t>(b ^ (1u << (rng_() % 8)));
          ++corrupted_;
        }
        in_flight_.push_back({arrival, b});
      }
      frame.clear();
    }
  }
}

Expected<size_t> SimulatedTriggerStream::Read(uint8_t* data, size_t size, int timeout_ms) {
  const int64_t deadline = now_ns_ + int64_t{timeout_ms} * 1'000'000;
  AdvanceMcu(now_ns_);
  if (in_flight_.empty() || in_flight_.front().arrival_ns > now_ns_) {
    // Run the MCU in steps until a frame has arrived or the timeout is reached.
    while (now_ns_ < deadline) {
      const int64_t step = std::min(deadline, now_ns_ + 1'000'000);
      AdvanceMcu(step);
      if (!in_flight_.empty() && in_flight_.front().arrival_ns <= step) {
        now_ns_ = std::max(now_ns_, in_flight_.front().arrival_ns);
        break;
      }
      now_ns_ = step;
    }
  }
  size_t n = 0;
  while (n < size && !in_flight_.empty() && in_flight_.front().arrival_ns <= now_ns_) {
    data[n++] = in_flight_.front().value;
    in_flight_.pop_front();
  }
  return n;
}

Status SimulatedTriggerStream::Write(const uint8_t* data, size_t size) {
  AdvanceMcu(now_ns_);
  if (app_ == nullptr) return Status::Ok();  // not booted yet: the bytes are lost
  const uint64_t now_us = McuUs(now_ns_);
  timers_->RunUntil(now_us, app_.get());
  for (size_t i = 0; i < size; ++i) app_->OnRxByte(data[i], now_us);
  return Status::Ok();
}

}  // namespace rigcal::sim
