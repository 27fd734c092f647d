// SPDX-License-Identifier: Apache-2.0
#pragma once
// The metric scale of the master odometry, lambda_world of thesis 5.5: in some master frames a
// target of known size is visible, so the master camera's centre is known there in metres
// (PnP, target_poses.h). The same centres in the master odometry (arbitrary unit) are related
// to them by a similarity; its scale (Umeyama's least-squares fit) is lambda_world, metres per
// master unit. Its σ is that of a least-squares slope: residual variance per coordinate over
// the spread of the odometry centres (sum of squared distances from their mean).

#include <cstdint>
#include <string>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/base/status.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::pattern {

struct WorldScale {
  double metres_per_unit = 1.0;  // lambda_world
  double std = 0.0;              // σ of lambda_world
  double fit_rms_m = 0.0;        // RMS distance of the fitted centres from the target's, metres
  int frames = 0;                // master frames with a target pose used
  std::string message;           // one line saying what was done
};

// Pairs the stamps of `master_odometry` and `master_target` within `tolerance_ns`. Errors:
// fewer than 3 paired frames, or their centres (nearly) coincide or lie on a line (the
// scale is then not determined; the message says so).
Expected<WorldScale> EstimateWorldScale(const TimedTrajectory& master_odometry,
                                        const TimedTrajectory& master_target,
                                        int64_t tolerance_ns);

// Multiplies every length of `result` by `metres_per_unit`: each slave's C, its σ, its axis
// offset σ and its scales (then slave unit -> metres).
void ScaleResult(double metres_per_unit, RigCalibration* result);

}  // namespace rigcal::pattern
