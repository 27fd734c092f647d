// SPDX-License-Identifier: Apache-2.0
#pragma once
// Frames of the trigger protocol on a byte stream (UART, USB CDC, pty):
//
//   COBS( payload | crc16 low byte | crc16 high byte ) 0x00
//
// payload = version, type, body (messages.h); crc16 = Crc16(payload). The 0x00 delimiter ends
// every frame; a receiver that sees garbage, loses bytes or starts mid-frame drops what it has
// at the next 0x00 and continues with the following frame (resynchronisation costs at most the
// frame in which the error happened and the one it ran into).
//
// MessageDecoder is the receiving state machine of both sides: one byte in, at most one event
// out, fixed memory (no heap), counters for every kind of loss. Freestanding C++17.

#include <cstddef>
#include <cstdint>

#include "rigcal/trigger_protocol/cobs.h"
#include "rigcal/trigger_protocol/crc16.h"
#include "rigcal/trigger_protocol/messages.h"

namespace rigcal::trigger_protocol {

inline constexpr size_t kCrcSize = 2;
// Longest encoded frame including the delimiter (a receiver drops anything longer).
inline constexpr size_t kMaxFrameSize = CobsEncodedSize(kMaxPayloadSize + kCrcSize) + 1;

// Writes the frame of `m` (encoded, with its trailing 0x00) into `out`. Returns its size, or 0
// when `out` is too small (kMaxFrameSize always suffices) or the type is unknown.
inline size_t EncodeFrame(const Message& m, uint8_t* out, size_t capacity) {
  uint8_t raw[kMaxPayloadSize + kCrcSize] = {};
  const size_t payload = EncodePayload(m, raw, kMaxPayloadSize);
  if (payload == 0) return 0;
  const uint16_t crc = Crc16(raw, payload);
  raw[payload] = static_cast<uint8_t>(crc & 0xFF);
  raw[payload + 1] = static_cast<uint8_t>(crc >> 8);
  if (capacity < 1) return 0;
  const size_t encoded = CobsEncode(raw, payload + kCrcSize, out, capacity - 1);
  if (encoded == 0) return 0;
  out[encoded] = 0;
  return encoded + 1;
}

// What one received byte completed.
enum class DecodeEvent : uint8_t {
  kNone = 0,            // nothing yet (inside a frame, or an empty frame between delimiters)
  kMessage,             // a valid message: message() holds it
  kOverflow,            // a frame longer than kMaxFrameSize: dropped up to the next 0x00
  kFramingError,        // not valid COBS, or shorter than header + CRC
  kCrcError,            // the CRC does not match
  kUnsupportedVersion,  // CRC good, version != kProtocolVersion
  kUnknownType,         // CRC good, unknown message type
  kBadLength,           // CRC good, body size wrong for the type
};

struct DecoderStats {
  uint32_t messages = 0;
  uint32_t overflows = 0;
  uint32_t framing_errors = 0;
  uint32_t crc_errors = 0;
  uint32_t rejected = 0;  // version / type / length errors
  uint32_t Errors() const { return overflows + framing_errors + crc_errors + rejected; }
};

class MessageDecoder {
 public:
  // Feeds one byte. After kMessage, message() is valid until the next Push. After a rejection
  // (kUnsupportedVersion, kUnknownType, kBadLength), raw_type() and command_id() describe the
  // refused frame (command_id() is 0 when its body was shorter than 2 bytes) and raw_version()
  // its version byte (a peer built for another protocol version: update its firmware or host).
  DecodeEvent Push(uint8_t byte) {
    if (byte != 0) {
      if (size_ < sizeof(buffer_)) {
        buffer_[size_++] = byte;
      } else {
        overflowed_ = true;
      }
      return DecodeEvent::kNone;
    }
    const size_t size = size_;
    const bool overflowed = overflowed_;
    size_ = 0;
    overflowed_ = false;
    if (overflowed) {
      ++stats_.overflows;
      return DecodeEvent::kOverflow;
    }
    if (size == 0) return DecodeEvent::kNone;
    const long decoded = CobsDecode(buffer_, size, buffer_, sizeof(buffer_));
    if (decoded < static_cast<long>(kHeaderSize + kCrcSize)) {
      ++stats_.framing_errors;
      return DecodeEvent::kFramingError;
    }
    const size_t payload = static_cast<size_t>(decoded) - kCrcSize;
    const uint16_t crc = static_cast<uint16_t>(buffer_[payload] |
                                               (static_cast<uint16_t>(buffer_[payload + 1]) << 8));
    if (Crc16(buffer_, payload) != crc) {
      ++stats_.crc_errors;
      return DecodeEvent::kCrcError;
    }
    raw_version_ = buffer_[0];
    raw_type_ = buffer_[1];
    command_id_ = 0;
    switch (ParsePayload(buffer_, payload, &message_, &command_id_)) {
      case ParseStatus::kOk:
        ++stats_.messages;
        return DecodeEvent::kMessage;
      case ParseStatus::kTooShort:  // excluded above
        ++stats_.framing_errors;
        return DecodeEvent::kFramingError;
      case ParseStatus::kUnsupportedVersion:
        ++stats_.rejected;
        return DecodeEvent::kUnsupportedVersion;
      case ParseStatus::kUnknownType:
        ++stats_.rejected;
        return DecodeEvent::kUnknownType;
      case ParseStatus::kBadLength:
        ++stats_.rejected;
        return DecodeEvent::kBadLength;
    }
    return DecodeEvent::kNone;
  }

  const Message& message() const { return message_; }
  uint8_t raw_type() const { return raw_type_; }
  uint8_t raw_version() const { return raw_version_; }
  uint16_t command_id() const { return command_id_; }
  const DecoderStats& stats() const { return stats_; }
  // Forgets a partial frame (e.g. after the port was reopened).
  void Reset() {
    size_ = 0;
    overflowed_ = false;
  }

 private:
  uint8_t buffer_[kMaxFrameSize] = {};
  size_t size_ = 0;
  bool overflowed_ = false;
  Message message_;
  uint8_t raw_version_ = 0;
  uint8_t raw_type_ = 0;
  uint16_t command_id_ = 0;
  DecoderStats stats_;
};

}  // namespace rigcal::trigger_protocol
