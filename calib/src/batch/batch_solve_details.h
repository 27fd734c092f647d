// SPDX-License-Identifier: Apache-2.0
#pragma once
// What the batch solve of one slave knows beyond its result: the covariance of independent
// motions beside the reported (cluster-robust) one, which the auto pair choice compares across
// spans (batch_pair_choice.h).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::internal {

struct SlaveSolveDetails {
  bool covariance_ok = false;
  int time_blocks = 0;  // blocks of the cluster-robust covariance (0 = none)
  // Covariances of the rotation vector (rad²) and C (master units²): reported (raised to the
  // cluster-robust one where that is larger), and of independent motions of equal error.
  Eigen::Matrix3d cov_rotation = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d cov_position = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d independent_cov_rotation = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d independent_cov_position = Eigen::Matrix3d::Zero();
};

// CalibrateSlave (rig_calibrator.h), also filling `details` (not touched when the solve stops
// before the refinement).
SlaveCalibration CalibrateSlave(const std::vector<RigMotion>& motions,
                                const CalibrationOptions& options, const std::string& name,
                                SlaveSolveDetails* details);

// CalibrateRig's result for slave `slave` alone: the glitches are found on every camera of
// `recording` (their times dropped for all, as in CalibrateRig), only this slave is solved.
SlaveCalibration CalibrateRigSlave(const RigRecording& recording, const CalibrationOptions& options,
                                   int slave);

}  // namespace rigcal::internal
