// SPDX-License-Identifier: Apache-2.0
// RigEstimator: the recursive estimator as a sequence of named stages (calib/src/online/ unless
// named with their folder):
//   AddSet       motions/pose_glitch_gate, then per slave:
//   UpdateSlave  motions/keyframe_pairing -> motion_gates -> statistics_accumulation
//   Publish      statistics_solution -> decalibration_check -> window_refinement ->
//                online_uncertainty -> convergence_check -> models/model_explanation
#include "rigcal/calib/rig_estimator.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <utility>

#include "batch/batch_acceptance.h"
#include "models/model_explanation.h"
#include "motions/keyframe_pairing.h"
#include "motions/master_travel.h"
#include "motions/motion_data.h"
#include "motions/pose_glitch_gate.h"
#include "motions/pose_quality_gate.h"
#include "online/convergence_check.h"
#include "online/decalibration_check.h"
#include "online/motion_gates.h"
#include "online/online_uncertainty.h"
#include "online/rig_estimator_slave.h"
#include "online/statistics_accumulation.h"
#include "online/statistics_solution.h"
#include "online/window_refinement.h"
#include "rigcal/base/format.h"
#include "rigcal/base/logging.h"
#include "rigcal/base/quaternion.h"

namespace rigcal {
namespace {

using internal::MotionData;

// The message of a published estimate: its state, the motions, the motion model and why
// (model_explanation.h). The online message states the equal-error boundary for the
// translational model and the model selection's figures (`selection`) for the planar one.
std::string OnlineMessage(const RigEstimatorOptions& o, const SlaveCalibration& published,
                          const std::string& selection, const std::optional<Similarity>& nominal) {
  if (!published.solved()) return published.message;
  internal::ModelExplanation e;
  e.model = published.motion_model;
  e.figures = published.observability;
  const bool translational = e.model == MotionModel::kTranslational;
  if (translational) e.boundary = internal::ModelExplanation::Boundary::kCompared;
  e.boundary_from_noise = o.model_selection.alpha_maxrot_noise_deg > 0.0;
  if (e.model == MotionModel::kPlanar) e.selection = selection;
  e.parallel = translational && !std::isfinite(published.rot_std_deg);
  e.axis_offset_std = published.axis_offset_std;
  e.nominal =
      e.model == MotionModel::kPlanar ? published.unobservable_from_prior : nominal.has_value();
  if (nominal) e.nominal_along_axis = published.observability.planar_axis.dot(nominal->C);
  e.nominal_sigma = o.nominal_sigma;
  std::string text = (published.state == SlaveState::kConverged ? "converged: " : "converging: ") +
                     std::to_string(published.motions.used) + " motions used, " +
                     std::to_string(published.motions.rejected()) + " rejected; " +
                     internal::ExplainModel(e);
  if (published.state == SlaveState::kDecalibrated) {
    text += "; DECALIBRATED (camera moved), re-converging";
  }
  return text;
}

}  // namespace

RigEstimator::RigEstimator(std::vector<std::string> camera_names, RigEstimatorOptions options)
    : names_(std::move(camera_names)), options_(std::move(options)) {
  RequireValid(options_.Check(), "RigEstimatorOptions");
  glitch_gate_ = std::make_unique<internal::PoseGlitchGate>(static_cast<int>(names_.size()));
  quality_gate_ = std::make_unique<internal::PoseQualityGate>(static_cast<int>(names_.size()));
  master_travel_ = std::make_unique<internal::MasterTravel>(2 * options_.keyframe_max_interval_ns);
  consumed_t_ns_.assign(names_.size(), -1);
  first_consumed_.assign(names_.size(), PoseFingerprint{});
  last_consumed_.assign(names_.size(), PoseFingerprint{});
  estimate_.rig.master = names_.empty() ? "" : names_[0];
  for (size_t i = 1; i < names_.size(); ++i) {
    slaves_.push_back(std::make_unique<Slave>(options_));
    SlaveCalibration c;
    c.name = names_[i];
    c.message = "initialising: no motion yet";
    estimate_.rig.slaves.push_back(c);
    estimate_.online.emplace_back();
  }
}

RigEstimator::~RigEstimator() = default;

const RigEstimate& RigEstimator::Estimate() const { return estimate_; }

std::optional<Similarity> RigEstimator::NominalOf(int index) const {
  return index < static_cast<int>(options_.nominal.size()) ? options_.nominal[index] : std::nullopt;
}

void RigEstimator::AddSet(int64_t t_ns, const std::vector<std::optional<CameraPose>>& poses) {
  if ((estimate_.sets > 0 && t_ns <= estimate_.t_ns) || poses.empty() || !poses[0] ||
      !poses[0]->pose.q.coeffs().allFinite() || !poses[0]->pose.C.allFinite()) {
    ++estimate_.rejected_sets;
    return;
  }
  estimate_.t_ns = t_ns;
  ++estimate_.sets;
  for (size_t c = 0; c < poses.size() && c < consumed_t_ns_.size(); ++c) {
    if (!poses[c]) continue;
    const CameraPose& p = *poses[c];
    const PoseFingerprint taken{p.t_ns, p.pose.q, p.pose.C};
    if (first_consumed_[c].t_ns < 0) first_consumed_[c] = taken;
    if (p.t_ns >= consumed_t_ns_[c]) last_consumed_[c] = taken;
    consumed_t_ns_[c] = std::max(consumed_t_ns_[c], p.t_ns);
  }
  const CameraPose& master = *poses[0];
  if (have_master_segment_ && master.segment != master_segment_ && options_.master_metric) {
    // A metric master keeps its unit: only pairs across the two master frames are impossible.
    ModuleLogger("calib")->info(
        "metric master odometry re-initialised (segment {} -> {}): keyframes restart, "
        "positions and scales (metres) are kept",
        master_segment_, master.segment);
    for (auto& s : slaves_) s->keyframes.clear();
  } else if (have_master_segment_ && master.segment != master_segment_) {
    // New master unit: positions and scales restart; rotations are unit-free and stay.
    ModuleLogger("calib")->info(
        "master odometry re-initialised (segment {} -> {}): position "
        "and scales restart in the new master unit",
        master_segment_, master.segment);
    for (auto& s : slaves_) {
      internal::RestartPositions(&s->stats);
      s->keyframes.clear();
      s->refined.reset();
      s->RestartHistory();
    }
    ++generation_;
  }
  master_segment_ = master.segment;
  have_master_segment_ = true;
  master_travel_->Add(t_ns, master.pose, master.segment);
  const double keyframe_min_translation =
      master_travel_->DistanceIn(options_.keyframe_min_travel_s);
  const internal::PoseGlitchGate::Verdict glitches = glitch_gate_->Check(t_ns, poses);
  const std::vector<bool> poor = quality_gate_->Check(poses);
  for (size_t i = 0; i < slaves_.size() && i + 1 < poses.size(); ++i) {
    const bool glitched =
        internal::CountGlitch(glitches, static_cast<int>(i), &slaves_[i]->glitches);
    if (!poses[i + 1]) continue;
    const CameraPose& slave = *poses[i + 1];
    if (!slave.pose.q.coeffs().allFinite() || !slave.pose.C.allFinite()) {
      ++slaves_[i]->counts.residual_outlier;
      PublishCounts(static_cast<int>(i));
      continue;
    }
    if (poor[0] || poor[i + 1]) {  // neither a keyframe nor in the history (pose_quality_gate)
      ++slaves_[i]->online.poorly_tracked;
      slaves_[i]->online.quality_threshold = quality_gate_->Threshold(poor[0] ? 0 : i + 1);
      estimate_.online[i].poorly_tracked = slaves_[i]->online.poorly_tracked;
      continue;
    }
    // The history holds every finite set: the batch calibrator finds glitches itself.
    slaves_[i]->RecordHistory(options_.history_sets, estimate_.sets - 1, t_ns, master, slave);
    if (glitched) {
      PublishCounts(static_cast<int>(i));
      continue;
    }
    UpdateSlave(static_cast<int>(i), t_ns, master, slave, keyframe_min_translation);
  }
}

void RigEstimator::UpdateSlave(int index, int64_t t_ns, const CameraPose& master,
                               const CameraPose& slave, double keyframe_min_translation) {
  Slave& s = *slaves_[index];
  const RigEstimatorOptions& o = options_;
  s.online.segment = slave.segment;

  // Keyframes, and the motion pair of a new one.
  if (!internal::OfferKeyframe(o, keyframe_min_translation, t_ns, master, slave, &s.keyframes))
    return;
  ++s.online.keyframes;
  const std::optional<internal::KeyframePair> pair = internal::PairNewestKeyframe(o, s.keyframes);
  if (!pair) return;
  const RigMotion& m = pair->motion;
  std::vector<MotionData> data = internal::ToMotionData({m});
  const MotionData& md = data[0];
  ++s.counts.total;

  // The motion model follows every formed motion (not only accepted ones): once the rig has
  // rotated by the equal-error boundary at the measured rotation noise (thesis 5.2) the
  // general model applies, and the residual statistics restart.
  if (!s.rotating &&
      md.angle0 * kDegPerRad >= internal::OnlineTranslationalBelowDeg(o, s.gates.angle_var)) {
    s.rotating = true;
    internal::RestartResidualGating(&s.gates);
    s.model_changed_ns = m.t_b_ns;
  }

  // Gates.
  const bool have_estimate =
      s.linear.solved() && (s.linear.motion_model != MotionModel::kTranslational) == s.rotating;
  if (s.linear.solved()) internal::AlignSignsWith(ToWxyz(s.linear.estimate.q), &data);
  const internal::GateOutcome gate =
      internal::GateMotion(o, s.gates, md, s.rotating, have_estimate ? &s.linear : nullptr);
  switch (gate.verdict) {
    case internal::GateVerdict::kAccepted:
      break;
    case internal::GateVerdict::kSmallRotation:
      ++s.counts.small_rotation;
      PublishCounts(index);
      return;
    case internal::GateVerdict::kAngleMismatch:
      ++s.counts.angle_mismatch;
      PublishCounts(index);
      return;
    case internal::GateVerdict::kScaleMismatch:
    case internal::GateVerdict::kOutlier:
      if (gate.verdict == internal::GateVerdict::kScaleMismatch) ++s.online.gated_scale;
      ++s.counts.residual_outlier;
      PublishCounts(index);
      internal::RecordResidualRejection(o, names_[index + 1], &s.gates);
      return;
  }
  internal::RecordAccepted(gate, md, have_estimate, &s.gates);
  internal::RecordPairDrift(*pair, &s.drift);

  // Forgetting, then accumulation.
  const Eigen::Quaterniond marginalise_at =
      have_estimate ? s.linear.estimate.q : Eigen::Quaterniond::Identity();
  internal::AccumulateMotion(o, m, md, gate.weight, marginalise_at, &s.stats);
  ++s.counts.used;
  s.restored_unchanged = false;
  s.online.last_update_ns = m.t_b_ns;
  Publish(index);
}

void RigEstimator::PublishCounts(int index) {
  const MotionCounts& c = slaves_[index]->counts;
  MotionCounts& p = estimate_.rig.slaves[index].motions;
  p.total = c.total;
  p.small_rotation = c.small_rotation;
  p.angle_mismatch = c.angle_mismatch;
  p.residual_outlier = c.residual_outlier;
  estimate_.rig.slaves[index].glitches = slaves_[index]->glitches;
}

void RigEstimator::Publish(int index) {
  Slave& s = *slaves_[index];
  const RigEstimatorOptions& o = options_;
  const std::optional<Similarity> nominal = NominalOf(index);
  s.online.flags = 0;
  const internal::MotionModelChoice choice =
      internal::ChooseMotionModel(o, s.rotating, s.gates.angle_var);
  s.SolveLongWindow(o, nominal, choice);
  // The σ inflation (of the time blocks before a decalibration clears them).
  const internal::SigmaInflation inflation =
      internal::InflationOf(o, s.gates.angle_var, s.drift, s.stats.rotation_blocks, s.rotating);
  const internal::WindowComparison windows = s.CompareWindows(o, nominal, choice, inflation);
  s.online.short_long_rot_deg = windows.rot_diff_deg;
  if (windows.decalibrated) {
    ModuleLogger("calib")->warn(
        "slave '{}' decalibrated: short and long windows differ by {:.2f} deg; following the "
        "new calibration",
        names_[index + 1], windows.rot_diff_deg);
    ++generation_;
    s.FollowShortWindow(o, nominal, choice);
  }
  const bool decalibrated =
      internal::RecentlyDecalibrated(o, s.decalibration, s.online.last_update_ns);

  SlaveCalibration published = s.Published(o, inflation, names_[index + 1]);
  s.online.flags |=
      internal::ConvergenceCheck(o, &published, s.linear, inflation.rotation, decalibrated,
                                 s.MasterMotionLength(), &s.convergence);
  const std::optional<std::string> unsupported = s.Unsupported(published, generation_);
  if (unsupported) {
    published.state = SlaveState::kInitialising;
    s.convergence.stable = 0;
  }
  published.message = OnlineMessage(o, published, s.linear.message, nominal);
  if (const std::string g = internal::GlitchText(s.glitches, "set", "skipped"); !g.empty()) {
    published.message += "; " + g;
  }
  if (s.online.poorly_tracked > 0) {
    published.message += "; " + std::to_string(s.online.poorly_tracked) +
                         " sets of poorly tracked poses not used (quality below " +
                         FixedText(s.online.quality_threshold, 2) + ")";
  }
  if (unsupported) published.message = "not usable: " + *unsupported + "; " + published.message;
  estimate_.rig.slaves[index] = published;
  estimate_.online[index] = s.online;
  PublishCounts(index);
}

RefinementJob RigEstimator::MakeRefinementJob(int slave, bool final) const {
  RefinementJob job;
  job.slave = slave;
  job.generation = generation_;
  const Slave& s = *slaves_.at(slave);
  if (options_.history_sets > 0 && s.history_complete &&
      static_cast<int>(s.history.sets().size()) >= options_.history_min_sets && s.linear.solved()) {
    // The batch calibrator on every set since the restart, when due; until then no job (an
    // unsolved start), so a window refinement does not replace the history's result.
    const int64_t period = static_cast<int64_t>(options_.history_refine_period_s * 1e9);
    const int64_t newest = s.history.sets().back().t_ns;
    if (!final && s.last_history_refine_ns != std::numeric_limits<int64_t>::min() &&
        newest - s.last_history_refine_ns < period) {
      return job;
    }
    RigRecording& h = job.history;
    h.master.name = names_[0];
    h.slaves.resize(1);
    h.slaves[0].name = names_[slave + 1];
    for (const auto& set : s.history.sets()) {
      h.t_ns.push_back(set.t_ns);
      h.master.poses.push_back(set.master);
      h.master.segment.push_back(set.master_segment);
      h.slaves[0].poses.push_back(set.slave);
      h.slaves[0].segment.push_back(set.slave_segment);
    }
    // The other slaves at the same times, each whose history holds them all: the batch
    // calibrator finds the glitches on every camera (a master glitch is told from a slave's by
    // the others) and drops their times, as it does on the whole recording.
    for (size_t other = 0; other < slaves_.size(); ++other) {
      if (static_cast<int>(other) == slave) continue;
      const std::deque<Slave::HistorySet>& oh = slaves_[other]->history.sets();
      CameraTrack camera;
      camera.name = names_[other + 1];
      auto it = oh.begin();
      for (const int64_t t : h.t_ns) {
        it = std::lower_bound(it, oh.end(), t,
                              [](const Slave::HistorySet& a, int64_t b) { return a.t_ns < b; });
        if (it == oh.end() || it->t_ns != t) break;
        camera.poses.push_back(it->slave);
        camera.segment.push_back(it->slave_segment);
      }
      if (camera.poses.size() == h.t_ns.size()) h.slaves.push_back(std::move(camera));
    }
    job.history_t_ns = newest;
    job.history_stride = s.history.stride();
    job.history_options = HistoryCalibrationOptions(options_);
    if (const std::optional<Similarity> nominal = NominalOf(slave)) {
      job.history_options.nominal[names_[slave + 1]] = *nominal;
    }
    // The window too: the refinement falls back to it when the batch cannot solve.
  }
  internal::CopyWindow(s.stats, &job);
  job.start = s.linear;
  const std::optional<Similarity> nominal = NominalOf(slave);
  if (nominal && options_.nominal_sigma > 0.0) {
    job.axis_prior = s.linear.observability.planar_axis.dot(nominal->C);
    job.axis_prior_sigma = options_.nominal_sigma;
  }
  return job;
}

bool RigEstimator::ApplyRefinement(const RefinementJob& job, const SlaveCalibration& refined) {
  if (job.generation != generation_ || !refined.solved()) return false;
  Slave& s = *slaves_.at(job.slave);
  // Nothing new since a restart: the saved estimate stays (a refinement of the statistics
  // alone is another minimum, not what was published before the restart).
  if (s.restored_unchanged) return false;
  s.refined = refined;
  // A batch result names its pairs; the window refinement (also the fallback of a history
  // job) keeps the online estimate's empty ones.
  s.refined_from_history = !job.history.t_ns.empty() && !refined.pairs.empty();
  if (s.refined_from_history) s.last_history_refine_ns = job.history_t_ns;
  Publish(job.slave);
  return (estimate_.online[job.slave].flags & kFlagRefined) != 0;
}

}  // namespace rigcal
