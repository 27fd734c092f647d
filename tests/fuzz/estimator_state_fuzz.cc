// SPDX-License-Identifier: Apache-2.0
// Fuzz target `estimator_state`: ParseEstimatorState (the `--resume` state file) on any bytes, and
// on the same bytes with the checksum line made right (io::WithEstimatorStateChecksum, as the
// writer computes it), so that the fuzzer reaches the parser behind the checksum: a hand-edited file.
// An accepted state formats to a text that parses to the same text again, and restoring it into
// an estimator for its cameras either works or fails with a message (never a crash).

#include <Eigen/Geometry>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_support.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/io/estimator_state_file.h"

namespace {

void ParseAndCheck(std::string_view text) {
  using namespace rigcal;
  Expected<RigEstimatorState> state = io::ParseEstimatorState(text);
  if (!state) {
    RIGCAL_FUZZ_EXPECT(!state.error().empty(), "an error says what is wrong");
    return;
  }
  const std::string formatted = io::FormatEstimatorState(*state);
  Expected<RigEstimatorState> again = io::ParseEstimatorState(formatted);
  RIGCAL_FUZZ_EXPECT(again.ok(), "a formatted state parses: " + formatted);
  RIGCAL_FUZZ_EXPECT(io::FormatEstimatorState(*again) == formatted,
                     "format and parse round-trip");
  // Small rigs only: the estimator's buffers grow with the camera count. And only for one state
  // in four (chosen by its text, so a rerun is the same): building an estimator allocates its
  // buffers, which under ASan costs more than all the parsing.
  if (state->cameras.size() >= 2 && state->cameras.size() <= 8 &&
      std::hash<std::string_view>{}(text) % 4 == 0) {
    RigEstimator estimator(state->cameras, RigEstimatorOptions{});
    const Status restored = estimator.RestoreState(*state);
    RIGCAL_FUZZ_EXPECT(restored.ok() || !restored.message().empty(), "a refused state says why");
    // A few sets of a turning rig, so that the restored statistics are used.
    for (int k = 0; k < 4; ++k) {
      std::vector<std::optional<CameraPose>> poses(state->cameras.size());
      for (size_t c = 0; c < poses.size(); ++c) {
        CameraPose pose;
        pose.camera = static_cast<int>(c);
        pose.t_ns = int64_t{1'000'000'000} * (k + 1);
        pose.pose.q = Eigen::Quaterniond(
            Eigen::AngleAxisd(0.3 * k, Eigen::Vector3d(1, k % 2, 0.5).normalized()));
        pose.pose.C = Eigen::Vector3d(0.5 * k, 0.1 * k * k, 0.2 * c);
        poses[c] = pose;
      }
      estimator.AddSet(int64_t{1'000'000'000} * (k + 1), poses);
    }
    (void)estimator.Estimate();
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rigcal::fuzz::QuietLogs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  ParseAndCheck(text);
  ParseAndCheck(rigcal::io::WithEstimatorStateChecksum(text));
  return 0;
}
