// SPDX-License-Identifier: Apache-2.0
// The gls pair policy (batch_gls.h).
#include "batch/batch_gls.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "batch/batch_motions.h"
#include "noise/time_blocks.h"
#include "refinement/gls_refinement.h"
#include "rigcal/base/format.h"
#include "rigcal/base/logging.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"
#include "rigcal/calib/pair_selection.h"

namespace rigcal::internal {
namespace {

// The span of the chains: auto's span, or for the walk the median span of its pairs.
int ChainSpan(const RigRecording& recording, const SlaveCalibration& r,
              const CalibrationOptions& options) {
  const std::string prefix = "relative:";
  if (r.pairs.rfind(prefix, 0) == 0) return std::max(1, std::stoi(r.pairs.substr(prefix.size())));
  PairOptions walk = options.pairs;
  walk.policy = PairOptions::Policy::kWalk;
  std::vector<double> spans;
  for (const IndexPair& p : SelectPairs(recording, walk)) spans.push_back(p.b - p.a);
  return spans.empty() ? 1 : std::max(1, static_cast<int>(std::lround(Median(spans))));
}

}  // namespace

std::vector<MotionData> ChainMotions(const RigRecording& recording, int slave, int span,
                                     const SlaveCalibration& r) {
  std::vector<IndexPair> pairs = RelativePairs(recording, span);
  std::stable_sort(pairs.begin(), pairs.end(),
                   [&](const IndexPair& x, const IndexPair& y) { return x.a % span < y.a % span; });
  MotionCounts counts;
  std::vector<MotionData> data = FormMotions(MotionsForSlave(recording, slave, pairs), &counts);
  std::vector<MotionData> out;
  out.reserve(data.size());
  for (MotionData& m : data) {
    int index = r.scale_model == ScaleModel::kSegments ? -1 : 0;
    for (size_t s = 0; index < 0 && s < r.scales.size(); ++s) {
      if (r.scales[s].segment == m.segment) index = static_cast<int>(s);
    }
    if (index < 0) continue;
    m.scale_index = index;
    out.push_back(m);
  }
  return out;
}

GlsInput GlsStartOf(const SlaveCalibration& r, const CalibrationOptions& options) {
  GlsInput in;
  in.q = r.estimate.q;
  in.C = r.estimate.C;
  for (const SegmentScale& s : r.scales) in.scales.push_back(s.scale);
  if (in.scales.empty()) in.scales.push_back(r.estimate.scale);
  in.translational = r.motion_model == MotionModel::kTranslational;
  const Eigen::Vector3d& axis = r.observability.planar_axis;
  const auto nominal = options.nominal.find(r.name);
  if (!in.translational && axis.norm() > 0.5) {
    if (r.motion_model == MotionModel::kPlanar) {
      in.axis = axis.normalized();
      in.axis_offset_fixed = true;  // at the auto result's offset: the prior's or 0
    } else if (nominal != options.nominal.end() && options.nominal_sigma > 0.0) {
      in.axis = axis.normalized();
      in.axis_prior = in.axis.dot(nominal->second.C);
      in.axis_prior_sigma = options.nominal_sigma;
    }
  }
  in.time_blocks = options.covariance_time_blocks;
  in.cancel = options.cancel;
  return in;
}

void TakeGls(const GlsResult& g, const GlsInput& in, const CalibrationOptions& options,
             SlaveCalibration* out) {
  SlaveCalibration& r = *out;
  r.estimate.q = g.q;
  if (!in.translational) r.estimate.C = g.C;
  r.estimate.scale = g.scales[0];
  for (size_t s = 0; s < r.scales.size() && s < g.scales.size(); ++s) {
    r.scales[s].scale = g.scales[s];
    r.scales[s].std = g.scale_std[s];
  }
  if (std::isfinite(r.rot_std_deg)) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(g.cov_rotation);
    r.rot_std_deg = std::sqrt(std::max(0.0, eig.eigenvalues()(2))) * kDegPerRad;
  }
  if (in.translational) return;
  Eigen::Matrix3d cov = g.cov_position;
  const auto nominal = options.nominal.find(r.name);
  const bool prior = nominal != options.nominal.end() && options.nominal_sigma > 0.0;
  const Eigen::Vector3d axis = r.observability.planar_axis;
  if (r.motion_model == MotionModel::kPlanar) {
    if (prior) {
      cov += options.nominal_sigma * options.nominal_sigma * axis * axis.transpose();
      r.pos_std = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
    } else {
      r.pos_std = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
    }
    return;
  }
  r.pos_std = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  if (axis.norm() > 0.5) {
    r.axis_offset_std =
        in.axis_prior_sigma > 0.0 ? g.axis_std : std::sqrt(std::max(0.0, axis.dot(cov * axis)));
  }
}

namespace {

// Motions per chain the rotation's chains of a mixture need (below).
constexpr int kMinMotionsPerChain = 8;

// One GLS refinement of `start` on the chains of its span: the refined result, or `start` with
// the reason in `why` when the GLS cannot run or its σ of rotation and of C are both larger.
struct GlsAttempt {
  SlaveCalibration result;
  bool refined = false;
  std::string why;
  Eigen::Matrix3d cov_rotation = Eigen::Matrix3d::Zero();  // rad², when refined
  std::string how;                                         // the message's text, when refined
};

GlsAttempt Refine(const RigRecording& recording, int slave, const SlaveCalibration& start,
                  const CalibrationOptions& options, const Eigen::Quaterniond& rotation_prior,
                  const Eigen::Matrix3d& rotation_prior_cov) {
  GlsAttempt out;
  out.result = start;
  if (start.scale_model == ScaleModel::kPartitions) {
    out.why = "time-partitioned scales";
    return out;
  }
  const int span = ChainSpan(recording, start, options);
  const std::vector<MotionData> motions = ChainMotions(recording, slave, span, start);
  GlsInput in = GlsStartOf(start, options);
  in.time_blocks = BlocksForDurations(motions, options.covariance_time_blocks);
  in.rotation_prior = rotation_prior;
  in.rotation_prior_cov = rotation_prior_cov;
  const GlsResult g = RefineGls(motions, in);
  if (!g.ok) {
    out.why = g.message;
    return out;
  }
  SlaveCalibration refined = start;
  TakeGls(g, in, options, &refined);
  // The data's own yardstick: when the GLS σ of rotation and of C are both larger than the
  // start's (cluster-robust, both honest), the chains carry less than its pairs (hand-held PnP
  // poses whose errors depend on the view: the walk's large rotations), and the start is kept.
  const bool rot_larger =
      std::isfinite(start.rot_std_deg) && refined.rot_std_deg > start.rot_std_deg;
  const bool pos_larger = in.translational || (start.pos_std.allFinite() &&
                                               refined.pos_std.norm() > start.pos_std.norm());
  if (options.pairs.gls_keep_more_certain && rot_larger && pos_larger) {
    out.why = "its sigma " + FixedText(refined.rot_std_deg, 4) + " deg, |C| " +
              SignificantText(refined.pos_std.norm(), 2) + " are larger than " + start.pairs + "'s";
    return out;
  }
  out.result = std::move(refined);
  out.refined = true;
  out.cov_rotation = g.cov_rotation;
  out.how = "generalised least squares on " + std::to_string(g.increments) + " motions of span " +
            std::to_string(span) + " in " + std::to_string(g.runs) + " chains (" +
            std::to_string(g.outliers) +
            " dropped by their whitened residual), whitened by the pose noise fitted per "
            "component, chi2 " +
            FixedText(g.chi2, 2) + ", from " + start.pairs;
  if (g.clustered_larger) out.how += ", sigma raised to the cluster-robust one";
  if (!in.translational) {
    out.how += g.regressor_noise_corrected
                   ? ", C corrected for the rotation noise in its regressor"
                   : ", C not corrected for rotation noise (the motions turn too little)";
  }
  return out;
}

// The rotation from the chains of the span that determines it best, C and the scales from the
// chains of the span that determines C best with that rotation (and its covariance) carried
// over as a prior: spans differ in what they determine (short ones the rotation under drift,
// long ones C under white noise). Empty state when the mixture cannot be formed.
std::optional<SlaveCalibration> Mixture(const RigRecording& recording, int slave,
                                        const AutoPairRanking& ranking,
                                        const CalibrationOptions& options) {
  if (!ranking.differ || !ranking.rotation.solved() || !ranking.position.solved()) return {};
  // The rotation's σ carries over into C's: its chains must be long enough for the noise fit to
  // tell a pose's own error from drift (neighbouring motions of a chain correlate), which a
  // walk's long spans on a short recording (chains of a few motions) are not; its σ come out
  // too small.
  const int rotation_span = ChainSpan(recording, ranking.rotation, options);
  if (static_cast<int>(recording.size()) < kMinMotionsPerChain * rotation_span) return {};
  const GlsAttempt rot = Refine(recording, slave, ranking.rotation, options,
                                Eigen::Quaterniond::Identity(), Eigen::Matrix3d::Zero());
  Eigen::Matrix3d cov = rot.cov_rotation;
  if (!rot.refined) {
    const double sd = rot.result.rot_std_deg / kDegPerRad;
    if (!(sd > 0.0) || !std::isfinite(sd)) return {};
    cov = sd * sd * Eigen::Matrix3d::Identity();
  }
  const GlsAttempt pos =
      Refine(recording, slave, ranking.position, options, rot.result.estimate.q, cov);
  if (!pos.refined) return {};
  SlaveCalibration r = pos.result;
  r.estimate.q = rot.result.estimate.q;
  r.rot_std_deg = rot.result.rot_std_deg;
  r.pairs = "gls";
  r.message +=
      "; pairs gls: rotation from " +
      (rot.refined ? rot.how : ranking.rotation.pairs + " (gls not applied: " + rot.why + ")") +
      "; C and scale by " + pos.how + " with that rotation carried over";
  return r;
}

}  // namespace

SlaveCalibration CalibrateSlaveGls(const RigRecording& recording,
                                   const AutoPairCandidates& candidates, int slave,
                                   const CalibrationOptions& options) {
  AutoPairRanking ranking;
  SlaveCalibration r = CalibrateSlaveAutoPairs(recording, candidates, slave, options, &ranking);
  if (!r.solved() || options.cancelled()) return r;
  // A model the data contradict on some span (auto's check of every candidate) makes any
  // estimate of it not usable: auto's result says so, and is refined alone.
  std::optional<SlaveCalibration> mixed;
  if (options.pairs.gls_mixture && r.contradiction.empty()) {
    mixed = Mixture(recording, slave, ranking, options);
  }
  if (mixed) return *mixed;
  GlsAttempt g =
      Refine(recording, slave, r, options, Eigen::Quaterniond::Identity(), Eigen::Matrix3d::Zero());
  if (!g.refined) {
    r.message += "; gls not applied (" + g.why + "): the auto result";
    ModuleLogger("calib")->debug("slave '{}': gls not applied: {}", r.name, g.why);
    return r;
  }
  r = std::move(g.result);
  r.pairs = "gls";
  r.message += "; pairs gls: " + g.how;
  return r;
}

}  // namespace rigcal::internal
