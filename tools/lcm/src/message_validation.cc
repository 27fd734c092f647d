// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/message_validation.h"

#include <utility>

namespace rigcal::lcm {

const char* ToString(RejectCause cause) {
  switch (cause) {
    case RejectCause::kWrongType:
      return "wrong_type";
    case RejectCause::kWrongVersion:
      return "wrong_version";
    case RejectCause::kTruncated:
      return "truncated";
    case RejectCause::kOversize:
      return "oversize";
    case RejectCause::kMalformed:
      return "malformed";
    case RejectCause::kBadSize:
      return "bad_size";
    case RejectCause::kNonFinite:
      return "non_finite";
    case RejectCause::kNonUnitQuaternion:
      return "non_unit_quaternion";
    case RejectCause::kUnknownCamera:
      return "unknown_camera";
    case RejectCause::kOutOfRange:
      return "out_of_range";
  }
  return "unknown";
}

int64_t DecodeStats::TotalRejected() const {
  int64_t total = 0;
  for (int64_t n : rejected) total += n;
  return total;
}

std::string DecodeStats::Summary() const {
  std::string out =
      "accepted " + std::to_string(accepted) + ", rejected " + std::to_string(TotalRejected());
  std::string causes;
  for (int i = 0; i < kNumRejectCauses; ++i) {
    if (rejected[i] == 0) continue;
    if (!causes.empty()) causes += ", ";
    causes +=
        std::string(ToString(static_cast<RejectCause>(i))) + " " + std::to_string(rejected[i]);
  }
  if (!causes.empty()) out += " (" + causes + ")";
  return out;
}

MessageValidator::MessageValidator(CameraNames camera_names) : names_(std::move(camera_names)) {}

Error MessageValidator::Reject(Rejection rejection) {
  ++stats_.rejected[static_cast<int>(rejection.cause)];
  Error error{rejection.message};
  stats_.last_rejection = std::move(rejection);
  return error;
}

}  // namespace rigcal::lcm
