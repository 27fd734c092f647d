// SPDX-License-Identifier: Apache-2.0
// Fuzz target `kitti_trajectory`: ReadKittiTrajectory on any pose file and time file. The input
// is the pose file, a NUL byte, then the time file (no NUL: the time file is empty). Accepted
// trajectories have one finite pose with a unit quaternion per time, times strictly increasing.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "fuzz_support.h"
#include "rigcal/io/trajectory_io.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rigcal::fuzz::QuietLogs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rigcal;
  static fuzz::InputFile poses_file("00.txt");
  static fuzz::InputFile times_file("times.txt");
  const auto* nul = static_cast<const uint8_t*>(std::memchr(data, 0, size));
  const size_t poses_size = nul != nullptr ? static_cast<size_t>(nul - data) : size;
  const uint8_t* times = nul != nullptr ? nul + 1 : data + size;
  const size_t times_size = static_cast<size_t>(data + size - times);
  Expected<TimedTrajectory> t = io::ReadKittiTrajectory(
      poses_file.Write(data, poses_size), times_file.Write(times, times_size));
  if (!t) {
    RIGCAL_FUZZ_EXPECT(!t.error().empty(), "an error says what is wrong");
    return 0;
  }
  RIGCAL_FUZZ_EXPECT(t->poses.size() == t->size() && t->segment.size() == t->size(),
                     "one pose and one segment per stamp");
  for (size_t k = 0; k < t->size(); ++k) {
    RIGCAL_FUZZ_EXPECT(k == 0 || t->t_ns[k] > t->t_ns[k - 1], "times strictly increasing");
    RIGCAL_FUZZ_EXPECT(t->poses[k].C.allFinite() && t->poses[k].q.coeffs().allFinite(),
                       "finite pose");
    RIGCAL_FUZZ_EXPECT(std::abs(t->poses[k].q.norm() - 1.0) < 1e-9, "unit quaternion");
  }
  return 0;
}
