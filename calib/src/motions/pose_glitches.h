// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 0 of the batch calibrator (CalibrateRig): gross pose outliers ("glitches") found from
// each camera's own trajectory, before the pairs of times are chosen. A glitch — a pose that
// jumps by far more than the camera moves and comes back, a rotated pose — would otherwise
// enter every motion that starts or ends at it and change which pairs are chosen.
//
// Per camera and odometry segment, step k is the move from pose k-1 to pose k:
//   - position jump: its speed |C_k - C_{k-1}| / dt is an outlier against the camera's typical
//     speed there (the larger of the local and the overall median step speed): above
//     jump_factor times it and above its median + outlier_sigmas robust σ (1.4826 MAD);
//   - rotation jump: the same for the angular speed angle(q_{k-1}, q_k) / dt;
//   - angle mismatch (scale-free, per master/slave pair): master and slave rotate by the same
//     angle between any two times whatever the extrinsics, so the step's angle difference is
//     an outlier beyond outlier_sigmas robust σ of all steps' differences. The glitch is the
//     camera whose own rotation between the neighbours is the less direct (the larger excess
//     angle of its steps over the bridged rotation).
// Poses a+1 .. b-1 are a glitch (a run of at most max_run poses) when the steps into and out of
// the run are outliers and the bridged step a -> b is not, and is below both by jump_factor:
// real motion, however fast it turns or accelerates, bridges at about the mean of its steps
// (a fast step makes the bridged step fast as well), while a pose that jumps away and back
// leaves the bridged step at the typical value. A run at the start or end of a segment has no
// bridge: the outlier step out of (into) it suffices when the step after (before) it is normal
// and below it by jump_factor.

#include <string>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::internal {

enum class GlitchCause { kNone, kPositionJump, kRotationJump, kAngleMismatch };

// Relative resolution below which two doubles are the same number for the glitch tests
// (positions and angles computed from unit quaternions carry ~1e-16 relative rounding).
inline constexpr double kGlitchResolution = 1e-9;

// The thresholds are relative to the data's own robust spread; these are only how far out.
struct GlitchTest {
  double jump_factor = 5.0;     // an outlier step is this many times the typical speed ...
  double outlier_sigmas = 8.0;  // ... and this many robust σ beyond the median
  int window = 10;              // local median over +- window steps
  int max_run = 5;              // longest run of consecutive glitched poses
  int min_steps = 8;            // fewer steps in a segment: too little to tell, nothing found
};

// One glitched pose: camera 0 = master, i + 1 = slave i.
struct PoseGlitch {
  int index = 0;
  int camera = 0;
  GlitchCause cause = GlitchCause::kNone;
};

struct GlitchReport {
  std::vector<PoseGlitch> glitches;  // by index, then camera; one entry per glitched pose
  std::vector<int> dropped;          // the glitched times, ascending and unique
  // The counts for slave `slave` (every dropped time counts once, under the first cause of
  // its glitches: position, rotation, angle mismatch).
  GlitchCounts CountsFor(int slave) const;
};

// The glitched poses of a consistent recording (RigRecording::Check ok; else none).
GlitchReport FindGlitches(const RigRecording& recording, const GlitchTest& test = {});

// The recording without the times of its glitches (every camera's pose at such a time), and
// what was found in `report` (when not null).
RigRecording WithoutGlitches(const RigRecording& recording, GlitchReport* report);

// Adds the glitch counts of slave `slave` to its result and, when poses were dropped, says so
// at the end of its message: "; N poses dropped as glitches (a position jumps, b rotation
// jumps, c angle mismatches; m in the master, s in this camera)".
void ReportGlitches(const GlitchReport& report, int slave, SlaveCalibration* result);

// "N <noun>s <verb> as glitches (...)" for counts with dropped() > 0, else "".
std::string GlitchText(const GlitchCounts& counts, const std::string& noun = "pose",
                       const std::string& verb = "dropped");

// The threshold above which a speed is an outlier against `typical` (a median speed) and the
// robust spread of the speeds (median, σ), never below `floor` (numerical resolution).
double OutlierSpeed(const GlitchTest& test, double typical, double median, double sigma,
                    double floor);

}  // namespace rigcal::internal
