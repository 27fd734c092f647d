// SPDX-License-Identifier: Apache-2.0
#pragma once
// CRC-16/CCITT-FALSE (polynomial 0x1021, initial value 0xFFFF, no reflection, no final XOR),
// the check value of every frame of the trigger protocol. Check value of "123456789": 0x29B1.
// Bitwise (no table): 8 shifts per byte is cheap for frames of a few dozen bytes and keeps the
// firmware small. Freestanding C++17: no heap, no exceptions.

#include <cstddef>
#include <cstdint>

namespace rigcal::trigger_protocol {

inline constexpr uint16_t kCrc16Initial = 0xFFFF;

// Continues a CRC over `size` bytes at `data` (start with kCrc16Initial).
constexpr uint16_t Crc16Update(uint16_t crc, const uint8_t* data, size_t size) {
  for (size_t i = 0; i < size; ++i) {
    crc = static_cast<uint16_t>(crc ^ (static_cast<uint16_t>(data[i]) << 8));
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x8000u) ? static_cast<uint16_t>((crc << 1) ^ 0x1021u)
                            : static_cast<uint16_t>(crc << 1);
    }
  }
  return crc;
}

constexpr uint16_t Crc16(const uint8_t* data, size_t size) {
  return Crc16Update(kCrc16Initial, data, size);
}

}  // namespace rigcal::trigger_protocol
