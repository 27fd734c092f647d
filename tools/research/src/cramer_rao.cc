// SPDX-License-Identifier: Apache-2.0
#include "rigcal/research/cramer_rao.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "rigcal/base/quaternion.h"

namespace rigcal::research {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Eigen::MatrixXd Infinite(int n) { return Eigen::MatrixXd::Constant(n, n, kInf); }

// A (J^+) A^T, or infinite when a row of A has a component in the null space of J (the function
// A p is then not determined by the data).
Eigen::MatrixXd BoundOfLinearFunction(const Eigen::MatrixXd& fisher, const Eigen::MatrixXd& a) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (fisher + fisher.transpose()));
  const Eigen::VectorXd& ev = es.eigenvalues();
  const double largest = ev.size() > 0 ? ev.maxCoeff() : 0.0;
  if (!(largest > 0.0)) return Infinite(static_cast<int>(a.rows()));
  const double tol = 1e-12 * largest;
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(ev.size());
  for (int i = 0; i < ev.size(); ++i) {
    if (ev[i] > tol) {
      inv[i] = 1.0 / ev[i];
    } else if ((a * es.eigenvectors().col(i)).norm() > 1e-6 * std::max(1.0, a.norm())) {
      return Infinite(static_cast<int>(a.rows()));
    }
  }
  Eigen::MatrixXd av = a * es.eigenvectors();
  return av * inv.asDiagonal() * av.transpose();
}

Eigen::Quaterniond ExpMap(const Eigen::Vector3d& v) {
  double angle = v.norm();
  if (angle < 1e-12)
    return Eigen::Quaterniond(1.0, 0.5 * v.x(), 0.5 * v.y(), 0.5 * v.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, v / angle));
}

Eigen::Vector3d LogMap(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.w() < 0 ? Eigen::Quaterniond(-q_in.coeffs()) : q_in;
  double n = q.vec().norm();
  if (n < 1e-15) return 2.0 * q.vec();
  return q.vec() * (2.0 * std::atan2(n, q.w()) / n);
}

// One pose k of the thesis problem around its true values. Local parameters
// x = (delta, dC, lambda, phi, c): theta and the pose's nuisance (left rotation vector and
// position offset of the master pose). Observations: the master's left rotation vector and
// position, then the slave's (12).
class PoseModel {
 public:
  PoseModel(const Pose& master, const Similarity& rig)
      : master_(master), rig_(rig), slave_(Slave(master, rig)) {}

  const Pose& master() const { return master_; }
  const Pose& slave() const { return slave_; }

  // Predicted minus true observation; zero at TrueParams().
  Eigen::Matrix<double, 12, 1> Residual(const Eigen::Matrix<double, 13, 1>& x) const {
    Similarity rig;
    rig.q = (rig_.q * ExpMap(x.segment<3>(0))).normalized();
    rig.C = x.segment<3>(3);
    rig.scale = x[6];
    Pose m;
    m.q = (ExpMap(x.segment<3>(7)) * master_.q).normalized();
    m.C = master_.C + x.segment<3>(10);
    Pose s = Slave(m, rig);
    Eigen::Matrix<double, 12, 1> r;
    r.segment<3>(0) = LogMap(m.q * master_.q.conjugate());
    r.segment<3>(3) = m.C - master_.C;
    r.segment<3>(6) = LogMap(s.q * slave_.q.conjugate());
    r.segment<3>(9) = s.C - slave_.C;
    return r;
  }

  Eigen::Matrix<double, 13, 1> TrueParams() const {
    Eigen::Matrix<double, 13, 1> x = Eigen::Matrix<double, 13, 1>::Zero();
    x.segment<3>(3) = rig_.C;
    x[6] = rig_.scale;
    return x;
  }

  // Central differences; the residual is smooth and of unit order, so one step fits all.
  Eigen::Matrix<double, 12, 13> Jacobian() const {
    const double h = 1e-6;
    const Eigen::Matrix<double, 13, 1> x0 = TrueParams();
    Eigen::Matrix<double, 12, 13> jac;
    for (int j = 0; j < 13; ++j) {
      Eigen::Matrix<double, 13, 1> plus = x0;
      Eigen::Matrix<double, 13, 1> minus = x0;
      plus[j] += h;
      minus[j] -= h;
      jac.col(j) = (Residual(plus) - Residual(minus)) / (2 * h);
    }
    return jac;
  }

  // Observation information (block diagonal) of the thesis noise at level eps, and the rows of
  // the exact radial observations (u^T times the position rows of `jac`; 2 rows).
  void Noise(const Eigen::Matrix<double, 12, 13>& jac, double eps_rad,
             const ThesisNoiseModel& noise, Eigen::Matrix<double, 12, 12>* weight,
             Eigen::Matrix<double, 2, 13>* radial) const {
    weight->setZero();
    radial->setZero();
    const double eps2 = eps_rad * eps_rad;
    const Eigen::Vector3d centres[2] = {master_.C, slave_.C};
    for (int cam = 0; cam < 2; ++cam) {
      const int o = 6 * cam;
      weight->block<3, 3>(o, o) =
          Eigen::Matrix3d::Identity() / (noise.rotation_variance_factor * eps2);
      const double len = centres[cam].norm();
      if (len < 1e-12) continue;  // centre at the reference: no position noise modelled
      const Eigen::Vector3d u = centres[cam] / len;
      weight->block<3, 3>(o + 3, o + 3) = (Eigen::Matrix3d::Identity() - u * u.transpose()) /
                                          (noise.position_variance_factor * eps2 * len * len);
      radial->row(cam) = u.transpose() * jac.block<3, 13>(o + 3, 0);
    }
  }

 private:
  // Eq. (5.1) and (5.2): R_i = dR^T R_0 dR, C_i = dR^T ((R_0 - I) dC + C_0) / lambda.
  static Pose Slave(const Pose& m, const Similarity& rig) {
    Pose s;
    s.q = (rig.q.conjugate() * m.q * rig.q).normalized();
    Eigen::Matrix3d dr = rig.q.toRotationMatrix();
    s.C = dr.transpose() * ((m.R() - Eigen::Matrix3d::Identity()) * rig.C + m.C) / rig.scale;
    return s;
  }

  Pose master_;
  Similarity rig_;
  Pose slave_;
};

// Information on theta contributed by one pose after eliminating its nuisance parameters
// n = (phi, c) subject to the pose's exact radial observations G_t dtheta + G_n dn = 0 (if any):
// dn = -G_n^+ G_t dtheta + N z with N a basis of null(G_n), then the Schur complement over z.
Eigen::Matrix<double, 7, 7> PoseInformation(const Eigen::Matrix<double, 13, 13>& fisher,
                                            const Eigen::MatrixXd& radial) {
  Eigen::MatrixXd t;
  if (radial.rows() == 0) {
    t = Eigen::MatrixXd::Identity(13, 13);
  } else {
    const Eigen::MatrixXd g_t = radial.leftCols(7);
    const Eigen::MatrixXd g_n = radial.rightCols(6);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(g_n, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::VectorXd& sv = svd.singularValues();
    const double tol = 1e-10 * std::max(1.0, sv.size() > 0 ? sv[0] : 0.0);
    int rank = 0;
    Eigen::MatrixXd pinv = Eigen::MatrixXd::Zero(6, g_n.rows());
    for (int i = 0; i < sv.size(); ++i) {
      if (sv[i] <= tol) continue;
      pinv += svd.matrixV().col(i) * svd.matrixU().col(i).transpose() / sv[i];
      ++rank;
    }
    const int m = 6 - rank;
    t = Eigen::MatrixXd::Zero(13, 7 + m);
    t.topLeftCorner(7, 7).setIdentity();
    t.bottomLeftCorner(6, 7) = -pinv * g_t;
    t.bottomRightCorner(6, m) = svd.matrixV().rightCols(m);
  }
  const Eigen::MatrixXd reduced = t.transpose() * fisher * t;
  const int m = static_cast<int>(reduced.rows()) - 7;
  Eigen::Matrix<double, 7, 7> info = reduced.topLeftCorner(7, 7);
  if (m > 0) {
    info -= reduced.topRightCorner(7, m) * PseudoInverseSpd(reduced.bottomRightCorner(m, m)) *
            reduced.bottomLeftCorner(m, 7);
  }
  return 0.5 * (info + info.transpose());
}

}  // namespace

Eigen::MatrixXd PseudoInverseSpd(const Eigen::MatrixXd& m, double rel_tol) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (m + m.transpose()));
  const Eigen::VectorXd& ev = es.eigenvalues();
  const double largest = ev.size() > 0 ? ev.maxCoeff() : 0.0;
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(ev.size());
  if (largest > 0.0) {
    for (int i = 0; i < ev.size(); ++i) {
      if (ev[i] > rel_tol * largest) inv[i] = 1.0 / ev[i];
    }
  }
  return es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
}

Eigen::MatrixXd FisherInformation(const Eigen::MatrixXd& jacobian, const Eigen::MatrixXd& weight) {
  Eigen::MatrixXd j = jacobian.transpose() * weight * jacobian;
  return 0.5 * (j + j.transpose());
}

Eigen::MatrixXd SchurComplementBound(const Eigen::MatrixXd& fisher, int num_interest) {
  const int n = static_cast<int>(fisher.rows());
  const int t = num_interest;
  Eigen::MatrixXd s = fisher.topLeftCorner(t, t);
  if (n > t) {
    s -= fisher.topRightCorner(t, n - t) *
         PseudoInverseSpd(fisher.bottomRightCorner(n - t, n - t)) *
         fisher.bottomLeftCorner(n - t, t);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (s + s.transpose()));
  const Eigen::VectorXd& ev = es.eigenvalues();
  if (ev.size() == 0 || !(ev.minCoeff() > 1e-12 * ev.maxCoeff()) || !(ev.minCoeff() > 0.0)) {
    return Infinite(t);
  }
  return es.eigenvectors() * ev.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
}

Eigen::MatrixXd ConstrainedBound(const Eigen::MatrixXd& fisher,
                                 const Eigen::MatrixXd& constraint_jacobian, int num_interest) {
  const int n = static_cast<int>(fisher.rows());
  Eigen::MatrixXd u;  // orthonormal basis of the null space of the constraint Jacobian
  if (constraint_jacobian.rows() == 0) {
    u = Eigen::MatrixXd::Identity(n, n);
  } else {
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(constraint_jacobian.transpose());
    qr.setThreshold(1e-10);
    const int rank = static_cast<int>(qr.rank());
    Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(n, n);
    u = q.rightCols(n - rank);
  }
  Eigen::MatrixXd reduced = u.transpose() * fisher * u;
  return BoundOfLinearFunction(reduced, u.topRows(num_interest));
}

ThesisFisherSystem ThesisFisher(const std::vector<Pose>& master_poses, const Similarity& rig,
                                double eps_rad, const ThesisNoiseModel& noise) {
  const int num_poses = static_cast<int>(master_poses.size());
  const int num_params = 7 + 6 * num_poses;
  Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(12 * num_poses, num_params);
  Eigen::MatrixXd weight = Eigen::MatrixXd::Zero(12 * num_poses, 12 * num_poses);
  ThesisFisherSystem system;
  system.constraints = Eigen::MatrixXd::Zero(noise.exact_lengths ? 2 * num_poses : 0, num_params);
  for (int k = 0; k < num_poses; ++k) {
    PoseModel model(master_poses[k], rig);
    const Eigen::Matrix<double, 12, 13> local = model.Jacobian();
    Eigen::Matrix<double, 12, 12> w;
    Eigen::Matrix<double, 2, 13> radial;
    model.Noise(local, eps_rad, noise, &w, &radial);
    const int row = 12 * k;
    const int col = 7 + 6 * k;
    jac.block(row, 0, 12, 7) = local.leftCols<7>();
    jac.block(row, col, 12, 6) = local.rightCols<6>();
    weight.block(row, row, 12, 12) = w;
    if (noise.exact_lengths) {
      system.constraints.block(2 * k, 0, 2, 7) = radial.leftCols<7>();
      system.constraints.block(2 * k, col, 2, 6) = radial.rightCols<6>();
    }
  }
  system.fisher = FisherInformation(jac, weight);
  return system;
}

ThesisBound ThesisCramerRaoBound(const std::vector<Pose>& master_poses, const Similarity& rig,
                                 double eps_rad, const ThesisNoiseModel& noise) {
  ThesisBound bound;
  bound.covariance.setConstant(kInf);
  bound.rot_deg = bound.dir_deg = bound.dist_pct = bound.scale_pct = kInf;
  if (master_poses.size() < 2 || !(rig.scale > 0.0) || !(eps_rad > 0.0)) return bound;

  // Poses are independent given theta: sum the per-pose information after eliminating each
  // pose's nuisance parameters (equivalent to the Schur complement of the full system).
  Eigen::Matrix<double, 7, 7> info = Eigen::Matrix<double, 7, 7>::Zero();
  for (const Pose& master : master_poses) {
    PoseModel model(master, rig);
    const Eigen::Matrix<double, 12, 13> jac = model.Jacobian();
    Eigen::Matrix<double, 12, 12> weight;
    Eigen::Matrix<double, 2, 13> radial;
    model.Noise(jac, eps_rad, noise, &weight, &radial);
    const Eigen::Matrix<double, 13, 13> fisher = jac.transpose() * weight * jac;
    info += PoseInformation(0.5 * (fisher + fisher.transpose()),
                            noise.exact_lengths ? Eigen::MatrixXd(radial) : Eigen::MatrixXd());
  }
  const Eigen::MatrixXd cov = SchurComplementBound(info, 7);
  if (!cov.allFinite()) return bound;

  bound.finite = true;
  bound.covariance = cov;
  bound.rot_deg = std::sqrt(std::max(0.0, cov.topLeftCorner<3, 3>().trace())) * kDegPerRad;
  const double len = rig.C.norm();
  const Eigen::Matrix3d cov_c = cov.block<3, 3>(3, 3);
  if (len > 0.0) {
    const Eigen::Vector3d u = rig.C / len;
    const Eigen::Matrix3d perp = Eigen::Matrix3d::Identity() - u * u.transpose();
    bound.dir_deg = std::sqrt(std::max(0.0, (perp * cov_c * perp).trace())) / len * kDegPerRad;
    bound.dist_pct = std::sqrt(std::max(0.0, u.dot(cov_c * u))) / len * 100.0;
  }
  bound.scale_pct = std::sqrt(std::max(0.0, cov(6, 6))) / rig.scale * 100.0;
  return bound;
}

}  // namespace rigcal::research
