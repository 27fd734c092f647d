// SPDX-License-Identifier: Apache-2.0
// Fuzz target `trajectory`: ReadTrajectory (TUM, EuRoC CSV, rigcal native, auto-detected) on any
// bytes. Accepted trajectories keep the reader's promises: one stamp, pose and segment per line,
// strictly increasing stamps, finite centres, unit quaternions; and MatchTrajectories of an
// accepted trajectory against itself keeps every stamp.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_support.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::fuzz {
namespace {

void CheckTrajectory(const TimedTrajectory& t) {
  RIGCAL_FUZZ_EXPECT(t.size() > 0, "an accepted trajectory has poses");
  RIGCAL_FUZZ_EXPECT(t.poses.size() == t.size() && t.segment.size() == t.size(),
                     "one pose and one segment per stamp");
  for (size_t k = 0; k < t.size(); ++k) {
    RIGCAL_FUZZ_EXPECT(k == 0 || t.t_ns[k] > t.t_ns[k - 1], "stamps strictly increasing");
    RIGCAL_FUZZ_EXPECT(t.poses[k].C.allFinite() && t.poses[k].q.coeffs().allFinite(),
                       "finite pose");
    RIGCAL_FUZZ_EXPECT(std::abs(t.poses[k].q.norm() - 1.0) < 1e-9, "unit quaternion");
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
  static fuzz::InputFile file("cam1.txt");
  io::TrajectoryFormat format;
  Expected<TimedTrajectory> trajectory =
      io::ReadTrajectory(file.Write(data, size), {}, &format);
  if (!trajectory) {
    RIGCAL_FUZZ_EXPECT(!trajectory.error().empty(), "an error says what is wrong");
    return 0;
  }
  fuzz::CheckTrajectory(*trajectory);
  TimedTrajectory copy = *trajectory;
  copy.name = "cam2";
  Expected<RigRecording> matched = io::MatchTrajectories(*trajectory, {copy}, 0);
  if (trajectory->size() >= 2) {
    RIGCAL_FUZZ_EXPECT(matched && matched->size() == trajectory->size(),
                       "a trajectory matches itself stamp for stamp");
  }
  return 0;
}
