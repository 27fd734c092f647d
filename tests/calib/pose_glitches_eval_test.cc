// SPDX-License-Identifier: Apache-2.0
// Glitch tolerance table (eval): 1 % of the poses glitched (jumps by 20-100 % of the
// trajectory's extent, rotations by 30-180 degrees, in a random camera) on several simulated
// recordings, batch and online, against the clean recordings and against the batch without
// the glitch stage. Requirement (issue "gross outliers"): within 1.2x of the clean accuracy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "glitch_injection.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/calib/synthetic_car.h"

namespace rigcal {
namespace {

using testing::GlitchOnePercent;
using testing::Track;

RigCalibration Online(const RigRecording& rec) {
  std::vector<std::string> names = {rec.master.name};
  for (const CameraTrack& s : rec.slaves) names.push_back(s.name);
  RigEstimator est(names, RigEstimatorOptions{});
  for (size_t k = 0; k < rec.size(); ++k) est.AddSet(rec.t_ns[k], rec.SetAt(k));
  return est.Estimate().rig;
}

// The batch without the glitch stage: the walk pairs (the earlier default) and the motions of
// the recording as it is.
RigCalibration Unguarded(const RigRecording& rec) {
  const CalibrationOptions o;
  PairOptions walk = o.pairs;
  walk.policy = PairOptions::Policy::kWalk;
  const std::vector<IndexPair> pairs = SelectPairs(rec, walk);
  RigCalibration out;
  for (size_t i = 0; i < rec.slaves.size(); ++i) {
    out.slaves.push_back(
        CalibrateSlave(MotionsForSlave(rec, static_cast<int>(i), pairs), o, rec.slaves[i].name));
  }
  return out;
}

struct Sums {
  double rot = 0.0, pos = 0.0;
  int count = 0, unusable = 0;
  // Rotation error and C error (in the plane of planar motion, where C along the axis is not
  // determined) of every slave against the truth.
  void Add(const RigCalibration& r, const std::vector<Similarity>& truth) {
    for (size_t i = 0; i < truth.size(); ++i) {
      const SlaveCalibration& s = r.slaves[i];
      if (!s.solved()) {
        ++unusable;
        continue;
      }
      const CalibrationError e = CompareToTruth(s.estimate, truth[i], s.observability.planar_axis);
      rot += e.rot_deg;
      pos += s.motion_model == MotionModel::kPlanar && std::isfinite(e.plane_err) ? e.plane_err
                                                                                  : e.trans_err;
      ++count;
    }
  }
  std::string Text() const {
    char text[96];
    std::snprintf(text, sizeof(text), "%9.4g %9.4g", rot / std::max(count, 1),
                  pos / std::max(count, 1));
    return unusable > 0 ? std::string(text) + " (" + std::to_string(unusable) + " unsolved)"
                        : std::string(text);
  }
};

struct Scenario {
  const char* name;
  std::function<SyntheticDrive(uint64_t seed)> make;
};

TEST(PoseGlitchesEval, OnePercentGlitchedTable) {
  const std::vector<std::string> names = {"front", "left", "back"};
  const std::vector<Scenario> scenarios = {
      {"6-DoF drive 20 Hz",
       [&](uint64_t seed) {
         DriveOptions d;
         d.seed = seed;
         return GenerateDrive(names, DemoRig(), d);
       }},
      {"fast rotation 5 Hz",
       [&](uint64_t seed) {
         DriveOptions d;
         d.seed = seed;
         d.num_frames = 600;
         d.frame_rate_hz = 5.0;
         d.rotation_amplitude_deg = 120.0;
         return GenerateDrive(names, DemoRig(), d);
       }},
      {"drift, VO resets 20 s",
       [&](uint64_t seed) {
         DriveOptions d;
         d.seed = seed;
         d.num_frames = 2400;
         d.drift_deg_per_frame = 0.01;
         d.segment_period_s = 20.0;
         return GenerateDrive(names, DemoRig(), d);
       }},
      {"car rig 20 Hz, 120 s",
       [&](uint64_t seed) {
         CarPathOptions path;
         path.duration_s = 120.0;
         DriveOptions d;
         d.seed = seed;
         return DriveCarRig(CarPath(path), d);
       }},
  };
  const int seeds = 12;
  std::printf("%-22s %-6s %-30s %-30s %-30s\n", "recording", "", "clean: rot [deg], C",
              "1 % glitched", "1 % glitched, walk, no stage");
  for (const Scenario& scenario : scenarios) {
    Sums clean, glitched, unguarded, clean_online, glitched_online;
    int missed = 0, extra = 0;
    for (int seed = 1; seed <= seeds; ++seed) {
      const SyntheticDrive drive = scenario.make(static_cast<uint64_t>(seed));
      RigRecording rec = drive.recording;
      std::mt19937_64 rng(static_cast<uint64_t>(seed) + 1000);
      const std::vector<int> where = GlitchOnePercent(&rec, rng);
      std::vector<int> dropped;
      WithoutGlitches(rec, &dropped);
      for (const int k : where) {
        missed += std::find(dropped.begin(), dropped.end(), k) == dropped.end();
      }
      for (const int k : dropped) extra += std::find(where.begin(), where.end(), k) == where.end();
      clean.Add(CalibrateRig(drive.recording, CalibrationOptions{}), drive.truth);
      glitched.Add(CalibrateRig(rec, CalibrationOptions{}), drive.truth);
      unguarded.Add(Unguarded(rec), drive.truth);
      clean_online.Add(Online(drive.recording), drive.truth);
      glitched_online.Add(Online(rec), drive.truth);
    }
    std::printf("%-22s %-6s %-30s %-30s %-30s\n", scenario.name, "batch", clean.Text().c_str(),
                glitched.Text().c_str(), unguarded.Text().c_str());
    std::printf("%-22s %-6s %-30s %-30s\n", "", "online", clean_online.Text().c_str(),
                glitched_online.Text().c_str());
    std::printf("%-22s %d glitches missed, %d good poses dropped (batch)\n", "", missed, extra);
    EXPECT_EQ(glitched.unusable, clean.unusable) << scenario.name;
    EXPECT_LE(glitched.rot, 1.2 * clean.rot) << scenario.name;
    EXPECT_LE(glitched.pos, 1.2 * clean.pos) << scenario.name;
    EXPECT_LE(glitched_online.rot, 1.2 * clean_online.rot) << scenario.name << " online";
    EXPECT_LE(glitched_online.pos, 1.2 * clean_online.pos) << scenario.name << " online";
  }
}

}  // namespace
}  // namespace rigcal
