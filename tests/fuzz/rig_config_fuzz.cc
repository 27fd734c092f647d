// SPDX-License-Identifier: Apache-2.0
// Fuzz target `rig_config`: LoadRigConfig on any bytes (seeds: the shipped config/*.yaml).
// An accepted config has at least one camera, distinct non-empty camera names, finite nominal
// and truth mountings with unit quaternions, and positive publishing rates.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>

#include "fuzz_support.h"
#include "rigcal/io/rig_config.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rigcal::fuzz::QuietLogs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rigcal;
  static fuzz::InputFile file("rig_config.yaml");
  Expected<io::RigConfig> config = io::LoadRigConfig(file.Write(data, size));
  if (!config) {
    RIGCAL_FUZZ_EXPECT(!config.error().empty(), "an error says what is wrong");
    return 0;
  }
  RIGCAL_FUZZ_EXPECT(!config->cameras.empty(), "a config has cameras");
  std::set<std::string> names;
  for (const io::CameraConfig& camera : config->cameras) {
    RIGCAL_FUZZ_EXPECT(!camera.name.empty(), "a camera has a name");
    RIGCAL_FUZZ_EXPECT(names.insert(camera.name).second, "distinct camera names");
    for (const auto* mounting : {&camera.nominal, &camera.truth}) {
      if (!mounting->has_value()) continue;
      const Similarity& s = **mounting;
      RIGCAL_FUZZ_EXPECT(s.q.coeffs().allFinite() && s.C.allFinite() && std::isfinite(s.scale),
                         "finite mounting of " + camera.name);
      RIGCAL_FUZZ_EXPECT(std::abs(s.q.norm() - 1.0) < 1e-6, "unit quaternion of " + camera.name);
    }
  }
  RIGCAL_FUZZ_EXPECT(config->publish.extrinsics_rate_hz > 0 && config->publish.status_rate_hz > 0,
                     "positive publishing rates");
  return 0;
}
