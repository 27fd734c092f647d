// SPDX-License-Identifier: Apache-2.0
#pragma once
// Which two-view relation explains a set of correspondences: the essential matrix (a general
// scene seen from two positions) or a homography (a plane, or no translation at all). Torr's
// Geometric Robust Information Criterion (GRIC; P. Torr, "An assessment of information criteria
// for motion model selection", CVPR 1997) scores a relation fitted to n correspondences by
//   GRIC = sum_i min(e_i^2 / σ^2, λ3 (r - d)) + λ1 d n + λ2 k,
// e_i the geometric distance of correspondence i to the relation (both views' errors, in the
// r = 4 dimensions of two image points), σ the per-axis noise, d the dimension of the relation's
// manifold in that space (E: 3, H: 2), k its parameters (E: 5, H: 8), λ1 = ln r, λ2 = ln(r n) and
// λ3 = 2: a correspondence that does not fit costs what a fitting one may cost at most (an
// outlier of either model). The lower GRIC wins: it is the relation with the shorter
// description of the data, so a homography wins on a plane and without translation (it fits as
// well with a lower-dimensional manifold) and loses as soon as the depths vary within the noise.
//
// ORB-SLAM (Mur-Artal et al. 2015) selects between the two by a ratio of similar robust scores
// with a threshold tuned on its sequences; GRIC needs no tuned constant.

#include <vector>

namespace rigcal::vo {

enum class TwoViewModel { kEssential, kHomography };

// GRIC of a relation of manifold dimension `manifold_dims` with `model_params` parameters, from
// the squared geometric distances of the correspondences over σ^2 (4-D data, see above).
double Gric(const std::vector<double>& squared_distances_over_sigma2, int manifold_dims,
            int model_params);

struct TwoViewModelChoice {
  TwoViewModel model = TwoViewModel::kEssential;
  double gric_essential = 0.0;
  double gric_homography = 0.0;
};

// Chooses between an essential matrix and a homography from the angles of every correspondence
// to each (the larger one-sided angle: EpipolarAngle, HomographyTransferAngle), radians, and the
// per-axis noise as an angle `sigma_rad`. A one-sided distance carries both views' noise, so the
// geometric distance in the 4-D space is the one-sided one over √2.
TwoViewModelChoice ChooseTwoViewModel(const std::vector<double>& epipolar_angles_rad,
                                      const std::vector<double>& transfer_angles_rad,
                                      double sigma_rad);

}  // namespace rigcal::vo
