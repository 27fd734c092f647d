// The gls pair policy (batch_gls.h).
#include "batch_gls.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "batch_motions.h"
#include "gls_refinement.h"
#include "rigcal/calib/format.h"
#include "rigcal/calib/logging.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/calib/quaternion.h"
#include "rigcal/calib/robust_statistics.h"
#include "time_blocks.h"

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

// The motions (k, k + span) of the slave as `span` chains of consecutive motions (k ≡ j mod
// span, in time order), with the scale variables of `r` (its scale keys: the segment ids, or
// one scale); motions of a segment without a scale are left out.
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

GlsInput StartOf(const SlaveCalibration& r, const CalibrationOptions& options) {
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
  return in;
}

// The GLS estimate and its σ in `r` (as the refinement's in batch_result.cc).
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

}  // namespace

SlaveCalibration CalibrateSlaveGls(const RigRecording& recording,
                                   const AutoPairCandidates& candidates, int slave,
                                   const CalibrationOptions& options) {
  SlaveCalibration r = CalibrateSlaveAutoPairs(recording, candidates, slave, options);
  if (!r.solved()) return r;
  const std::string start = r.pairs;
  auto keep = [&](const std::string& why) {
    r.message += "; gls not applied (" + why + "): the auto result";
    ModuleLogger("calib")->debug("slave '{}': gls not applied: {}", r.name, why);
    return r;
  };
  if (r.scale_model == ScaleModel::kPartitions) return keep("time-partitioned scales");
  const int span = ChainSpan(recording, r, options);
  const std::vector<MotionData> motions = ChainMotions(recording, slave, span, r);
  GlsInput in = StartOf(r, options);
  in.time_blocks = BlocksForDurations(motions, options.covariance_time_blocks);
  const GlsResult g = RefineGls(motions, in);
  if (!g.ok) return keep(g.message);
  SlaveCalibration refined = r;
  TakeGls(g, in, options, &refined);
  // The data's own yardstick: when the GLS σ of rotation and of C are both larger than auto's
  // (cluster-robust, both honest), the chains carry less than auto's pairs (hand-held PnP
  // poses whose errors depend on the view: the walk's large rotations), and auto's is kept.
  const bool rot_larger = std::isfinite(r.rot_std_deg) && refined.rot_std_deg > r.rot_std_deg;
  const bool pos_larger =
      in.translational || (r.pos_std.allFinite() && refined.pos_std.norm() > r.pos_std.norm());
  if (options.pairs.gls_keep_more_certain && rot_larger && pos_larger) {
    return keep("its sigma " + FixedText(refined.rot_std_deg, 4) + " deg, |C| " +
                SignificantText(refined.pos_std.norm(), 2) + " are larger than auto's");
  }
  r = std::move(refined);
  r.pairs = "gls";
  r.message += "; pairs gls: generalised least squares on " + std::to_string(g.increments) +
               " motions of span " + std::to_string(span) + " in " + std::to_string(g.runs) +
               " chains (" + std::to_string(g.outliers) +
               " dropped by their whitened residual), whitened by the pose noise fitted per "
               "component, chi2 " +
               FixedText(g.chi2, 2) + ", from auto's " + start;
  if (g.clustered_larger) r.message += "; gls sigma raised to the cluster-robust one";
  return r;
}

}  // namespace rigcal::internal
