// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/pair_options.h"

#include <sstream>

namespace rigcal {

Status PairOptions::Check() const {
  if (step < 1) return Error{"step: must be >= 1, got " + std::to_string(step)};
  if (!(target_angle_deg > 0.0)) return Error{"target_angle_deg: must be > 0"};
  if (!(target_translation_fraction > 0.0)) {
    return Error{"target_translation_fraction: must be > 0"};
  }
  if (min_angle_deg < 0.0) return Error{"min_angle_deg: must be >= 0"};
  if (min_translation_fraction < 0.0) return Error{"min_translation_fraction: must be >= 0"};
  if (!(max_span_fraction > 0.0 && max_span_fraction <= 1.0)) {
    std::ostringstream e;
    e << "max_span_fraction: must be in (0, 1], got " << max_span_fraction;
    return Error{e.str()};
  }
  if (max_pairs < 1) return Error{"max_pairs: must be >= 1"};
  if (max_pairs_per_end < 0) return Error{"max_pairs_per_end: must be >= 0 (0 = no limit)"};
  if (!(auto_max_span_fraction > 0.0 && auto_max_span_fraction <= 0.5)) {
    return Error{"auto_max_span_fraction: must be in (0, 0.5]"};
  }
  return Status::Ok();
}

std::string PairsText(const PairOptions& options) {
  const std::string policy = ToString(options.policy);
  return options.policy == PairOptions::Policy::kRelative
             ? policy + ":" + std::to_string(options.step)
             : policy;
}

std::string ToString(PairOptions::Policy policy) {
  switch (policy) {
    case PairOptions::Policy::kSinceStart:
      return "start";
    case PairOptions::Policy::kRelative:
      return "relative";
    case PairOptions::Policy::kAuto:
      return "auto";
    case PairOptions::Policy::kWalk:
      return "walk";
    case PairOptions::Policy::kGls:
      return "gls";
  }
  return "?";
}

}  // namespace rigcal
