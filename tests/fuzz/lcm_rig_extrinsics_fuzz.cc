// SPDX-License-Identifier: Apache-2.0
// Fuzz target `lcm_rig_extrinsics`: rig_extrinsics_t from any bytes (lcm_decode_fuzz.h).

#include "lcm_decode_fuzz.h"
#include "rigcal/lcm/extrinsics_message.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rigcal::fuzz::QuietLogs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rigcal;
  const char* channel = "RIGCAL_EXTRINSICS";
  fuzz::DecodeAndCheck<rig_extrinsics_t>(channel, fuzz::kFuzzNames, data, size);
  fuzz::DecodeAndCheck<rig_extrinsics_t>(channel, {}, data, size);
  return 0;
}
