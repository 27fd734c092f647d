// SPDX-License-Identifier: Apache-2.0
#include "rigcal/io/truth_alignment.h"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <cmath>

namespace rigcal::io {
namespace {

// One slave's contribution: its true and estimated C, both restricted to the estimated
// components (the plane of a planar slave without a nominal mounting), and the σ per master
// axis of the estimate.
struct Sample {
  std::string name;
  Eigen::Vector3d truth;
  Eigen::Vector3d estimate;
  Eigen::Vector3d std;
  int dims = 3;  // scalar components the vectors carry
};

std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> Pairs(const std::vector<Sample>& samples,
                                                               size_t skip) {
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs;
  for (size_t i = 0; i < samples.size(); ++i) {
    if (i != skip) pairs.emplace_back(samples[i].truth, samples[i].estimate);
  }
  return pairs;
}

std::string Names(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

}  // namespace

UnitFit FitUnit(const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& metric_and_unit) {
  UnitFit fit;
  double num = 0.0;
  double den = 0.0;
  for (const auto& [metric, unit] : metric_and_unit) {
    num += metric.dot(unit);
    den += unit.squaredNorm();
  }
  fit.count = static_cast<int>(metric_and_unit.size());
  fit.metres_per_unit = den > 0.0 ? num / den : 0.0;
  if (fit.count == 0) return fit;
  double sum_sq = 0.0;
  for (const auto& [metric, unit] : metric_and_unit) {
    sum_sq += (metric - fit.metres_per_unit * unit).squaredNorm();
  }
  fit.fit_rms_m = std::sqrt(sum_sq / static_cast<double>(fit.count));
  return fit;
}

const char* ToString(TruthUnit unit) {
  switch (unit) {
    case TruthUnit::kAuto:
      return "auto";
    case TruthUnit::kMetric:
      return "metric";
    case TruthUnit::kMaster:
      return "master";
  }
  return "auto";
}

bool ParseTruthUnit(const std::string& text, TruthUnit* unit) {
  for (const TruthUnit u : {TruthUnit::kAuto, TruthUnit::kMetric, TruthUnit::kMaster}) {
    if (text == ToString(u)) {
      *unit = u;
      return true;
    }
  }
  return false;
}

namespace {

// Per usable slave with a true mounting: its true and estimated C on the directions the data
// determined (C along an unobservable direction is 0 or the nominal's).
std::vector<Sample> ObservableSamples(const RigCalibration& result,
                                      const std::map<std::string, Similarity>& truth) {
  std::vector<Sample> samples;
  for (const SlaveCalibration& s : result.slaves) {
    const auto it = truth.find(s.name);
    if (it == truth.end() || !s.usable() || !s.position_observable) continue;
    Eigen::Matrix3d keep = Eigen::Matrix3d::Identity();
    for (const Eigen::Vector3d& d : s.unobservable) {
      const Eigen::Vector3d u = d.normalized();
      keep -= u * u.transpose();
    }
    Sample sample;
    sample.name = s.name;
    sample.truth = keep * it->second.C;
    sample.estimate = keep * s.estimate.C;
    sample.std = s.pos_std;
    sample.dims = 3 - static_cast<int>(std::min<size_t>(s.unobservable.size(), 3));
    if (sample.dims > 0 && sample.estimate.squaredNorm() > 0.0) samples.push_back(sample);
  }
  return samples;
}

// Robust to one slave: with 3 or more, the index of the slave whose C disagrees most with the
// unit the others give, when it disagrees by far more than the others scatter; else size().
size_t OutlyingSample(const std::vector<Sample>& samples) {
  size_t excluded = samples.size();
  if (samples.size() < 3) return excluded;
  double worst_ratio = 0.0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const UnitFit others = FitUnit(Pairs(samples, i));
    const double off = (samples[i].truth - others.metres_per_unit * samples[i].estimate).norm();
    const double ratio = off / std::max(others.fit_rms_m, 1e-300);
    if (off > 5.0 * others.fit_rms_m && off > 0.01 * samples[i].truth.norm() &&
        ratio > worst_ratio) {
      worst_ratio = ratio;
      excluded = i;
    }
  }
  return excluded;
}

// Fits the unit on `used` into `a` (metres_per_unit, fit_rms_m, std); returns "<k>\t(± <σ>,
// how)", the tab where the unit ("m") goes.
std::string FitUnitInto(const std::vector<Sample>& used, TruthAlignment* a) {
  const UnitFit fit = FitUnit(Pairs(used, used.size()));
  const double k = fit.metres_per_unit;
  a->metres_per_unit = k;
  a->fit_rms_m = fit.fit_rms_m;
  // σ of k = Σ t·v / Σ v·v: the estimate's position σ propagated (dk ≈ -k Σ v·dv / Σ v·v),
  // and the scatter of the fit (residual variance over the components minus one).
  double den = 0.0;
  double var_num = 0.0;
  int components = 0;
  for (const Sample& s : used) {
    den += s.estimate.squaredNorm();
    var_num += s.estimate.cwiseProduct(s.std).squaredNorm();
    components += s.dims;
  }
  const double propagated = std::abs(k) * std::sqrt(var_num) / den;
  const double scatter =
      components > 1 ? std::sqrt(fit.fit_rms_m * fit.fit_rms_m * static_cast<double>(used.size()) /
                                 static_cast<double>(components - 1) / den)
                     : std::numeric_limits<double>::quiet_NaN();
  a->std = std::isfinite(propagated) ? std::max(propagated, std::isfinite(scatter) ? scatter : 0.0)
                                     : scatter;
  return fmt::format(
      "{:.6g}\t(± {:.2g}, least squares of the truth's C on the estimated C of {}{})", k, a->std,
      Names(a->slaves_used),
      a->slave_excluded.empty()
          ? ""
          : "; " + a->slave_excluded + " left out: its C disagrees with the others' unit");
}

// What was done with the fitted unit, and whether it is applied.
void DecideAlignment(const std::string& fitted, size_t slaves_used, TruthAlignment* a) {
  auto fitted_with = [&fitted](const std::string& unit) {
    std::string text = fitted;
    return text.replace(text.find('\t'), 1, unit + " ");
  };
  const double k = a->metres_per_unit;
  if (a->mode == TruthUnit::kMaster) {
    a->message =
        "the truth is taken to be in master units (--truth-unit master); truth C / "
        "estimated C: " +
        fitted_with("");
    return;
  }
  if (!(k > 0.0)) {
    a->message =
        "the truth is compared as given: the estimated C do not point where the truth's "
        "do (fitted unit not positive)";
    return;
  }
  if (a->mode == TruthUnit::kAuto) {
    const double tolerance = std::max(std::isfinite(a->std) ? 3.0 * a->std : 0.0, 0.02);
    if (std::abs(k - 1.0) <= tolerance) {
      a->message = fmt::format(
          "the truth is in master units (no alignment): truth C / estimated C = {}, 1 within "
          "{:.2g}",
          fitted_with(""), tolerance);
      return;
    }
  }
  a->applied = true;
  a->message = "positions compared after aligning the master unit to the truth: 1 master unit = " +
               fitted_with(" m") + "; the truth's C divided by it";
  if (slaves_used == 1) {
    a->message +=
        " (one slave: the fit absorbs its distance error; its direction, rotation and "
        "scale errors remain)";
  }
}

}  // namespace

TruthAlignment AlignTruthUnit(const RigCalibration& result,
                              const std::map<std::string, Similarity>& truth, TruthUnit mode) {
  TruthAlignment a;
  a.mode = mode;
  const std::vector<Sample> samples = ObservableSamples(result, truth);
  const size_t excluded = OutlyingSample(samples);
  std::vector<Sample> used;
  for (size_t i = 0; i < samples.size(); ++i) {
    if (i == excluded) {
      a.slave_excluded = samples[i].name;
    } else {
      used.push_back(samples[i]);
      a.slaves_used.push_back(samples[i].name);
    }
  }
  if (used.empty()) {
    a.message =
        "the truth is compared as given: no usable slave has an estimated position to fit the "
        "master unit to";
    return a;
  }
  const std::string fitted = FitUnitInto(used, &a);
  DecideAlignment(fitted, used.size(), &a);
  return a;
}

std::map<std::string, Similarity> TruthInMasterUnits(const std::map<std::string, Similarity>& truth,
                                                     const TruthAlignment& alignment) {
  if (!alignment.applied) return truth;
  std::map<std::string, Similarity> out = truth;
  for (auto& [name, rig] : out) {
    rig.C /= alignment.metres_per_unit;
    rig.scale = std::numeric_limits<double>::quiet_NaN();  // the slave's unit is unknown
  }
  return out;
}

}  // namespace rigcal::io
