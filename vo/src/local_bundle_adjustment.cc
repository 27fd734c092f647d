// SPDX-License-Identifier: Apache-2.0
#include "local_bundle_adjustment.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <unordered_set>

#include "bearing_cost.h"
#include "triangulation.h"

namespace rigcal::vo {
namespace {

double ObservationAngle(const Keyframe& kf, const Landmark& lm, const Observation& obs) {
  return VectorAngle(obs.bearing, kf.q_world_from_cam.conjugate() * (lm.point - kf.C));
}

}  // namespace

LocalBaSummary LocalBundleAdjust(const std::vector<int>& window, const LocalBaOptions& options,
                                 VoMap* map) {
  LocalBaSummary summary;
  std::set<int> in_window;
  for (int id : window) {
    if (map->keyframe(id) != nullptr) in_window.insert(id);
  }
  if (in_window.size() < 2) return summary;

  ceres::Problem::Options problem_options;
  // Manifolds and the loss (shared by all residual blocks) live on this stack frame.
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::EigenQuaternionManifold quaternion_manifold;
  ceres::SphereManifold<3> sphere_manifold;
  ceres::HuberLoss huber(options.huber_rad);
  ceres::LossFunction* loss = &huber;
  ceres::Problem problem(problem_options);

  std::unordered_set<int> used_keyframes;
  for (auto& [id, lm] : map->landmarks()) {
    int count = 0;
    for (const Observation& obs : lm.observations) count += in_window.count(obs.keyframe_id);
    if (count < 2) continue;
    ++summary.num_landmarks;
    for (const Observation& obs : lm.observations) {
      if (!in_window.count(obs.keyframe_id)) continue;
      Keyframe* kf = map->keyframe(obs.keyframe_id);
      problem.AddResidualBlock(new BearingCost(obs.bearing), loss,
                               kf->q_world_from_cam.coeffs().data(), kf->C.data(), lm.point.data());
      used_keyframes.insert(obs.keyframe_id);
      ++summary.num_residuals;
    }
  }
  if (used_keyframes.size() < 2) return summary;

  int index = 0;
  for (int id : in_window) {
    Keyframe* kf = map->keyframe(id);
    if (!used_keyframes.count(id)) {
      ++index;
      continue;
    }
    problem.SetManifold(kf->q_world_from_cam.coeffs().data(), &quaternion_manifold);
    if (index < options.num_fixed) {
      problem.SetParameterBlockConstant(kf->q_world_from_cam.coeffs().data());
      problem.SetParameterBlockConstant(kf->C.data());
    } else if (options.unit_baseline && index == options.num_fixed) {
      if (kf->C.norm() > 0.0) kf->C.normalize();
      problem.SetManifold(kf->C.data(), &sphere_manifold);
    }
    ++index;
  }
  summary.num_keyframes = static_cast<int>(used_keyframes.size());

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  solver_options.function_tolerance = 1e-6;
  ceres::Solver::Summary solver_summary;
  ceres::Solve(solver_options, &problem, &solver_summary);
  summary.initial_cost = solver_summary.initial_cost;
  summary.final_cost = solver_summary.final_cost;
  summary.iterations = static_cast<int>(solver_summary.iterations.size());
  summary.success = solver_summary.IsSolutionUsable();

  // Remove observations that do not fit, and landmarks left without two observations.
  std::vector<int> dead;
  for (auto& entry : map->landmarks()) {  // no structured binding: the lambda captures `lm`
    Landmark& lm = entry.second;
    auto& obs = lm.observations;
    const size_t before = obs.size();
    obs.erase(std::remove_if(obs.begin(), obs.end(),
                             [&](const Observation& o) {
                               const Keyframe* kf = map->keyframe(o.keyframe_id);
                               return kf == nullptr ||
                                      !(ObservationAngle(*kf, lm, o) <= options.outlier_rad);
                             }),
              obs.end());
    summary.removed_observations += static_cast<int>(before - obs.size());
    if (before >= 2 && obs.size() < 2) dead.push_back(entry.first);
  }
  for (int id : dead) map->RemoveLandmark(id);
  summary.removed_landmarks = static_cast<int>(dead.size());
  return summary;
}

}  // namespace rigcal::vo
