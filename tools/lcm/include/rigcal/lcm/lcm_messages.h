#pragma once
// The rigcal LCM messages (lcmtypes/*.lcm, generated into namespace rigcal) and the project's
// types: conversion both ways, and validation of every message that crosses a process boundary.
//
// Receiving: subscribe with LCM's raw-buffer form, subscribeFunction(channel, handler, context)
// with `void handler(const lcm::ReceiveBuffer*, const std::string& channel, Context*)`, and
// decode with a MessageValidator. Do not use LCM's typed subscribe: the generated decode()
// trusts the array lengths in the buffer (a corrupt length allocates gigabytes or throws from
// inside lcm::LCM::handle()) and checks nothing of the content. Avoid LCM 1.3.1's
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
//   - quaternions are unit within kUnitTolerance; within it they are normalised exactly;
//   - camera names are non-empty and, with a non-empty name table, in the table (the master of
//     rig_extrinsics_t must be names[0]); no name appears twice in one message;
//   - times, counters and standard deviations are >= 0, enum fields hold a defined constant,
//     flag fields hold only defined bits, ranges as documented in the .lcm files.
// Rejection messages name the channel, the field and the rule:
//   "RIGCAL_POSE_left: camera_pose_t.q: |q| = 1.1 is not 1 within 1e-06 (non_unit_quaternion)".

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/status.h"
#include "rigcal/calib/types.h"
#include "rigcal/camera_pose_t.hpp"
#include "rigcal/image_t.hpp"
#include "rigcal/rig_extrinsics_t.hpp"
#include "rigcal/rig_status_t.hpp"

namespace rigcal::tools {

// Channels (DESIGN.md "Data flow").
inline constexpr char kExtrinsicsChannel[] = "RIGCAL_EXTRINSICS";
inline constexpr char kStatusChannel[] = "RIGCAL_STATUS";
std::string PoseChannel(std::string_view camera);   // "RIGCAL_POSE_<camera>"
std::string ImageChannel(std::string_view camera);  // "RIGCAL_IMAGE_<camera>"

// The rig's camera names; the index is the camera id of CameraPose (0 = master, 1..N = slaves).
using CameraNames = std::vector<std::string>;

// slave_extrinsics_t::FLAG_* as int32_t: lcm-gen emits every constant as its own anonymous enum,
// and C++20 deprecates `|` between different enums. Combine these instead.
inline constexpr int32_t kFlagInitialising = slave_extrinsics_t::FLAG_INITIALISING;
inline constexpr int32_t kFlagConverged = slave_extrinsics_t::FLAG_CONVERGED;
inline constexpr int32_t kFlagTranslationalOnly = slave_extrinsics_t::FLAG_TRANSLATIONAL_ONLY;
inline constexpr int32_t kFlagPlanar = slave_extrinsics_t::FLAG_PLANAR_UNOBSERVABLE_AXIS;
inline constexpr int32_t kFlagDecalibrated = slave_extrinsics_t::FLAG_DECALIBRATED;
inline constexpr int32_t kFlagAxisFromPrior = slave_extrinsics_t::FLAG_AXIS_FROM_PRIOR;
inline constexpr int32_t kKnownFlags = kFlagInitialising | kFlagConverged | kFlagTranslationalOnly |
                                       kFlagPlanar | kFlagDecalibrated | kFlagAxisFromPrior;

// Largest accepted | |q| - 1 | of a quaternion (and |a| - 1 of slave_extrinsics_t.planar_axis).
inline constexpr double kUnitTolerance = 1e-6;

enum class RejectCause {
  kWrongType,          // the buffer's LCM fingerprint is not the expected type's (another type,
                       // or a different field layout of it)
  kWrongVersion,       // version != the type's VERSION constant
  kTruncated,          // the buffer ends before the message does (or a length points past it)
  kOversize,           // bytes left over after the message
  kMalformed,          // a string length < 1, an embedded NUL in a name, a length LCM cannot decode
  kBadSize,            // a negative array length, or one that disagrees with its vector or with
                       // width/height/stride
  kNonFinite,          // NaN or infinity
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

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// A CameraPose as carried by camera_pose_t.
struct PoseMessage {
  CameraPose pose;
  // Covariance of (rotation vector, camera centre), rotation error on the left (world frame):
  // R = Exp(dtheta) R_est. Absent when the sender had none.
  std::optional<Matrix6d> covariance;
  int64_t utime = 0;  // publish time, µs
};

// ---- Validation of in-memory messages (stateless; any thread) ----

// Checks `msg` against the rules above as if it had been received on `channel`, and normalises
// its quaternions (and planar axes) that are within kUnitTolerance of unit length. `names` may
// be empty: then any non-empty camera name is accepted. Returns the first rule that fails, or
// nullopt when the message is valid. `msg` must not be null.
std::optional<Rejection> CheckMessage(std::string_view channel, const CameraNames& names,
                                      camera_pose_t* msg);
std::optional<Rejection> CheckMessage(std::string_view channel, const CameraNames& names,
                                      rig_extrinsics_t* msg);
std::optional<Rejection> CheckMessage(std::string_view channel, const CameraNames& names,
                                      rig_status_t* msg);
std::optional<Rejection> CheckMessage(std::string_view channel, const CameraNames& names,
                                      image_t* msg);

// Checks `msg` (CheckMessage) and encodes it into LCM's wire format, ready for
// lcm::LCM::publish(channel, data, size) or lcm::LogFile. Never calls LCM's encode on an
// inconsistent message (LCM indexes the vectors with the num_* fields unchecked).
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

// ---- Conversion ----

// camera_pose_t of `pose` published at `utime` (µs); the camera name is names[pose.camera].
// `covariance` (nullable): 6x6 covariance of (rotation vector, centre), see PoseMessage.
// Fails when pose.camera is not an index of `names` or the message would not pass CheckMessage
// (the message names the field). The quaternion is normalised.
Expected<camera_pose_t> CameraPoseToLcm(const CameraPose& pose, const CameraNames& names,
                                        int64_t utime, const Matrix6d* covariance = nullptr);

// The CameraPose of a camera_pose_t received on `channel`: checks it (CheckMessage) and maps
// the camera name to its index in `names`; a name not in `names` (or an empty `names`) is
// rejected with kUnknownCamera. Rejections are not counted (MessageValidator counts).
Expected<PoseMessage> CameraPoseFromLcm(std::string_view channel, const camera_pose_t& msg,
                                        const CameraNames& names);

// Flags of slave_extrinsics_t for a calibration result:
//   CONVERGED                when slave.usable(), else INITIALISING (no usable estimate yet);
//   TRANSLATIONAL_ONLY       when the motion model is translational (position unobservable);
//   PLANAR_UNOBSERVABLE_AXIS when observability.planar.
// DECALIBRATED is never set here: change detection belongs to the online estimator, which ORs
// kFlagDecalibrated into the message it publishes.
int32_t SlaveFlags(const SlaveCalibration& slave);

// slave_extrinsics_t of one slave. scale/segment/scale_std are those of the current segment
// (the entry of slave.scales with the largest segment id; estimate.scale and segment 0 when
// there is none). rotation_eigen_gap = λ2 - λ1 of observability.rotation_eigenvalues.
// message = ToString(termination) + ": " + slave.message.
// Placeholders: a slave that is not usable gets identity q, zero C and scale 1 where its
// estimate is not finite; non-finite standard deviations and observability figures become 0
// ("not computed"). Fails when a usable slave's q, C or scale is not finite, when
// observability.planar holds without a finite non-zero axis, or when the result does not pass
// CheckMessage.
Expected<slave_extrinsics_t> SlaveCalibrationToLcm(const SlaveCalibration& slave);

// rig_extrinsics_t of a calibration result published at `utime` (µs). `t_ns`: capture time of
// the newest poses the result includes (0 for a batch result); `distance_unit`: one of
// rig_extrinsics_t::UNIT_*. Fails as SlaveCalibrationToLcm does, naming the slave.
Expected<rig_extrinsics_t> RigCalibrationToLcm(
    const RigCalibration& result, int64_t utime, int64_t t_ns = 0,
    int8_t distance_unit = rig_extrinsics_t::UNIT_MASTER_ODOMETRY);

// ---- Decoding received buffers ----

// Decodes raw LCM buffers (lcm::ReceiveBuffer data/size, lcm::LogEvent data/datalen) into
// checked messages and counts what it rejects, by cause.
// Thread-safety: not thread-safe; use one validator per receiving thread (LCM dispatches
// handlers on the thread that calls handle()).
class MessageValidator {
 public:
  // `camera_names`: the rig's cameras (see CameraNames); empty accepts any camera name except in
  // DecodeCameraPose, which needs the camera's index.
  explicit MessageValidator(CameraNames camera_names = {});

  // Decodes one message of type Message (camera_pose_t, rig_extrinsics_t, rig_status_t or
  // image_t) that arrived on `channel`. `data` may be null only when `size` is 0. The buffer
  // must hold exactly one message: fingerprint, version, array lengths and size are checked
  // before LCM decodes anything, then the content (CheckMessage). Counts the outcome.
  template <typename Message>
  Expected<Message> Decode(std::string_view channel, const void* data, int64_t size);

  // Decode<camera_pose_t> then CameraPoseFromLcm with the validator's names. Counts the outcome.
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

extern template Expected<camera_pose_t> MessageValidator::Decode(std::string_view, const void*,
                                                                 int64_t);
extern template Expected<rig_extrinsics_t> MessageValidator::Decode(std::string_view, const void*,
                                                                    int64_t);
extern template Expected<rig_status_t> MessageValidator::Decode(std::string_view, const void*,
                                                                int64_t);
extern template Expected<image_t> MessageValidator::Decode(std::string_view, const void*, int64_t);

}  // namespace rigcal::tools
