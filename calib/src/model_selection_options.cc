#include "rigcal/calib/model_selection_options.h"

#include <cmath>
#include <sstream>

namespace rigcal {

Status ModelSelectionOptions::Check() const {
  std::ostringstream e;
  if (!(alpha_maxrot_deg >= 0.0 && alpha_maxrot_deg < 180.0))
    e << "alpha_maxrot_deg: must be in [0, 180), got " << alpha_maxrot_deg;
  else if (!(alpha_maxrot_noise_deg >= 0.0) || std::isinf(alpha_maxrot_noise_deg))
    e << "alpha_maxrot_noise_deg: must be finite and >= 0 (0 = fixed alpha_maxrot_deg), got "
      << alpha_maxrot_noise_deg;
  else if (!(planar_axis_spread_deg >= 0.0))
    e << "planar_axis_spread_deg: must be >= 0, got " << planar_axis_spread_deg;
  else if (!(min_tilt_snr >= 0.0))
    e << "min_tilt_snr: must be >= 0, got " << min_tilt_snr;
  else if (!(general_axis_spread_deg > 0.0))
    e << "general_axis_spread_deg: must be > 0, got " << general_axis_spread_deg;
  else if (!(max_axis_std_ratio > 0.0))
    e << "max_axis_std_ratio: must be > 0, got " << max_axis_std_ratio;
  if (e.str().empty()) return Status::Ok();
  return Error{e.str()};
}

}  // namespace rigcal
