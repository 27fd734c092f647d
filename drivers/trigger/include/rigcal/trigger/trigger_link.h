// SPDX-License-Identifier: Apache-2.0
#pragma once
// TriggerLink: the host end of the trigger generator's serial protocol
// (firmware/protocol, the same header the firmware compiles). Decodes frames from a ByteStream
// into messages stamped with their host receive time, and sends configuration commands,
// waiting for their Ack or Nack.
//
// Threads: one thread owns a TriggerLink (TriggerReceiver runs it); not thread-safe.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/trigger/serial_port.h"
#include "rigcal/trigger_protocol/frame_codec.h"

namespace rigcal::trigger {

namespace trigger_proto = ::rigcal::trigger_protocol;

// One received message and when the read that completed it returned (ByteStream::NowNs, host
// CLOCK_MONOTONIC ns), less its UART wire time when the link has one (set_uart_byte_ns).
struct TriggerEvent {
  trigger_proto::Message message;
  int64_t rx_ns = 0;
};

// One trigger line as the host configures it.
struct TriggerLineSettings {
  int line = 0;                 // [0, 8)
  int64_t width_us = 1000;      // pulse width, [10, period - 10] (trigger_protocol::kMinWidthUs)
  int64_t phase_offset_us = 0;  // exposure centre relative to the tick
  int64_t exposure_us = 0;      // camera exposure (the rise leads the centre by half of it)
  // The camera's exposure output wired to the line's capture input: the generator then reports
  // each measured exposure (ExposureReport) and the matcher uses its centre.
  trigger_proto::ExposureInput exposure_input = trigger_proto::ExposureInput::kNone;
};

// What the host asks the generator for. Check() applies the firmware's ranges and link budget
// (messages.h) so that a bad value is reported by field before anything is sent.
struct TriggerSettings {
  double rate_hz = 20.0;                   // [0.1, 400]
  std::vector<TriggerLineSettings> lines;  // >= 1, distinct lines
  int heartbeat_ms = 100;                  // 0 = off, else [10, 10000]
  Status Check() const;
  uint32_t RateMilliHz() const;
};

class TriggerLink {
 public:
  explicit TriggerLink(std::unique_ptr<ByteStream> stream);

  // Reads what arrives within `timeout_ms` and appends the decoded messages to `events`.
  // Corrupted frames are dropped and counted (stats()). Error: the stream failed.
  Status Poll(int timeout_ms, std::vector<TriggerEvent>* events);
  // Sends `command` (its command id is set here) and waits up to `timeout_ms` for its answer;
  // every other message read meanwhile is appended to `events`. Error on a Nack (naming the
  // command, the reason and the field), a timeout or a stream failure.
  Status Command(trigger_proto::Message command, int timeout_ms, std::vector<TriggerEvent>* events);
  // SetHeartbeat, SetRate, and SetLine for every line (the others disabled), then Start.
  Status Apply(const TriggerSettings& settings, int timeout_ms, std::vector<TriggerEvent>* events);
  Status Stop(int timeout_ms, std::vector<TriggerEvent>* events);

  // The reports cross a UART whose bytes take `byte_ns` each (10 bits: 1e10 / baud; 0 = no
  // UART, the default). The MCU stamps a message before its first byte leaves, and the bytes
  // of a read crossed the wire one after another before the read returned, so a message
  // completed at byte i of an n-byte read, whose frame is L bytes long, is stamped
  // rx - (L + n - 1 - i) * byte_ns: still never before its MCU time, and without the wire time
  // (1.6 ms for a pulse report at 115200 baud) that would otherwise bias the clock map late.
  void set_uart_byte_ns(double byte_ns) { uart_byte_ns_ = byte_ns; }

  const trigger_proto::DecoderStats& stats() const { return decoder_.stats(); }
  // The version of the last frame refused for its protocol version (0: none): a generator
  // built for another protocol version than this host's.
  uint8_t other_version() const { return other_version_; }
  ByteStream& stream() { return *stream_; }

 private:
  std::unique_ptr<ByteStream> stream_;
  trigger_proto::MessageDecoder decoder_;
  uint16_t next_command_id_ = 1;
  double uart_byte_ns_ = 0.0;
  size_t frame_bytes_ = 0;  // bytes of the frame being received (since the last delimiter)
  uint8_t other_version_ = 0;
};

// "SetLine", "Start", ...; "type 0x7f" for unknown ones.
std::string TriggerMessageName(uint8_t type);

}  // namespace rigcal::trigger
