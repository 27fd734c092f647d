// SPDX-License-Identifier: Apache-2.0
// Local bundle adjustment of the VO map: convergence from perturbed poses and points with
// bearings all around the sphere, gauge (fixed keyframes, unit baseline) and outlier removal.

#include "../../vo/src/local_bundle_adjustment.h"

#include <gtest/gtest.h>

#include <random>

#include "rigcal/calib/synthetic.h"

namespace rigcal::vo {
namespace {

struct Truth {
  std::vector<Eigen::Quaterniond> q;
  std::vector<Eigen::Vector3d> C;
  std::vector<Eigen::Vector3d> points;
};

// `keyframes` cameras on a short arc looking in all directions (bearings cover the sphere).
Truth MakeScene(int keyframes, int points, std::mt19937* rng) {
  Truth t;
  std::normal_distribution<double> g(0.0, 1.0);
  for (int k = 0; k < keyframes; ++k) {
    t.q.push_back(Eigen::Quaterniond(Eigen::AngleAxisd(0.05 * k, Eigen::Vector3d::UnitY())));
    t.C.push_back(Eigen::Vector3d(0.3 * k, 0.05 * k * k, 0.1 * k));
  }
  t.C[1] = t.C[1].normalized();  // unit first baseline (keyframe 0 at the origin)
  while (static_cast<int>(t.points.size()) < points) {
    const Eigen::Vector3d p = RandomVector3(g, *rng);
    t.points.push_back(p.normalized() * (3.0 + 2.0 * std::abs(g(*rng))));
  }
  return t;
}

VoMap MakeMap(const Truth& t, double pose_noise, double point_noise, std::mt19937* rng,
              std::vector<int>* keyframe_ids) {
  std::normal_distribution<double> g(0.0, 1.0);
  VoMap map;
  for (size_t k = 0; k < t.q.size(); ++k) {
    const bool fixed = k < 2;
    Eigen::Quaterniond q = t.q[k];
    Eigen::Vector3d c = t.C[k];
    if (!fixed) {
      q = q *
          Eigen::Quaterniond(Eigen::AngleAxisd(pose_noise, RandomVector3(g, *rng).normalized()));
      c += pose_noise * RandomVector3(g, *rng);
    }
    keyframe_ids->push_back(map.AddKeyframe(static_cast<int64_t>(k), q, c));
  }
  for (const Eigen::Vector3d& p : t.points) {
    const int id = map.AddLandmark(p + point_noise * RandomVector3(g, *rng));
    for (size_t k = 0; k < t.q.size(); ++k) {
      map.AddObservation(id, (*keyframe_ids)[k], (t.q[k].conjugate() * (p - t.C[k])).normalized());
    }
  }
  return map;
}

TEST(LocalBundleAdjustment, ConvergesWithTwoFixedKeyframes) {
  std::mt19937 rng(1);
  const Truth truth = MakeScene(5, 150, &rng);
  std::vector<int> ids;
  VoMap map = MakeMap(truth, 0.02, 0.05, &rng, &ids);
  LocalBaOptions options;
  options.num_fixed = 2;
  options.max_iterations = 30;
  const LocalBaSummary summary = LocalBundleAdjust(ids, options, &map);
  ASSERT_TRUE(summary.success);
  EXPECT_EQ(summary.num_keyframes, 5);
  EXPECT_EQ(summary.num_landmarks, 150);
  EXPECT_LT(summary.final_cost, 1e-12);
  EXPECT_EQ(summary.removed_observations, 0);
  for (size_t k = 0; k < ids.size(); ++k) {
    const Keyframe* kf = map.keyframe(ids[k]);
    EXPECT_LT(kf->q_world_from_cam.angularDistance(truth.q[k]), 1e-6) << k;
    EXPECT_LT((kf->C - truth.C[k]).norm(), 1e-6) << k;
  }
  for (const auto& [id, lm] : map.landmarks()) {
    EXPECT_LT((lm.point - truth.points[id]).norm(), 1e-5);
  }
}

TEST(LocalBundleAdjustment, TwoViewInitialisationKeepsAUnitBaseline) {
  std::mt19937 rng(2);
  const Truth truth = MakeScene(2, 100, &rng);
  std::vector<int> ids;
  VoMap map = MakeMap(truth, 0.0, 0.05, &rng, &ids);
  map.keyframe(ids[1])->C = truth.C[1] * 1.3 + Eigen::Vector3d(0.05, -0.02, 0.03);
  LocalBaOptions options;
  options.num_fixed = 1;
  options.unit_baseline = true;
  options.max_iterations = 50;
  ASSERT_TRUE(LocalBundleAdjust(ids, options, &map).success);
  EXPECT_NEAR(map.keyframe(ids[1])->C.norm(), 1.0, 1e-12);
  EXPECT_LT((map.keyframe(ids[1])->C - truth.C[1]).norm(), 1e-5);
  EXPECT_TRUE(map.keyframe(ids[0])->C.isZero());
}

TEST(LocalBundleAdjustment, OutlierObservationsAreRemoved) {
  std::mt19937 rng(3);
  const Truth truth = MakeScene(4, 80, &rng);
  std::vector<int> ids;
  VoMap map = MakeMap(truth, 0.0, 0.0, &rng, &ids);
  // Landmark 0: one wrong bearing (an outlier track); landmark 1: wrong in all but one view.
  map.landmark(0)->observations[3].bearing = Eigen::Vector3d(0.3, 0.2, 1.0).normalized();
  for (int k = 1; k < 4; ++k) {
    map.landmark(1)->observations[k].bearing =
        (map.landmark(1)->observations[k].bearing + Eigen::Vector3d(0.2 * k, -0.1, 0.1))
            .normalized();
  }
  LocalBaOptions options;
  const LocalBaSummary summary = LocalBundleAdjust(ids, options, &map);
  ASSERT_TRUE(summary.success);
  ASSERT_NE(map.landmark(0), nullptr);
  EXPECT_EQ(map.landmark(0)->observations.size(), 3u);
  EXPECT_EQ(map.landmark(1), nullptr);  // fewer than two consistent observations left
  EXPECT_GE(summary.removed_observations, 4);
  EXPECT_EQ(summary.removed_landmarks, 1);
  for (size_t k = 2; k < ids.size(); ++k) {
    EXPECT_LT((map.keyframe(ids[k])->C - truth.C[k]).norm(), 1e-3);  // Huber: small pull left
  }
}

TEST(VoMap, PruneKeepsTheNewestKeyframesAndLiveLandmarks) {
  VoMap map;
  std::vector<int> kf;
  for (int k = 0; k < 5; ++k) {
    kf.push_back(map.AddKeyframe(k, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero()));
  }
  const int old_only = map.AddLandmark(Eigen::Vector3d::UnitZ());
  map.AddObservation(old_only, kf[0], Eigen::Vector3d::UnitZ());
  const int old_alive = map.AddLandmark(Eigen::Vector3d::UnitZ());
  map.AddObservation(old_alive, kf[1], Eigen::Vector3d::UnitZ());
  const int recent = map.AddLandmark(Eigen::Vector3d::UnitZ());
  map.AddObservation(recent, kf[1], Eigen::Vector3d::UnitZ());
  map.AddObservation(recent, kf[4], Eigen::Vector3d::UnitZ());
  map.PruneKeyframes(3, [&](int id) { return id == old_alive; });
  EXPECT_EQ(map.keyframes().size(), 3u);
  EXPECT_EQ(map.keyframes().begin()->first, kf[2]);
  EXPECT_EQ(map.landmark(old_only), nullptr);
  ASSERT_NE(map.landmark(old_alive), nullptr);
  EXPECT_TRUE(map.landmark(old_alive)->observations.empty());
  ASSERT_NE(map.landmark(recent), nullptr);
  EXPECT_EQ(map.landmark(recent)->observations.size(), 1u);
  EXPECT_EQ(map.NewestKeyframes(2), (std::vector<int>{kf[3], kf[4]}));
}

}  // namespace
}  // namespace rigcal::vo
