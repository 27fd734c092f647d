// SPDX-License-Identifier: Apache-2.0
#include "support/relative_pose_errors.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rigcal::support {
namespace {

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

}  // namespace

RelativePoseError CompareRelativeMotion(const Pose& estimate_a, const Pose& estimate_b,
                                        const Pose& reference_a, const Pose& reference_b) {
  const Pose estimate = estimate_a.Between(estimate_b);
  const Pose reference = reference_a.Between(reference_b);
  RelativePoseError e;
  e.rotation_deg = Eigen::AngleAxisd(estimate.q.conjugate() * reference.q).angle() * 180.0 / M_PI;
  e.reference_length = reference.C.norm();
  const double estimate_length = estimate.C.norm();
  if (e.reference_length > 0.0 && estimate_length > 0.0) {
    e.direction_deg = AngleDeg(estimate.C, reference.C);
    e.scale = e.reference_length / estimate_length;
  }
  return e;
}

std::vector<RelativePoseError> RelativePoseErrors(const std::map<int, Pose>& estimate,
                                                  const std::map<int, Pose>& reference, int step) {
  std::vector<RelativePoseError> out;
  for (const auto& [a, pose_a] : estimate) {
    const int b = a + step;
    const auto est_b = estimate.find(b);
    const auto ref_a = reference.find(a);
    const auto ref_b = reference.find(b);
    if (est_b == estimate.end() || ref_a == reference.end() || ref_b == reference.end()) continue;
    RelativePoseError e =
        CompareRelativeMotion(pose_a, est_b->second, ref_a->second, ref_b->second);
    e.a = a;
    e.b = b;
    out.push_back(e);
  }
  return out;
}

ErrorStats Stats(std::vector<double> values) {
  ErrorStats s;
  s.count = static_cast<int>(values.size());
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  s.median = values[(values.size() - 1) / 2];
  s.p90 =
      values[std::min(values.size() - 1, static_cast<size_t>(std::ceil(0.9 * values.size())) - 1)];
  return s;
}

double ScaleSpread(const std::vector<RelativePoseError>& errors, double min_reference_length) {
  std::vector<double> scales;
  for (const RelativePoseError& e : errors) {
    if (e.scale > 0.0 && e.reference_length >= min_reference_length) scales.push_back(e.scale);
  }
  if (scales.size() < 2) return 0.0;
  const double median = Stats(scales).median;
  std::vector<double> deviation;
  for (double s : scales) deviation.push_back(std::abs(s / median - 1.0));
  return Stats(deviation).median;
}

std::string Describe(const std::vector<RelativePoseError>& errors) {
  std::vector<double> rotation, direction;
  for (const RelativePoseError& e : errors) {
    rotation.push_back(e.rotation_deg);
    if (e.scale > 0.0) direction.push_back(e.direction_deg);
  }
  const ErrorStats r = Stats(rotation), d = Stats(direction);
  char text[160];
  std::snprintf(text, sizeof(text),
                "rotation median %.3f p90 %.3f deg, direction median %.1f p90 %.1f deg (n %d)",
                r.median, r.p90, d.median, d.p90, r.count);
  return text;
}

}  // namespace rigcal::support
