// SPDX-License-Identifier: Apache-2.0
#pragma once
// Target-based reference rig calibration (thesis 4.2, global reference pose model): every
// camera's pose in one target frame at the same instants, T_0^k (master) and T_i^k (slave);
// then T_0^k dT_i = T_i^k, so each instant measures dT_i = (T_0^k)^-1 T_i^k. The estimate is
// their mean (rotation: the chordal L2 mean of the quaternions; centre: the arithmetic mean)
// after instants whose rotation or centre deviates from the median estimate by more than
// 5 * 1.4826 * MAD are dropped. Its standard deviations are those of a mean of independent
// measurements (spread / sqrt(n)): a lower bound when the instants' errors are correlated.
// Positions are in the target's unit (metres for a metric target): the scale is 1.

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/pattern/target_views.h"

namespace rigcal::pattern {

struct ReferenceEstimate {
  std::string slave;
  Similarity master_from_slave;  // q, C of the slave in the master frame; scale 1
  double rot_std_deg = 0.0;      // σ of the mean rotation, largest axis
  Eigen::Vector3d pos_std = Eigen::Vector3d::Zero();  // σ of the mean centre, per axis
  double rot_spread_deg = 0.0;  // RMS deviation of one instant's rotation from the mean
  double pos_spread = 0.0;      // RMS deviation of one instant's centre from the mean
  int instants = 0;             // used
  int rejected = 0;             // dropped as outliers
};

// Stamps of master and slave are paired when equal within `tolerance_ns`. Errors: fewer than 3
// paired instants (the message gives the counts).
Expected<ReferenceEstimate> EstimateGlobalReference(const TimedTrajectory& master,
                                                    const TimedTrajectory& slave,
                                                    int64_t tolerance_ns);

// OpenCV stereoCalibrate with both cameras' intrinsics fixed (CALIB_FIX_INTRINSIC) on the
// views both cameras have (same key; the corners both detected, matched by their target
// coordinates): the slave's pose in the master frame minimising the reprojection error of all
// those views jointly, as Bouguet's toolbox and OpenCV's stereo_calib sample do. σ and spread
// are not computed (0); *rms_px (may be null) gets the joint RMS reprojection error. Pinhole
// cameras only. Errors: another model, fewer than 3 shared views, OpenCV failing.
Expected<ReferenceEstimate> EstimateStereoReference(const CameraViews& master,
                                                    const camera::CameraSpec& master_spec,
                                                    const CameraViews& slave,
                                                    const camera::CameraSpec& slave_spec,
                                                    double* rms_px);

// One line: q, C, |C|, σ, instants.
std::string FormatReference(const ReferenceEstimate& estimate, const std::string& unit);

}  // namespace rigcal::pattern
