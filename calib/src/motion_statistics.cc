#include "motion_statistics.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>

#include "linear_solvers.h"
#include "rigcal/calib/quaternion.h"

namespace rigcal::internal {
namespace {

// vec(dR) column-major, so that dR C = (C^T ⊗ I3) vec(dR).
Eigen::Matrix<double, 9, 1> Vec(const Eigen::Matrix3d& r) {
  return Eigen::Map<const Eigen::Matrix<double, 9, 1>>(r.data());
}

Eigen::Matrix<double, 3, 9> KronTransposeIdentity(const Eigen::Vector3d& c) {
  Eigen::Matrix<double, 3, 9> k = Eigen::Matrix<double, 3, 9>::Zero();
  for (int j = 0; j < 3; ++j) k.block<3, 3>(0, 3 * j) = c(j) * Eigen::Matrix3d::Identity();
  return k;
}

template <typename Derived>
void Write(std::ostream& out, const char* label, const Eigen::MatrixBase<Derived>& m) {
  out << label;
  for (Eigen::Index i = 0; i < m.size(); ++i) out << ' ' << m.derived().data()[i];
  out << '\n';
}

template <typename Derived>
bool Read(std::istream& in, const char* label, Eigen::MatrixBase<Derived>& m) {
  std::string word;
  if (!(in >> word) || word != label) return false;
  for (Eigen::Index i = 0; i < m.size(); ++i) {
    if (!(in >> m.derived().data()[i]) || !std::isfinite(m.derived().data()[i])) return false;
  }
  return true;
}

bool ReadScalar(std::istream& in, const char* label, double* v) {
  std::string word;
  return (in >> word) && word == label && (in >> *v) && std::isfinite(*v);
}

}  // namespace

void MotionStatistics::Add(const MotionData& m, int segment, double w) {
  const Eigen::Matrix4d a = RotationConstraintMatrix(m);
  M_.noalias() += w * a.transpose() * a;  // (4.10)
  const double v0 = m.q0.tail<3>().norm();
  if (v0 > 1e-12) {
    const Eigen::Vector3d r0 = m.q0.tail<3>() / v0;
    axis_scatter_.noalias() += w * r0 * r0.transpose();
  }
  const Eigen::Matrix3d i_r0 = Eigen::Matrix3d::Identity() - m.R0;
  H_cc_.noalias() += w * i_r0.transpose() * i_r0;
  g_c_.noalias() += w * i_r0.transpose() * m.C0;
  c0_sq_ += w * m.C0.squaredNorm();
  SegmentStatistics& s = segments_[segment];
  s.P.noalias() += w * i_r0.transpose() * KronTransposeIdentity(m.Ci);
  s.n += w * m.Ci.squaredNorm();
  s.Q.noalias() += w * m.C0 * m.Ci.transpose();
  const double ni = m.Ci.norm(), n0 = m.C0.norm();
  s.len_cross += w * ni * n0;
  s.len_sq += w * ni * ni;
  s.weight += w;
  if (ni > 0.0 && n0 > 0.0) S_dir_.noalias() += w * (m.Ci / ni) * (m.C0 / n0).transpose();
  weight_ += w;
  max_rotation_ = std::max(max_rotation_, m.angle0);
  ++motions_;
}

void MotionStatistics::Decay(double f) {
  M_ *= f;
  axis_scatter_ *= f;
  H_cc_ *= f;
  g_c_ *= f;
  c0_sq_ *= f;
  S_dir_ *= f;
  H_marg_ *= f;
  g_marg_ *= f;
  c0_sq_marg_ *= f;
  weight_ *= f;
  for (auto& [id, s] : segments_) {
    s.P *= f;
    s.n *= f;
    s.Q *= f;
    s.len_cross *= f;
    s.len_sq *= f;
    s.weight *= f;
  }
}

Eigen::Quaterniond MotionStatistics::SolveRotation(Eigen::Vector4d* eigenvalues) const {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(M_);
  if (eigenvalues) *eigenvalues = eig.eigenvalues();
  return Canonical(FromWxyz(eig.eigenvectors().col(0)).normalized());  // (4.11)
}

Eigen::Quaterniond MotionStatistics::SolveTranslationalRotation() const {
  return SolveAbsoluteOrientation(S_dir_);  // (4.30)
}

PositionSolution MotionStatistics::SolvePosition(const Eigen::Quaterniond& dq) const {
  PositionSolution out;
  const int n_open = static_cast<int>(segments_.size());
  const int dim = 3 + n_open;
  const Eigen::Matrix<double, 9, 1> r = Vec(dq.toRotationMatrix());
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(dim, dim);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(dim);
  h.topLeftCorner<3, 3>() = H_cc_ + H_marg_;
  b.head<3>() = g_c_ + g_marg_;
  int j = 3;
  std::vector<int> ids;
  for (const auto& [id, s] : segments_) {
    const Eigen::Vector3d cross = s.P * r;  // sum w (I-R0)^T dR C_i
    h.block<3, 1>(0, j) = cross;
    h.block<1, 3>(j, 0) = cross.transpose();
    h(j, j) = s.n;
    b(j) = (dq.toRotationMatrix().array() * s.Q.array()).sum();  // sum w C_0^T dR C_i
    ids.push_back(id);
    ++j;
  }
  if (weight_ <= 0.0) return out;
  const Eigen::VectorXd d = h.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd hn = d.asDiagonal() * h * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(hn);
  out.min_eigenvalue = eig.eigenvalues()(0);
  if (!(out.min_eigenvalue > 1e-12)) return out;
  const Eigen::VectorXd x = d.asDiagonal() * hn.ldlt().solve(d.asDiagonal() * b);
  if (!x.allFinite()) return out;
  out.C = x.head<3>();
  for (int k = 0; k < n_open; ++k) out.scales[ids[k]] = x(3 + k);
  // Information of C with the open scales marginalised (Schur complement).
  Eigen::Matrix3d info = h.topLeftCorner<3, 3>();
  for (int k = 0; k < n_open; ++k) {
    const Eigen::Vector3d cross = h.block<3, 1>(0, 3 + k);
    if (h(3 + k, 3 + k) > 0.0) info -= cross * cross.transpose() / h(3 + k, 3 + k);
  }
  out.information = info;
  out.residual_ss = std::max(0.0, c0_sq_ + c0_sq_marg_ - 2.0 * x.dot(b) + x.dot(h * x));
  out.ok = true;
  return out;
}

std::map<int, double> MotionStatistics::SolveTranslationalScales() const {
  std::map<int, double> scales;
  for (const auto& [id, s] : segments_) {
    if (s.len_sq > 0.0) scales[id] = s.len_cross / s.len_sq;  // (4.32)
  }
  return scales;
}

void MotionStatistics::MarginaliseSegment(int segment, const Eigen::Quaterniond& dq) {
  auto it = segments_.find(segment);
  if (it == segments_.end()) return;
  const SegmentStatistics& s = it->second;
  if (s.n > 0.0) {
    const Eigen::Matrix3d dr = dq.toRotationMatrix();
    const Eigen::Vector3d h = s.P * Vec(dr);
    const double rhs = (dr.array() * s.Q.array()).sum();
    H_marg_ -= h * h.transpose() / s.n;
    g_marg_ -= h * rhs / s.n;
    c0_sq_marg_ -= rhs * rhs / s.n;
  }
  closed_scales_[segment] = s.last_scale;
  segments_.erase(it);
}

void MotionStatistics::ResetPosition() {
  H_cc_.setZero();
  g_c_.setZero();
  c0_sq_ = 0.0;
  H_marg_.setZero();
  g_marg_.setZero();
  c0_sq_marg_ = 0.0;
  S_dir_.setZero();
  segments_.clear();
}

void MotionStatistics::SetSegmentScale(int segment, double scale) {
  auto it = segments_.find(segment);
  if (it != segments_.end()) it->second.last_scale = scale;
}

std::string MotionStatistics::Serialize() const {
  std::ostringstream out;
  out.precision(17);
  Write(out, "M", M_);
  Write(out, "axis", axis_scatter_);
  Write(out, "Hcc", H_cc_);
  Write(out, "gc", g_c_);
  out << "c0sq " << c0_sq_ << '\n';
  Write(out, "Sdir", S_dir_);
  Write(out, "Hmarg", H_marg_);
  Write(out, "gmarg", g_marg_);
  out << "c0sqmarg " << c0_sq_marg_ << '\n';
  out << "weight " << weight_ << "\nmaxrot " << max_rotation_ << "\nmotions " << motions_ << '\n';
  out << "segments " << segments_.size() << '\n';
  for (const auto& [id, s] : segments_) {
    out << "segment " << id << '\n';
    Write(out, "P", s.P);
    Write(out, "Q", s.Q);
    out << "n " << s.n << "\nlc " << s.len_cross << "\nls " << s.len_sq << "\nw " << s.weight
        << "\nscale " << s.last_scale << '\n';
  }
  out << "closed " << closed_scales_.size() << '\n';
  for (const auto& [id, v] : closed_scales_) out << id << ' ' << v << '\n';
  return out.str();
}

bool MotionStatistics::Parse(const std::string& text) {
  std::istringstream in(text);
  MotionStatistics s;
  double motions = 0.0, count = 0.0;
  if (!Read(in, "M", s.M_) || !Read(in, "axis", s.axis_scatter_) || !Read(in, "Hcc", s.H_cc_) ||
      !Read(in, "gc", s.g_c_) || !ReadScalar(in, "c0sq", &s.c0_sq_) ||
      !Read(in, "Sdir", s.S_dir_) || !Read(in, "Hmarg", s.H_marg_) ||
      !Read(in, "gmarg", s.g_marg_) || !ReadScalar(in, "c0sqmarg", &s.c0_sq_marg_) ||
      !ReadScalar(in, "weight", &s.weight_) || !ReadScalar(in, "maxrot", &s.max_rotation_) ||
      !ReadScalar(in, "motions", &motions) || !ReadScalar(in, "segments", &count)) {
    return false;
  }
  s.motions_ = static_cast<int>(motions);
  if (count < 0 || count > 1e6) return false;
  for (int k = 0; k < static_cast<int>(count); ++k) {
    double id = 0.0;
    SegmentStatistics seg;
    if (!ReadScalar(in, "segment", &id) || !Read(in, "P", seg.P) || !Read(in, "Q", seg.Q) ||
        !ReadScalar(in, "n", &seg.n) || !ReadScalar(in, "lc", &seg.len_cross) ||
        !ReadScalar(in, "ls", &seg.len_sq) || !ReadScalar(in, "w", &seg.weight) ||
        !ReadScalar(in, "scale", &seg.last_scale)) {
      return false;
    }
    s.segments_[static_cast<int>(id)] = seg;
  }
  if (!ReadScalar(in, "closed", &count) || count < 0 || count > 1e6) return false;
  for (int k = 0; k < static_cast<int>(count); ++k) {
    int id = 0;
    double v = 0.0;
    if (!(in >> id >> v) || !std::isfinite(v)) return false;
    s.closed_scales_[id] = v;
  }
  *this = s;
  return true;
}

}  // namespace rigcal::internal
