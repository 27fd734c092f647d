#pragma once
// Error model of thesis 5.1.1: compares an estimate with the true rig parameters.

#include <vector>

#include "rigcal/calib/types.h"

namespace rigcal {

struct CalibrationError {
  double rot_deg = 0.0;    // rotation orientation error: 2 acos(q_hat^* q)_w
  double dir_deg = 0.0;    // position orientation error: angle between C and C_hat
  double dist_pct = 0.0;   // distance error: | |C| - |C_hat| | / |C| in percent
  double trans_err = 0.0;  // |C - C_hat| in master units
  double scale_pct = 0.0;  // | s - s_hat | / s in percent
};

CalibrationError CompareToTruth(const Similarity& estimate, const Similarity& truth);

// Constraint residua of one motion against given rig parameters (thesis 5.1.1).
struct ConstraintResidual {
  double rotation_deg = 0.0;          // angle between R_0 dR and dR R_i
  double position_dir_deg = 0.0;      // angle between R_0 dC + C_0 and s dR C_i + dC
  double position_abs = 0.0;          // |(R_0 - I) dC + C_0 - s dR C_i|
  double scale_pct = 0.0;             // |s - lambda_meas| / s, percent (0 if degenerate)
};

ConstraintResidual ResidualOf(const RigMotion& motion, const Similarity& rig);

}  // namespace rigcal
