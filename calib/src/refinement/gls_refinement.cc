// SPDX-License-Identifier: Apache-2.0
// Generalised least squares on the consecutive motions (gls_refinement.h).
#include "refinement/gls_refinement.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "models/planar_solver.h"
#include "noise/loewner.h"
#include "noise/regressor_noise.h"
#include "noise/time_blocks.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal::internal {
namespace {

Eigen::Matrix3d Exp(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  return angle > 0.0 ? Eigen::AngleAxisd(angle, v / angle).toRotationMatrix()
                     : Eigen::Matrix3d::Identity();
}

Eigen::Vector3d Log(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

// The parameters about the current point: rotation δ (dR = Exp(δ) dR), the free coordinates of
// C in the frame `t` (columns b_1, b_2, axis, or the identity), the scales.
struct Layout {
  bool translational = false;
  bool axis = false;  // C in the frame of a unit axis: t = [b_1 b_2 axis]
  Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
  int c_free = 3;  // free coordinates of C: 3, or 2 with the axis offset fixed; 0 translational
  int scales = 0;
  int Size() const { return 3 + c_free + scales; }
  int ScaleColumn(int s) const { return 3 + c_free + s; }
};

struct GlsPoint {
  Eigen::Matrix3d dR = Eigen::Matrix3d::Identity();
  Eigen::Vector3d z = Eigen::Vector3d::Zero();  // C = t z
  std::vector<double> scales;
};

GlsPoint Moved(const GlsPoint& p, const Layout& layout, const Eigen::VectorXd& step) {
  GlsPoint out = p;
  out.dR = Eigen::Quaterniond(Exp(step.head<3>()) * p.dR).normalized().toRotationMatrix();
  for (int i = 0; i < layout.c_free; ++i) out.z(i) += step(3 + i);
  for (int s = 0; s < layout.scales; ++s) out.scales[s] += step(layout.ScaleColumn(s));
  return out;
}

// Per motion, the master rotation from its run's start to its first pose (the frame its
// residuals are expressed in, so that the errors of poses add across motions), and the first
// motion of every run.
struct Frames {
  std::vector<Eigen::Matrix3d> world_from_a;
  std::vector<int> run_start;  // ascending, with motions.size() at the end
};

Frames RunFrames(const std::vector<MotionData>& motions) {
  Frames f;
  f.world_from_a.resize(motions.size());
  for (size_t k = 0; k < motions.size(); ++k) {
    const MotionData& m = motions[k];
    const bool restart = k == 0 || m.t_a_ns != motions[k - 1].t_b_ns ||
                         m.segment != motions[k - 1].segment ||
                         m.scale_index != motions[k - 1].scale_index;
    if (restart) {
      f.run_start.push_back(static_cast<int>(k));
      f.world_from_a[k].setIdentity();
    } else {
      f.world_from_a[k] = f.world_from_a[k - 1] * motions[k - 1].R0;
    }
  }
  f.run_start.push_back(static_cast<int>(motions.size()));
  return f;
}

// The residual increments (rows: motions; columns: rotation then position, or position only)
// in the run frames: rotation log(R0 dR Ri^T dR^T), position (I - R0) C + λ dR Ci - C0.
Eigen::MatrixXd Increments(const std::vector<MotionData>& motions, const Frames& frames,
                           const Layout& layout, const GlsPoint& p) {
  const int dims = layout.translational ? 3 : 6;
  Eigen::MatrixXd out(motions.size(), dims);
  const Eigen::Vector3d c = layout.t * p.z;
  for (size_t k = 0; k < motions.size(); ++k) {
    const MotionData& m = motions[k];
    const Eigen::Matrix3d& w = frames.world_from_a[k];
    const double s = p.scales[m.scale_index];
    Eigen::Vector3d position = s * (p.dR * m.Ci) - m.C0;
    if (!layout.translational) {
      const Eigen::Matrix3d ri = FromWxyz(m.qi).toRotationMatrix();
      out.row(k).head<3>() = (w * Log(m.R0 * p.dR * ri.transpose() * p.dR.transpose())).transpose();
      position += (Eigen::Matrix3d::Identity() - m.R0) * c;
    }
    out.row(k).tail<3>() = (w * position).transpose();
  }
  return out;
}

// The whitened system at a point: rows A, b (b the whitened residuals) and the motion of every
// row; the increments' residual columns for the noise fit.
struct System {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  std::vector<int> motion;
  Eigen::MatrixXd residuals;
};

System Whitened(const std::vector<MotionData>& motions, const Frames& frames, const Layout& layout,
                const GlsPoint& p, const std::vector<LevelNoise>& noise) {
  System sys;
  sys.residuals = Increments(motions, frames, layout, p);
  const int dims = static_cast<int>(sys.residuals.cols());
  const int n = static_cast<int>(motions.size());
  const int params = layout.Size();
  // Central differences: the increments are linear in C and the scales, smooth in δ.
  std::vector<Eigen::MatrixXd> jacobian(params);
  for (int j = 0; j < params; ++j) {
    double h = 1e-6;
    if (j >= 3 && j < 3 + layout.c_free) h = 1e-6 * (1.0 + p.z.norm());
    if (j >= 3 + layout.c_free) h = 1e-6 * std::max(1.0, std::abs(p.scales[j - 3 - layout.c_free]));
    Eigen::VectorXd step = Eigen::VectorXd::Zero(params);
    step(j) = h;
    jacobian[j] = (Increments(motions, frames, layout, Moved(p, layout, step)) -
                   Increments(motions, frames, layout, Moved(p, layout, -step))) /
                  (2.0 * h);
  }
  sys.a.resize(static_cast<Eigen::Index>(n) * dims, params);
  sys.b.resize(static_cast<Eigen::Index>(n) * dims);
  sys.motion.resize(static_cast<size_t>(n) * dims);
  int row = 0;
  for (int c = 0; c < dims; ++c) {
    for (size_t r = 0; r + 1 < frames.run_start.size(); ++r) {
      const int first = frames.run_start[r], count = frames.run_start[r + 1] - first;
      Eigen::MatrixXd block(count, 1 + params);
      block.col(0) = sys.residuals.col(c).segment(first, count);
      for (int j = 0; j < params; ++j) block.col(1 + j) = jacobian[j].col(c).segment(first, count);
      const Eigen::MatrixXd white = WhitenIncrements(block, noise[c]);
      sys.b.segment(row, count) = white.col(0);
      sys.a.block(row, 0, count, params) = white.rightCols(params);
      for (int i = 0; i < count; ++i) sys.motion[row + i] = first + i;
      row += count;
    }
  }
  return sys;
}

// Per component; empty when `cancel` is set before the last one is fitted.
std::vector<LevelNoise> FitNoise(const Eigen::MatrixXd& residuals, const Frames& frames,
                                 const std::atomic<bool>* cancel) {
  std::vector<LevelNoise> noise;
  for (Eigen::Index c = 0; c < residuals.cols(); ++c) {
    if (cancel != nullptr && cancel->load(std::memory_order_relaxed)) return {};
    std::vector<Eigen::VectorXd> runs;
    for (size_t r = 0; r + 1 < frames.run_start.size(); ++r) {
      const int first = frames.run_start[r], count = frames.run_start[r + 1] - first;
      runs.push_back(residuals.col(c).segment(first, count));
    }
    noise.push_back(FitLevelNoise(runs, cancel));
  }
  return noise;
}

// The prior row on the axis offset h, when it is free and weighted.
bool HasAxisPrior(const GlsInput& input, const Layout& layout) {
  return layout.c_free == 3 && input.axis.norm() > 0.5 && input.axis_prior_sigma > 0.0 &&
         std::isfinite(input.axis_prior_sigma);
}

void AddAxisPrior(const GlsInput& input, const Layout& layout, const GlsPoint& p, System* sys) {
  if (!HasAxisPrior(input, layout)) return;
  const Eigen::Index rows = sys->a.rows();
  sys->a.conservativeResize(rows + 1, Eigen::NoChange);
  sys->b.conservativeResize(rows + 1);
  sys->a.row(rows).setZero();
  sys->a(rows, 5) = 1.0 / input.axis_prior_sigma;
  sys->b(rows) = (p.z(2) - input.axis_prior) / input.axis_prior_sigma;
  sys->motion.push_back(-1);
}

// The prior rows on the rotation, when it has one: L⁻¹ log(dR dR_prior^T), cov = L Lᵀ.
void AddRotationPrior(const GlsInput& input, const GlsPoint& p, System* sys) {
  if (input.translational || !(input.rotation_prior_cov.trace() > 0.0)) return;
  const Eigen::LLT<Eigen::Matrix3d> llt(input.rotation_prior_cov);
  if (llt.info() != Eigen::Success) return;
  const Eigen::Matrix3d white = llt.matrixL().solve(Eigen::Matrix3d::Identity());
  const Eigen::Vector3d r =
      Log(p.dR * input.rotation_prior.normalized().toRotationMatrix().transpose());
  const Eigen::Index rows = sys->a.rows();
  sys->a.conservativeResize(rows + 3, Eigen::NoChange);
  sys->b.conservativeResize(rows + 3);
  sys->a.bottomRows(3).setZero();
  sys->a.bottomLeftCorner(3, 3) = white;
  sys->b.tail(3) = white * r;
  for (int i = 0; i < 3; ++i) sys->motion.push_back(-1);
}

// The errors-in-variables term of C (regressor_noise.h) per motion, in C's coordinates z (fixed
// ones included), with the fitted noise. The rotation residual's noise is the master's and the
// slave's; the master's share, which R0 carries, is taken as half (cameras of like odometry:
// which camera is noisier the residual cannot tell). Empty for the translational model.
std::vector<Eigen::Matrix3d> AttenuationTerms(const std::vector<MotionData>& motions,
                                              const Frames& frames, const Layout& layout,
                                              const std::vector<LevelNoise>& noise, int round) {
  if (layout.translational || layout.c_free == 0 || noise.size() < 6) return {};
  RegressorNoiseInput in;
  in.lever.resize(motions.size());
  for (size_t k = 0; k < motions.size(); ++k) {
    in.lever[k] = frames.world_from_a[k] * motions[k].R0 * layout.t;
  }
  in.run_start = frames.run_start;
  for (int j = 0; j < 3; ++j) {
    in.rotation[j] = noise[j];
    in.rotation[j].white *= 0.5;
    in.rotation[j].correlated *= 0.5;
    in.rotation[j].walk *= 0.5;
    in.position[j] = noise[3 + j];
  }
  in.seed = 0x5eed + static_cast<uint64_t>(round);
  return RegressorNoiseGram(in);
}

// The corrected normal equations (H - Ξ) step = -(Aᵀb - Ξ z): Ξ the sum of the terms over C's
// free coordinates. Not applied (`applies` false) when Ξ would take away half of C's
// information in some direction or more: the motions' rotations too small for the noise, where
// the first-order correction does not hold.
struct Attenuation {
  std::vector<Eigen::Matrix3d> terms;
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  bool applies = false;

  void Decide(const Layout& layout, const Eigen::MatrixXd& h) {
    applies = false;
    if (terms.empty()) return;
    sum.setZero();
    for (const Eigen::Matrix3d& term : terms) sum += term;
    const int n = layout.c_free;
    const Eigen::LLT<Eigen::MatrixXd> llt(h.block(3, 3, n, n));
    if (llt.info() != Eigen::Success) return;
    const Eigen::MatrixXd l_inv = llt.matrixL().solve(Eigen::MatrixXd::Identity(n, n));
    const Eigen::MatrixXd relative = l_inv * sum.topLeftCorner(n, n) * l_inv.transpose();
    applies =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(relative).eigenvalues().maxCoeff() < 0.5;
  }
  // The normal matrix h less Ξ.
  Eigen::MatrixXd Normal(const Layout& layout, Eigen::MatrixXd h) const {
    if (applies) {
      h.block(3, 3, layout.c_free, layout.c_free) -=
          sum.topLeftCorner(layout.c_free, layout.c_free);
    }
    return h;
  }
  // The gradient g less Ξ z.
  Eigen::VectorXd Gradient(const Layout& layout, const GlsPoint& p, Eigen::VectorXd g) const {
    if (applies) g.segment(3, layout.c_free) -= (sum * p.z).head(layout.c_free);
    return g;
  }
  // Per motion, its share of Ξ z over every parameter (the cluster-robust scores' offsets).
  std::vector<Eigen::VectorXd> ScoreOffsets(const Layout& layout, const GlsPoint& p) const {
    std::vector<Eigen::VectorXd> out;
    if (!applies) return out;
    out.assign(terms.size(), Eigen::VectorXd::Zero(layout.Size()));
    for (size_t k = 0; k < terms.size(); ++k) {
      out[k].segment(3, layout.c_free) = (terms[k] * p.z).head(layout.c_free);
    }
    return out;
  }
};

// H⁻¹ of the normal matrix, or empty when it is singular.
Eigen::MatrixXd Inverse(const Eigen::MatrixXd& h) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(h);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  if (!(lambda(0) > 1e-12 * lambda(lambda.size() - 1))) return {};
  return eig.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
}

// The cluster-robust (sandwich) covariance of the whitened system: motions in `blocks` time
// blocks, the prior row a cluster of its own; times B / (B - 1). A motion's score is taken less
// its `score_offset` (empty: none), the expectation the corrected normal equations remove.
Eigen::MatrixXd Clustered(const System& sys, const Eigen::MatrixXd& h_inv,
                          const std::vector<int>& block_of_motion, int blocks,
                          const std::vector<Eigen::VectorXd>& score_offset) {
  const Eigen::Index params = sys.a.cols();
  std::vector<Eigen::VectorXd> g(blocks + 1, Eigen::VectorXd::Zero(params));
  for (Eigen::Index row = 0; row < sys.a.rows(); ++row) {
    const int motion = sys.motion[row];
    const int cluster = motion < 0 ? blocks : block_of_motion[motion];
    g[cluster] += sys.a.row(row).transpose() * sys.b(row);
  }
  for (size_t k = 0; k < score_offset.size(); ++k) g[block_of_motion[k]] -= score_offset[k];
  Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(params, params);
  for (int c = 0; c <= blocks; ++c) {
    meat += (c < blocks ? blocks / (blocks - 1.0) : 1.0) * g[c] * g[c].transpose();
  }
  return h_inv * meat * h_inv;
}

// The parameters of `input`: C in the axis frame when the input has a unit axis (its offset
// fixed or free), none for the translational model.
Layout LayoutOf(const GlsInput& input) {
  Layout layout;
  layout.translational = input.translational;
  layout.scales = static_cast<int>(input.scales.size());
  if (input.translational) {
    layout.c_free = 0;
  } else if (input.axis.norm() > 0.5) {
    layout.axis = true;
    const Eigen::Vector3d axis = input.axis.normalized();
    layout.t.leftCols<2>() = PlaneBasis(axis);
    layout.t.col(2) = axis;
    layout.c_free = input.axis_offset_fixed ? 2 : 3;
  }
  return layout;
}

// Why the motions cannot be refined (a motion without a scale variable, fewer equations than
// twice the parameters), or empty.
std::string UnusableReason(const std::vector<MotionData>& motions, const Layout& layout) {
  for (const MotionData& m : motions) {
    if (m.scale_index < 0 || m.scale_index >= layout.scales) {
      return "a motion without a scale variable";
    }
  }
  const int dims = layout.translational ? 3 : 6;
  if (static_cast<int>(motions.size()) * dims < 2 * layout.Size()) {
    return "too few consecutive motions";
  }
  return "";
}

// Drops from `kept` the motions whose whitened residual (in any row of `sys`) lies beyond
// `factor` robust σ (1.4826 MAD of every row): a glitched pose, a PnP flip. Returns how many.
int DropOutliers(const System& sys, double factor, std::vector<MotionData>* kept) {
  std::vector<double> magnitude(kept->size(), 0.0);
  for (Eigen::Index row = 0; row < sys.b.size(); ++row) {
    if (sys.motion[row] >= 0) {
      magnitude[sys.motion[row]] = std::max(magnitude[sys.motion[row]], std::abs(sys.b(row)));
    }
  }
  std::vector<double> all(sys.b.data(), sys.b.data() + sys.b.size());
  for (double& v : all) v = std::abs(v);
  const double limit = factor * 1.4826 * Median(all);
  std::vector<MotionData> inliers;
  for (size_t k = 0; k < kept->size(); ++k) {
    if (magnitude[k] <= limit) inliers.push_back((*kept)[k]);
  }
  const int dropped = static_cast<int>(kept->size() - inliers.size());
  kept->swap(inliers);
  return dropped;
}

// The whitened system at `p` with the prior rows of `input`.
System WhitenedWithPriors(const std::vector<MotionData>& motions, const Frames& frames,
                          const Layout& layout, const GlsPoint& p,
                          const std::vector<LevelNoise>& noise, const GlsInput& input) {
  System sys = Whitened(motions, frames, layout, p, noise);
  AddAxisPrior(input, layout, p, &sys);
  AddRotationPrior(input, p, &sys);
  return sys;
}

// Whether input.cancel is set.
bool Cancelled(const GlsInput& input) {
  return input.cancel != nullptr && input.cancel->load(std::memory_order_relaxed);
}

// Gauss-Newton on the corrected normal equations at fixed noise, from `p`: at most 20 steps,
// until a step is below 1e-10 of the point's size; whether to correct for the regressor noise
// is decided at the first. The last system in `sys`. False when a step is not finite (singular
// normal equations) or it was cancelled.
bool GaussNewton(const std::vector<MotionData>& motions, const Frames& frames, const Layout& layout,
                 const std::vector<LevelNoise>& noise, const GlsInput& input,
                 Attenuation* attenuation, GlsPoint* p, System* sys) {
  const int params = layout.Size();
  for (int iteration = 0; iteration < 20; ++iteration) {
    if (Cancelled(input)) return false;
    *sys = WhitenedWithPriors(motions, frames, layout, *p, noise, input);
    const Eigen::MatrixXd h = sys->a.transpose() * sys->a;
    if (iteration == 0) attenuation->Decide(layout, h);
    const Eigen::VectorXd step = -attenuation->Normal(layout, h).ldlt().solve(
        attenuation->Gradient(layout, *p, sys->a.transpose() * sys->b));
    if (!step.allFinite()) return false;
    *p = Moved(*p, layout, step);
    const double size =
        step.head<3>().norm() +
        step.tail(params - 3).norm() /
            (1.0 + p->z.norm() +
             Eigen::Map<const Eigen::VectorXd>(p->scales.data(), layout.scales).norm());
    if (size < 1e-10) break;
  }
  return true;
}

// The covariance of C in the master frame from a covariance of the parameters.
Eigen::Matrix3d PositionCovariance(const Layout& layout, const Eigen::MatrixXd& c) {
  if (layout.c_free == 0) return Eigen::Matrix3d::Zero();
  const Eigen::MatrixXd t = layout.t.leftCols(layout.c_free);
  return t * c.block(3, 3, layout.c_free, layout.c_free) * t.transpose();
}

// Raises the covariances in `out` to the cluster-robust one of `blocks` time blocks of the
// motions where that is larger.
void RaiseToClustered(const System& sys, const Eigen::MatrixXd& h_inv,
                      const std::vector<MotionData>& motions, int blocks, const Layout& layout,
                      const Attenuation& attenuation, const GlsPoint& p, GlsResult* out) {
  const Eigen::MatrixXd robust = Clustered(sys, h_inv, TimeBlocks(motions, blocks), blocks,
                                           attenuation.ScoreOffsets(layout, p));
  if (!robust.allFinite()) return;
  bool larger = false;
  out->cov_rotation = LoewnerMax(out->cov_rotation, robust.topLeftCorner<3, 3>(), &larger);
  out->cov_position = LoewnerMax(out->cov_position, PositionCovariance(layout, robust), &larger);
  for (int s = 0; s < layout.scales; ++s) {
    const int col = layout.ScaleColumn(s);
    const double sd = std::sqrt(std::max(0.0, robust(col, col)));
    if (sd > out->scale_std[s]) {
      out->scale_std[s] = sd;
      larger = true;
    }
  }
  if (layout.axis && layout.c_free == 3) {
    out->axis_std = std::max(out->axis_std, std::sqrt(std::max(0.0, robust(5, 5))));
  }
  out->clustered_larger = larger;
}

// The estimate at `p` with its covariance (the sandwich of the corrected normal equations,
// scaled by the mean square of the whitened residuals; raised to the cluster-robust one of
// input.time_blocks) in `out`. False (the message in `out`) when the normal matrix is singular.
bool TakeEstimate(const std::vector<MotionData>& motions, const Frames& frames,
                  const Layout& layout, const std::vector<LevelNoise>& noise, const GlsInput& input,
                  const Attenuation& attenuation, const GlsPoint& p, GlsResult* out) {
  const int params = layout.Size();
  const System sys = WhitenedWithPriors(motions, frames, layout, p, noise, input);
  const Eigen::MatrixXd h = sys.a.transpose() * sys.a;
  const Eigen::MatrixXd h_inv = Inverse(attenuation.Normal(layout, h));
  if (h_inv.size() == 0) {
    out->message = "the consecutive motions do not determine the parameters";
    return false;
  }
  const Eigen::Index rows = sys.a.rows();
  out->chi2 = rows > params ? sys.b.squaredNorm() / static_cast<double>(rows - params) : 1.0;
  Eigen::MatrixXd cov = out->chi2 * h_inv * h * h_inv;

  out->q = Canonical(Eigen::Quaterniond(p.dR).normalized());
  out->C = layout.t * p.z;
  out->scales = p.scales;
  out->noise = noise;
  out->increments = static_cast<int>(motions.size());
  out->regressor_noise_corrected = attenuation.applies;
  out->runs = static_cast<int>(frames.run_start.size()) - 1;
  out->cov_rotation = cov.topLeftCorner<3, 3>();
  out->cov_position = PositionCovariance(layout, cov);
  for (int s = 0; s < layout.scales; ++s) {
    const int col = layout.ScaleColumn(s);
    out->scale_std.push_back(std::sqrt(std::max(0.0, cov(col, col))));
  }
  if (layout.axis && layout.c_free == 3) out->axis_std = std::sqrt(std::max(0.0, cov(5, 5)));
  if (input.time_blocks >= 2) {
    RaiseToClustered(sys, h_inv, motions, input.time_blocks, layout, attenuation, p, out);
  }
  return true;
}

}  // namespace

GlsResult RefineGls(const std::vector<MotionData>& motions, const GlsInput& input) {
  GlsResult out;
  const Layout layout = LayoutOf(input);
  out.message = UnusableReason(motions, layout);
  if (!out.message.empty()) return out;
  GlsPoint p;
  p.dR = input.q.normalized().toRotationMatrix();
  p.z = layout.t.transpose() * (input.translational ? Eigen::Vector3d::Zero() : input.C);
  p.scales = input.scales;

  // Rounds of: the noise fitted to the residuals at the point, then Gauss-Newton with it; from
  // the second round on without the motions whose whitened residual is an outlier (their
  // chains restart after them).
  std::vector<LevelNoise> noise;
  System sys;
  Attenuation attenuation;
  std::vector<MotionData> kept = motions;
  Frames frames = RunFrames(kept);
  for (int round = 0; round < std::max(1, input.noise_rounds); ++round) {
    if (round > 0 && input.outlier_factor > 0.0) {
      out.outliers += DropOutliers(sys, input.outlier_factor, &kept);
      frames = RunFrames(kept);
    }
    noise = FitNoise(Increments(kept, frames, layout, p), frames, input.cancel);
    if (Cancelled(input)) break;
    attenuation.terms = AttenuationTerms(kept, frames, layout, noise, round);
    if (!GaussNewton(kept, frames, layout, noise, input, &attenuation, &p, &sys)) {
      out.message = Cancelled(input) ? "cancelled" : "singular GLS normal equations";
      return out;
    }
  }
  if (Cancelled(input)) {
    out.message = "cancelled";
    return out;
  }
  if (!TakeEstimate(kept, frames, layout, noise, input, attenuation, p, &out)) return out;
  out.ok = out.cov_rotation.allFinite() && out.cov_position.allFinite();
  if (!out.ok) out.message = "non-finite covariance";
  return out;
}

}  // namespace rigcal::internal
