// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 0 of the recursive estimator (RigEstimator::AddSet), beside pose_glitch_gate.h: a pose
// that its odometry tracked poorly (CameraPose::quality, the VO's inlier ratio times its
// inliers over 100: a blurred, over-exposed or half-covered frame) must not become a keyframe,
// enter a motion pair or the pose history of the batch refinement, so that motions start and
// end at well tracked frames.
//
// The threshold comes from the quality's own distribution, per camera: the median m and the
// robust σ (1.4826 MAD) of its last kWindow accepted qualities. A pose is poorly tracked when
//   quality < m - max(sigmas * σ, drop * m)
// i.e. far out in the camera's own distribution AND below (1 - drop) of its usual quality; the
// second term keeps the gate shut on a camera whose quality barely varies (σ near 0: poses read
// from files and LCM logs without a quality carry 1) and on the tail of a clean run, whose
// results it leaves bit for bit as they were. The first kWindow poses of a camera only fill its
// window (a camera whose tracking is poor from the start has no better frames to prefer).
// Poorly tracked poses do not enter the window, so a long burst cannot lower the threshold;
// a camera whose poses are all rejected for kWindow poses in a row has changed for good (a
// darker scene): its window restarts from its newest quality.

#include <optional>
#include <vector>

#include "rigcal/base/types.h"
#include "sync/fixed_ring.h"

namespace rigcal::internal {

struct QualityGateOptions {
  double sigmas = 6.0;  // robust σ below the median
  double drop = 0.5;    // and this fraction of the median below it
};

class PoseQualityGate {
 public:
  static constexpr int kWindow = 41;

  // `cameras`: the master and the slaves.
  explicit PoseQualityGate(int cameras, QualityGateOptions options = {});

  // Per camera of the set (poses[0] the master): true when its pose is poorly tracked. Absent
  // poses are false.
  std::vector<bool> Check(const std::vector<std::optional<CameraPose>>& poses);

  // The current threshold of camera `camera` (NaN while its window fills).
  double Threshold(int camera) const;

 private:
  struct Camera {
    FixedRing<double> window{kWindow, 0.0};
    int rejected_in_row = 0;
    double threshold = 0.0;  // valid when the window is full
  };
  void Accept(Camera* c, double quality) const;

  QualityGateOptions options_;
  std::vector<Camera> cameras_;
};

}  // namespace rigcal::internal
