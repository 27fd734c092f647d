// SPDX-License-Identifier: Apache-2.0
#pragma once
// The decoder and encoder skeleton shared by every rigcal LCM message type (private to
// rigcal_lcm): the checks of a received buffer before LCM decodes it (fingerprint, version, every
// array length against the bytes left), LCM's decode, then the checks of the content: the schema
// version and the type's own rules. A message type's .cc specialises MessageTraits and
// instantiates MessageValidator::Decode and EncodeMessage for its type.

#include <climits>
#include <cstdint>
#include <exception>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "message_checker.h"
#include "rigcal/lcm/message_validation.h"

namespace rigcal::lcm {
namespace internal {

inline constexpr int kHashBytes = 8;

// The big-endian integer of `bytes` bytes at `data`.
inline int64_t ReadBigEndian(const uint8_t* data, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | data[i];
  return static_cast<int64_t>(v);
}

// Reads LCM's big-endian wire format without trusting it.
class Cursor {
 public:
  Cursor(const uint8_t* data, int64_t size) : data_(data), size_(size) {}
  int64_t remaining() const { return size_ - pos_; }
  bool Skip(int64_t bytes) {
    if (remaining() < bytes) return false;
    pos_ += bytes;
    return true;
  }
  bool ReadInt32(int32_t* value) {
    if (remaining() < 4) return false;
    *value = static_cast<int32_t>(ReadBigEndian(data_ + pos_, 4));
    pos_ += 4;
    return true;
  }

 private:
  const uint8_t* data_;
  int64_t size_;
  int64_t pos_ = kHashBytes;  // the fingerprint is checked separately
};

// Steps through the fields that precede an array length. The first failure is kept in the
// Checker.
class LayoutWalk {
 public:
  LayoutWalk(const uint8_t* data, int64_t size, Checker* check)
      : cursor_(data, size), check_(check) {}
  void Fixed(std::string_view field, int64_t bytes) {
    if (check_->ok() && !cursor_.Skip(bytes)) Truncated(field);
  }
  void String(std::string_view field) {
    int32_t length = 0;
    if (!check_->ok()) return;
    if (!cursor_.ReadInt32(&length)) return Truncated(field);
    if (length < 1) {
      return check_->Fail(RejectCause::kMalformed, field,
                          "string length " + std::to_string(length) + " (< 1)");
    }
    if (!cursor_.Skip(length)) Truncated(field);
  }
  // An array length, and the least number of bytes each element takes. Returns the length, or 0
  // after a failure.
  int32_t Count(std::string_view field, int64_t min_element_bytes) {
    int32_t count = 0;
    if (!check_->ok()) return 0;
    if (!cursor_.ReadInt32(&count)) {
      Truncated(field);
      return 0;
    }
    if (count < 0) {
      check_->Fail(RejectCause::kBadSize, field, "negative length " + std::to_string(count));
      return 0;
    }
    if (count * min_element_bytes > cursor_.remaining()) {
      check_->Fail(RejectCause::kTruncated, field,
                   std::to_string(count) + " elements need at least " +
                       std::to_string(count * min_element_bytes) + " bytes, " +
                       std::to_string(cursor_.remaining()) + " left in the buffer");
      return 0;
    }
    return count;
  }

 private:
  void Truncated(std::string_view field) {
    check_->Fail(RejectCause::kTruncated, field, "the buffer ends inside this field");
  }
  Cursor cursor_;
  Checker* check_;
};

// What the skeleton needs of one message type; each type's .cc specialises it:
//   static constexpr char kTypeName[];  the LCM type name, "camera_pose_t"
//   WalkLayout(LayoutWalk* walk)        steps through every field of the .lcm file in order, nested
//       elements and strings included (nested types have fixed-size arrays only): LCM's decode
//       computes `length - 1` of a string length unchecked, undefined for INT32_MIN (found by the
//       lcm_log fuzz target under UBSan), so every string length is checked here first.
//   CheckContent(const CameraNames& names, Message* msg, Checker* check)
//                                       the type's own rules (all but the schema version),
//       normalising quaternions and axes in place.
template <typename Message>
struct MessageTraits;

}  // namespace internal

// The schema version, then the type's own rules.
template <typename Message>
std::optional<Rejection> CheckMessage(std::string_view channel, const CameraNames& names,
                                      Message* msg) {
  internal::Checker check(channel, internal::MessageTraits<Message>::kTypeName);
  check.Version(msg->version, Message::VERSION);
  internal::MessageTraits<Message>::CheckContent(names, msg, &check);
  return check.TakeRejection();
}

template <typename Message>
Expected<std::vector<uint8_t>> EncodeMessage(std::string_view channel, const CameraNames& names,
                                             Message msg) {
  if (std::optional<Rejection> rejection = CheckMessage(channel, names, &msg)) {
    return Error{rejection->message};
  }
  std::vector<uint8_t> buffer(msg.getEncodedSize());
  const int size = static_cast<int>(buffer.size());
  if (msg.encode(buffer.data(), 0, size) != size) {
    return Error{std::string(channel) + ": LCM could not encode the message"};
  }
  return buffer;
}

template <typename Message>
std::optional<Rejection> MessageValidator::DecodeUncounted(std::string_view channel,
                                                           const void* data, int64_t size,
                                                           Message* msg) const {
  using internal::kHashBytes;
  using internal::ReadBigEndian;
  using Traits = internal::MessageTraits<Message>;
  const char* type = Traits::kTypeName;
  internal::Checker check(channel, type);
  const auto* bytes = static_cast<const uint8_t*>(data);
  if (size < 0 || (size > 0 && data == nullptr)) {
    check.Fail(RejectCause::kTruncated, "buffer", "no data (size " + std::to_string(size) + ")");
    return check.TakeRejection();
  }
  if (size > INT_MAX) {
    check.Fail(RejectCause::kOversize, "buffer",
               std::to_string(size) + " bytes is more than LCM can decode");
    return check.TakeRejection();
  }
  if (size < kHashBytes) {
    check.Fail(RejectCause::kTruncated, "fingerprint",
               "the buffer has " + std::to_string(size) + " bytes, fewer than the fingerprint");
    return check.TakeRejection();
  }
  const int64_t hash = ReadBigEndian(bytes, kHashBytes);
  if (hash != Message::getHash()) {
    check.Fail(RejectCause::kWrongType, "fingerprint",
               "the buffer does not hold a " + std::string(type) + " of this schema");
    return check.TakeRejection();
  }
  if (size < kHashBytes + 2) {
    check.Fail(RejectCause::kTruncated, "version", "the buffer ends inside this field");
    return check.TakeRejection();
  }
  check.Version(static_cast<int16_t>(ReadBigEndian(bytes + kHashBytes, 2)), Message::VERSION);
  internal::LayoutWalk walk(bytes, size, &check);
  Traits::WalkLayout(&walk);
  if (!check.ok()) return check.TakeRejection();

  int decoded = -1;
  try {
    decoded = msg->decode(data, 0, static_cast<int>(size));
  } catch (const std::exception& e) {
    check.Fail(RejectCause::kMalformed, "buffer", std::string("LCM decode failed: ") + e.what());
    return check.TakeRejection();
  }
  if (decoded < 0) {
    check.Fail(RejectCause::kTruncated, "buffer",
               "LCM decode ran past the end of the " + std::to_string(size) + "-byte buffer");
  } else if (decoded != size) {
    check.Fail(RejectCause::kOversize, "buffer",
               std::to_string(size - decoded) + " bytes left over after the " +
                   std::to_string(decoded) + "-byte message");
  }
  if (!check.ok()) return check.TakeRejection();
  return CheckMessage(channel, names_, msg);
}

template <typename Message>
Expected<Message> MessageValidator::Decode(std::string_view channel, const void* data,
                                           int64_t size) {
  Message msg;
  if (std::optional<Rejection> rejection = DecodeUncounted(channel, data, size, &msg)) {
    return Reject(std::move(*rejection));
  }
  ++stats_.accepted;
  return msg;
}

}  // namespace rigcal::lcm
