// SPDX-License-Identifier: Apache-2.0
// Kalman whitening and maximum-likelihood fit of the level noise (noise_whitening.h).
#include "rigcal/calib/noise_whitening.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>

namespace rigcal {
namespace {

constexpr double kFloor = 1e-8;  // least variance of a part, in the increments' variance
constexpr double kMaxPhi = 0.999;

// The filter of one run: the state (x, a) of every column with the covariance P shared by all
// columns (the gains do not depend on the data). After the level y_0 = 0 with a diffuse x_0:
// x = y_0 - a - w, so P_xx = P_a + white, P_xa = -P_a, P_aa = P_a.
struct Filter {
  explicit Filter(const LevelNoise& n)
      : noise(n),
        pxx(n.correlated + n.white),
        pxa(-n.correlated),
        paa(n.correlated),
        innovation_ar(n.correlated * (1.0 - n.phi * n.phi)) {}
  // Predicts one step and returns the innovation variance F and the gains (kx, ka); updates P.
  double Step(double* kx, double* ka) {
    pxx += noise.walk;
    pxa *= noise.phi;
    paa = noise.phi * noise.phi * paa + innovation_ar;
    const double f = pxx + 2.0 * pxa + paa + noise.white;
    *kx = (pxx + pxa) / f;
    *ka = (pxa + paa) / f;
    const double nxx = pxx - *kx * *kx * f;
    const double nxa = pxa - *kx * *ka * f;
    const double naa = paa - *ka * *ka * f;
    pxx = nxx;
    pxa = nxa;
    paa = naa;
    return f;
  }
  LevelNoise noise;
  double pxx, pxa, paa, innovation_ar;
};

double RunLogLikelihood(const Eigen::VectorXd& d, const LevelNoise& noise) {
  Filter filter(noise);
  double y = 0.0, x = 0.0, a = 0.0, ll = 0.0;
  double last_f = -1.0, log_f = 0.0;  // the filter reaches its steady state: log once
  for (Eigen::Index t = 0; t < d.size(); ++t) {
    y += d(t);
    a *= noise.phi;
    double kx = 0.0, ka = 0.0;
    const double f = filter.Step(&kx, &ka);
    const double v = y - x - a;
    x += kx * v;
    a += ka * v;
    if (std::abs(f - last_f) > 1e-13 * f) {
      log_f = std::log(2.0 * M_PI * f);
      last_f = f;
    }
    ll -= 0.5 * (log_f + v * v / f);
  }
  return ll;
}

using Point = Eigen::Vector4d;

LevelNoise FromPoint(const Point& u, double scale) {
  LevelNoise n;
  n.white = scale * (kFloor + std::exp(u(0)));
  n.correlated = scale * (kFloor + std::exp(u(1)));
  n.phi = kMaxPhi * std::tanh(u(2));
  n.walk = scale * (kFloor + std::exp(u(3)));
  return n;
}

Point ToPoint(double white, double correlated, double phi, double walk) {
  return {std::log(white), std::log(correlated), std::atanh(phi / kMaxPhi), std::log(walk)};
}

// Minimises f by Nelder-Mead from `start` (steps of 1 in every coordinate).
Point NelderMead(const std::function<double(const Point&)>& f, const Point& start,
                 int max_evaluations) {
  std::array<Point, 5> x;
  std::array<double, 5> fx;
  x[0] = start;
  for (int i = 0; i < 4; ++i) {
    x[i + 1] = start;
    x[i + 1](i) += 1.0;
  }
  for (int i = 0; i < 5; ++i) fx[i] = f(x[i]);
  int evaluations = 5;
  while (evaluations < max_evaluations) {
    std::array<int, 5> order = {0, 1, 2, 3, 4};
    std::sort(order.begin(), order.end(), [&](int a, int b) { return fx[a] < fx[b]; });
    const int best = order[0], worst = order[4], second = order[3];
    if (std::abs(fx[worst] - fx[best]) < 1e-9 * (1.0 + std::abs(fx[best]))) break;
    Point centroid = Point::Zero();
    for (int i = 0; i < 4; ++i) centroid += x[order[i]] / 4.0;
    const Point reflected = centroid + (centroid - x[worst]);
    const double fr = f(reflected);
    ++evaluations;
    if (fr < fx[best]) {
      const Point expanded = centroid + 2.0 * (centroid - x[worst]);
      const double fe = f(expanded);
      ++evaluations;
      if (fe < fr) {
        x[worst] = expanded;
        fx[worst] = fe;
      } else {
        x[worst] = reflected;
        fx[worst] = fr;
      }
    } else if (fr < fx[second]) {
      x[worst] = reflected;
      fx[worst] = fr;
    } else {
      const Point contracted = centroid + 0.5 * (x[worst] - centroid);
      const double fc = f(contracted);
      ++evaluations;
      if (fc < fx[worst]) {
        x[worst] = contracted;
        fx[worst] = fc;
      } else {
        for (int i = 1; i < 5; ++i) {
          x[order[i]] = x[best] + 0.5 * (x[order[i]] - x[best]);
          fx[order[i]] = f(x[order[i]]);
        }
        evaluations += 4;
      }
    }
  }
  int best = 0;
  for (int i = 1; i < 5; ++i) {
    if (fx[i] < fx[best]) best = i;
  }
  return x[best];
}

}  // namespace

Eigen::MatrixXd WhitenIncrements(const Eigen::MatrixXd& increments, const LevelNoise& noise) {
  const Eigen::Index n = increments.rows(), m = increments.cols();
  Eigen::MatrixXd out(n, m);
  Filter filter(noise);
  Eigen::RowVectorXd y = Eigen::RowVectorXd::Zero(m);
  Eigen::RowVectorXd x = y, a = y;
  for (Eigen::Index t = 0; t < n; ++t) {
    y += increments.row(t);
    a *= noise.phi;
    double kx = 0.0, ka = 0.0;
    const double f = filter.Step(&kx, &ka);
    const Eigen::RowVectorXd v = y - x - a;
    x += kx * v;
    a += ka * v;
    out.row(t) = v / std::sqrt(f);
  }
  return out;
}

double IncrementLogLikelihood(const std::vector<Eigen::VectorXd>& runs, const LevelNoise& noise) {
  double ll = 0.0;
  for (const auto& run : runs) ll += RunLogLikelihood(run, noise);
  return ll;
}

LevelNoise FitLevelNoise(const std::vector<Eigen::VectorXd>& runs,
                         const std::atomic<bool>* cancel) {
  // Variance and lag-1 autocovariance of the increments, for the scale and the first start.
  double s0 = 0.0, s1 = 0.0;
  long n0 = 0, n1 = 0;
  for (const auto& run : runs) {
    for (Eigen::Index t = 0; t < run.size(); ++t) {
      s0 += run(t) * run(t);
      ++n0;
      if (t > 0) {
        s1 += run(t) * run(t - 1);
        ++n1;
      }
    }
  }
  LevelNoise none;
  if (n0 == 0 || !(s0 > 0.0) || !std::isfinite(s0)) {
    none.white = std::max(s0 / std::max<long>(n0, 1), std::numeric_limits<double>::min());
    return none;
  }
  const double scale = s0 / n0;
  const double lag1 = n1 > 0 ? s1 / n1 / scale : 0.0;  // -1/2 for white levels, 0 for a walk
  const double white = std::clamp(-lag1, 0.02, 0.5);
  auto cancelled = [&] { return cancel != nullptr && cancel->load(std::memory_order_relaxed); };
  auto cost = [&](const Point& u) {
    // Cancelled: every evaluation costs nothing and the simplex stops moving.
    if (cancelled()) return 0.0;
    const double ll = IncrementLogLikelihood(runs, FromPoint(u, scale));
    return std::isfinite(ll) ? -ll : std::numeric_limits<double>::max();
  };
  const std::array<Point, 4> starts = {
      ToPoint(white, 0.05, 0.5, std::max(1.0 - 2.0 * white, 0.02)),  // by the moments
      ToPoint(0.5, 0.01, 0.9, 1e-4),                                 // white levels
      ToPoint(1e-3, 1e-3, 0.5, 1.0),                                 // a random walk
      ToPoint(0.05, 1.0, 0.95, 1e-3),                                // correlated levels
  };
  Point best = starts[0];
  double best_cost = std::numeric_limits<double>::infinity();
  for (const Point& start : starts) {
    if (cancelled()) break;
    const Point p = NelderMead(cost, start, 400);
    const double c = cost(p);
    if (c < best_cost) {
      best_cost = c;
      best = p;
    }
  }
  best = NelderMead(cost, best, 400);  // a restart from the best escapes a collapsed simplex
  return FromPoint(best, scale);
}

}  // namespace rigcal
