// SPDX-License-Identifier: Apache-2.0
// The estimator state file: exact round trip, corrupt, truncated, other-version and foreign
// files, version-2 files, and a file written before the state left calib (fixtures/).
#include "rigcal/io/estimator_state_file.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <functional>
#include <sstream>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/calib/refinement_job.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal::io {
namespace {

// A drive of the demo rig's first `slaves` slaves (front is the master), fed to `est`.
SyntheticDrive DemoDrive(DriveOptions d, int slaves) {
  std::vector<Similarity> rigs = DemoRig();
  rigs.resize(slaves);
  std::vector<std::string> names = {"front", "left", "back"};
  names.resize(slaves + 1);
  return GenerateDrive(names, rigs, d);
}

std::vector<std::string> CameraNames(const RigRecording& rec) {
  std::vector<std::string> names = {rec.master.name};
  for (const auto& s : rec.slaves) names.push_back(s.name);
  return names;
}

void FeedAll(RigEstimator* est, const RigRecording& rec) {
  for (size_t k = 0; k < rec.size(); ++k) est->AddSet(rec.t_ns[k], rec.SetAt(k));
}

// The estimator's state file.
std::string StateFile(const RigEstimator& est) { return FormatEstimatorState(est.SaveState()); }

// Restores a state file into `est`; false with the parser's or RestoreState's message.
bool Restore(RigEstimator* est, const std::string& text, std::string* error) {
  const Expected<RigEstimatorState> state = ParseEstimatorState(text);
  const Status status = state ? est->RestoreState(*state) : state.status();
  *error = status.message();
  return status.ok();
}

// Every slave's background refinement made and applied, as the refinement thread does.
void RefineAll(RigEstimator* est, int slaves, bool final) {
  for (int i = 0; i < slaves; ++i) {
    const RefinementJob job = est->MakeRefinementJob(i, final);
    if (!job.start.solved()) continue;
    est->ApplyRefinement(job, RefineWindow(job));
  }
}

// A resume without new data publishes the estimate of before the restart bit for bit: the batch
// calibrator's on the pose history, which the statistics cannot reproduce (before state version
// 6: re-solved from them, 2-3.5σ away in rotation, C and scale, and σ 1.6-3.6 times larger), and
// no final refinement replaces it. New data then go on from it.
TEST(EstimatorStateFile, AResumeWithoutNewDataPublishesTheSameEstimate) {
  DriveOptions d;
  d.num_frames = 1200;
  d.seed = 6;
  const SyntheticDrive drive = DemoDrive(d, 2);
  const auto names = CameraNames(drive.recording);
  RigEstimator est(names, RigEstimatorOptions{});
  FeedAll(&est, drive.recording);
  RefineAll(&est, 2, /*final=*/true);
  ASSERT_TRUE(est.Estimate().online[0].flags & kFlagRefined);
  const std::string state = StateFile(est);

  RigEstimator restored(names, RigEstimatorOptions{});
  std::string error;
  ASSERT_TRUE(Restore(&restored, state, &error)) << error;
  RefineAll(&restored, 2, /*final=*/true);  // the end of a run without new data
  for (int i = 0; i < 2; ++i) {
    const SlaveCalibration& a = est.Estimate().rig.slaves[i];
    const SlaveCalibration& b = restored.Estimate().rig.slaves[i];
    EXPECT_EQ(a.estimate.q.coeffs(), b.estimate.q.coeffs()) << i;
    EXPECT_EQ(a.estimate.C, b.estimate.C) << i;
    EXPECT_EQ(a.estimate.scale, b.estimate.scale) << i;
    EXPECT_EQ(a.rot_std_deg, b.rot_std_deg) << i;
    EXPECT_EQ(a.pos_std, b.pos_std) << i;
    EXPECT_EQ(a.state, b.state) << i;
    EXPECT_EQ(a.message, b.message) << i;
    EXPECT_EQ(est.Estimate().online[i].flags, restored.Estimate().online[i].flags) << i;
  }
  EXPECT_EQ(StateFile(restored), state);

  // New data: the estimate moves on (a refinement of the new window, the saved one its prior).
  d.seed = 7;
  const SyntheticDrive more = DemoDrive(d, 2);
  const int64_t shift = drive.recording.t_ns.back() + 50'000'000 - more.recording.t_ns.front();
  for (size_t k = 0; k < more.recording.size(); ++k) {
    restored.AddSet(more.recording.t_ns[k] + shift, more.recording.SetAt(k));
  }
  EXPECT_GT(restored.Estimate().rig.slaves[0].motions.used,
            est.Estimate().rig.slaves[0].motions.used);
  EXPECT_TRUE(restored.MakeRefinementJob(0, true).start.solved());
}

// A camera moved between two drives, the second resumed from the first's state on a continuing
// clock: the decalibration alarm fires and the end is the new mounting within its σ, never the
// old values called usable.
TEST(EstimatorStateFile, ACameraMovedBetweenDrivesEndsAtTheNewMountingWithinSigma) {
  DriveOptions d;
  d.num_frames = 1200;
  d.seed = 8;
  const SyntheticDrive first = DemoDrive(d, 1);
  const auto names = CameraNames(first.recording);
  RigEstimator est(names, RigEstimatorOptions{});
  FeedAll(&est, first.recording);
  RefineAll(&est, 1, /*final=*/true);
  ASSERT_TRUE(est.Estimate().rig.slaves[0].usable());

  Similarity moved = DemoRig()[0];
  moved.q = (moved.q * Eigen::AngleAxisd(5.0 * kRadPerDeg, Eigen::Vector3d::UnitY())).normalized();
  moved.C += Eigen::Vector3d(0.05, 0.0, 0.0);
  d.seed = 9;
  d.num_frames = 2400;
  const SyntheticDrive second = GenerateDrive(names, {moved}, d);
  RigEstimator resumed(names, RigEstimatorOptions{});
  std::string error;
  ASSERT_TRUE(Restore(&resumed, StateFile(est), &error)) << error;
  const int64_t shift =
      first.recording.t_ns.back() + 600'000'000'000 - second.recording.t_ns.front();
  for (size_t k = 0; k < second.recording.size(); ++k) {
    resumed.AddSet(second.recording.t_ns[k] + shift, second.recording.SetAt(k));
    if (k % 200 == 199) RefineAll(&resumed, 1, false);
  }
  RefineAll(&resumed, 1, /*final=*/true);
  const SlaveCalibration& b = resumed.Estimate().rig.slaves[0];
  EXPECT_GE(resumed.Estimate().online[0].decalibration_events, 1);
  const CalibrationError e = CompareToTruth(b.estimate, moved);
  std::printf("moved camera, resumed: %s, rotation %.4f deg (σ %.4f, %.1fσ), C %.5f (σ %s)\n",
              std::string(ToString(b.state)).c_str(), e.rot_deg, b.rot_std_deg,
              e.rot_deg / b.rot_std_deg, e.trans_err, "see below");
  for (int a = 0; a < 3; ++a) {
    std::printf("  C[%d] error %.2fσ\n", a, (b.estimate.C[a] - moved.C[a]) / b.pos_std[a]);
  }
  if (b.usable()) {
    EXPECT_LT(e.rot_deg / b.rot_std_deg, 4.0) << b.message;
    for (int a = 0; a < 3; ++a) {
      EXPECT_LT(std::abs(b.estimate.C[a] - moved.C[a]) / b.pos_std[a], 4.0) << a << b.message;
    }
  }
}

// A drive of front and left in which left is knocked by 2° at frame 2400 (of 4800, 20 Hz) and
// the first frame at which the estimator fed with it says decalibrated (-1: never).
struct BumpedDrive {
  SyntheticDrive drive;
  int alarm_frame = -1;
};

BumpedDrive BumpAndRaiseTheAlarm(RigEstimator* est) {
  DriveOptions d;
  d.num_frames = 4800;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  Similarity bumped = DemoRig()[0];
  bumped.q = AxisAngle(Eigen::Vector3d(0.3, 1.0, -0.2), 2.0 * kRadPerDeg) * bumped.q;
  d.change_frame = 2400;
  d.changed_rigs = {bumped};
  BumpedDrive out{GenerateDrive({"front", "left"}, {DemoRig()[0]}, d), -1};
  const RigRecording& rec = out.drive.recording;
  for (size_t k = 0; k < rec.size() && out.alarm_frame < 0; ++k) {
    est->AddSet(rec.t_ns[k], rec.SetAt(k));
    if (est->Estimate().rig.slaves[0].state == SlaveState::kDecalibrated) {
      out.alarm_frame = static_cast<int>(k);
    }
  }
  return out;
}

// A slave found decalibrated before a restart is still decalibrated after it (state version 7):
// the alarm round-trips through the file, holds on new data exactly as in the uninterrupted
// run, and on a clock that restarted (a reboot) holds for short_half_life_s of the new clock. A
// version-6 state resumes without it.
TEST(EstimatorStateFile, ADecalibrationAlarmSurvivesARestart) {
  RigEstimator est({"front", "left"}, RigEstimatorOptions{});
  const BumpedDrive bumped = BumpAndRaiseTheAlarm(&est);
  ASSERT_GE(bumped.alarm_frame, 2400) << "the bump raised no alarm";
  const RigRecording& rec = bumped.drive.recording;
  const std::string state = StateFile(est);
  const Expected<RigEstimatorState> parsed = ParseEstimatorState(state);
  ASSERT_TRUE(parsed.ok()) << parsed.error();
  const DecalibrationAlarmState& alarm = parsed->slaves[0].resume.decalibration;
  EXPECT_EQ(alarm.decalibrated_at_ns, rec.t_ns[bumped.alarm_frame]);
  EXPECT_EQ(FormatEstimatorState(*parsed), state);

  // New data on the continuing clock: decalibrated as long as in the uninterrupted run (5 s;
  // the alarm holds for short_half_life_s, 20 s).
  RigEstimator resumed({"front", "left"}, RigEstimatorOptions{});
  std::string error;
  ASSERT_TRUE(Restore(&resumed, state, &error)) << error;
  EXPECT_EQ(resumed.Estimate().rig.slaves[0].state, SlaveState::kDecalibrated);
  const size_t from = static_cast<size_t>(bumped.alarm_frame) + 1;
  for (size_t k = from; k < from + 100; ++k) {
    est.AddSet(rec.t_ns[k], rec.SetAt(k));
    resumed.AddSet(rec.t_ns[k], rec.SetAt(k));
  }
  ASSERT_EQ(est.Estimate().rig.slaves[0].state, SlaveState::kDecalibrated);
  EXPECT_EQ(resumed.Estimate().rig.slaves[0].state, SlaveState::kDecalibrated)
      << resumed.Estimate().rig.slaves[0].message;
  EXPECT_GT(resumed.Estimate().rig.slaves[0].motions.used,
            parsed->slaves[0].resume.published.motions.used);

  // A clock that began again at the first stamp of the drive: still decalibrated 5 s later,
  // no longer once short_half_life_s of the new clock has passed.
  RigEstimator rebooted({"front", "left"}, RigEstimatorOptions{});
  ASSERT_TRUE(Restore(&rebooted, state, &error)) << error;
  const int64_t back = rec.t_ns[from] - rec.t_ns[0];
  size_t k = from;
  for (; k < from + 100; ++k) rebooted.AddSet(rec.t_ns[k] - back, rec.SetAt(k));
  EXPECT_EQ(rebooted.Estimate().rig.slaves[0].state, SlaveState::kDecalibrated);
  for (; k < from + 600; ++k) rebooted.AddSet(rec.t_ns[k] - back, rec.SetAt(k));
  EXPECT_NE(rebooted.Estimate().rig.slaves[0].state, SlaveState::kDecalibrated)
      << rebooted.Estimate().rig.slaves[0].message;

  // The same state as version 6 (no decalibration line): read, and resumed without the alarm.
  std::string v6;
  std::istringstream lines(state);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("checksum ", 0) == 0) continue;
    if (line.rfind("decalibration ", 0) == 0) continue;
    if (line.rfind("posweight ", 0) == 0) continue;  // version 8
    v6 += line + '\n';
  }
  v6.replace(0, v6.find('\n'), "rigcal-estimator-state 6");
  RigEstimator old({"front", "left"}, RigEstimatorOptions{});
  ASSERT_TRUE(Restore(&old, WithEstimatorStateChecksum(v6), &error)) << error;
  for (size_t j = from; j < from + 100; ++j) old.AddSet(rec.t_ns[j], rec.SetAt(j));
  EXPECT_NE(old.Estimate().rig.slaves[0].state, SlaveState::kDecalibrated);
}

// Text after the checksum line is an error naming the line (it is not covered by the checksum).
TEST(EstimatorStateFile, TextAfterTheChecksumLineIsAnError) {
  DriveOptions d;
  d.num_frames = 300;
  const SyntheticDrive drive = DemoDrive(d, 1);
  RigEstimator est(CameraNames(drive.recording), RigEstimatorOptions{});
  FeedAll(&est, drive.recording);
  const std::string state = StateFile(est);
  const auto lines = std::count(state.begin(), state.end(), '\n');
  EXPECT_TRUE(ParseEstimatorState(state + "\n  \n").ok());
  const Expected<RigEstimatorState> garbage = ParseEstimatorState(state + "\nslave 0\n");
  ASSERT_FALSE(garbage.ok());
  EXPECT_EQ(garbage.error(),
            "line " + std::to_string(lines + 2) + ": text after the checksum line");
  std::string same_line = state;
  same_line.insert(same_line.size() - 1, " x");
  ASSERT_FALSE(ParseEstimatorState(same_line).ok());
  EXPECT_EQ(ParseEstimatorState(same_line).error(),
            "line " + std::to_string(lines) + ": text after the checksum line");
}

TEST(EstimatorStateFile, RoundTripAndCorruptFiles) {
  DriveOptions d;
  d.num_frames = 1200;
  d.seed = 4;
  const SyntheticDrive drive = DemoDrive(d, 2);
  const auto names = CameraNames(drive.recording);
  RigEstimator est(names, RigEstimatorOptions{});
  FeedAll(&est, drive.recording);
  const std::string state = StateFile(est);

  RigEstimator restored(names, RigEstimatorOptions{});
  std::string error;
  ASSERT_TRUE(Restore(&restored, state, &error)) << error;
  for (int i = 0; i < 2; ++i) {
    const auto& a = est.Estimate().rig.slaves[i].estimate;
    const auto& b = restored.Estimate().rig.slaves[i].estimate;
    EXPECT_LT(AngleBetween(a.q, b.q), 1e-12);
    EXPECT_LT((a.C - b.C).norm(), 1e-12);
    EXPECT_NEAR(a.scale, b.scale, 1e-12);
  }
  // Every sum survives the text exactly (17 significant digits).
  EXPECT_EQ(StateFile(restored), state);

  RigEstimator fresh(names, RigEstimatorOptions{});
  std::string corrupt = state;
  corrupt[corrupt.size() / 2] = corrupt[corrupt.size() / 2] == '1' ? '2' : '1';
  EXPECT_FALSE(Restore(&fresh, corrupt, &error));
  EXPECT_NE(error.find("checksum"), std::string::npos) << error;
  EXPECT_FALSE(Restore(&fresh, state.substr(0, state.size() / 3), &error));
  std::string other_version = state;
  const std::string header =
      "rigcal-estimator-state " + std::to_string(kEstimatorStateVersion) + "\n";
  ASSERT_EQ(other_version.rfind(header, 0), 0u);
  other_version.replace(0, header.size(), "rigcal-estimator-state 9\n");
  EXPECT_FALSE(Restore(&fresh, other_version, &error));
  EXPECT_NE(error.find("version 9"), std::string::npos) << error;
  RigEstimator other_rig({"front", "left", "rear"}, RigEstimatorOptions{});
  EXPECT_FALSE(Restore(&other_rig, state, &error));
  EXPECT_NE(error.find("different rig"), std::string::npos) << error;
  EXPECT_FALSE(Restore(&fresh, "garbage", &error));
  EXPECT_EQ(fresh.Estimate().rig.slaves[0].motions.used, 0);  // unchanged
}

// A version-2 state (no translation-direction moments) is read: the moments are derived from
// the others, so the translational model's estimate is the same and its σ close.
TEST(EstimatorStateFile, ReadsVersionTwoStates) {
  DriveOptions d;
  d.motion = DriveOptions::Motion::kTranslationOnly;
  d.rotation_noise_deg = 0.02;
  d.position_noise = 0.002;
  const SyntheticDrive drive = GenerateDrive({"front", "back"}, {DemoRig()[1]}, d);
  const auto names = CameraNames(drive.recording);
  RigEstimator est(names, RigEstimatorOptions{});
  FeedAll(&est, drive.recording);
  const std::string state = StateFile(est);

  // The same state as version 2 wrote it: no "Ddir" lines, header 2, its checksum.
  std::istringstream in(state);
  std::string line, body;
  std::getline(in, line);
  ASSERT_EQ(line, "rigcal-estimator-state " + std::to_string(kEstimatorStateVersion));
  int removed = 0;
  while (std::getline(in, line)) {
    if (line.rfind("checksum ", 0) == 0) break;
    if (line.rfind("consumed ", 0) == 0) continue;    // version 4
    if (line.rfind("clocks ", 0) == 0) continue;      // version 5
    if (line.rfind("fingerprint", 0) == 0) continue;  // version 6
    if (line.rfind("posweight ", 0) == 0) continue;   // version 8
    if (line == "published") {                        // version 6, up to its "end"
      while (std::getline(in, line) && line != "end") {
      }
      continue;
    }
    if (line.rfind("Ddir ", 0) == 0) {
      ++removed;
      continue;
    }
    body += line + '\n';
  }
  ASSERT_EQ(removed, 2);  // long and short statistics
  const std::string v2 = WithEstimatorStateChecksum("rigcal-estimator-state 2\n" + body);

  RigEstimator restored(names, RigEstimatorOptions{});
  std::string error;
  ASSERT_TRUE(Restore(&restored, v2, &error)) << error;
  const auto& a = est.Estimate().rig.slaves[0];
  const auto& b = restored.Estimate().rig.slaves[0];
  ASSERT_EQ(b.motion_model, MotionModel::kTranslational);
  EXPECT_LT(AngleBetween(a.estimate.q, b.estimate.q), 1e-12);
  // The derived moments stand for the translation directions' spread approximately: 7.5 % here
  // with a keyframe at every set of this steady drive (within 5 % with the former 0.05-unit rule).
  EXPECT_NEAR(b.rot_std_deg, a.rot_std_deg, 0.1 * a.rot_std_deg);
  EXPECT_FALSE(Restore(&restored, "rigcal-estimator-state 1\n" + body, &error));
  EXPECT_NE(error.find("version 1"), std::string::npos) << error;
}

// A version-3 text as version `version` (4 to 8) writes it: that header, `consumed_line` after
// master_segment (and for version 5 `clocks_line` after it), its checksum.
std::string AsVersion(int version, const std::string& v3, const std::string& consumed_line,
                      const std::string& clocks_line = "clocks 0") {
  std::istringstream in(v3);
  std::string line, body;
  std::getline(in, line);
  while (std::getline(in, line)) {
    if (line.rfind("checksum ", 0) == 0) break;
    body += line + '\n';
    // Version 8: the position sums' weight, "weight" when the master never re-initialised.
    if (version >= 8 && line.rfind("weight ", 0) == 0) body += "pos" + line + '\n';
    if (line.rfind("master_segment ", 0) == 0) {
      body += consumed_line + '\n';
      if (version >= 5) body += clocks_line + '\n';
      if (version >= 6) body += "fingerprints 0\n";
    }
  }
  // The checksum line appended as the writer writes it (compared byte for byte below).
  return WithEstimatorStateChecksum("rigcal-estimator-state " + std::to_string(version) + "\n" +
                                    body);
}

// A state file without the parts of version 6 an estimator adds (the pose fingerprints and the
// published estimates), its checksum made right.
std::string WithoutVersionSixParts(const std::string& text) {
  std::istringstream in(text);
  std::string line, out;
  while (std::getline(in, line)) {
    if (line.rfind("checksum ", 0) == 0) break;
    if (line.rfind("fingerprint ", 0) == 0) continue;
    if (line.rfind("fingerprints ", 0) == 0) line = "fingerprints 0";
    if (line == "published") {
      while (std::getline(in, line) && line != "end") {
      }
      continue;
    }
    out += line + '\n';
  }
  return WithEstimatorStateChecksum(out);
}

// A state file written by the estimator before its state became a plain struct (a drive with
// scale segments, two of them closed): read, restored, and written again byte for byte (as
// the current version: consumed stamps unknown in the file, none in a restored estimator; no
// clock offsets).
TEST(EstimatorStateFile, ReadsAndRewritesEarlierFilesExactly) {
  std::ifstream in(std::string(RIGCAL_SOURCE_DIR) + "/tests/io/fixtures/estimator_state_v3.txt",
                   std::ios::binary);
  ASSERT_TRUE(in.good());
  std::ostringstream text;
  text << in.rdbuf();
  const Expected<RigEstimatorState> state = ParseEstimatorState(text.str());
  ASSERT_TRUE(state.ok()) << state.error();
  EXPECT_TRUE(state->consumed_t_ns.empty());
  EXPECT_EQ(FormatEstimatorState(*state),
            AsVersion(kEstimatorStateVersion, text.str(), "consumed 0"));
  ASSERT_EQ(state->cameras, (std::vector<std::string>{"front", "left"}));
  ASSERT_EQ(state->slaves.size(), 1u);
  EXPECT_EQ(state->slaves[0].long_stats.closed_scales.size(), 2u);
  EXPECT_EQ(state->slaves[0].long_stats.segments.size(), 1u);
  EXPECT_FALSE(state->slaves[0].long_stats.position_weight) << "none before version 8";

  RigEstimatorOptions options;
  options.max_open_segments = 1;
  RigEstimator est({"front", "left"}, options);
  const Status restored = est.RestoreState(*state);
  ASSERT_TRUE(restored.ok()) << restored.message();
  const SlaveCalibration& r = est.Estimate().rig.slaves[0];
  ASSERT_TRUE(r.usable()) << r.message;
  EXPECT_EQ(r.motions.used, 537);
  EXPECT_EQ(WithoutVersionSixParts(StateFile(est)),
            AsVersion(kEstimatorStateVersion, text.str(), "consumed 2 -1 -1"));
}

// A hand-edited file with a valid checksum: values no estimator can have are rejected, and the
// error names the slave and the field.
TEST(EstimatorStateFile, ValuesOutOfRangeAreRejectedDespiteTheChecksum) {
  std::ifstream in(std::string(RIGCAL_SOURCE_DIR) + "/tests/io/fixtures/estimator_state_v3.txt",
                   std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  const Expected<RigEstimatorState> good = ParseEstimatorState(text.str());
  ASSERT_TRUE(good.ok()) << good.error();
  const auto error_of = [&](const std::function<void(SlaveEstimatorState*)>& edit) {
    RigEstimatorState state = *good;
    edit(&state.slaves[0]);
    const Expected<RigEstimatorState> parsed = ParseEstimatorState(FormatEstimatorState(state));
    return parsed.ok() ? std::string("accepted") : parsed.error();
  };
  EXPECT_EQ(error_of([](SlaveEstimatorState*) {}), "accepted");
  // A wrong checksum line is replaced by the writer's.
  const std::string formatted = FormatEstimatorState(*good);
  const size_t sum = formatted.rfind("checksum ");
  ASSERT_NE(sum, std::string::npos);
  EXPECT_EQ(WithEstimatorStateChecksum(formatted.substr(0, sum) + "checksum 123\n"), formatted);
  EXPECT_EQ(WithEstimatorStateChecksum(formatted), formatted);
  EXPECT_EQ(error_of([](SlaveEstimatorState* s) { s->counts.total = -3; }),
            "slave left: counts total = -3 is out of range [0, 1e+100]");
  EXPECT_EQ(error_of([](SlaveEstimatorState* s) { s->counts.used = s->counts.total + 1; }),
            "slave left: counts used = " + std::to_string(good->slaves[0].counts.total + 1) +
                " is out of range [0, " + std::to_string(good->slaves[0].counts.total) + "]");
  EXPECT_EQ(error_of([](SlaveEstimatorState* s) { s->long_stats.weight = 1e300; }),
            "slave left: long: weight = 1e+300 is out of range [0, 1e+100]");
  EXPECT_EQ(error_of([](SlaveEstimatorState* s) { s->pos_var.value = -1.0; }),
            "slave left: noise position = -1 is out of range [0, 1e+100]");
  EXPECT_EQ(error_of([](SlaveEstimatorState* s) { s->short_stats.rotation(2, 1) = -1e300; }),
            "slave left: short: M[6] = -1e+300 is out of range [-1e+100, 1e+100]");
  EXPECT_EQ(error_of([](SlaveEstimatorState* s) {
              s->long_stats.segments.begin()->second.weight = -2.0;
            }).find("slave left: long: segment "),
            0u);
  EXPECT_EQ(
      error_of([](SlaveEstimatorState* s) { s->long_stats.max_rotation = 7.0; }).substr(0, 34),
      "slave left: long: maxrot = 7 is ou");
  // Within range but beyond what motions can sum to (each weighs at most 1): a weight of 9e99
  // over a few hundred motions would make every σ vanish (1e-51 degrees).
  const int motions = good->slaves[0].long_stats.motions;
  ASSERT_GT(motions, 0);
  EXPECT_EQ(error_of([](SlaveEstimatorState* s) { s->long_stats.weight = 9e99; }),
            "slave left: long: weight = 9e+99 exceeds motions = " + std::to_string(motions) +
                " (each motion weighs at most 1)");
  EXPECT_EQ(error_of([](SlaveEstimatorState* s) {
              s->short_stats.weight = s->short_stats.motions + 1.0;
            }).find("slave left: short: weight = "),
            0u);
  EXPECT_NE(error_of([](SlaveEstimatorState* s) {
              s->long_stats.segments.begin()->second.weight = s->long_stats.weight + 1.0;
            }).find("exceeds the total weight"),
            std::string::npos);
  EXPECT_EQ(error_of([](SlaveEstimatorState* s) {
              s->long_stats.rotation = 1e50 * Eigen::Matrix4d::Identity();
            }).find("slave left: long: M: trace 4e+50 is not within [0, 16 x weight"),
            0u);
}

}  // namespace
}  // namespace rigcal::io

namespace rigcal::io {
namespace {

// Version 4: how far each camera was consumed (the newest stamp of a set the estimator took)
// survives the file; a stamp below -1 or a count other than the cameras' is rejected.
TEST(EstimatorStateFile, ConsumedStampsRoundTripAndAreChecked) {
  DriveOptions d;
  d.num_frames = 300;
  const SyntheticDrive drive = DemoDrive(d, 2);
  const auto names = CameraNames(drive.recording);
  RigEstimator est(names, RigEstimatorOptions{});
  FeedAll(&est, drive.recording);
  const RigEstimatorState saved = est.SaveState();
  const int64_t last = drive.recording.t_ns.back();
  EXPECT_EQ(saved.consumed_t_ns, std::vector<int64_t>(3, last));
  const Expected<RigEstimatorState> parsed = ParseEstimatorState(FormatEstimatorState(saved));
  ASSERT_TRUE(parsed.ok()) << parsed.error();
  EXPECT_EQ(parsed->consumed_t_ns, saved.consumed_t_ns);
  RigEstimator restored(names, RigEstimatorOptions{});
  ASSERT_TRUE(restored.RestoreState(*parsed).ok());
  EXPECT_EQ(restored.SaveState().consumed_t_ns, saved.consumed_t_ns);

  RigEstimatorState bad = saved;
  bad.consumed_t_ns[1] = -5;
  Expected<RigEstimatorState> rejected = ParseEstimatorState(FormatEstimatorState(bad));
  ASSERT_FALSE(rejected.ok());
  EXPECT_NE(rejected.error().find("consumed stamp of camera 'left'"), std::string::npos)
      << rejected.error();
  bad = saved;
  bad.consumed_t_ns.pop_back();
  rejected = ParseEstimatorState(FormatEstimatorState(bad));
  ASSERT_FALSE(rejected.ok());
  EXPECT_NE(rejected.error().find("one per camera"), std::string::npos) << rejected.error();
}

// Version 5: the clock offsets of free-running slaves survive the file exactly; a version-4
// file (none) is read with none; malformed or out-of-range clock lines are rejected, naming the
// slave and the field.
TEST(EstimatorStateFile, ClockOffsetsRoundTripAndVersionFourFilesHaveNone) {
  std::ifstream in(std::string(RIGCAL_SOURCE_DIR) + "/tests/io/fixtures/estimator_state_v3.txt",
                   std::ios::binary);
  std::ostringstream v3;
  v3 << in.rdbuf();
  const Expected<RigEstimatorState> v4 =
      ParseEstimatorState(AsVersion(4, v3.str(), "consumed 2 -1 -1"));
  ASSERT_TRUE(v4.ok()) << v4.error();
  EXPECT_TRUE(v4->clock_offsets.empty());
  EXPECT_EQ(v4->consumed_t_ns, (std::vector<int64_t>{-1, -1}));

  RigEstimatorState state = *v4;
  ClockOffsetState c;
  c.initialised = true;
  c.offset_s = -39.950123456789012;
  c.drift = 4.9e-5;
  c.covariance << 2.5e-8, -1.25e-11, -1.25e-11, 4e-12;
  c.t_ns = 70'000'000'123;
  c.measurements = 17;
  c.jumps = 2;
  state.clock_offsets = {c};
  const std::string text = FormatEstimatorState(state);
  EXPECT_NE(text.find("\nclocks 1\nclock 0 1 -39.950123456789"), std::string::npos)
      << text.substr(0, 400);
  const Expected<RigEstimatorState> parsed = ParseEstimatorState(text);
  ASSERT_TRUE(parsed.ok()) << parsed.error();
  ASSERT_EQ(parsed->clock_offsets.size(), 1u);
  const ClockOffsetState& r = parsed->clock_offsets[0];
  EXPECT_TRUE(r.initialised);
  EXPECT_EQ(r.offset_s, c.offset_s);
  EXPECT_EQ(r.drift, c.drift);
  EXPECT_EQ(r.covariance, c.covariance);
  EXPECT_EQ(r.t_ns, c.t_ns);
  EXPECT_EQ(r.measurements, 17);
  EXPECT_EQ(r.jumps, 2);
  EXPECT_EQ(FormatEstimatorState(*parsed), text);

  const auto error_of = [&](const std::function<void(ClockOffsetState*)>& edit) {
    RigEstimatorState bad = state;
    edit(&bad.clock_offsets[0]);
    const Expected<RigEstimatorState> p = ParseEstimatorState(FormatEstimatorState(bad));
    return p.ok() ? std::string("accepted") : p.error();
  };
  EXPECT_EQ(error_of([](ClockOffsetState* s) { s->covariance(0, 0) = -1.0; }),
            "slave left: clock P00 = -1 is out of range [0, 1e+100]");
  EXPECT_EQ(error_of([](ClockOffsetState* s) { s->offset_s = 1e6; }),
            "slave left: clock offset_s = 1e+06 is out of range [-86400, 86400]");
  EXPECT_EQ(error_of([](ClockOffsetState* s) { s->jumps = -1; }),
            "slave left: clock jumps = -1 is out of range [0, 1e+100]");
  // Two clock lines for one slave.
  std::string two = AsVersion(5, v3.str(), "consumed 2 -1 -1", "clocks 2");
  const Expected<RigEstimatorState> rejected = ParseEstimatorState(two);
  ASSERT_FALSE(rejected.ok());
  EXPECT_EQ(rejected.error(), "malformed clock offsets (none, or one per slave)");
}

}  // namespace
}  // namespace rigcal::io
