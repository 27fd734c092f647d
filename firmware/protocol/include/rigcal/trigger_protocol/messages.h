// SPDX-License-Identifier: Apache-2.0
#pragma once
// The messages of the trigger protocol between the trigger-generator MCU (firmware/) and the
// host (drivers/ trigger link), version 2. One definition for both sides, so they cannot drift.
//
// Version history (a receiver speaks exactly one version, see below):
//   1  Hello {firmware_version, max_lines, mcu_time_us}; SetLine without exposure_input.
//   2  Hello gains clock_status (ClockStatus bits: HSE fallback, PLL, timer clock, test image)
//      and hse_mhz; SetLine gains exposure_input; new ExposureReport (measured exposure of a
//      wired line, from the board's input capture); widths and gaps of at least kMinWidthUs
//      (edges are timer output compares re-armed by an interrupt); a link budget
//      (LinkBytesPerSecond) that every configuration must fit.
//
// Payload of every frame (before CRC and COBS, see frame_codec.h):
//   u8 version (kProtocolVersion) | u8 MessageType | body (little-endian fields below)
// A receiver rejects a payload of another version (MCU: Nack kUnsupportedVersion), of an
// unknown type (Nack kUnknownType) or whose body is not exactly the type's size (kBadLength).
// A later version may add types; a changed body layout needs a new version.
//
// Time on the MCU: `mcu_time_us`, microseconds since the MCU booted (its own crystal; the host
// maps it to CLOCK_MONOTONIC). Sequence numbers count trigger ticks from boot, wrap at 2^32.
//
// Edges: the board drives every line from a timer output-compare channel armed ahead of the
// edge, so an edge happens at its scheduled µs whatever the main loop does (docs/firmware.md).
//
// Exposure-centred pulses: tick k has the nominal time T_k = t_start + k * period. Line L with
// exposure e_L and phase offset p_L rises at T_k + p_L - e_L / 2 and falls width_L later, so the
// middle of its camera's exposure is at T_k + p_L. A PulseReport carries T_k (not the rise): the
// exposure centre of every line with phase offset 0, which is what a frame should be stamped
// with. It is sent at or after T_k and after every line of the tick has risen, never before:
// the host may use (mcu_time_us, receive time) as a clock sample whose delay is >= 0.
//
// Freestanding C++17 (no heap, no exceptions, no RTTI): compiled into the firmware.

#include <cstddef>
#include <cstdint>

#include "rigcal/trigger_protocol/wire.h"

namespace rigcal::trigger_protocol {

inline constexpr uint8_t kProtocolVersion = 2;
inline constexpr int kMaxLines = 8;  // trigger lines of the generator (bits of a line mask)

enum class MessageType : uint8_t {
  // MCU -> host
  kHello = 0x01,           // at boot and on GetInfo: the MCU (re)started or identifies itself
  kPulseReport = 0x02,     // one per trigger tick
  kHeartbeat = 0x03,       // periodic, also while stopped (a clock sample and health counters)
  kAck = 0x04,             // a command was applied
  kNack = 0x05,            // a command was refused, with the reason and the field at fault
  kExposureReport = 0x06,  // measured exposure of a wired line for one tick (version 2)
  // host -> MCU (every command carries a host-chosen command_id, echoed by Ack/Nack)
  kSetRate = 0x10,
  kSetLine = 0x11,
  kStart = 0x12,
  kStop = 0x13,
  kSetHeartbeat = 0x14,
  kGetInfo = 0x15,
};

// Why a command was refused.
enum class NackReason : uint8_t {
  kNone = 0,
  kUnsupportedVersion = 1,  // payload version != kProtocolVersion
  kUnknownType = 2,         // not a command type
  kBadLength = 3,           // body size does not match the type
  kOutOfRange = 4,          // a field outside its range (Nack::field says which)
  kBusy = 5,                // the configuration cannot change while the trigger runs
  kNoLinesEnabled = 6,      // Start with every line disabled
};

// The field a Nack kOutOfRange (or kBusy) refers to.
enum class Field : uint8_t {
  kNone = 0,
  kRate = 1,
  kLine = 2,
  kWidth = 3,
  kPhaseOffset = 4,
  kExposure = 5,
  kHeartbeatPeriod = 6,
  kExposureInput = 7,  // SetLine.exposure_input unknown, or the link budget cannot carry it
};

// Whether a line's camera reports its exposure back (its strobe / exposure-active output wired to
// the line's input-capture pin), and at which level it is active.
enum class ExposureInput : uint8_t {
  kNone = 0,        // not wired: the host uses the scheduled exposure centre
  kActiveHigh = 1,  // the input is high while the camera exposes
  kActiveLow = 2,   // the input is low while the camera exposes (open-collector / opto outputs)
};

// Hello.clock_status bits: how the board's clocks came up (docs/firmware.md "Clock tree").
enum ClockStatusBit : uint8_t {
  // The crystal (HSE) did not report ready within its start-up timeout: the PLL runs from the
  // 16 MHz internal RC oscillator (HSI, +-1 % over temperature): the MCU clock is that far off.
  kClockHseFallback = 1u << 0,
  // The PLL did not lock, or the switch to it was not confirmed (SWS): the core may run at
  // 16 MHz, and every derived rate (baud, µs) would be wrong. QEMU reports it (no RCC model).
  kClockPllFailed = 1u << 1,
  // The µs timer's input clock, measured against the core clock at boot, differs from the
  // configured one by more than 2 %: its prescaler was set from the measurement (QEMU: 1 GHz).
  kClockTimerMeasured = 1u << 2,
  // A test image (its µs counter was preset near 2^32, CMake TRIGGER_TEST_COUNTER_PRESET):
  // mcu_time_us does not start at 0. Never flash it for use.
  kClockTestImage = 1u << 7,
};

// Ranges the MCU enforces (the host checks them too, to give a better message first).
inline constexpr uint32_t kMinRateMilliHz = 100;      // 0.1 Hz
inline constexpr uint32_t kMaxRateMilliHz = 400'000;  // 400 Hz (reports fit 115200 baud)
// Width and the gap to the next rise (period - width): the board re-arms a line's compare for
// its next edge in an interrupt, whose worst-case response (every line's edge at the same µs:
// eight services of ~2-2.6 µs, docs/firmware.md "Timing") stays below this.
inline constexpr uint32_t kMinWidthUs = 25;
inline constexpr uint32_t kMaxExposureUs = 1'000'000;  // and |offset| + exposure / 2 < period
inline constexpr uint16_t kMinHeartbeatMs = 10;        // 0 = heartbeats off
inline constexpr uint16_t kMaxHeartbeatMs = 10'000;

// Tick period in µs of a rate in mHz, rounded down (the scheduler uses exact tick times
// t_start + floor(k * 1e9 / rate_mhz), so rates with a fractional period do not drift).
constexpr uint32_t PeriodUs(uint32_t rate_mhz) {
  return rate_mhz == 0 ? 0 : static_cast<uint32_t>(1'000'000'000ull / rate_mhz);
}

struct Hello {
  uint16_t firmware_version = 0;
  uint8_t max_lines = kMaxLines;
  uint64_t mcu_time_us = 0;
  uint8_t clock_status = 0;  // ClockStatusBit flags; 0: crystal, PLL and timers as configured
  uint8_t hse_mhz = 0;       // the crystal the image was built for (CMake TRIGGER_HSE_HZ), MHz
};
struct PulseReport {
  uint8_t line_mask = 0;     // lines that pulsed for this tick (bit L = line L)
  uint32_t seq = 0;          // tick number since boot
  uint64_t mcu_time_us = 0;  // T_k: exposure centre of the lines with phase offset 0
};
// The exposure of line `line`'s camera for tick `seq`, as its exposure-active output showed it
// (input capture of both edges, µs). Sent when the exposure ends, for wired lines only
// (SetLine.exposure_input); centre = start_us + duration_us / 2.
struct ExposureReport {
  uint32_t seq = 0;
  uint8_t line = 0;
  uint64_t start_us = 0;     // MCU time the input went active
  uint32_t duration_us = 0;  // until it went inactive
  uint64_t CentreUs() const { return start_us + duration_us / 2; }
};
struct Heartbeat {
  uint64_t mcu_time_us = 0;    // when the heartbeat was queued
  uint32_t next_seq = 0;       // sequence number the next tick will get
  uint8_t running = 0;         // 1 while the trigger runs
  uint16_t late_edges = 0;     // edges raised more than the scheduler's tolerance late (saturates)
  uint16_t rx_errors = 0;      // frames received with a bad CRC / framing / length (saturates)
  uint16_t tx_dropped = 0;     // outgoing frames dropped because the UART queue was full
  uint16_t skipped_ticks = 0;  // ticks skipped after the MCU fell > 1 period behind (saturates)
};
struct Ack {
  uint16_t command_id = 0;
  MessageType command = MessageType::kGetInfo;
};
struct Nack {
  uint16_t command_id = 0;
  uint8_t command = 0;  // raw type byte of the refused command (may be unknown)
  NackReason reason = NackReason::kNone;
  Field field = Field::kNone;
};
struct SetRate {
  uint16_t command_id = 0;
  uint32_t rate_mhz = 0;  // tick rate, millihertz
};
struct SetLine {
  uint16_t command_id = 0;
  uint8_t line = 0;  // [0, kMaxLines)
  uint8_t enabled = 0;
  uint32_t width_us = 0;
  int32_t phase_offset_us = 0;  // exposure centre relative to the tick
  uint32_t exposure_us = 0;     // the camera's exposure: the rise leads the centre by half of it
  ExposureInput exposure_input = ExposureInput::kNone;
};
struct SetHeartbeat {
  uint16_t command_id = 0;
  uint16_t period_ms = 0;  // 0 = off, else [kMinHeartbeatMs, kMaxHeartbeatMs]
};
// Start, Stop, GetInfo carry only a command_id.
struct SimpleCommand {
  uint16_t command_id = 0;
};

// One decoded message: `type` says which member holds it (the others are default values).
struct Message {
  MessageType type = MessageType::kHeartbeat;
  Hello hello;
  PulseReport pulse;
  Heartbeat heartbeat;
  Ack ack;
  Nack nack;
  ExposureReport exposure;
  SetRate set_rate;
  SetLine set_line;
  SetHeartbeat set_heartbeat;
  SimpleCommand simple;  // kStart, kStop, kGetInfo
};

// Body sizes in bytes; -1 for a type this version does not know.
constexpr int BodySize(uint8_t type) {
  switch (static_cast<MessageType>(type)) {
    case MessageType::kHello:
      return 13;
    case MessageType::kPulseReport:
      return 13;
    case MessageType::kHeartbeat:
      return 21;
    case MessageType::kAck:
      return 3;
    case MessageType::kNack:
      return 5;
    case MessageType::kExposureReport:
      return 17;
    case MessageType::kSetRate:
      return 6;
    case MessageType::kSetLine:
      return 17;
    case MessageType::kSetHeartbeat:
      return 4;
    case MessageType::kStart:
    case MessageType::kStop:
    case MessageType::kGetInfo:
      return 2;
  }
  return -1;
}

inline constexpr size_t kHeaderSize = 2;  // version, type
inline constexpr size_t kMaxBodySize = 21;
inline constexpr size_t kMaxPayloadSize = kHeaderSize + kMaxBodySize;

constexpr bool IsCommand(uint8_t type) { return type >= 0x10 && BodySize(type) >= 0; }

// The link's capacity: 115200 baud, 8N1 (10 bits a byte), as the board's USART runs it.
inline constexpr uint32_t kLinkBaud = 115'200;
inline constexpr uint32_t kLinkBytesPerSecond = kLinkBaud / 10;
// Encoded frame of a message type: payload (header + body) + CRC, COBS's one overhead byte (every
// payload here is below 254 bytes) and the delimiter.
constexpr uint32_t FrameBytes(MessageType type) {
  return static_cast<uint32_t>(kHeaderSize + BodySize(static_cast<uint8_t>(type)) + 2 + 1 + 1);
}
// What a configuration sends per second at most: a PulseReport per tick, an ExposureReport per
// tick and wired line, a Heartbeat per period (0 = off). Every configuration must keep it within
// 90 % of kLinkBytesPerSecond, so reports never queue up (the MCU refuses one that does not).
constexpr uint64_t LinkMilliBytesPerSecond(uint32_t rate_mhz, int wired_lines,
                                           uint16_t heartbeat_ms) {
  const uint64_t per_tick =
      FrameBytes(MessageType::kPulseReport) +
      static_cast<uint64_t>(wired_lines) * FrameBytes(MessageType::kExposureReport);
  const uint64_t heartbeat =
      heartbeat_ms == 0 ? 0 : 1'000'000ull * FrameBytes(MessageType::kHeartbeat) / heartbeat_ms;
  return per_tick * rate_mhz + heartbeat;
}
constexpr bool FitsLink(uint32_t rate_mhz, int wired_lines, uint16_t heartbeat_ms) {
  return LinkMilliBytesPerSecond(rate_mhz, wired_lines, heartbeat_ms) * 10 <=
         9ull * kLinkBytesPerSecond * 1000;
}

// Writes the payload of `m` (version, type, body) into `out`. Returns its size, or 0 when `out`
// is too small or the type is unknown.
inline size_t EncodePayload(const Message& m, uint8_t* out, size_t capacity) {
  const int body = BodySize(static_cast<uint8_t>(m.type));
  if (body < 0 || capacity < kHeaderSize + static_cast<size_t>(body)) return 0;
  WireWriter w(out, capacity);
  w.U8(kProtocolVersion);
  w.U8(static_cast<uint8_t>(m.type));
  switch (m.type) {
    case MessageType::kHello:
      w.U16(m.hello.firmware_version);
      w.U8(m.hello.max_lines);
      w.U64(m.hello.mcu_time_us);
      w.U8(m.hello.clock_status);
      w.U8(m.hello.hse_mhz);
      break;
    case MessageType::kPulseReport:
      w.U8(m.pulse.line_mask);
      w.U32(m.pulse.seq);
      w.U64(m.pulse.mcu_time_us);
      break;
    case MessageType::kHeartbeat:
      w.U64(m.heartbeat.mcu_time_us);
      w.U32(m.heartbeat.next_seq);
      w.U8(m.heartbeat.running);
      w.U16(m.heartbeat.late_edges);
      w.U16(m.heartbeat.rx_errors);
      w.U16(m.heartbeat.tx_dropped);
      w.U16(m.heartbeat.skipped_ticks);
      break;
    case MessageType::kAck:
      w.U16(m.ack.command_id);
      w.U8(static_cast<uint8_t>(m.ack.command));
      break;
    case MessageType::kNack:
      w.U16(m.nack.command_id);
      w.U8(m.nack.command);
      w.U8(static_cast<uint8_t>(m.nack.reason));
      w.U8(static_cast<uint8_t>(m.nack.field));
      break;
    case MessageType::kExposureReport:
      w.U32(m.exposure.seq);
      w.U8(m.exposure.line);
      w.U64(m.exposure.start_us);
      w.U32(m.exposure.duration_us);
      break;
    case MessageType::kSetRate:
      w.U16(m.set_rate.command_id);
      w.U32(m.set_rate.rate_mhz);
      break;
    case MessageType::kSetLine:
      w.U16(m.set_line.command_id);
      w.U8(m.set_line.line);
      w.U8(m.set_line.enabled);
      w.U32(m.set_line.width_us);
      w.I32(m.set_line.phase_offset_us);
      w.U32(m.set_line.exposure_us);
      w.U8(static_cast<uint8_t>(m.set_line.exposure_input));
      break;
    case MessageType::kSetHeartbeat:
      w.U16(m.set_heartbeat.command_id);
      w.U16(m.set_heartbeat.period_ms);
      break;
    case MessageType::kStart:
    case MessageType::kStop:
    case MessageType::kGetInfo:
      w.U16(m.simple.command_id);
      break;
  }
  return w.ok() ? w.size() : 0;
}

enum class ParseStatus : uint8_t {
  kOk = 0,
  kTooShort,            // fewer than the two header bytes
  kUnsupportedVersion,  // first byte != kProtocolVersion
  kUnknownType,
  kBadLength,  // body size differs from BodySize(type)
};

// Parses a payload into `*out`. On kUnsupportedVersion / kUnknownType / kBadLength, out->type
// is left unchanged, but *command_id (when not null) receives the first two body bytes if there
// are at least two: every command starts with its id, so the MCU can name it in a Nack.
inline ParseStatus ParsePayload(const uint8_t* payload, size_t size, Message* out,
                                uint16_t* command_id = nullptr) {
  if (size < kHeaderSize) return ParseStatus::kTooShort;
  if (command_id != nullptr && size >= kHeaderSize + 2) {
    *command_id = static_cast<uint16_t>(payload[2] | (payload[3] << 8));
  }
  if (payload[0] != kProtocolVersion) return ParseStatus::kUnsupportedVersion;
  const uint8_t type = payload[1];
  const int body = BodySize(type);
  if (body < 0) return ParseStatus::kUnknownType;
  if (size != kHeaderSize + static_cast<size_t>(body)) return ParseStatus::kBadLength;
  WireReader r(payload + kHeaderSize, size - kHeaderSize);
  Message m;
  m.type = static_cast<MessageType>(type);
  switch (m.type) {
    case MessageType::kHello:
      m.hello.firmware_version = r.U16();
      m.hello.max_lines = r.U8();
      m.hello.mcu_time_us = r.U64();
      m.hello.clock_status = r.U8();
      m.hello.hse_mhz = r.U8();
      break;
    case MessageType::kPulseReport:
      m.pulse.line_mask = r.U8();
      m.pulse.seq = r.U32();
      m.pulse.mcu_time_us = r.U64();
      break;
    case MessageType::kHeartbeat:
      m.heartbeat.mcu_time_us = r.U64();
      m.heartbeat.next_seq = r.U32();
      m.heartbeat.running = r.U8();
      m.heartbeat.late_edges = r.U16();
      m.heartbeat.rx_errors = r.U16();
      m.heartbeat.tx_dropped = r.U16();
      m.heartbeat.skipped_ticks = r.U16();
      break;
    case MessageType::kAck:
      m.ack.command_id = r.U16();
      m.ack.command = static_cast<MessageType>(r.U8());
      break;
    case MessageType::kNack:
      m.nack.command_id = r.U16();
      m.nack.command = r.U8();
      m.nack.reason = static_cast<NackReason>(r.U8());
      m.nack.field = static_cast<Field>(r.U8());
      break;
    case MessageType::kExposureReport:
      m.exposure.seq = r.U32();
      m.exposure.line = r.U8();
      m.exposure.start_us = r.U64();
      m.exposure.duration_us = r.U32();
      break;
    case MessageType::kSetRate:
      m.set_rate.command_id = r.U16();
      m.set_rate.rate_mhz = r.U32();
      break;
    case MessageType::kSetLine:
      m.set_line.command_id = r.U16();
      m.set_line.line = r.U8();
      m.set_line.enabled = r.U8();
      m.set_line.width_us = r.U32();
      m.set_line.phase_offset_us = r.I32();
      m.set_line.exposure_us = r.U32();
      m.set_line.exposure_input = static_cast<ExposureInput>(r.U8());
      break;
    case MessageType::kSetHeartbeat:
      m.set_heartbeat.command_id = r.U16();
      m.set_heartbeat.period_ms = r.U16();
      break;
    case MessageType::kStart:
    case MessageType::kStop:
    case MessageType::kGetInfo:
      m.simple.command_id = r.U16();
      break;
  }
  if (!r.ok() || r.remaining() != 0) return ParseStatus::kBadLength;
  *out = m;
  return ParseStatus::kOk;
}

// Names for logs and error messages.
constexpr const char* NackReasonName(NackReason reason) {
  switch (reason) {
    case NackReason::kNone:
      return "none";
    case NackReason::kUnsupportedVersion:
      return "unsupported protocol version";
    case NackReason::kUnknownType:
      return "unknown command";
    case NackReason::kBadLength:
      return "bad message length";
    case NackReason::kOutOfRange:
      return "value out of range";
    case NackReason::kBusy:
      return "not while the trigger runs";
    case NackReason::kNoLinesEnabled:
      return "no trigger line enabled";
  }
  return "unknown reason";
}
constexpr const char* FieldName(Field field) {
  switch (field) {
    case Field::kNone:
      return "none";
    case Field::kRate:
      return "rate";
    case Field::kLine:
      return "line";
    case Field::kWidth:
      return "width";
    case Field::kPhaseOffset:
      return "phase_offset";
    case Field::kExposure:
      return "exposure";
    case Field::kHeartbeatPeriod:
      return "heartbeat_period";
    case Field::kExposureInput:
      return "exposure_input";
  }
  return "unknown field";
}

}  // namespace rigcal::trigger_protocol
