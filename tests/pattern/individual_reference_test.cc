// SPDX-License-Identifier: Apache-2.0
// The individual reference pose model (thesis 4.2, two-pattern setup of 5.7) on simulated
// views: a two-camera rig (slave turned 90 deg about the master's y axis, 0.33 m away, as the
// thesis's virtual rig of 5.7 at a tenth of its size) moves in front of two fixed chessboards,
// the master seeing board A and the slave board B, never the same. The corners are projected
// with OpenCV plus Gaussian noise of 0.1 px, and each camera's pose in its own board's frame
// comes from PnP (target_poses.h), as it does on real images.
//
// Tolerances from the math: the estimate's errors divided by its reported σ are standard
// normal when σ is right; over 10 independent runs (30 numbers per quantity) their RMS is 1
// with a standard deviation of about 1 / sqrt(2 * 30) = 0.13, so [0.5, 2] fails only for a σ
// wrong by a factor of two, and 5 σ per single run bounds the error itself.

#include "rigcal/pattern/individual_reference.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "rigcal/calib/synthetic.h"
#include "rigcal/pattern/target_poses.h"
#include "rigcal/pattern/target_views.h"
#include "support/board_views.h"

namespace rigcal::pattern {
namespace {

using camera::CameraSpec;

CameraSpec Camera(const std::string& name) {
  return test_support::EurocLikeCamera(name, CameraSpec::Model::kPinhole);
}

// The board seen by `spec` from `target_from_cam`.
pattern::TargetView Project(const CameraSpec& spec, const Pose& target_from_cam, std::mt19937& rng,
                   double noise_px, int64_t t_ns) {
  return test_support::ProjectBoard(spec, target_from_cam.Inverse(), rng, noise_px, t_ns,
                                    std::to_string(t_ns) + ".csv");
}

// A camera 0.7 m in front of the board's centre, looking at it.
Pose NominalTargetFromCam() {
  Pose cam_from_target;
  cam_from_target.C = Eigen::Vector3d(0.0, 0.0, 0.7) - Eigen::Vector3d(0.16, 0.10, 0.0);
  return cam_from_target.Inverse();
}

Pose Rig() {
  Pose d;  // slave in the master frame
  d.q = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()));
  d.C = Eigen::Vector3d(-0.1, 0.1, 0.3);
  return d;
}

struct Recording {
  TimedTrajectory master;
  TimedTrajectory slave;
  Pose w;  // board B in board A's frame
};

// `n` instants; the rig turns about random axes (up to `max_angle` rad) when `one_axis` is
// false, else about the master's y axis only.
Recording Simulate(unsigned seed, int n, double max_angle, bool one_axis, double noise_px = 0.1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Pose d = Rig();
  const Pose a_from_cam0 = NominalTargetFromCam();
  const Pose b_from_cam1 = NominalTargetFromCam();
  Recording rec;
  rec.w = a_from_cam0 * d * b_from_cam1.Inverse();
  pattern::CameraViews views0;
  pattern::CameraViews views1;
  views0.camera = "cam0";
  views1.camera = "cam1";
  views0.width = views1.width = 752;
  views0.height = views1.height = 480;
  for (int k = 0; k < n; ++k) {
    Pose motion;  // the rig's motion, in the master's nominal frame
    // Vectors drawn through RandomVector3 (a fixed order of the components).
    Eigen::Vector3d axis =
        one_axis ? Eigen::Vector3d::UnitY() : RandomVector3(unit, rng).normalized();
    motion.q = Eigen::Quaterniond(Eigen::AngleAxisd(max_angle * unit(rng), axis));
    motion.C = 0.08 * RandomVector3(unit, rng);
    const Pose a_cam0 = a_from_cam0 * motion;
    const Pose b_cam1 = rec.w.Inverse() * a_cam0 * d;
    const int64_t t = (k + 1) * 50000000LL;
    views0.views.push_back(Project(Camera("cam0"), a_cam0, rng, noise_px, t));
    views1.views.push_back(Project(Camera("cam1"), b_cam1, rng, noise_px, t));
  }
  auto poses0 = pattern::EstimateTargetPoses(views0, Camera("cam0"));
  auto poses1 = pattern::EstimateTargetPoses(views1, Camera("cam1"));
  EXPECT_TRUE(poses0.ok() && poses1.ok());
  if (poses0.ok()) rec.master = pattern::PosesAsTrajectory("cam0", *poses0, 2.0);
  if (poses1.ok()) rec.slave = pattern::PosesAsTrajectory("cam1", *poses1, 2.0);
  return rec;
}

TEST(IndividualReference, RecoversTheRigWithHonestSigma) {
  const Pose truth = Rig();
  double rot_sq = 0.0;
  double pos_sq = 0.0;
  int count = 0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const Recording rec = Simulate(seed, 60, 0.3, false);
    ASSERT_EQ(rec.master.size(), 60u);
    ASSERT_EQ(rec.slave.size(), 60u);
    auto fit = pattern::EstimateIndividualReference(rec.master, rec.slave, 1000000);
    ASSERT_TRUE(fit.ok()) << fit.error();
    const pattern::ReferenceEstimate& e = fit->estimate;
    EXPECT_EQ(e.slave, "cam1");
    EXPECT_DOUBLE_EQ(e.master_from_slave.scale, 1.0);
    // Rotation error (right perturbation, slave frame) against the largest-axis σ.
    const Eigen::AngleAxisd rot_err(truth.q.conjugate() * e.master_from_slave.q);
    const double rot_err_deg = rot_err.angle() * 180.0 / M_PI;
    EXPECT_LT(rot_err_deg, 5.0 * e.rot_std_deg) << "seed " << seed;
    const Eigen::Vector3d pos_err = e.master_from_slave.C - truth.C;
    for (int a = 0; a < 3; ++a) {
      ASSERT_GT(e.pos_std[a], 0.0);
      EXPECT_LT(std::abs(pos_err[a]), 5.0 * e.pos_std[a]) << "seed " << seed << " axis " << a;
      pos_sq += (pos_err[a] / e.pos_std[a]) * (pos_err[a] / e.pos_std[a]);
    }
    // The rotation's σ is the largest axis: its normalised error is at most that of a 3-D
    // standard normal vector; count it as one number per axis.
    rot_sq += (rot_err_deg / e.rot_std_deg) * (rot_err_deg / e.rot_std_deg);
    count += 3;
    // The boards' relative pose.
    EXPECT_LT(fit->master_target_from_slave_target.q.angularDistance(rec.w.q), 0.01);
    EXPECT_LT((fit->master_target_from_slave_target.C - rec.w.C).norm(), 0.01);
  }
  const double pos_rms = std::sqrt(pos_sq / count);
  const double rot_rms = std::sqrt(rot_sq / (count / 3));
  std::printf("normalised error RMS: position %.2f, rotation %.2f (sqrt(3) for exact σ)\n", pos_rms,
              rot_rms);
  EXPECT_GT(pos_rms, 0.5);
  EXPECT_LT(pos_rms, 2.0);
  // The rotation error norm over the largest-axis σ: RMS at most sqrt(3) = 1.73 for honest σ.
  EXPECT_GT(rot_rms, 0.5);
  EXPECT_LT(rot_rms, 2.0 * std::sqrt(3.0));
}

TEST(IndividualReference, NoiselessPosesKeepEveryInstant) {
  // Residuals are rounding: no instant is an outlier, and the rig comes back exactly.
  const Recording rec = Simulate(2, 30, 0.3, false, /*noise_px=*/0.0);
  auto fit = pattern::EstimateIndividualReference(rec.master, rec.slave, 1000000);
  ASSERT_TRUE(fit.ok()) << fit.error();
  EXPECT_EQ(fit->estimate.rejected, 0);
  EXPECT_EQ(fit->estimate.instants, 30);
  EXPECT_LT(fit->estimate.master_from_slave.q.angularDistance(Rig().q), 1e-6);
  EXPECT_LT((fit->estimate.master_from_slave.C - Rig().C).norm(), 1e-6);
}

TEST(IndividualReference, RotationAboutOneAxisIsReportedNotDetermined) {
  const Recording rec = Simulate(3, 40, 0.3, true);
  auto fit = pattern::EstimateIndividualReference(rec.master, rec.slave, 1000000);
  ASSERT_FALSE(fit.ok());
  EXPECT_NE(fit.error().find("one axis"), std::string::npos) << fit.error();
}

TEST(IndividualReference, TooFewInstantsIsAnError) {
  Recording rec = Simulate(4, 3, 0.3, false);
  auto fit = pattern::EstimateIndividualReference(rec.master, rec.slave, 1000000);
  ASSERT_FALSE(fit.ok());
  EXPECT_NE(fit.error().find("need 4"), std::string::npos) << fit.error();
}

}  // namespace
}  // namespace rigcal::pattern
