// SPDX-License-Identifier: Apache-2.0
// Monte Carlo Gram matrix of the whitened regressor noise of C (regressor_noise.h).
#include "noise/regressor_noise.h"

#include <cmath>
#include <random>

namespace rigcal::internal {
namespace {

// A draw of n increments of a level y_t = x_t + a_t + w_t (noise_whitening.h): x a random walk,
// a a stationary AR(1), w white.
Eigen::VectorXd SampleIncrements(const LevelNoise& noise, Eigen::Index n, std::mt19937_64& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  const double white = std::sqrt(std::max(0.0, noise.white));
  const double walk = std::sqrt(std::max(0.0, noise.walk));
  const double stationary = std::sqrt(std::max(0.0, noise.correlated));
  const double innovation =
      std::sqrt(std::max(0.0, noise.correlated * (1.0 - noise.phi * noise.phi)));
  double x = 0.0;
  double a = stationary * gauss(rng);
  double y = a + white * gauss(rng);
  Eigen::VectorXd out(n);
  for (Eigen::Index t = 0; t < n; ++t) {
    x += walk * gauss(rng);
    a = noise.phi * a + innovation * gauss(rng);
    const double next = x + a + white * gauss(rng);
    out(t) = next - y;
    y = next;
  }
  return out;
}

}  // namespace

std::vector<Eigen::Matrix3d> RegressorNoiseGram(const RegressorNoiseInput& input) {
  std::vector<Eigen::Matrix3d> gram(input.lever.size(), Eigen::Matrix3d::Zero());
  if (input.samples <= 0) return gram;
  std::mt19937_64 rng(input.seed);
  const int samples = input.samples;
  for (size_t r = 0; r + 1 < input.run_start.size(); ++r) {
    const int first = input.run_start[r];
    const int count = input.run_start[r + 1] - first;
    if (count <= 0) continue;
    // Per position component, the regressor's change -[δ_k]× G_k T of every draw side by side
    // (columns 3s..3s+2 for draw s): the filter's gains do not depend on the data, so one pass
    // whitens every column.
    Eigen::MatrixXd change[3] = {Eigen::MatrixXd(count, 3 * samples),
                                 Eigen::MatrixXd(count, 3 * samples),
                                 Eigen::MatrixXd(count, 3 * samples)};
    for (int s = 0; s < samples; ++s) {
      Eigen::MatrixXd delta(count, 3);
      for (int j = 0; j < 3; ++j) delta.col(j) = SampleIncrements(input.rotation[j], count, rng);
      for (int k = 0; k < count; ++k) {
        const Eigen::Vector3d turn = delta.row(k).transpose();
        Eigen::Matrix3d d;
        for (int j = 0; j < 3; ++j) d.col(j) = -turn.cross(input.lever[first + k].col(j));
        for (int c = 0; c < 3; ++c) change[c].block<1, 3>(k, 3 * s) = d.row(c);
      }
    }
    Eigen::MatrixXd white[3];
    for (int c = 0; c < 3; ++c) white[c] = WhitenIncrements(change[c], input.position[c]);
    for (int s = 0; s < samples; ++s) {
      for (int c = 0; c < 3; ++c) {
        for (int k = 0; k < count; ++k) {
          const Eigen::RowVector3d row = white[c].block<1, 3>(k, 3 * s);
          gram[first + k] += row.transpose() * row / samples;
        }
      }
    }
  }
  return gram;
}

}  // namespace rigcal::internal
