// SPDX-License-Identifier: Apache-2.0
#pragma once
// Validation of the rigcal LCM messages (lcmtypes/*.lcm, generated into namespace rigcal): the
// rules every message that crosses a process boundary is checked against, the causes of a
// rejection, the checked encoder and the decoder of received buffers with its counters. Each
// message type has its own header with its checks and conversions: pose_message.h (camera_pose_t),
// extrinsics_message.h (rig_extrinsics_t), status_message.h (rig_status_t), image_message.h
// (image_t); channels.h names the channels.
//
// Receiving: subscribe with LCM's raw-buffer form, subscribeFunction(channel, handler, context)
// with `void handler(const ::lcm::ReceiveBuffer*, const std::string& channel, Context*)`, and
// decode with a MessageValidator. Do not use LCM's typed subscribe: the generated decode()
// trusts the array lengths in the buffer (a corrupt length allocates gigabytes or throws from
// inside ::lcm::LCM::handle()) and checks nothing of the content. Avoid LCM 1.3.1's
// member-function subscribe too: built with GCC 12 and -fsanitize=vptr (RIGCAL_ASAN_ENABLED) its
// pointer-to-member call in lcm-cpp-impl.hpp crashes (a GCC bug; plain builds work).
// Sending: build messages with the *ToLcm functions (they return only messages that pass
// CheckMessage) or check a hand-built message with EncodeMessage / CheckMessage first.
//
// Rules every message is checked against (RejectCause says which one failed):
//   - the buffer holds exactly one message of the expected type (LCM type fingerprint) and
//     schema version (the VERSION constant of the .lcm file);
//   - array lengths are >= 0 and agree with the vectors and with the buffer size;
//   - every floating-point field is finite (covariance only when has_covariance is set);
//   - quaternions are unit within kUnitTolerance; within it they are normalised exactly (one
//     already unit to rounding, within 4 ulp, is left bit for bit);
//   - camera names are non-empty and, with a non-empty name table, in the table (the master of
//     rig_extrinsics_t must be names[0]); no name appears twice in one message;
//   - times, counters and standard deviations are >= 0, enum fields hold a defined constant,
//     flag fields hold only defined bits, ranges as documented in the .lcm files.
// Rejection messages name the channel, the field and the rule:
//   "RIGCAL_POSE_left: camera_pose_t.q: |q| = 1.1 is not 1 within 1e-06 (non_unit_quaternion)".
// CheckMessage, EncodeMessage and MessageValidator::Decode are defined for camera_pose_t,
// rig_extrinsics_t, rig_status_t and image_t; include the type's header, which states its rules.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal::lcm {

// The rig's camera names; the index is the camera id of CameraPose (0 = master, 1..N = slaves).
using CameraNames = std::vector<std::string>;

// Largest accepted | |q| - 1 | of a quaternion (and |a| - 1 of slave_extrinsics_t.planar_axis).
inline constexpr double kUnitTolerance = 1e-6;

enum class RejectCause {
  kWrongType,     // the buffer's LCM fingerprint is not the expected type's (another type,
                  // or a different field layout of it)
  kWrongVersion,  // version != the type's VERSION constant
  kTruncated,     // the buffer ends before the message does (or a length points past it)
  kOversize,      // bytes left over after the message
  kMalformed,     // a string length < 1, an embedded NUL in a string, a length LCM cannot decode
  kBadSize,       // a negative array length, or one that disagrees with its vector or with
                  // width/height/stride
  kNonFinite,     // NaN or infinity
  kNonUnitQuaternion,  // quaternion norm off 1 by more than kUnitTolerance
  kUnknownCamera,      // empty camera name, or not in the name table
  kOutOfRange,         // any other documented range (negative time, quality > 1, unknown enum
                       // value or flag bit, duplicate camera, ...)
};
inline constexpr int kNumRejectCauses = static_cast<int>(RejectCause::kOutOfRange) + 1;
// snake_case name of the cause: "wrong_type", "wrong_version", ..., "out_of_range".
const char* ToString(RejectCause cause);

struct Rejection {
  RejectCause cause = RejectCause::kMalformed;
  std::string message;  // "<channel>: <type>.<field>: <what> (<cause>)"
};

// Counters of one MessageValidator.
struct DecodeStats {
  int64_t accepted = 0;
  std::array<int64_t, kNumRejectCauses> rejected{};  // indexed by RejectCause
  std::optional<Rejection> last_rejection;

  int64_t Rejected(RejectCause cause) const { return rejected[static_cast<int>(cause)]; }
  int64_t TotalRejected() const;
  // "accepted 12, rejected 3 (wrong_version 1, non_finite 2)".
  std::string Summary() const;
};

// Checks `msg` against the rules above as if it had been received on `channel`, and normalises
// its quaternions (and planar axes) that are within kUnitTolerance of unit length. `names` may be
// empty: then any non-empty camera name is accepted. Returns the first rule that fails, or
// nullopt when the message is valid. `msg` must not be null. Stateless; any thread.
template <typename Message>
std::optional<Rejection> CheckMessage(std::string_view channel, const CameraNames& names,
                                      Message* msg);

// Checks `msg` (CheckMessage) and encodes it into LCM's wire format, ready for
// ::lcm::LCM::publish(channel, data, size) or ::lcm::LogFile. Never calls LCM's encode on an
// inconsistent message (LCM indexes the vectors with the num_* fields unchecked).
template <typename Message>
Expected<std::vector<uint8_t>> EncodeMessage(std::string_view channel, const CameraNames& names,
                                             Message msg);

struct PoseMessage;  // pose_message.h

// Decodes raw LCM buffers (::lcm::ReceiveBuffer data/size, ::lcm::LogEvent data/datalen) into
// checked messages and counts what it rejects, by cause.
// Thread-safety: not thread-safe; use one validator per receiving thread (LCM dispatches
// handlers on the thread that calls handle()).
class MessageValidator {
 public:
  // `camera_names`: the rig's cameras (see CameraNames); empty accepts any camera name except in
  // DecodeCameraPose, which needs the camera's index.
  explicit MessageValidator(CameraNames camera_names = {});

  // Decodes one message of type Message that arrived on `channel`. `data` may be null only when
  // `size` is 0. The buffer must hold exactly one message: fingerprint, version, array lengths
  // and size are checked before LCM decodes anything, then the content (CheckMessage). Counts
  // the outcome.
  template <typename Message>
  Expected<Message> Decode(std::string_view channel, const void* data, int64_t size);

  // Decode<camera_pose_t> then CameraPoseFromLcm with the validator's names (pose_message.h).
  // Counts the outcome.
  Expected<PoseMessage> DecodeCameraPose(std::string_view channel, const void* data, int64_t size);

  const CameraNames& camera_names() const { return names_; }
  const DecodeStats& stats() const { return stats_; }
  void ResetStats() { stats_ = DecodeStats(); }

 private:
  template <typename Message>
  std::optional<Rejection> DecodeUncounted(std::string_view channel, const void* data, int64_t size,
                                           Message* msg) const;
  Error Reject(Rejection rejection);

  CameraNames names_;
  DecodeStats stats_;
};

}  // namespace rigcal::lcm
