// SPDX-License-Identifier: Apache-2.0
#pragma once
// The report's tables beside the final calibration: the baseline of every slave (|C| with its σ,
// in metres when the unit is known) and the cameras' intrinsics from the rig config.

#include <sstream>

#include "rigcal/report/report_data.h"

namespace rigcal::report::internal {

// |C| of one slave and its first-order σ from the per-axis σ of C (correlations between the
// axes are not published, so they are left out): σ_|C| = sqrt(Σ (C_k σ_k)²) / |C|. NaN σ when
// some σ_k is unknown or C = 0.
struct Baseline {
  double norm = 0.0;
  double std = kUnknown;
};
Baseline BaselineOf(const Eigen::Vector3d& C, const Eigen::Vector3d& C_std);

// <table class="baseline">: per slave a <tr data-slave="name"> with |C| ± σ in the result's unit
// and, when data.metres_per_unit is known, in metres (|C| times it) with where the unit comes
// from; else a sentence saying which unit C is in and what would give metres.
void RenderBaselineTable(const ReportData& data, std::ostringstream& out);

// <table class="intrinsics">: per camera of the config a <tr data-camera="name"> with the model,
// fx fy cx cy (scaramuzza: the centre and the polynomial), the distortion coefficients and the
// resolution; without a config a sentence saying how to get it.
void RenderIntrinsicsTable(const ReportData& data, std::ostringstream& out);

}  // namespace rigcal::report::internal
