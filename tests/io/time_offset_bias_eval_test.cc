// SPDX-License-Identifier: Apache-2.0
// Bias and σ of the offset the data prefer (label eval): CorrelateAngularSpeed and
// RefineTimeOffset, as CheckGivenTimeOffsets measures them, on rigs whose slave captures with
// the master and stamps 0, ±0.25, ±0.5, ±0.6 or ±1 frame interval off, at 10, 20 and 30 Hz,
// with white pose noise of three levels and drift-like noise, over many draws. An interpolated
// pose averages the noise of its neighbours: unweighted residuals make the cost lowest between
// frames, whatever the truth. Per case: the mean error (ms and σ), and the RMS of error/σ
// (1 when σ is honest).
// Run: ctest --test-dir build -L eval -R io/time_offset_bias_eval -V
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "../calib/free_running_rig.h"
#include "rigcal/base/logging.h"
#include "rigcal/calib/clock_offset.h"

namespace rigcal {
namespace {

using free_running::CameraClock;

struct Noise {
  const char* name;
  double rotation_deg;
  double position;
  double drift_deg_per_frame;
};

const Noise kNoises[] = {{"white 0.02deg", 0.02, 0.001, 0.0},
                         {"white 0.05deg", 0.05, 0.002, 0.0},
                         {"white 0.15deg", 0.15, 0.006, 0.0},
                         {"drift 0.02deg/frame", 0.01, 0.001, 0.02}};
const double kRatesHz[] = {10.0, 20.0, 30.0};
const double kOffsetsIntervals[] = {0.0, 0.25, -0.25, 0.5, -0.5, 0.6, -0.6, 1.0, -1.0};
constexpr int kDraws = 8;

struct Stats {
  int n = 0;
  double sum_e = 0.0, sum_z = 0.0, sum_z2 = 0.0;
  int beyond_3 = 0;
  void Add(double e, double z) {
    ++n, sum_e += e, sum_z += z, sum_z2 += z * z;
    beyond_3 += std::abs(z) > 3.0;
  }
  double MeanE() const { return sum_e / n; }
  double MeanZ() const { return sum_z / n; }
  double RmsZ() const { return std::sqrt(sum_z2 / n); }
};

// Two motions: the brisk general motion of the free-running rigs (30 s), and the demo drive
// (GenerateDrive, 60 s, one slow period: little angular acceleration, a weak offset signal).
enum class Motion { kBrisk, kDemo };
const char* Name(Motion m) { return m == Motion::kBrisk ? "brisk" : "demo"; }

TimedTrajectory Timed(const std::string& name, const std::vector<int64_t>& t_ns,
                      const CameraTrack& track, int64_t offset_ns) {
  return free_running::ToTimed(name, t_ns, track, offset_ns);
}

// Master and one slave (DemoRig()[0]) capturing together at `rate_hz`, the slave's stamps
// `offset_s` late.
free_running::FreeRunningRig MakeRig(Motion motion, double rate_hz, double offset_s,
                                     const DriveOptions& options) {
  const std::vector<Similarity> rigs = {DemoRig()[0]};
  if (motion == Motion::kBrisk) {
    return free_running::MakeFreeRunningRig({rate_hz, 0.0, 0.0}, {{rate_hz, 0.0, offset_s}}, rigs,
                                            30.0, options);
  }
  DriveOptions o = options;
  o.frame_rate_hz = rate_hz;
  o.num_frames = static_cast<int>(60.0 * rate_hz);
  const SyntheticDrive drive = GenerateDrive({"master", "cam1"}, rigs, o);
  free_running::FreeRunningRig out;
  out.truth = drive.truth;
  out.master = Timed("master", drive.recording.t_ns, drive.recording.master, 0);
  out.slaves.push_back(
      Timed("cam1", drive.recording.t_ns, drive.recording.slaves[0], std::llround(offset_s * 1e9)));
  return out;
}

// The offset the data prefer around 0 (as the timing check measures it), with the true rotation.
std::optional<TimeOffsetEstimate> Preferred(const free_running::FreeRunningRig& rig) {
  const auto correlated = CorrelateAngularSpeed(rig.master, rig.slaves[0], {});
  if (!correlated) return std::nullopt;
  const TimeOffsetEstimate refined =
      RefineTimeOffset(rig.master, rig.slaves[0], rig.truth[0].q, *correlated, {});
  if (!std::isfinite(refined.std_s)) return std::nullopt;
  return refined;
}

// Over a group of kDraws * 9 offsets: the mean normalised error within 4 of its standard errors
// (its own scatter over sqrt(n)) of 0. On the brisk drive the RMS of error/σ within the 99.9 %
// bounds of χ² with n degrees of freedom (0.75..1.27 for n = 72) widened by a tenth (the draws of
// a case share their motion), and so the RMS over all cases; on the demo drive below 2.5 (where
// the noise's slope rivals the signal's, a draw's minimum can still land on a wiggle of the cost
// a few of its σ away: the worst group, 0.02° at 20 Hz, reaches 2.25 through one draw at 15σ; see
// docs/evaluations.md).
TEST(TimeOffsetBiasEval, PreferredOffsetIsUnbiasedWithHonestSigma) {
  SetLogLevel("warn");
  std::printf(
      "\nPreferred offset (correlation + RefineTimeOffset, true rotation), slave\n"
      "capturing with the master, stamps off by the offset (frame intervals); %d draws "
      "per case; 'flag': |preferred| beyond 3σ of 0, as the timing check without --time-offset\n",
      kDraws);
  std::printf("%-6s %-20s %5s %7s | %9s %9s %8s %7s %4s %4s\n", "motion", "noise", "Hz", "offset",
              "mean e ms", "mean σ ms", "mean z", "rms z", ">3σ", "flag");
  Stats all;
  int false_alarms = 0, synchronised = 0;
  std::vector<std::string> failed;
  uint64_t seed = 1000;
  for (const Motion motion : {Motion::kBrisk, Motion::kDemo}) {
    for (const Noise& noise : kNoises) {
      for (const double rate : kRatesHz) {
        Stats group;
        for (const double fraction : kOffsetsIntervals) {
          Stats s;
          double sum_sigma = 0.0;
          int flagged = 0;
          for (int draw = 0; draw < kDraws; ++draw) {
            DriveOptions options;
            options.seed = ++seed;
            options.rotation_noise_deg = noise.rotation_deg;
            options.position_noise = noise.position;
            options.drift_deg_per_frame = noise.drift_deg_per_frame;
            const double offset_s = fraction / rate;
            const auto preferred = Preferred(MakeRig(motion, rate, offset_s, options));
            ASSERT_TRUE(preferred) << Name(motion) << " " << noise.name << " " << rate << " Hz";
            const double e = preferred->offset_s - offset_s;
            s.Add(e, e / preferred->std_s);
            group.Add(e, e / preferred->std_s);
            all.Add(e, e / preferred->std_s);
            sum_sigma += preferred->std_s;
            flagged += std::abs(preferred->offset_s) > 3.0 * preferred->std_s;
          }
          if (fraction == 0.0) false_alarms += flagged, synchronised += kDraws;
          std::printf("%-6s %-20s %5.0f %+7.2f | %+9.3f %9.3f %+8.2f %7.2f %4d %4d\n", Name(motion),
                      noise.name, rate, fraction, s.MeanE() * 1e3, sum_sigma / kDraws * 1e3,
                      s.MeanZ(), s.RmsZ(), s.beyond_3, flagged);
        }
        const std::string name = std::string(Name(motion)) + " " + noise.name + " " +
                                 std::to_string(static_cast<int>(rate)) + " Hz";
        if (std::abs(group.MeanZ()) > 4.0 * group.RmsZ() / std::sqrt(group.n)) {
          failed.push_back(name + ": mean z " + std::to_string(group.MeanZ()));
        }
        const double hi = motion == Motion::kBrisk ? 1.27 * 1.1 : 2.5;
        const double lo = motion == Motion::kBrisk ? 0.75 / 1.1 : 0.0;
        if (group.RmsZ() > hi || group.RmsZ() < lo) {
          failed.push_back(name + ": rms z " + std::to_string(group.RmsZ()));
        }
        std::printf("  group %s: mean z %+.2f, rms z %.2f\n", name.c_str(), group.MeanZ(),
                    group.RmsZ());
      }
    }
  }
  std::printf("all %d: mean z %+.2f, rms z %.2f, %d beyond 3σ (%.1f expected)\n", all.n,
              all.MeanZ(), all.RmsZ(), all.beyond_3, 0.0027 * all.n);
  std::printf("synchronised stamps flagged: %d of %d (%.1f expected at 3σ)\n", false_alarms,
              synchronised, 0.0027 * synchronised);
  if (all.RmsZ() > 1.27 * 1.1 || all.RmsZ() < 0.75 / 1.1) {
    failed.push_back("all: rms z " + std::to_string(all.RmsZ()));
  }
  for (const std::string& f : failed) ADD_FAILURE() << f;
}

}  // namespace
}  // namespace rigcal
