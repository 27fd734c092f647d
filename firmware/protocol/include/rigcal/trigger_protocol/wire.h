// SPDX-License-Identifier: Apache-2.0
#pragma once
// Little-endian field writer and reader of the trigger protocol's message bodies (explicit
// byte order, no struct copies: the MCU and the host agree whatever their ABI). Freestanding.

#include <cstddef>
#include <cstdint>

namespace rigcal::trigger_protocol {

class WireWriter {
 public:
  WireWriter(uint8_t* out, size_t capacity) : out_(out), capacity_(capacity) {}
  void U8(uint8_t v) { Put(v, 1); }
  void U16(uint16_t v) { Put(v, 2); }
  void U32(uint32_t v) { Put(v, 4); }
  void I32(int32_t v) { Put(static_cast<uint32_t>(v), 4); }
  void U64(uint64_t v) { Put(v, 8); }
  // Bytes written; ok() is false when a write did not fit (the rest was not written).
  size_t size() const { return size_; }
  bool ok() const { return ok_; }

 private:
  void Put(uint64_t v, size_t bytes) {
    if (size_ + bytes > capacity_) {
      ok_ = false;
      return;
    }
    for (size_t i = 0; i < bytes; ++i) out_[size_++] = static_cast<uint8_t>(v >> (8 * i));
  }
  uint8_t* out_;
  size_t capacity_;
  size_t size_ = 0;
  bool ok_ = true;
};

class WireReader {
 public:
  WireReader(const uint8_t* in, size_t size) : in_(in), size_(size) {}
  uint8_t U8() { return static_cast<uint8_t>(Get(1)); }
  uint16_t U16() { return static_cast<uint16_t>(Get(2)); }
  uint32_t U32() { return static_cast<uint32_t>(Get(4)); }
  int32_t I32() { return static_cast<int32_t>(static_cast<uint32_t>(Get(4))); }
  uint64_t U64() { return Get(8); }
  // False when a read ran past the end (those reads returned 0).
  bool ok() const { return ok_; }
  size_t remaining() const { return size_ - pos_; }

 private:
  uint64_t Get(size_t bytes) {
    if (pos_ + bytes > size_) {
      ok_ = false;
      pos_ = size_;
      return 0;
    }
    uint64_t v = 0;
    for (size_t i = 0; i < bytes; ++i) v |= static_cast<uint64_t>(in_[pos_++]) << (8 * i);
    return v;
  }
  const uint8_t* in_;
  size_t size_;
  size_t pos_ = 0;
  bool ok_ = true;
};

}  // namespace rigcal::trigger_protocol
