// SPDX-License-Identifier: Apache-2.0
// Fuzz target `lcm_rig_status`: rig_status_t from any bytes (lcm_decode_fuzz.h).

#include "lcm_decode_fuzz.h"
#include "rigcal/lcm/status_message.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rigcal::fuzz::QuietLogs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rigcal;
  const char* channel = "RIGCAL_STATUS";
  fuzz::DecodeAndCheck<rig_status_t>(channel, fuzz::kFuzzNames, data, size);
  fuzz::DecodeAndCheck<rig_status_t>(channel, {}, data, size);
  return 0;
}
