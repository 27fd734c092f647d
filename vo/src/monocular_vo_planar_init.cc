// SPDX-License-Identifier: Apache-2.0
// MonocularVo initialisation on a plane (or with too little depth variation for the essential
// matrix): the homography of the two views, the choice between it and the essential matrix
// (GRIC, two_view_model_selection.h) and the motion its decomposition gives.

#include <cmath>
#include <vector>

#include "homography.h"
#include "monocular_vo_impl.h"
#include "two_view_model_selection.h"

namespace rigcal::vo {
namespace {

// Support of one relative pose: the correspondences within the epipolar gate of its essential
// matrix, and those of them that triangulate in front of both views.
struct PoseSupport {
  std::vector<char> inliers;
  int num_inliers = 0;
  int num_in_front = 0;
};

PoseSupport SupportOf(const InitialViews& views, const RelativePose& pose, double gate_rad) {
  PoseSupport support;
  const Eigen::Matrix3d e = EssentialFromPose(pose);
  support.inliers.assign(views.reference.size(), 0);
  if (e.isZero()) return support;  // no translation: no epipolar geometry
  for (size_t i = 0; i < views.reference.size(); ++i) {
    if (EpipolarAngle(e, views.reference[i], views.current[i]) > gate_rad) continue;
    support.inliers[i] = 1;
    ++support.num_inliers;
  }
  support.num_in_front = InliersInFront(pose, views.reference, views.current, support.inliers);
  return support;
}

}  // namespace

void MonocularVo::Impl::PreferPlanarMotion(const InitialViews& views,
                                           RelativePoseRansacResult* motion, VoResult* result) {
  HomographyRansacOptions ransac;
  ransac.max_transfer_angle_rad = PairGateRad();
  ransac.max_iterations = options_.ransac_max_iterations;
  ransac.confidence = options_.ransac_confidence;
  const HomographyRansacResult h = EstimateHomography(views.reference, views.current, ransac);
  if (!h.success) return;
  // Both relations' angles to every track (a track the model cannot hold costs its cap).
  const size_t n = views.reference.size();
  const Eigen::Matrix3d h_inverse = h.H_1_from_2.inverse();
  std::vector<double> epipolar_rad(n, M_PI / 2), transfer_rad(n, M_PI / 2);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& f1 = views.reference[i];
    const Eigen::Vector3d& f2 = views.current[i];
    if (!motion->E.isZero()) epipolar_rad[i] = EpipolarAngle(motion->E, f1, f2);
    transfer_rad[i] = HomographyTransferAngle(h.H_1_from_2, h_inverse, f1, f2);
  }
  const TwoViewModelChoice choice = ChooseTwoViewModel(epipolar_rad, transfer_rad, NoiseRad());
  log_->debug("camera {}: two-view GRIC essential {:.0f} ({} inliers), homography {:.0f} ({})",
              camera_index_, choice.gric_essential, motion->num_inliers, choice.gric_homography,
              h.num_inliers);
  if (choice.model == TwoViewModel::kEssential) return;

  // The decompositions whose epipolar geometry the tracks support in front of both views (the
  // tracks off the plane count too, which is what tells the two physical decompositions apart
  // when the plane alone cannot). Exactly one must pass; with two, the essential matrix decides.
  const double gate = PairGateRad();
  const double needed = options_.min_init_cheirality_fraction * h.num_inliers;
  int accepted = 0;
  PoseSupport best;
  RelativePose best_pose;
  for (const PlanarMotion& m : DecomposeHomography(h.H_1_from_2)) {
    PoseSupport support = SupportOf(views, m.pose, gate);
    if (support.num_in_front < needed) continue;
    ++accepted;
    if (support.num_in_front > best.num_in_front) {
      best = std::move(support);
      best_pose = m.pose;
    }
  }
  if (accepted != 1) {
    // The plane alone cannot tell the motions apart (yet): the essential matrix's own gates
    // decide, as without a homography.
    log_->debug(
        "camera {}: homography ({} of {} tracks) preferred to the essential matrix, but {} of "
        "its decompositions have {:.0f} tracks in front of both views; essential matrix kept",
        camera_index_, h.num_inliers, n, accepted, needed);
    return;
  }
  motion->success = true;
  motion->pose = best_pose;
  motion->E = EssentialFromPose(best_pose);
  motion->inliers = std::move(best.inliers);
  motion->num_inliers = best.num_inliers;
  motion->num_in_front = best.num_in_front;
  result->inliers = motion->num_inliers;
  log_->debug("camera {}: planar initialisation, {} of {} tracks support the motion", camera_index_,
              motion->num_inliers, n);
}

}  // namespace rigcal::vo
