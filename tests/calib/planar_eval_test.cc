// SPDX-License-Identifier: Apache-2.0
// Evaluation of the planar-motion handling on a four-camera car rig (front master; left, right,
// rear): prints rotation, in-plane, vertical and scale errors for
//   - synthetic flat yaw-only drives,
//   - the real KITTI 00 trajectory (nearly planar: slopes and bumps),
//   - KITTI 00 flattened to pure yaw,
//   - the online estimator on a drive that is planar for 2.5 minutes and then climbs a ramp,
// with 0.02 deg rotation and 1 cm position noise per pose, several noise seeds each.
// `ctest -R calib/planar_eval --output-on-failure -V` shows the tables. The assertions are the
// acceptance limits (a broken model misses them by orders of magnitude).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "rigcal/calib/error_model.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/calib/synthetic_car.h"
#include "support/kitti.h"
#include "support/skip.h"

namespace rigcal {
namespace {

constexpr double kRotationNoiseDeg = 0.02;
constexpr double kPositionNoise = 0.01;  // metres
constexpr int kSeeds = 5;

// The car rig along `path` with the pose noise above.
SyntheticDrive NoisyDrive(const SampledTrajectory& path, uint64_t seed) {
  DriveOptions d;
  d.rotation_noise_deg = kRotationNoiseDeg;
  d.position_noise = kPositionNoise;
  d.seed = seed;
  return DriveCarRig(path, d);
}

// Worst case over slaves and seeds.
struct Worst {
  double rot_deg = 0.0, plane = 0.0, axis = 0.0, scale_pct = 0.0;
  double axis_std_min = 1e300, axis_std_max = 0.0;
  double axis_over_std = 0.0;  // |vertical error| / σ (general model)
  double rot_over_std = 0.0, plane_over_std = 0.0;
  int planar = 0, general = 0, other = 0;
  void Add(const SlaveCalibration& r, const Similarity& truth) {
    const CalibrationError e = CompareToTruth(r.estimate, truth, r.observability.planar_axis);
    rot_deg = std::max(rot_deg, e.rot_deg);
    plane = std::max(plane, e.plane_err);
    axis = std::max(axis, e.axis_err);
    scale_pct = std::max(scale_pct, e.scale_pct);
    if (r.rot_std_deg > 0.0) rot_over_std = std::max(rot_over_std, e.rot_deg / r.rot_std_deg);
    const double plane_std = std::max(r.pos_std.x(), r.pos_std.z());
    if (plane_std > 0.0) plane_over_std = std::max(plane_over_std, e.plane_err / plane_std);
    if (r.motion_model == MotionModel::kPlanar) {
      ++planar;
    } else if (r.motion_model == MotionModel::kGeneral) {
      ++general;
      axis_std_min = std::min(axis_std_min, r.axis_offset_std);
      axis_std_max = std::max(axis_std_max, r.axis_offset_std);
      axis_over_std = std::max(axis_over_std, e.axis_err / r.axis_offset_std);
    } else {
      ++other;
    }
  }
  void Print(const std::string& what) const {
    std::printf(
        "%-34s planar %2d general %2d | rotation %.4f deg  in-plane %.1f mm  vertical %.1f mm  "
        "scale %.4f %%",
        what.c_str(), planar, general, rot_deg, plane * 1e3, axis * 1e3, scale_pct);
    if (general > 0) {
      std::printf("  | vertical sigma %.1f..%.1f mm, error <= %.1f sigma", axis_std_min * 1e3,
                  axis_std_max * 1e3, axis_over_std);
    }
    std::printf("  | rot <= %.1f sigma, plane <= %.1f sigma\n", rot_over_std, plane_over_std);
  }
};

Worst Evaluate(const SampledTrajectory& path, const CalibrationOptions& options,
               const std::string& what) {
  Worst w;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const SyntheticDrive drive = NoisyDrive(path, static_cast<uint64_t>(seed));
    const RigCalibration cal = CalibrateRig(drive.recording, options);
    for (size_t i = 0; i < cal.slaves.size(); ++i) {
      EXPECT_TRUE(cal.slaves[i].usable()) << what << ": " << cal.slaves[i].message;
      w.Add(cal.slaves[i], drive.truth[i]);
      if (seed == 1 && i == 0)
        std::printf("  %s, left: %s\n", what.c_str(), cal.slaves[i].message.c_str());
    }
  }
  w.Print(what);
  return w;
}

void ExpectAccurate(const Worst& w) {
  EXPECT_LT(w.rot_deg, 0.02);
  EXPECT_LT(w.plane, 0.02);
  EXPECT_LT(w.scale_pct, 0.02);
}

TEST(PlanarEval, SyntheticFlatYawDrive) {
  CarPathOptions o;
  o.duration_s = 240.0;
  o.rate_hz = 10.0;
  const Worst w = Evaluate(CarPath(o), CalibrationOptions{}, "flat yaw drive, 4 min");
  EXPECT_EQ(w.planar, 3 * kSeeds);
  ExpectAccurate(w);
}

class KittiEval : public ::testing::Test {
 protected:
  void SetUp() override {
    auto kitti = support::LoadKitti00();
    if (!kitti) RIGCAL_SKIP_MISSING() << kitti.error();
    path_ = std::move(*kitti);
  }
  SampledTrajectory path_;
};

TEST_F(KittiEval, RealTrajectory) {
  const Worst w = Evaluate(path_, CalibrationOptions{}, "KITTI 00 (real)");
  EXPECT_EQ(w.general, 3 * kSeeds);
  ExpectAccurate(w);
  EXPECT_LT(w.axis_over_std, 5.0);
}

// The same with at most one auto pair per end pose: KITTI's turns end up to ~100 pairs at one
// pose by default, whose noise they then share (more accurate, and σ consistent with it).
TEST_F(KittiEval, RealTrajectoryOnePairPerEndPose) {
  CalibrationOptions o;
  o.pairs.max_pairs_per_end = 1;
  const Worst w = Evaluate(path_, o, "KITTI 00 (real), 1 pair/end pose");
  EXPECT_EQ(w.general, 3 * kSeeds);
  ExpectAccurate(w);
  EXPECT_LT(w.axis_over_std, 5.0);
}

TEST_F(KittiEval, RealTrajectoryWithNominalPrior) {
  // Nominal heights 2 cm off, σ 3 cm: combined with the data's (large) σ along the vertical.
  CalibrationOptions o;
  o.nominal_sigma = 0.03;
  const std::vector<Similarity> rig = CarRig();
  for (size_t i = 0; i < rig.size(); ++i) {
    Similarity nominal = rig[i];
    nominal.C.y() += 0.02;
    o.nominal[CarRigNames()[i + 1]] = nominal;
  }
  const Worst w = Evaluate(path_, o, "KITTI 00 (real) + prior 3 cm");
  EXPECT_EQ(w.general, 3 * kSeeds);
  ExpectAccurate(w);
}

TEST_F(KittiEval, FlattenedToPureYaw) {
  const SampledTrajectory flat = FlattenToYaw(path_);
  const Worst w = Evaluate(flat, CalibrationOptions{}, "KITTI 00 flattened to pure yaw");
  EXPECT_EQ(w.planar, 3 * kSeeds);
  ExpectAccurate(w);
  // The thesis's linear general method on the same data: the two smallest eigenvalues of
  // (4.10) coincide and the rotation about the vertical is arbitrary.
  CalibrationOptions thesis;
  thesis.method = Method::kLinear;
  thesis.motion_model = MotionModel::kGeneral;
  const SyntheticDrive drive = NoisyDrive(flat, 1);
  const RigCalibration cal = CalibrateRig(drive.recording, thesis);
  for (size_t i = 0; i < cal.slaves.size(); ++i) {
    const SlaveCalibration& r = cal.slaves[i];
    std::printf(
        "  thesis linear general model, %s: %s, its rotation off by %.1f deg (eigenvalues of "
        "4.10: %.3g %.3g %.3g %.3g)\n",
        r.name.c_str(), ToString(r.termination).c_str(),
        AngleBetween(r.estimate.q, drive.truth[i].q) * kDegPerRad,
        r.observability.rotation_eigenvalues[0], r.observability.rotation_eigenvalues[1],
        r.observability.rotation_eigenvalues[2], r.observability.rotation_eigenvalues[3]);
    EXPECT_EQ(r.termination, Termination::kDegenerate);
  }
}

// Online: planar for 150 s, then a 6 deg ramp (pitch up over 3 s, 15 s climbing, level again)
// and turning on the upper level. Prints when the vertical offset is flagged and resolved.
TEST(PlanarEval, OnlinePlanarThenRamp) {
  CarPathOptions po;
  po.duration_s = 210.0;
  po.ramp_at_s = 150.0;
  const SampledTrajectory path = CarPath(po);
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const SyntheticDrive drive = NoisyDrive(path, static_cast<uint64_t>(seed));
    const RigRecording& rec = drive.recording;
    RigEstimator est(CarRigNames(), RigEstimatorOptions{});
    std::vector<double> flagged(3, -1.0), resolved(3, -1.0);
    std::vector<int> changes(3, 0);
    std::vector<bool> was_planar(3, false);
    for (size_t k = 0; k < rec.size(); ++k) {
      est.AddSet(rec.t_ns[k], rec.SetAt(k));
      const double t = rec.t_ns[k] * 1e-9;
      for (int i = 0; i < 3; ++i) {
        const uint32_t flags = est.Estimate().online[i].flags;
        const bool planar = flags & kFlagPlanar;
        if (est.Estimate().rig.slaves[i].state != SlaveState::kConverged) continue;
        if (planar && flagged[i] < 0.0) flagged[i] = t;
        if (!planar && flagged[i] >= 0.0 && resolved[i] < 0.0) resolved[i] = t;
        if (flagged[i] >= 0.0 && flagged[i] < t && planar != was_planar[i]) ++changes[i];
        was_planar[i] = planar;
      }
    }
    for (int i = 0; i < 3; ++i) {
      const SlaveCalibration& r = est.Estimate().rig.slaves[i];
      const CalibrationError e =
          CompareToTruth(r.estimate, drive.truth[i], Eigen::Vector3d::UnitY());
      std::printf(
          "online seed %d %-5s: planar (vertical flagged) at %5.1f s, general (resolved) at "
          "%5.1f s, %d model change(s) after the flag | end: rotation %.4f deg, in-plane %.1f mm, "
          "vertical %.1f mm "
          "(sigma %.1f mm), scale %.4f %%\n",
          seed, r.name.c_str(), flagged[i], resolved[i], changes[i], e.rot_deg, e.plane_err * 1e3,
          e.axis_err * 1e3, r.axis_offset_std * 1e3, e.scale_pct);
      EXPECT_GE(flagged[i], 0.0);
      EXPECT_LT(flagged[i], po.ramp_at_s);
      EXPECT_GT(resolved[i], po.ramp_at_s);
      EXPECT_EQ(changes[i], 1);  // resolved once, no flipping
      EXPECT_LT(e.axis_err, 5.0 * r.axis_offset_std);
      EXPECT_LT(e.rot_deg, 0.05);
      EXPECT_LT(e.plane_err, 0.02);
    }
  }
}

}  // namespace
}  // namespace rigcal
