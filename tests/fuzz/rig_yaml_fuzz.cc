// SPDX-License-Identifier: Apache-2.0
// Fuzz target `rig_yaml`: the rig YAML readers on any bytes: ReadRigYaml (truth and result files),
// ReadTrueMountings (a rig YAML, or a rig config's cameras[].truth) and ReadCamchain. Accepted
// mountings have finite values, unit quaternions and a positive scale; RigToYaml of them reads
// back to the same mountings.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

#include "fuzz_support.h"
#include "rigcal/io/rig_files.h"

namespace rigcal::fuzz {
namespace {

void CheckMountings(const std::map<std::string, Similarity>& rig) {
  for (const auto& [name, s] : rig) {
    RIGCAL_FUZZ_EXPECT(!name.empty(), "a slave has a name");
    RIGCAL_FUZZ_EXPECT(s.q.coeffs().allFinite() && s.C.allFinite() && std::isfinite(s.scale),
                       "finite mounting of " + name);
    RIGCAL_FUZZ_EXPECT(std::abs(s.q.norm() - 1.0) < 1e-9, "unit quaternion of " + name);
    RIGCAL_FUZZ_EXPECT(s.scale > 0, "positive scale of " + name);
  }
}

}  // namespace
}  // namespace rigcal::fuzz

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rigcal::fuzz::QuietLogs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rigcal;
  static fuzz::InputFile file("rig.yaml");
  static fuzz::InputFile again("again.yaml");
  const std::string& path = file.Write(data, size);
  if (auto rig = io::ReadRigYaml(path)) {
    fuzz::CheckMountings(*rig);
    const std::string text = io::RigToYaml(*rig);
    auto back =
        io::ReadRigYaml(again.Write(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
    RIGCAL_FUZZ_EXPECT(back.ok(), "RigToYaml reads back: " + text);
    RIGCAL_FUZZ_EXPECT(back->size() == rig->size(), "RigToYaml keeps every slave");
    for (const auto& [name, s] : *rig) {
      const auto it = back->find(name);
      RIGCAL_FUZZ_EXPECT(it != back->end(), "RigToYaml keeps slave " + name);
      RIGCAL_FUZZ_EXPECT(it->second.C == s.C && it->second.scale == s.scale,
                         "RigToYaml round-trips C and scale of " + name);
    }
  }
  if (auto truth = io::ReadTrueMountings(path)) fuzz::CheckMountings(*truth);
  if (auto chain = io::ReadCamchain(path)) {
    for (const auto& camera : *chain) {
      RIGCAL_FUZZ_EXPECT(camera.cn_from_cnm1.allFinite(), "finite camchain transform");
    }
  }
  return 0;
}
