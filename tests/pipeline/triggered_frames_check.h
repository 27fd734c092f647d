// SPDX-License-Identifier: Apache-2.0
#pragma once
// The check of the live trigger tests on the pulses the frames of two triggered cameras got:
// frame k of every camera carries pulse first + k (the same pulse for both cameras). A frame
// without a pulse is allowed only when its camera counted why: a late report (the pulse report
// had not reached the host TriggeredCamera::wait_ns() after the frame: a thread of the loaded
// test host stalled) or a clock map that was not synced (it restarted), and only for a few
// frames: more would be a receiver that is stuck rather than busy. A frame between pulses (a
// spurious frame, or one stamped off its pulse) fails, but for one per clock-map restart: a
// frame stamped with the map before the restart and matched after it is off its pulse by the
// restart's shift. Header-only.

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "rigcal/trigger/triggered_camera.h"

namespace rigcal::testing {

// At most this share of a camera's frames may lack their pulse (late reports, map not synced).
inline constexpr int kMaxLateShareDenominator = 8;

// `seqs[c][k]`: the pulse of camera c's frame k, -1 for none; `map_restarts`: the matcher's.
// Returns the first frame's pulse.
inline std::optional<int64_t> CheckTriggeredFrames(
    const std::array<std::vector<int64_t>, 2>& seqs,
    const std::array<const trigger::TriggeredCamera*, 2>& cameras, int64_t map_restarts) {
  std::optional<int64_t> first;  // pulse - frame index, the same for every matched frame
  for (int c = 0; c < 2; ++c) {
    int64_t missing = 0;
    for (size_t k = 0; k < seqs[c].size(); ++k) {
      if (seqs[c][k] < 0) {
        ++missing;
        continue;
      }
      const int64_t offset = seqs[c][k] - static_cast<int64_t>(k);
      if (!first) first = offset;
      EXPECT_EQ(offset, *first) << "camera " << c << " frame " << k << ": pulse " << seqs[c][k];
    }
    EXPECT_EQ(missing, cameras[c]->unmatched()) << "camera " << c;
    const int64_t explained = cameras[c]->late_reports() + cameras[c]->unsynced();
    EXPECT_LE(missing, explained + map_restarts)
        << "camera " << c << ": a frame without a pulse whose report was neither late nor "
        << "waiting for the clock map (" << cameras[c]->late_reports() << " late, "
        << cameras[c]->unsynced() << " unsynced, " << map_restarts << " clock-map restarts)";
    EXPECT_GE(missing, explained) << "camera " << c;
    EXPECT_LE(missing * kMaxLateShareDenominator, static_cast<int64_t>(seqs[c].size()))
        << "camera " << c << ": " << missing << " of " << seqs[c].size()
        << " frames without their pulse";
  }
  EXPECT_TRUE(first.has_value()) << "no frame got a pulse";
  return first;
}

}  // namespace rigcal::testing
