// SPDX-License-Identifier: Apache-2.0
#include "models/scale_measurement.h"

#include <algorithm>
#include <cmath>

#include "rigcal/base/robust_statistics.h"

namespace rigcal::internal {

std::vector<ScaleMeasurement> MeasureScales(const std::vector<MotionData>& motions, double epsilon,
                                            bool translational) {
  std::vector<ScaleMeasurement> out;
  const double delta = 3.0 * epsilon;  // (4.23) with L = 0.5
  for (size_t k = 0; k < motions.size(); ++k) {
    const auto& m = motions[k];
    if (translational) {
      const double ni = m.Ci.norm();
      if (ni > delta) out.push_back({m.C0.norm() / ni, static_cast<int>(k)});  // (4.31)
      continue;
    }
    const double v0 = m.q0.tail<3>().norm(), vi = m.qi.tail<3>().norm();
    if (v0 < 1e-9 || vi < 1e-9) continue;  // no rotation axis
    const double s0 = m.C0.dot(m.q0.tail<3>() / v0);
    const double si = m.Ci.dot(m.qi.tail<3>() / vi);
    if (std::abs(si) <= delta) continue;
    out.push_back({s0 / si, static_cast<int>(k)});  // (4.18)
  }
  return out;
}

ScaleSummary SummarizeScales(const std::vector<ScaleMeasurement>& measurements,
                             const std::vector<MotionData>& motions, int scale_index) {
  std::vector<double> v;
  for (const auto& m : measurements) {
    if (motions[m.motion].scale_index == scale_index) v.push_back(m.value);
  }
  ScaleSummary s;
  s.count = static_cast<int>(v.size());
  if (v.empty()) return s;
  double sum = 0.0;
  for (double x : v) sum += x;
  s.mean = sum / v.size();
  double ss = 0.0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.sigma_thesis = std::sqrt(ss);
  s.std = v.size() > 1 ? std::sqrt(ss / (v.size() - 1)) : 0.0;
  s.median = UpperMedian(std::move(v));
  return s;
}

}  // namespace rigcal::internal
