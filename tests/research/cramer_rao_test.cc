// SPDX-License-Identifier: Apache-2.0
#include "rigcal/research/cramer_rao.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <random>

#include "rigcal/calib/error_model.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/research/experiments.h"

namespace rigcal {
namespace {

Eigen::MatrixXd RandomSpd(int n, int rank, std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd a(n, rank);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < rank; ++j) a(i, j) = g(rng);
  }
  return a * a.transpose();
}

TEST(CramerRaoTest, PseudoInverseOfSingularMatrix) {
  std::mt19937_64 rng(1);
  const Eigen::MatrixXd m = RandomSpd(6, 4, rng);
  const Eigen::MatrixXd p = research::PseudoInverseSpd(m);
  EXPECT_LT((m * p * m - m).norm(), 1e-9 * m.norm());
  EXPECT_LT((p * m * p - p).norm(), 1e-9 * p.norm());
  EXPECT_LT((p - p.transpose()).norm(), 1e-12 * p.norm());
  const Eigen::MatrixXd full = RandomSpd(5, 5, rng);
  EXPECT_LT((research::PseudoInverseSpd(full) - full.inverse()).norm(), 1e-8 * full.inverse().norm());
}

// Straight line y_j = theta + beta x_j + e_j, e_j ~ N(0, sigma^2), beta a nuisance parameter:
// the bound on the intercept is sigma^2 sum x^2 / (n sum x^2 - (sum x)^2).
TEST(CramerRaoTest, LinearRegressionInterceptClosedForm) {
  const std::vector<double> x = {-1.0, 0.5, 2.0, 3.5, 7.0};
  const double sigma = 0.3;
  Eigen::MatrixXd h(x.size(), 2);
  double sx = 0.0, sxx = 0.0;
  for (size_t j = 0; j < x.size(); ++j) {
    h(j, 0) = 1.0;
    h(j, 1) = x[j];
    sx += x[j];
    sxx += x[j] * x[j];
  }
  const double n = static_cast<double>(x.size());
  const Eigen::MatrixXd w = Eigen::MatrixXd::Identity(x.size(), x.size()) / (sigma * sigma);
  const Eigen::MatrixXd fisher = research::FisherInformation(h, w);
  const double expected = sigma * sigma * sxx / (n * sxx - sx * sx);
  EXPECT_NEAR(research::SchurComplementBound(fisher, 1)(0, 0), expected, 1e-12);
  EXPECT_NEAR(research::ConstrainedBound(fisher, Eigen::MatrixXd(0, 2), 1)(0, 0), expected, 1e-12);
  // Without the nuisance (beta known): sigma^2 / n.
  EXPECT_NEAR(research::SchurComplementBound(fisher.topLeftCorner(1, 1), 1)(0, 0), sigma * sigma / n, 1e-12);
}

// y1 = t1 + b + e1, y2 = t2 + b + e2, y3 = b + e3: only y3 tells b, so t_i = y_i - y3 and the
// bound is [[s1^2 + s3^2, s3^2], [s3^2, s2^2 + s3^2]].
TEST(CramerRaoTest, SharedNuisanceClosedForm) {
  const double s1 = 0.5, s2 = 2.0, s3 = 0.7;
  Eigen::MatrixXd h(3, 3);
  h << 1, 0, 1,  //
      0, 1, 1,   //
      0, 0, 1;
  Eigen::MatrixXd w = Eigen::Vector3d(1 / (s1 * s1), 1 / (s2 * s2), 1 / (s3 * s3)).asDiagonal();
  Eigen::Matrix2d expected;
  expected << s1 * s1 + s3 * s3, s3 * s3, s3 * s3, s2 * s2 + s3 * s3;
  const Eigen::MatrixXd fisher = research::FisherInformation(h, w);
  EXPECT_LT((research::SchurComplementBound(fisher, 2) - expected).norm(), 1e-12);
  EXPECT_LT((research::ConstrainedBound(fisher, Eigen::MatrixXd(0, 3), 2) - expected).norm(), 1e-12);
  EXPECT_LT(
      (research::SchurComplementBound(fisher, 2) - Eigen::MatrixXd(fisher.inverse()).topLeftCorner(2, 2))
          .norm(),
      1e-12);
}

TEST(CramerRaoTest, UndeterminedParametersGiveInfiniteBound) {
  // theta appears in no observation.
  Eigen::MatrixXd h(2, 2);
  h << 0, 1,  //
      0, 2;
  const Eigen::MatrixXd fisher = research::FisherInformation(h, Eigen::MatrixXd::Identity(2, 2));
  EXPECT_TRUE(std::isinf(research::SchurComplementBound(fisher, 1)(0, 0)));
  EXPECT_TRUE(std::isinf(research::ConstrainedBound(fisher, Eigen::MatrixXd(0, 2), 1)(0, 0)));
  // An undetermined nuisance that does not couple to theta does not matter.
  Eigen::MatrixXd h2(1, 2);
  h2 << 2, 0;
  const Eigen::MatrixXd f2 = research::FisherInformation(h2, Eigen::MatrixXd::Identity(1, 1));
  EXPECT_NEAR(research::SchurComplementBound(f2, 1)(0, 0), 0.25, 1e-12);
  EXPECT_NEAR(research::ConstrainedBound(f2, Eigen::MatrixXd(0, 2), 1)(0, 0), 0.25, 1e-12);
}

// An exact observation is the limit of ever more precise ones: the constrained bound equals the
// Schur bound with a huge weight on the constrained directions.
TEST(CramerRaoTest, ConstrainedBoundIsLimitOfPreciseObservations) {
  std::mt19937_64 rng(7);
  const Eigen::MatrixXd fisher = RandomSpd(8, 8, rng);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd constraints(2, 8);
  for (int i = 0; i < constraints.size(); ++i) constraints.data()[i] = g(rng);
  const Eigen::MatrixXd exact = research::ConstrainedBound(fisher, constraints, 3);
  // The difference falls as 1/weight (1e-4 relative at 1e4); much larger weights lose digits.
  const Eigen::MatrixXd precise =
      research::SchurComplementBound(fisher + 1e6 * constraints.transpose() * constraints, 3);
  EXPECT_LT((exact - precise).norm(), 1e-4 * exact.norm());
  // Constraints add information: the bound shrinks (in the positive semi-definite order).
  const Eigen::MatrixXd free = research::SchurComplementBound(fisher, 3);
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(free - exact).eigenvalues().minCoeff(),
            -1e-12);
}

struct Geometry {
  std::vector<Pose> master;  // k = 1..K
  Similarity rig;
  RigRecording recording;  // noise-free
};

Geometry RandomGeometry(int num_poses, double max_rotation_deg, std::mt19937_64& rng) {
  ThesisSampleOptions options;
  options.num_poses = num_poses;
  options.max_rotation_deg = max_rotation_deg;
  Geometry g;
  std::vector<Similarity> truth;
  g.recording = ThesisSample(options, rng, &truth);
  g.rig = truth.at(0);
  g.master.assign(g.recording.master.poses.begin() + 1, g.recording.master.poses.end());
  return g;
}

TEST(CramerRaoTest, PoseByPoseEliminationEqualsFullSystem) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    const Geometry g = RandomGeometry(3 + trial, 180.0, rng);
    const double eps = 1.0 * kRadPerDeg;
    const research::ThesisBound bound = research::ThesisCramerRaoBound(g.master, g.rig, eps);
    ASSERT_TRUE(bound.finite);
    const research::ThesisFisherSystem system = research::ThesisFisher(g.master, g.rig, eps);
    EXPECT_EQ(system.fisher.rows(), 7 + 6 * (3 + trial));
    EXPECT_EQ(system.constraints.rows(), 2 * (3 + trial));
    const Eigen::MatrixXd dense = research::ConstrainedBound(system.fisher, system.constraints, 7);
    EXPECT_LT((dense - bound.covariance).norm(), 1e-8 * bound.covariance.norm());
  }
}

TEST(CramerRaoTest, BoundIsLinearInEpsAndShrinksWithMorePoses) {
  std::mt19937_64 rng(5);
  const Geometry g = RandomGeometry(12, 180.0, rng);
  const research::ThesisBound one = research::ThesisCramerRaoBound(g.master, g.rig, 1.0 * kRadPerDeg);
  const research::ThesisBound two = research::ThesisCramerRaoBound(g.master, g.rig, 2.0 * kRadPerDeg);
  ASSERT_TRUE(one.finite);
  EXPECT_NEAR(two.rot_deg, 2.0 * one.rot_deg, 1e-6 * one.rot_deg);
  EXPECT_NEAR(two.dir_deg, 2.0 * one.dir_deg, 1e-6 * one.dir_deg);
  EXPECT_NEAR(two.dist_pct, 2.0 * one.dist_pct, 1e-6 * one.dist_pct);
  EXPECT_NEAR(two.scale_pct, 2.0 * one.scale_pct, 1e-6 * one.scale_pct);
  // Dropping poses loses information.
  const std::vector<Pose> fewer(g.master.begin(), g.master.begin() + 4);
  const research::ThesisBound four = research::ThesisCramerRaoBound(fewer, g.rig, 1.0 * kRadPerDeg);
  EXPECT_GT(four.rot_deg, one.rot_deg);
  EXPECT_GT(four.dir_deg, one.dir_deg);
  // Without any length information the scale is not determined.
  research::ThesisNoiseModel no_lengths;
  no_lengths.exact_lengths = false;
  EXPECT_FALSE(research::ThesisCramerRaoBound(g.master, g.rig, 1.0 * kRadPerDeg, no_lengths).finite);
}

// The noise model's covariances are the second moments of the thesis perturbation (PerturbPose).
TEST(CramerRaoTest, NoiseModelMatchesThesisPerturbation) {
  std::mt19937_64 rng(3);
  const double eps = 1.0 * kRadPerDeg;
  Pose pose;
  pose.q = AxisAngle(Eigen::Vector3d(1, 2, 3), 0.7);
  pose.C = Eigen::Vector3d(3.0, -4.0, 12.0);
  const int n = 40000;
  Eigen::Matrix3d rot_cov = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d pos_cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Pose noisy = PerturbPose(pose, eps, rng);
    const Eigen::AngleAxisd aa(noisy.q * pose.q.conjugate());
    const Eigen::Vector3d r = aa.angle() * aa.axis();
    const Eigen::Vector3d d = noisy.C - pose.C;
    rot_cov += r * r.transpose() / n;
    pos_cov += d * d.transpose() / n;
  }
  const research::ThesisNoiseModel model;
  const Eigen::Matrix3d rot_expected =
      model.rotation_variance_factor * eps * eps * Eigen::Matrix3d::Identity();
  const double len2 = pose.C.squaredNorm();
  const Eigen::Matrix3d pos_expected =
      model.position_variance_factor * eps * eps *
      (len2 * Eigen::Matrix3d::Identity() - pose.C * pose.C.transpose());
  // 40000 samples: relative sampling error of a variance about sqrt(2/n) ~ 0.7 %.
  EXPECT_LT((rot_cov - rot_expected).norm(), 0.03 * rot_expected.norm());
  EXPECT_LT((pos_cov - pos_expected).norm(), 0.03 * pos_expected.norm());
}

// The bound is a lower bound: the non-linear estimator's RMS rotation error over many samples
// (small noise, many poses: the linearisation holds) is not below it. Rotations stay below 150
// deg, away from the 180 deg quaternion sign ambiguity, so that no gross failure masks the test.
TEST(CramerRaoTest, NonlinearEstimatorDoesNotBeatTheBound) {
  const int num_samples = 300;
  const int num_poses = 12;
  const double eps = 0.2 * kRadPerDeg;
  double err_rot2 = 0.0, bound_rot2 = 0.0, err_dir2 = 0.0, bound_dir2 = 0.0;
  int used = 0;
  for (int i = 0; i < num_samples; ++i) {
    std::mt19937_64 rng = research::SampleRng(42, 0, i);
    const Geometry g = RandomGeometry(num_poses, 150.0, rng);
    const research::ThesisBound bound = research::ThesisCramerRaoBound(g.master, g.rig, eps);
    if (!bound.finite) continue;
    RigRecording noisy = g.recording;
    for (int k = 1; k <= num_poses; ++k) {
      noisy.master.poses[k] = PerturbPose(noisy.master.poses[k], eps, rng);
      noisy.slaves[0].poses[k] = PerturbPose(noisy.slaves[0].poses[k], eps, rng);
    }
    PairOptions pairs;
    pairs.policy = PairOptions::Policy::kSinceStart;
    const auto motions = MotionsForSlave(noisy, 0, SelectPairs(noisy, pairs));
    const SlaveCalibration result = CalibrateSlave(
        motions,
        research::ThesisCalibrationOptions(Method::kNonlinear, MotionModel::kGeneral, ScaleModel::kFixed));
    ASSERT_TRUE(result.usable()) << result.message;
    const CalibrationError error = CompareToTruth(result.estimate, g.rig);
    err_rot2 += error.rot_deg * error.rot_deg;
    err_dir2 += error.dir_deg * error.dir_deg;
    bound_rot2 += bound.rot_deg * bound.rot_deg;
    bound_dir2 += bound.dir_deg * bound.dir_deg;
    ++used;
  }
  ASSERT_GT(used, num_samples * 9 / 10);
  const double rms_rot = std::sqrt(err_rot2 / used);
  const double crb_rot = std::sqrt(bound_rot2 / used);
  const double rms_dir = std::sqrt(err_dir2 / used);
  const double crb_dir = std::sqrt(bound_dir2 / used);
  std::printf("NL RMS rotation %.4f deg (bound %.4f), direction %.4f deg (bound %.4f)\n", rms_rot,
              crb_rot, rms_dir, crb_dir);
  // 0.8: sampling error of an RMS over 300 samples is a few percent; 0.8 leaves a wide margin.
  EXPECT_GE(rms_rot, 0.8 * crb_rot) << "rms " << rms_rot << " bound " << crb_rot;
  EXPECT_GE(rms_dir, 0.8 * crb_dir) << "rms " << rms_dir << " bound " << crb_dir;
  // And the bound is informative: a sound estimator comes within a small factor of it.
  EXPECT_LE(rms_rot, 3.0 * crb_rot) << "rms " << rms_rot << " bound " << crb_rot;
}

}  // namespace
}  // namespace rigcal
