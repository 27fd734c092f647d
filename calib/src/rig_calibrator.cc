// The batch rig calibrator (thesis chapter 4) as a sequence of named stages (calib/src/):
//   pose_glitches (CalibrateRig, before the pairs) -> batch_motions -> batch_model_selection ->
//   batch_linear_solution -> batch_refinement -> batch_result (with model_explanation).
#include "rigcal/calib/rig_calibrator.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "batch_acceptance.h"
#include "batch_gls.h"
#include "batch_linear_solution.h"
#include "batch_model_selection.h"
#include "batch_motions.h"
#include "batch_pair_choice.h"
#include "batch_refinement.h"
#include "batch_result.h"
#include "batch_solve_details.h"
#include "motion_data.h"
#include "pose_glitches.h"
#include "rigcal/calib/logging.h"
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

RigCalibration CalibrateRig(const RigRecording& input, const CalibrationOptions& options) {
  // Glitched poses (pose_glitches.h) go first: neither the pair choice nor a motion sees them.
  internal::GlitchReport glitches;
  const RigRecording recording = internal::WithoutGlitches(input, &glitches);
  RigCalibration out;
  out.master = recording.master.name;
  const std::string invalid = recording.Check().message();
  const bool options_ok = options.Check().ok();
  const bool solvable = invalid.empty() && options_ok;
  const bool gls = options.pairs.policy == PairOptions::Policy::kGls;
  const bool auto_pairs = options.pairs.policy == PairOptions::Policy::kAuto || gls;
  std::vector<IndexPair> pairs;
  internal::AutoPairCandidates candidates;
  if (solvable && auto_pairs) {
    candidates = internal::MakeAutoPairCandidates(recording, options.pairs);
  } else if (solvable) {
    pairs = SelectPairs(recording, options.pairs);
  }
  out.pairs_selected = static_cast<int>(pairs.size());
  for (size_t i = 0; i < recording.slaves.size(); ++i) {
    const int slave = static_cast<int>(i);
    SlaveCalibration r;
    r.name = recording.slaves[i].name;
    if (!invalid.empty()) {
      r = internal::Failed(r, Termination::kInvalidInput, "invalid recording: " + invalid);
    } else if (solvable && auto_pairs) {
      r = gls ? internal::CalibrateSlaveGls(recording, candidates, slave, options)
              : internal::CalibrateSlaveAutoPairs(recording, candidates, slave, options);
      out.pairs_selected = std::max(out.pairs_selected, r.motions.total);
    } else {
      r = CalibrateSlave(MotionsForSlave(recording, slave, pairs), options, r.name);
      r.pairs = PairsText(options.pairs);
    }
    if (invalid.empty()) internal::ReportGlitches(glitches, slave, &r);
    out.slaves.push_back(std::move(r));
  }
  return out;
}

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
