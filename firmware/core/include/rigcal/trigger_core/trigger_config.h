// SPDX-License-Identifier: Apache-2.0
#pragma once
// The configuration of the trigger generator and its range check, as the MCU applies it from
// SetRate / SetLine / SetHeartbeat commands (messages.h). Freestanding C++17.

#include <cstdint>

#include "rigcal/trigger_protocol/messages.h"

namespace rigcal::trigger_core {

namespace proto = ::rigcal::trigger_protocol;

struct LineConfig {
  bool enabled = false;
  uint32_t width_us = 100;      // pulse width, [kMinWidthUs, period - kMinWidthUs]
  int32_t phase_offset_us = 0;  // exposure centre relative to the tick
  uint32_t exposure_us = 0;     // camera exposure; the rise leads the centre by exposure / 2
  // The camera's exposure output on the line's capture input (ExposureReport), or none.
  proto::ExposureInput exposure_input = proto::ExposureInput::kNone;
  bool wired() const { return enabled && exposure_input != proto::ExposureInput::kNone; }
  // Rise relative to the tick time T_k, µs (negative: before T_k).
  int64_t RiseOffsetUs() const {
    return static_cast<int64_t>(phase_offset_us) - static_cast<int64_t>(exposure_us / 2);
  }
};

struct TriggerConfig {
  uint32_t rate_mhz = 20'000;  // 20 Hz
  LineConfig lines[proto::kMaxLines];
  uint16_t heartbeat_period_ms = 100;

  uint8_t EnabledMask() const {
    uint8_t mask = 0;
    for (int i = 0; i < proto::kMaxLines; ++i) {
      if (lines[i].enabled) mask = static_cast<uint8_t>(mask | (1u << i));
    }
    return mask;
  }
  int WiredLines() const {
    int n = 0;
    for (const LineConfig& line : lines) n += line.wired() ? 1 : 0;
    return n;
  }
  // The reports of this configuration fit the serial link (proto::FitsLink).
  bool FitsLink() const { return proto::FitsLink(rate_mhz, WiredLines(), heartbeat_period_ms); }
};

// A violated range: the Nack reason and field (reason kNone when valid).
struct ConfigProblem {
  proto::NackReason reason = proto::NackReason::kNone;
  proto::Field field = proto::Field::kNone;
  bool ok() const { return reason == proto::NackReason::kNone; }
};

// Line `line` at tick rate `rate_mhz`: width in [kMinWidthUs, period - kMinWidthUs] (the board
// re-arms a line's compare between its edges), a known exposure input, exposure <=
// kMaxExposureUs, |phase_offset| + exposure / 2 < period (a rise stays within one period of its
// tick, so the reports of consecutive ticks keep their order). Checked even for a disabled line,
// so that enabling it later cannot make the configuration invalid.
inline ConfigProblem CheckLine(const LineConfig& line, uint32_t rate_mhz) {
  const uint32_t period = proto::PeriodUs(rate_mhz);
  if (line.width_us < proto::kMinWidthUs ||
      uint64_t{line.width_us} + proto::kMinWidthUs > uint64_t{period}) {
    return {proto::NackReason::kOutOfRange, proto::Field::kWidth};
  }
  if (static_cast<uint8_t>(line.exposure_input) >
      static_cast<uint8_t>(proto::ExposureInput::kActiveLow)) {
    return {proto::NackReason::kOutOfRange, proto::Field::kExposureInput};
  }
  if (line.exposure_us > proto::kMaxExposureUs) {
    return {proto::NackReason::kOutOfRange, proto::Field::kExposure};
  }
  const int64_t offset = line.phase_offset_us < 0 ? -static_cast<int64_t>(line.phase_offset_us)
                                                  : static_cast<int64_t>(line.phase_offset_us);
  if (offset + line.exposure_us / 2 >= period) {
    return {proto::NackReason::kOutOfRange, proto::Field::kPhaseOffset};
  }
  return {};
}

inline ConfigProblem CheckRate(uint32_t rate_mhz) {
  if (rate_mhz < proto::kMinRateMilliHz || rate_mhz > proto::kMaxRateMilliHz) {
    return {proto::NackReason::kOutOfRange, proto::Field::kRate};
  }
  return {};
}

inline ConfigProblem CheckHeartbeat(uint16_t period_ms) {
  if (period_ms != 0 &&
      (period_ms < proto::kMinHeartbeatMs || period_ms > proto::kMaxHeartbeatMs)) {
    return {proto::NackReason::kOutOfRange, proto::Field::kHeartbeatPeriod};
  }
  return {};
}

// The whole configuration: the rate, then every line against it, the heartbeat, and the link
// budget (reported as a rate problem; the command handlers name their own field instead).
inline ConfigProblem CheckConfig(const TriggerConfig& config) {
  if (ConfigProblem p = CheckRate(config.rate_mhz); !p.ok()) return p;
  for (const LineConfig& line : config.lines) {
    if (ConfigProblem p = CheckLine(line, config.rate_mhz); !p.ok()) return p;
  }
  if (ConfigProblem p = CheckHeartbeat(config.heartbeat_period_ms); !p.ok()) return p;
  if (!config.FitsLink()) return {proto::NackReason::kOutOfRange, proto::Field::kRate};
  return {};
}

}  // namespace rigcal::trigger_core
