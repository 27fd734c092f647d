// SPDX-License-Identifier: Apache-2.0
#pragma once
// Consistent Overhead Byte Stuffing (Cheshire & Baker 1999): the framing of the trigger
// protocol. An encoded frame contains no zero byte, so a single 0x00 delimits frames and a
// receiver that lost bytes (or started mid-frame) resynchronises at the next 0x00. Overhead:
// one byte per 254 bytes of payload, plus the delimiter. Freestanding C++17.

#include <cstddef>
#include <cstdint>

namespace rigcal::trigger_protocol {

// Bytes CobsEncode writes for `size` input bytes (without the delimiter).
constexpr size_t CobsEncodedSize(size_t size) { return size + size / 254 + 1; }

// Encodes `size` bytes of `in` into `out` (capacity `out_capacity`), without a delimiter.
// Returns the encoded length, or 0 when `out` is too small. `in` and `out` must not overlap.
constexpr size_t CobsEncode(const uint8_t* in, size_t size, uint8_t* out, size_t out_capacity) {
  if (out_capacity < CobsEncodedSize(size)) return 0;
  size_t code_index = 0;  // where the current block's length code goes
  size_t write = 1;
  uint8_t code = 1;
  for (size_t i = 0; i < size; ++i) {
    if (in[i] == 0) {
      out[code_index] = code;
      code = 1;
      code_index = write++;
      continue;
    }
    out[write++] = in[i];
    if (++code == 0xFF) {  // a full block of 254 non-zero bytes: no implied zero follows
      out[code_index] = code;
      code = 1;
      code_index = write++;
    }
  }
  out[code_index] = code;
  return write;
}

// Decodes `size` encoded bytes (without the delimiter) of `in` into `out` (capacity
// `out_capacity`; may be `in` itself: decoding never writes ahead of reading). Returns the
// decoded length, or -1 when the input is not valid COBS (a zero byte, a block running past the
// end) or `out` is too small.
constexpr long CobsDecode(const uint8_t* in, size_t size, uint8_t* out, size_t out_capacity) {
  size_t read = 0;
  size_t write = 0;
  while (read < size) {
    const uint8_t code = in[read++];
    if (code == 0) return -1;
    for (uint8_t i = 1; i < code; ++i) {
      if (read >= size || in[read] == 0 || write >= out_capacity) return -1;
      out[write++] = in[read++];
    }
    // A block shorter than 0xFF ends in an implied zero, except the last block.
    if (code != 0xFF && read < size) {
      if (write >= out_capacity) return -1;
      out[write++] = 0;
    }
  }
  return static_cast<long>(write);
}

}  // namespace rigcal::trigger_protocol
