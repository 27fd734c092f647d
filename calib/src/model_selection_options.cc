// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/model_selection_options.h"

#include <cmath>
#include <sstream>

namespace rigcal {
namespace {

// "<field>: must <constraint>, got <value>".
Status Violated(const char* field, const char* constraint, double value) {
  std::ostringstream e;
  e << field << ": must " << constraint << ", got " << value;
  return Error{e.str()};
}

}  // namespace

Status ModelSelectionOptions::Check() const {
  if (!(alpha_maxrot_deg >= 0.0 && alpha_maxrot_deg < 180.0)) {
    return Violated("alpha_maxrot_deg", "be in [0, 180)", alpha_maxrot_deg);
  }
  if (!(alpha_maxrot_noise_deg >= 0.0) || std::isinf(alpha_maxrot_noise_deg)) {
    return Violated("alpha_maxrot_noise_deg", "be finite and >= 0 (0 = fixed alpha_maxrot_deg)",
                    alpha_maxrot_noise_deg);
  }
  if (!(planar_axis_spread_deg >= 0.0)) {
    return Violated("planar_axis_spread_deg", "be >= 0", planar_axis_spread_deg);
  }
  if (!(min_tilt_snr >= 0.0)) return Violated("min_tilt_snr", "be >= 0", min_tilt_snr);
  if (!(general_axis_spread_deg > 0.0)) {
    return Violated("general_axis_spread_deg", "be > 0", general_axis_spread_deg);
  }
  if (!(max_axis_std_ratio > 0.0)) {
    return Violated("max_axis_std_ratio", "be > 0", max_axis_std_ratio);
  }
  return Status::Ok();
}

}  // namespace rigcal
