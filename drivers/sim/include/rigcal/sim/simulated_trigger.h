// SPDX-License-Identifier: Apache-2.0
#pragma once
// A simulated trigger generator on a simulated serial link, for tests and for the simulated
// rig: the real firmware core (firmware/core TriggerApp) runs on a simulated MCU clock with ideal
// output-compare timers (IdealLineTimers: every edge exactly at its time), and its
// bytes reach the host through a link with a transport delay, jitter and corruption.
//
//   MCU clock    mcu_us = (host_ns - boot_host_ns) * (1 + drift_ppm 1e-6) / 1000; a reset
//                reboots the MCU (clock back to 0, configuration lost, Hello sent).
//   transport    each frame arrives delay_min_ns + U(0, delay_jitter_ns) after it was sent
//                (USB-like, one-sided), never before the frame before it; each byte is
//                corrupted (one bit flipped) with corrupt_probability.
//   time         simulated: NowNs() is the simulated host time, advanced by Read (a Read with a
//                timeout jumps to the next arrival or to the timeout at once), so a minute of
//                link runs in milliseconds, deterministically for a seed.
// Commands written by the host reach the MCU at the current simulated time.
//
// Threads: one reader/writer (TriggerLink's owner).

#include <cstdint>
#include <deque>
#include <memory>
#include <random>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/trigger/serial_port.h"

namespace rigcal::trigger_core {
class IdealLineTimers;
class TriggerApp;
}  // namespace rigcal::trigger_core

namespace rigcal::sim {

struct SimulatedTriggerOptions {
  int64_t start_host_ns = 1'000'000'000;  // simulated host time at construction
  int64_t boot_host_ns = 1'000'000'000;   // the MCU boots here (>= start_host_ns)
  double drift_ppm = 0.0;                 // MCU clock rate error, |.| <= 10000
  int64_t delay_min_ns = 0;               // >= 0
  int64_t delay_jitter_ns = 0;            // >= 0
  double corrupt_probability = 0.0;       // per byte, [0, 1)
  std::vector<int64_t> reset_host_ns;     // MCU reboots (increasing)
  uint64_t seed = 1;
  Status Check() const;
};

class SimulatedTriggerStream final : public trigger::ByteStream {
 public:
  explicit SimulatedTriggerStream(SimulatedTriggerOptions options);
  ~SimulatedTriggerStream() override;

  Expected<size_t> Read(uint8_t* data, size_t size, int timeout_ms) override;
  Status Write(const uint8_t* data, size_t size) override;
  int64_t NowNs() const override { return now_ns_; }

  // Ground truth: the host time of MCU time `mcu_us` during boot `boot` (0 = the first).
  int64_t TrueHostNs(int boot, uint64_t mcu_us) const;
  // The boot the MCU is in at the current simulated time.
  int boot() const { return static_cast<int>(boots_.size()) - 1; }
  int64_t corrupted_bytes() const { return corrupted_; }

 private:
  struct Byte {
    int64_t arrival_ns;
    uint8_t value;
  };
  uint64_t McuUs(int64_t host_ns) const;
  int64_t HostNs(uint64_t mcu_us) const;
  void Boot(int64_t host_ns);
  // Runs the MCU up to host time `to_ns`, queueing its frames for delivery.
  void AdvanceMcu(int64_t to_ns);

  SimulatedTriggerOptions options_;
  std::mt19937_64 rng_;
  int64_t now_ns_;
  int64_t mcu_time_ns_;         // host time the MCU has been run to
  std::vector<int64_t> boots_;  // boot host times
  size_t next_reset_ = 0;
  std::unique_ptr<trigger_core::IdealLineTimers> timers_;  // the MCU's timers (ideal edges)
  std::unique_ptr<trigger_core::TriggerApp> app_;
  std::deque<Byte> in_flight_;
  int64_t last_arrival_ns_ = 0;
  int64_t corrupted_ = 0;
};

}  // namespace rigcal::sim
