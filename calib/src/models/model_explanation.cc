// SPDX-License-Identifier: Apache-2.0
// The motion-model explanation of the batch and the online results (model_explanation.h).
#include "models/model_explanation.h"

#include <cmath>
#include <sstream>
#include <vector>

#include "rigcal/base/format.h"

namespace rigcal::internal {
namespace {

std::string VectorText3(const Eigen::Vector3d& v) { return VectorText(v, 3); }

// Thesis 5.2: the largest rotation against the equal-error boundary at the rotation noise.
std::string BoundaryReason(const ModelExplanation& e) {
  const Observability& f = e.figures;
  const std::string largest = "largest rotation " + FixedText(f.max_rotation_deg, 2) + " deg";
  if (e.boundary == ModelExplanation::Boundary::kLargestRotation) return largest;
  const std::string boundary =
      e.boundary_from_noise ? FixedText(f.translational_below_deg, 2) +
                                  " deg, the equal-error boundary at the measured rotation noise " +
                                  FixedText(f.rotation_noise_deg, 3) + " deg"
                            : FixedText(f.translational_below_deg, 1) + " deg";
  return largest + (e.model == MotionModel::kTranslational ? " < " : " >= ") + boundary;
}

// What the model leaves undetermined, or how weakly general motion determines C along the axis.
std::string Consequence(const ModelExplanation& e) {
  const Eigen::Vector3d& axis = e.figures.planar_axis;
  if (e.parallel) {
    return ": the translations are all parallel, so the rotation about their direction is "
           "undetermined (drive a curve)";
  }
  if (e.model == MotionModel::kTranslational) {
    return ": rotation and scale only, position unobservable";
  }
  if (e.model == MotionModel::kPlanar) {
    std::string text = ": C along the rotation axis " + VectorText3(axis) + " is unobservable";
    if (!e.nominal) return text + ", reported as 0 (unknown; a nominal mounting would fill it in)";
    text += ", taken from the nominal mounting (" + FixedText(e.nominal_along_axis, 4) +
            " along the axis";
    if (e.nominal_sigma > 0.0) text += ", sigma " + FixedText(e.nominal_sigma, 4);
    return text + ")";
  }
  if (e.figures.axis_std_ratio > 3.0 && std::isfinite(e.axis_offset_std)) {
    std::string text = "; nearly planar: C along the mean rotation axis " + VectorText3(axis) +
                       " has sigma " + FixedText(e.axis_offset_std, 4);
    if (e.nominal && e.nominal_sigma > 0.0) text += " (with the nominal mounting as a prior)";
    return text;
  }
  return "";
}

}  // namespace

std::string ExplainModel(const ModelExplanation& e) {
  std::vector<std::string> why;
  if (e.boundary != ModelExplanation::Boundary::kNone) why.push_back(BoundaryReason(e));
  if (e.model != MotionModel::kTranslational && !e.selection.empty()) why.push_back(e.selection);
  std::string text = ToString(e.model) + " motion";
  if (!why.empty()) {
    text += " (" + why[0];
    for (size_t j = 1; j < why.size(); ++j) text += "; " + why[j];
    text += ")";
  }
  return text + Consequence(e);
}

}  // namespace rigcal::internal
