// SPDX-License-Identifier: Apache-2.0
#pragma once
// Poses of a camera that runs free (its own capture instants, its own clock) at the master's
// instants, never across a gap of more than a few of the camera's frame intervals and never
// across a scale segment boundary: cubic (Lagrange through the two poses on either side, the
// rotation as rotation vectors in the tangent space of the pose before the instant) when the
// poses on both sides are there, else SLERP of the rotation and linear interpolation of the
// centre between the two poses around it. SLERP/linear alone err by a·dt²/8 (a the angular or
// linear acceleration), a bias that shrinks the motion and shifts the estimated centre by
// several σ on brisk drives; the cubic error is O(dt⁴).

#include <cstdint>
#include <optional>
#include <vector>

#include "rigcal/calib/pose_interpolation.h"
#include "rigcal/base/status.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::io {

struct InterpolationOptions {
  // Two neighbouring poses further apart than this many median frame intervals of their
  // camera are a gap: nothing is interpolated across it.
  double max_gap_intervals = 3.0;
};

// MedianInterval, InterpolatedPose and InterpolatePose: calib/pose_interpolation.h.

// The slave's poses at the master's stamps `master_t_ns`, where the slave clock reads
// t_master + offset_ns (time offset = slave stamp - master clock). Stamps where no pose can be
// interpolated are left out; the result carries the master stamps.
TimedTrajectory ResampleAt(const TimedTrajectory& slave, const std::vector<int64_t>& master_t_ns,
                           int64_t offset_ns, const InterpolationOptions& options = {});

// The slave with its stamps moved to the master clock (t - offset_ns).
TimedTrajectory ShiftedToMasterClock(const TimedTrajectory& slave, int64_t offset_ns);

// Whether the slave's stamps, moved to the master clock, coincide with the master's: at least
// 90 % of the master stamps inside the slave's range have a slave stamp within
// min(tolerance_ns, master frame interval / 50). Synchronised cameras are matched by stamp.
bool StampsCoincide(const TimedTrajectory& master, const TimedTrajectory& slave, int64_t offset_ns,
                    int64_t tolerance_ns);

// MatchTrajectories for cameras that may run free: per slave, its stamps moved to the master
// clock by offsets_ns[i]; slaves whose stamps then coincide with the master's are matched by
// stamp (exactly as MatchTrajectories), the others interpolated at the master's stamps (by
// stamp too when no pose can be interpolated: MatchTrajectories then names the time ranges).
// `interpolated`, when not null, receives per slave whether it was interpolated.
Expected<RigRecording> MatchFreeRunning(const TimedTrajectory& master,
                                        const std::vector<TimedTrajectory>& slaves,
                                        const std::vector<int64_t>& offsets_ns,
                                        int64_t tolerance_ns,
                                        const InterpolationOptions& options = {},
                                        std::vector<bool>* interpolated = nullptr);

}  // namespace rigcal::io
