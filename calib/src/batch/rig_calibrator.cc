// SPDX-License-Identifier: Apache-2.0
// The batch rig calibrator (thesis chapter 4) as a sequence of named stages (calib/src/batch/
// unless named with their folder):
//   motions/pose_glitches (CalibrateRig, before the pairs) -> batch_motions ->
//   batch_model_selection -> batch_linear_solution -> batch_refinement -> batch_result (with
//   models/model_explanation) -> batch_acceptance; the auto and gls pair policies around them
//   (batch_pair_choice, batch_gls) and, last, their σ floor (batch_sigma_floor).
#include "rigcal/calib/rig_calibrator.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "batch/batch_acceptance.h"
#include "batch/batch_gls.h"
#include "batch/batch_linear_solution.h"
#include "batch/batch_model_selection.h"
#include "batch/batch_motions.h"
#include "batch/batch_pair_choice.h"
#include "batch/batch_refinement.h"
#include "batch/batch_result.h"
#include "batch/batch_sigma_floor.h"
#include "batch/batch_solve_details.h"
#include "batch/batch_units.h"
#include "motions/motion_data.h"
#include "motions/pose_glitches.h"
#include "rigcal/base/logging.h"
#include "rigcal/calib/pair_selection.h"

namespace rigcal {
namespace {

// The batch state (slave_state.h): initialising unless the solve produced an estimate the data
// support (`supported`, batch_acceptance.h); then converged when its σ were computed from the
// covariance (finite), else usable.
SlaveState BatchState(const SlaveCalibration& r, bool supported) {
  if (!r.solved() || !supported) return SlaveState::kInitialising;
  bool sigma_known = std::isfinite(r.rot_std_deg) && r.rot_std_deg > 0.0 &&
                     (!r.position_observable || r.pos_std.allFinite());
  for (const SegmentScale& s : r.scales) sigma_known = sigma_known && std::isfinite(s.std);
  return sigma_known ? SlaveState::kConverged : SlaveState::kUsable;
}

// CalibrateSlave's stages, without the state; `supported`: whether the data support a solved
// estimate (batch_acceptance.h; the message then says what is missing).
SlaveCalibration SolveSlave(const std::vector<RigMotion>& motions,
                            const CalibrationOptions& options, const std::string& name,
                            bool* supported, internal::SlaveSolveDetails* details) {
  SlaveCalibration r;
  r.name = name;
  if (const Status checked = options.Check(); !checked.ok()) {
    return internal::Failed(r, Termination::kInvalidInput, "invalid options: " + checked.message());
  }

  // The motions, the motion model they call for (thesis 5.2), and those the model can use.
  std::vector<internal::MotionData> data = internal::FormMotions(motions, &r.motions);
  const internal::BatchSetting setting =
      internal::SelectMotionModel(options, name, data, &r.observability);
  r.motion_model = setting.translational ? MotionModel::kTranslational : MotionModel::kGeneral;
  internal::RemoveUnusableMotions(options, setting.translational, &data, &r.motions);
  if (static_cast<int>(data.size()) < options.min_motions) {
    r.motions.used = static_cast<int>(data.size());
    return internal::Failed(
        r, Termination::kInsufficientMotion,
        internal::TooFewMotionsMessage(options, setting.translational, data.size(),
                                       r.observability.max_rotation_deg));
  }

  // The scale model (thesis 5.5), then the linear estimate with misfit removal.
  const internal::ScaleModelChoice scale = internal::SelectScaleModel(options, setting, &data);
  r.scale_model = scale.model;
  const internal::LinearEstimate linear =
      internal::SolveLinear(options, setting, &data, &r.motions);
  internal::TakeLinearFigures(setting, linear, static_cast<int>(data.size()), &r);
  if (auto undetermined = internal::UndeterminedResult(options, setting, linear, r)) {
    return *undetermined;
  }

  if (options.cancelled()) return internal::Failed(r, Termination::kCancelled, "cancelled");
  // Non-linear refinement and covariance (4.26-4.27), then the result.
  const internal::BatchRefinement refinement =
      internal::RefineBatch(options, setting, data, linear, r.observability.planar_axis,
                            r.motion_model == MotionModel::kPlanar, scale.epsilon);
  internal::AssembleResult(options, setting, data, linear, refinement, scale, &r);
  if (details != nullptr) {
    const internal::RefinementResult& refined = refinement.refined;
    details->covariance_ok = refined.covariance_ok;
    details->time_blocks = refinement.time_blocks;
    details->cov_rotation = refined.cov_rotation;
    details->cov_position = refined.cov_position;
    details->independent_cov_rotation = refined.independent_cov_rotation;
    details->independent_cov_position = refined.independent_cov_position;
  }
  if (r.solved()) {
    bool contradiction = false;
    if (auto reason = internal::UnsupportedReason(options, setting, data, r, &contradiction)) {
      *supported = false;
      if (contradiction) r.contradiction = *reason;
      r.message = "not usable: " + *reason + "; " + r.message;
    }
  }
  ModuleLogger("calib")->debug("slave '{}': {}", name, r.message);
  return r;
}

}  // namespace

SlaveCalibration CalibrateSlave(const std::vector<RigMotion>& motions,
                                const CalibrationOptions& options, const std::string& name) {
  return internal::CalibrateSlave(motions, options, name, nullptr);
}

namespace internal {

SlaveCalibration CalibrateSlave(const std::vector<RigMotion>& motions,
                                const CalibrationOptions& options, const std::string& name,
                                SlaveSolveDetails* details) {
  bool supported = true;
  SlaveCalibration r = SolveSlave(motions, options, name, &supported, details);
  r.state = BatchState(r, supported);
  return r;
}

}  // namespace internal

namespace {

// CalibrateRig's stage 0 and the pair candidates every slave shares.
struct RigPreparation {
  internal::GlitchReport glitches;
  RigRecording recording;  // without the glitched times
  std::string invalid;     // why the recording cannot be calibrated, or empty
  bool solvable = false;
  bool gls = false;
  bool auto_pairs = false;
  std::vector<IndexPair> pairs;  // fixed policies
  internal::AutoPairCandidates candidates;
};

RigPreparation Prepare(const RigRecording& input, const CalibrationOptions& options) {
  // Glitched poses (pose_glitches.h) go first: neither the pair choice nor a motion sees them.
  RigPreparation p;
  p.recording = internal::WithoutGlitches(input, &p.glitches);
  p.invalid = p.recording.Check().message();
  p.solvable = p.invalid.empty() && options.Check().ok();
  p.gls = options.pairs.policy == PairOptions::Policy::kGls;
  p.auto_pairs = options.pairs.policy == PairOptions::Policy::kAuto || p.gls;
  if (p.solvable && p.auto_pairs) {
    p.candidates = internal::MakeAutoPairCandidates(p.recording, options.pairs);
  } else if (p.solvable) {
    p.pairs = SelectPairs(p.recording, options.pairs);
  }
  return p;
}

SlaveCalibration CalibratePrepared(const RigPreparation& p, const CalibrationOptions& options,
                                   int slave) {
  SlaveCalibration r;
  r.name = p.recording.slaves[slave].name;
  if (!p.invalid.empty()) {
    return internal::Failed(r, Termination::kInvalidInput, "invalid recording: " + p.invalid);
  }
  if (options.cancelled()) return internal::Failed(r, Termination::kCancelled, "cancelled");
  if (p.solvable && p.auto_pairs) {
    r = p.gls ? internal::CalibrateSlaveGls(p.recording, p.candidates, slave, options)
              : internal::CalibrateSlaveAutoPairs(p.recording, p.candidates, slave, options);
    // Last: σ only, after every choice the σ of the candidates made.
    internal::HoldSigmaToConsecutiveGls(p.recording, slave, options, &r);
  } else {
    r = CalibrateSlave(MotionsForSlave(p.recording, slave, p.pairs), options, r.name);
    r.pairs = PairsText(options.pairs);
  }
  internal::ReportGlitches(p.glitches, slave, &r);
  return r;
}

}  // namespace

RigCalibration CalibrateRig(const RigRecording& recording, const CalibrationOptions& given) {
  // In the data's own length unit (batch_units.h).
  const double unit = internal::LengthUnitOf(recording);
  const RigRecording input = internal::InLengthUnit(recording, unit);
  const CalibrationOptions options = internal::InLengthUnit(given, unit);
  const RigPreparation p = Prepare(input, options);
  RigCalibration out;
  out.master = p.recording.master.name;
  out.pairs_selected = static_cast<int>(p.pairs.size());
  for (size_t i = 0; i < p.recording.slaves.size(); ++i) {
    SlaveCalibration r = CalibratePrepared(p, options, static_cast<int>(i));
    internal::FromLengthUnit(unit, &r);
    if (p.solvable && p.auto_pairs) {
      out.pairs_selected = std::max(out.pairs_selected, r.motions.total);
    }
    out.slaves.push_back(std::move(r));
  }
  return out;
}

RigRecording WithoutGlitches(const RigRecording& recording, std::vector<int>* dropped) {
  internal::GlitchReport report;
  RigRecording out = internal::WithoutGlitches(recording, &report);
  if (dropped != nullptr) *dropped = report.dropped;
  return out;
}

namespace internal {

SlaveCalibration CalibrateRigSlave(const RigRecording& recording, const CalibrationOptions& given,
                                   int slave) {
  const double unit = LengthUnitOf(recording);
  const CalibrationOptions options = InLengthUnit(given, unit);
  SlaveCalibration r =
      CalibratePrepared(Prepare(InLengthUnit(recording, unit), options), options, slave);
  FromLengthUnit(unit, &r);
  return r;
}

}  // namespace internal

std::string ToString(Termination t) {
  switch (t) {
    case Termination::kSolved:
      return "solved";
    case Termination::kNoConvergence:
      return "no_convergence";
    case Termination::kInsufficientMotion:
      return "insufficient_motion";
    case Termination::kDegenerate:
      return "degenerate";
    case Termination::kInvalidInput:
      return "invalid_input";
    case Termination::kCancelled:
      return "cancelled";
  }
  return "?";
}

std::string RigCalibration::BriefReport() const {
  std::ostringstream s;
  s << "master " << master << ", " << pairs_selected << " time pairs\n";
  for (const auto& r : slaves) {
    s << "  " << r.name << ": " << ToString(r.termination) << " - " << r.message << "\n";
  }
  return s.str();
}

}  // namespace rigcal
