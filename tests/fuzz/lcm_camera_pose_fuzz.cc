// SPDX-License-Identifier: Apache-2.0
// Fuzz target `lcm_camera_pose`: camera_pose_t from any bytes (lcm_decode_fuzz.h), and
// MessageValidator::DecodeCameraPose, whose accepted poses have a camera index of the rig.

#include "lcm_decode_fuzz.h"
#include "rigcal/lcm/pose_message.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rigcal::fuzz::QuietLogs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rigcal;
  const char* channel = "RIGCAL_POSE_left";
  fuzz::DecodeAndCheck<camera_pose_t>(channel, fuzz::kFuzzNames, data, size);
  fuzz::DecodeAndCheck<camera_pose_t>(channel, {}, data, size);
  lcm::MessageValidator validator(fuzz::kFuzzNames);
  Expected<lcm::PoseMessage> pose =
      validator.DecodeCameraPose(channel, data, static_cast<int64_t>(size));
  if (pose) {
    RIGCAL_FUZZ_EXPECT(
        pose->pose.camera >= 0 && pose->pose.camera < static_cast<int>(fuzz::kFuzzNames.size()),
        "a camera index of the rig");
    RIGCAL_FUZZ_EXPECT(pose->pose.pose.C.allFinite() && pose->pose.pose.q.coeffs().allFinite(),
                       "a finite pose");
  }
  return 0;
}
