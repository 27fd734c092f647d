// The batch rig calibrator (thesis chapter 4) as a sequence of named stages (calib/src/):
//   pose_glitches (CalibrateRig, before the pairs) -> batch_motions -> batch_model_selection ->
//   batch_linear_solution -> batch_refinement -> batch_result (with model_explanation).
#include "rigcal/calib/rig_calibrator.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "batch_acceptance.h"
#include "batch_linear_solution.h"
#include "batch_model_selection.h"
#include "batch_motions.h"
#include "batch_pair_choice.h"
#include "batch_refinement.h"
#include "batch_result.h"
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
                            bool* supported) {
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
  bool supported = true;
  SlaveCalibration r = SolveSlave(motions, options, name, &supported);
  r.state = BatchState(r, supported);
  return r;
}

RigCalibration CalibrateRig(const RigRecording& input, const CalibrationOptions& options) {
  // Glitched poses (pose_glitches.h) go first: neither the pair choice nor a motion sees them.
  internal::GlitchReport glitches;
  const RigRecording recording = internal::WithoutGlitches(input, &glitches);
  RigCalibration out;
  out.master = recording.master.name;
  const std::string invalid = recording.Check().message();
  const bool options_ok = options.Check().ok();
  std::vector<IndexPair> pairs;
  const bool auto_pairs = options.pairs.policy == PairOptions::Policy::kAuto;
  if (invalid.empty() && options_ok && !auto_pairs) pairs = SelectPairs(recording, options.pairs);
  out.pairs_selected = static_cast<int>(pairs.size());
  for (size_t i = 0; i < recording.slaves.size(); ++i) {
    const auto& name = recording.slaves[i].name;
    if (!invalid.empty()) {
      SlaveCalibration r;
      r.name = name;
      out.slaves.push_back(
          internal::Failed(r, Termination::kInvalidInput, "invalid recording: " + invalid));
      continue;
    }
    if (auto_pairs && options_ok) {
      out.slaves.push_back(
          internal::CalibrateSlaveAutoPairs(recording, static_cast<int>(i), options));
      out.pairs_selected = std::max(out.pairs_selected, out.slaves.back().motions.total);
      internal::ReportGlitches(glitches, static_cast<int>(i), &out.slaves.back());
      continue;
    }
    out.slaves.push_back(
        CalibrateSlave(MotionsForSlave(recording, static_cast<int>(i), pairs), options, name));
    out.slaves.back().pairs =
        ToString(options.pairs.policy) + (options.pairs.policy == PairOptions::Policy::kRelative
                                              ? ":" + std::to_string(options.pairs.step)
                                              : "");
    internal::ReportGlitches(glitches, static_cast<int>(i), &out.slaves.back());
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
