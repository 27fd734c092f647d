// SPDX-License-Identifier: Apache-2.0
#pragma once
// Options of the motion-model decision, one set for the batch calibrator
// (CalibrationOptions::model_selection) and the recursive estimator
// (RigEstimatorOptions::model_selection), so that both decide alike: the purely translational
// model (thesis 4.5) below the equal-error boundary of thesis 5.2, and general or planar motion
// for a rotating rig (calib/src/models/model_selection.h). Plain struct, documented defaults,
// Check().

#include "rigcal/base/status.h"

namespace rigcal {

struct ModelSelectionOptions {
  // Purely translational model (thesis 4.5) when no motion rotates by the equal-error boundary
  // of thesis 5.2 (fig. 5.5): alpha_maxrot_deg at an orientation error of alpha_maxrot_noise_deg
  // of the input poses (the thesis's 10 deg at the 1 deg it expects), scaled by
  // sqrt(eps / alpha_maxrot_noise_deg) for the rotation noise eps measured from the motions
  // (the master-minus-slave rotation angle differences: their robust σ in the batch, their
  // running RMS online), never below the smallest rotation the general model uses
  // (CalibrationOptions::alpha_threshold_deg, RigEstimatorOptions::pair_min_angle_deg).
  // alpha_maxrot_noise_deg = 0: the fixed alpha_maxrot_deg.
  double alpha_maxrot_deg = 10.0;
  double alpha_maxrot_noise_deg = 1.0;

  // General or planar (a rotating rig, motion model auto): the general model needs the master's
  // rotation axes to tilt by at least min_tilt_snr times what rotation noise alone explains (or
  // to spread by general_axis_spread_deg: noisy rotations about clearly different axes), and
  // the σ of C along the mean rotation axis within max_axis_std_ratio times its in-plane σ;
  // otherwise the planar model is used. Spread: RMS angle of the rotation vectors about their
  // principal axis. Master axes whose spread is below planar_axis_spread_deg count as one axis
  // whatever the other figures (0 = decided by the figures alone).
  double min_tilt_snr = 10.0;
  double max_axis_std_ratio = 100.0;
  double general_axis_spread_deg = 10.0;
  double planar_axis_spread_deg = 0.0;

  // The first violated constraint as "<field>: <constraint>, got <value>". The field is named
  // as the rig config and the command line name it (alpha_maxrot_deg, not
  // model_selection.alpha_maxrot_deg), in either options struct.
  Status Check() const;
};

}  // namespace rigcal
