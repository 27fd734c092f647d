// SPDX-License-Identifier: Apache-2.0
#include "two_view_model_selection.h"

#include <algorithm>
#include <cmath>

namespace rigcal::vo {
namespace {

constexpr int kDataDims = 4;  // two image points
constexpr int kEssentialDims = 3;
constexpr int kEssentialParams = 5;
constexpr int kHomographyDims = 2;
constexpr int kHomographyParams = 8;

std::vector<double> SquaredGeometric(const std::vector<double>& one_sided_rad, double sigma_rad) {
  std::vector<double> out;
  out.reserve(one_sided_rad.size());
  const double variance = sigma_rad * sigma_rad;
  for (double a : one_sided_rad) out.push_back(0.5 * a * a / variance);
  return out;
}

}  // namespace

double Gric(const std::vector<double>& squared_distances_over_sigma2, int manifold_dims,
            int model_params) {
  const double n = static_cast<double>(squared_distances_over_sigma2.size());
  const double cap = 2.0 * (kDataDims - manifold_dims);
  double sum = 0.0;
  for (double e2 : squared_distances_over_sigma2) {
    sum += std::isfinite(e2) ? std::min(e2, cap) : cap;
  }
  return sum + std::log(kDataDims) * manifold_dims * n +
         std::log(kDataDims * std::max(1.0, n)) * model_params;
}

TwoViewModelChoice ChooseTwoViewModel(const std::vector<double>& epipolar_angles_rad,
                                      const std::vector<double>& transfer_angles_rad,
                                      double sigma_rad) {
  TwoViewModelChoice choice;
  choice.gric_essential =
      Gric(SquaredGeometric(epipolar_angles_rad, sigma_rad), kEssentialDims, kEssentialParams);
  choice.gric_homography =
      Gric(SquaredGeometric(transfer_angles_rad, sigma_rad), kHomographyDims, kHomographyParams);
  choice.model = choice.gric_homography < choice.gric_essential ? TwoViewModel::kHomography
                                                                : TwoViewModel::kEssential;
  return choice;
}

}  // namespace rigcal::vo
