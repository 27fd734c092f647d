// SPDX-License-Identifier: Apache-2.0
// Runs the pair-policy evaluation and formats its table (pair_evaluation.h).
#include "rigcal/research/pair_evaluation.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <mutex>
#include <sstream>
#include <thread>

#include "rigcal/base/format.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/pipeline/online_replay.h"

namespace rigcal::research {
namespace {

// Sums of squares of one policy over the draws of a scenario.
struct Sums {
  int results = 0, failed = 0;
  double rot = 0, pos = 0, scale = 0, rot_sigma = 0, pos_sigma = 0;
  int pos_count = 0, rot_sigma_count = 0, pos_sigma_count = 0;
  double rot_z = 0, pos_z = 0;  // squared errors over their σ
  int rot_z_count = 0, pos_z_count = 0;
  std::string chosen;
};

// Position error: |C - C_hat| in master units, without the directions the estimate leaves
// undetermined (the rotation axis of planar motion; every direction of the translational model).
double PositionError(const SlaveCalibration& s, const Similarity& truth, bool planar) {
  Eigen::Vector3d d = s.estimate.C - truth.C;
  if (!s.position_observable) return kNotAvailable;
  for (const auto& u : s.unobservable) d -= u.dot(d) * u;
  const Eigen::Vector3d& axis = s.observability.planar_axis;
  if (planar && axis.norm() > 0.5) d -= axis.normalized().dot(d) * axis.normalized();
  return d.norm();
}

void Accumulate(const SlaveCalibration& s, const Similarity& truth, bool planar, Sums* sums) {
  if (!s.solved()) {
    ++sums->failed;
    return;
  }
  ++sums->results;
  const CalibrationError e = CompareToTruth(s.estimate, truth);
  sums->rot += e.rot_deg * e.rot_deg;
  const double pos = PositionError(s, truth, planar);
  if (std::isfinite(pos)) {
    sums->pos += pos * pos;
    ++sums->pos_count;
  }
  sums->scale += e.scale_pct * e.scale_pct;
  if (std::isfinite(s.rot_std_deg)) {
    sums->rot_sigma += s.rot_std_deg * s.rot_std_deg;
    ++sums->rot_sigma_count;
  }
  if (s.pos_std.allFinite() && s.position_observable) {
    sums->pos_sigma += s.pos_std.squaredNorm();
    ++sums->pos_sigma_count;
  }
  // Normalised errors: the rotation angle over √3 times the largest axis σ (1 for an isotropic
  // honest σ, less otherwise), |ΔC| over |σ_C| (1 for an honest σ).
  if (std::isfinite(s.rot_std_deg) && s.rot_std_deg > 0.0) {
    sums->rot_z += std::pow(e.rot_deg / (std::sqrt(3.0) * s.rot_std_deg), 2);
    ++sums->rot_z_count;
  }
  if (std::isfinite(pos) && s.pos_std.allFinite() && s.pos_std.norm() > 0.0) {
    sums->pos_z += std::pow(pos / s.pos_std.norm(), 2);
    ++sums->pos_z_count;
  }
}

PolicyFigures Figures(const std::string& policy, int span, const Sums& s) {
  PolicyFigures f;
  f.policy = policy;
  f.span = span;
  f.results = s.results;
  f.failed = s.failed;
  f.chosen = s.chosen;
  if (s.results > 0) {
    f.rot_rms_deg = std::sqrt(s.rot / s.results);
    // No position from some result (translational model): no comparable position error.
    if (s.pos_count == s.results) f.pos_rms = std::sqrt(s.pos / s.results);
    f.scale_rms_pct = std::sqrt(s.scale / s.results);
  }
  if (s.rot_sigma_count > 0) f.rot_sigma_rms_deg = std::sqrt(s.rot_sigma / s.rot_sigma_count);
  if (s.pos_sigma_count > 0) f.pos_sigma_rms = std::sqrt(s.pos_sigma / s.pos_sigma_count);
  if (s.rot_z_count > 0) f.rot_z_rms = std::sqrt(s.rot_z / s.rot_z_count);
  if (s.pos_z_count > 0) f.pos_z_rms = std::sqrt(s.pos_z / s.pos_z_count);
  return f;
}

// The policies of one draw, in the order of PairScenarioResult::policies.
void RunDraw(const PairScenario& scenario, uint64_t seed, const PairEvaluationOptions& options,
             const std::vector<int>& spans, std::vector<Sums>* sums, std::vector<Sums>* half,
             std::mutex* mutex) {
  const RigRecording rec = NoisyRecording(scenario, seed);
  std::vector<RigCalibration> results;
  CalibrationOptions calib = options.calibration;
  calib.pairs.policy = PairOptions::Policy::kAuto;
  results.push_back(CalibrateRig(rec, calib));
  for (int span : spans) {
    calib.pairs.policy = PairOptions::Policy::kRelative;
    calib.pairs.step = span;
    results.push_back(CalibrateRig(rec, calib));
  }
  if (options.gls) {
    calib.pairs.policy = PairOptions::Policy::kGls;
    results.push_back(CalibrateRig(rec, calib));
  }
  if (options.online) {
    std::map<std::string, Similarity> truth;
    for (size_t i = 0; i < scenario.rig.size(); ++i) truth[scenario.names[i + 1]] = scenario.rig[i];
    pipeline::OnlineReplayOptions replay;
    replay.report_every_s = 0.0;
    if (options.online_history_sets >= 0) {
      replay.estimator.history_sets = options.online_history_sets;
    }
    results.push_back(pipeline::ReplayOnline(rec, replay, &truth).estimate.rig);
  }
  const std::lock_guard<std::mutex> lock(*mutex);
  for (size_t p = 0; p < results.size(); ++p) {
    for (size_t i = 0; i < results[p].slaves.size() && i < scenario.rig.size(); ++i) {
      const SlaveCalibration& s = results[p].slaves[i];
      Accumulate(s, scenario.rig[i], scenario.planar, &(*sums)[p]);
      Accumulate(s, scenario.rig[i], scenario.planar, &(*half)[p]);
      if (p == 0 && (*sums)[p].chosen.size() < 60) {
        if (!(*sums)[p].chosen.empty()) (*sums)[p].chosen += " ";
        (*sums)[p].chosen += s.pairs.empty() ? "?" : s.pairs;
      }
    }
  }
}

// The fixed span (policies 1..spans) best on one half of the draws, judged on the other; RMS
// of both ways.
double CrossValidated(const std::array<std::vector<Sums>, 2>& halves, size_t spans,
                      double PolicyFigures::*measure) {
  double sum = 0.0;
  for (int h = 0; h < 2; ++h) {
    int best = -1;
    double best_value = 0.0;
    for (size_t p = 1; p <= spans; ++p) {
      const PolicyFigures f = Figures("", 0, halves[h][p]);
      const double v = f.*measure;
      if (f.failed > 0 || !std::isfinite(v)) continue;
      if (best < 0 || v < best_value) {
        best = static_cast<int>(p);
        best_value = v;
      }
    }
    if (best < 0) return kNotAvailable;
    const double judged = Figures("", 0, halves[1 - h][best]).*measure;
    if (!std::isfinite(judged)) return kNotAvailable;
    sum += judged * judged;
  }
  return std::sqrt(sum / 2.0);
}

// A seed per scenario name (FNV-1a), so a scenario gets the same draws whichever others run.
uint64_t NameSeed(const std::string& name) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : name) h = (h ^ c) * 1099511628211ull;
  return h;
}

std::string Ratio(double value, double best) {
  if (!std::isfinite(value) || !std::isfinite(best) || best <= 0.0) return "-";
  return FixedText(value / best, 2);
}

}  // namespace

// One noisy recording of a scenario: the exact drive along its master, then each camera's
// odometry errors.
RigRecording NoisyRecording(const PairScenario& scenario, uint64_t seed) {
  DriveOptions exact;
  exact.rotation_noise_deg = 0.0;
  exact.position_noise = 0.0;
  exact.seed = seed;
  SyntheticDrive drive = GenerateDriveAlong(scenario.names, scenario.rig, scenario.master, exact);
  std::mt19937_64 rng(seed * 7919 + 17);
  RigRecording& rec = drive.recording;
  rec.master = AddPoseNoise(rec.master, scenario.noise, 1.0, rng);
  for (size_t i = 0; i < rec.slaves.size(); ++i) {
    rec.slaves[i] = AddPoseNoise(rec.slaves[i], scenario.noise, scenario.rig[i].scale, rng);
  }
  return rec;
}

const PolicyFigures* PairScenarioResult::Find(const std::string& policy) const {
  for (const auto& p : policies) {
    if (p.policy == policy) return &p;
  }
  return nullptr;
}

std::vector<PairScenarioResult> RunPairEvaluation(const std::vector<PairScenario>& scenarios,
                                                  const PairEvaluationOptions& options) {
  std::vector<const PairScenario*> chosen;
  for (const auto& s : scenarios) {
    if (options.only.empty() || s.name.find(options.only) != std::string::npos)
      chosen.push_back(&s);
  }
  std::vector<PairScenarioResult> out(chosen.size());
  std::vector<std::vector<Sums>> sums(chosen.size());
  std::vector<std::array<std::vector<Sums>, 2>> halves(chosen.size());
  std::vector<std::vector<int>> spans(chosen.size());
  for (size_t c = 0; c < chosen.size(); ++c) {
    const int n = static_cast<int>(chosen[c]->master.poses.size());
    for (int span : options.spans) {
      if (span < n / 2) spans[c].push_back(span);
    }
    sums[c].resize(1 + spans[c].size() + (options.gls ? 1 : 0) + (options.online ? 1 : 0));
    for (auto& half : halves[c]) half.resize(sums[c].size());
  }
  const int64_t total = static_cast<int64_t>(chosen.size()) * options.repeats;
  std::atomic<int64_t> next{0};
  std::atomic<int64_t> done{0};
  std::mutex mutex;
  auto worker = [&] {
    for (int64_t job = next++; job < total; job = next++) {
      const size_t c = static_cast<size_t>(job / options.repeats);
      const int draw = static_cast<int>(job % options.repeats);
      RunDraw(*chosen[c], options.seed * 1000003 + NameSeed(chosen[c]->name) + draw, options,
              spans[c], &sums[c], &halves[c][draw % 2], &mutex);
      const int64_t finished = ++done;
      if (options.progress) {
        const std::lock_guard<std::mutex> lock(mutex);
        options.progress(finished, total);
      }
    }
  };
  const int threads =
      options.threads > 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();

  for (size_t c = 0; c < chosen.size(); ++c) {
    const PairScenario& s = *chosen[c];
    PairScenarioResult& r = out[c];
    r.name = s.name;
    r.source = s.source;
    r.noise = s.noise.name;
    r.poses = static_cast<int>(s.master.poses.size());
    r.duration_s =
        r.poses > 1 ? 1e-9 * static_cast<double>(s.master.t_ns.back() - s.master.t_ns.front()) : 0;
    r.rate_hz = r.duration_s > 0 ? (r.poses - 1) / r.duration_s : 0.0;
    r.policies.push_back(Figures("auto", 0, sums[c][0]));
    for (size_t k = 0; k < spans[c].size(); ++k) {
      r.policies.push_back(
          Figures("relative:" + std::to_string(spans[c][k]), spans[c][k], sums[c][1 + k]));
    }
    if (options.gls) r.policies.push_back(Figures("gls", 0, sums[c][1 + spans[c].size()]));
    if (options.online) r.policies.push_back(Figures("online", 0, sums[c].back()));
    for (size_t p = 1; p <= spans[c].size(); ++p) {
      const PolicyFigures& f = r.policies[p];
      if (f.failed > 0 || !std::isfinite(f.rot_rms_deg)) continue;
      if (r.best_rot < 0 || f.rot_rms_deg < r.policies[r.best_rot].rot_rms_deg) {
        r.best_rot = static_cast<int>(p);
      }
      if (std::isfinite(f.pos_rms) &&
          (r.best_pos < 0 || f.pos_rms < r.policies[r.best_pos].pos_rms)) {
        r.best_pos = static_cast<int>(p);
      }
    }
    if (options.repeats >= 2) {
      r.cv_rot_rms_deg = CrossValidated(halves[c], spans[c].size(), &PolicyFigures::rot_rms_deg);
      r.cv_pos_rms = CrossValidated(halves[c], spans[c].size(), &PolicyFigures::pos_rms);
    }
  }
  return out;
}

namespace {

// How many scenarios a policy meets the requirement on: its worse ratio (rotation, position)
// to the best fixed span (or the cross-validated one) within 1.2x and 1.5x.
struct Counts {
  int within_12 = 0, within_15 = 0, scored = 0;
  int cv_12 = 0, cv_15 = 0, cv_scored = 0;
  double rot_z = 0, pos_z = 0;  // sums of squared RMS normalised errors
  int rot_z_n = 0, pos_z_n = 0;
  void Add(const PairScenarioResult& r, const PolicyFigures* f) {
    const PolicyFigures* br = r.best_rot >= 0 ? &r.policies[r.best_rot] : nullptr;
    const PolicyFigures* bp = r.best_pos >= 0 ? &r.policies[r.best_pos] : nullptr;
    if (f == nullptr) return;
    if (std::isfinite(f->rot_z_rms)) {
      rot_z += f->rot_z_rms * f->rot_z_rms;
      ++rot_z_n;
    }
    if (std::isfinite(f->pos_z_rms)) {
      pos_z += f->pos_z_rms * f->pos_z_rms;
      ++pos_z_n;
    }
    const double xr = br ? f->rot_rms_deg / br->rot_rms_deg : kNotAvailable;
    const double xp = bp ? f->pos_rms / bp->pos_rms : kNotAvailable;
    if (std::isfinite(xr)) {
      ++scored;
      const double worst = std::isfinite(xp) ? std::max(xr, xp) : xr;
      if (worst <= 1.2) ++within_12;
      if (worst <= 1.5) ++within_15;
    }
    if (std::isfinite(r.cv_rot_rms_deg)) {
      ++cv_scored;
      const double cr = f->rot_rms_deg / r.cv_rot_rms_deg;
      const double cp = std::isfinite(r.cv_pos_rms) ? f->pos_rms / r.cv_pos_rms : 0.0;
      if (std::max(cr, cp) <= 1.2) ++cv_12;
      if (std::max(cr, cp) <= 1.5) ++cv_15;
    }
  }
  std::string Text(const std::string& name) const {
    std::ostringstream s;
    s << name << " within 1.2x of the best fixed span (rotation and position): " << within_12 << "/"
      << scored << "; within 1.5x: " << within_15 << "/" << scored << "\n";
    if (cv_scored > 0) {
      s << name
        << " within 1.2x of the cross-validated best fixed span (best on half the draws, judged "
           "on the other half): "
        << cv_12 << "/" << cv_scored << "; within 1.5x: " << cv_15 << "/" << cv_scored << "\n";
    }
    return s.str() + ZText(name);
  }
  std::string ZText(const std::string& name) const {
    std::ostringstream s;
    s << name << " normalised errors, RMS over scenarios: rotation angle/(sqrt(3) sigma_max) "
      << (rot_z_n > 0 ? FixedText(std::sqrt(rot_z / rot_z_n), 2) : "-") << ", |dC|/|sigma_C| "
      << (pos_z_n > 0 ? FixedText(std::sqrt(pos_z / pos_z_n), 2) : "-") << " (1 = honest)\n";
    return s.str();
  }
};

std::string Z(const PolicyFigures* f) {
  if (f == nullptr) return "-";
  return (std::isfinite(f->rot_z_rms) ? FixedText(f->rot_z_rms, 1) : std::string("-")) + "/" +
         (std::isfinite(f->pos_z_rms) ? FixedText(f->pos_z_rms, 1) : std::string("-"));
}

}  // namespace

std::string FormatPairTable(const std::vector<PairScenarioResult>& results) {
  std::ostringstream s;
  char line[640];
  std::snprintf(line, sizeof(line),
                "%-28s %5s %4s | %-12s %-12s | %5s %5s %5s %5s | %5s %5s %5s %5s | %-7s %-7s | "
                "%-5s %-5s %-5s | %s\n",
                "scenario", "poses", "Hz", "best rot", "best pos", "auto", "auto", "auto", "auto",
                "gls", "gls", "gls", "gls", "z auto", "z gls", "onl/b", "onl/b", "onl/b",
                "auto pairs (per slave, draw)");
  s << line;
  std::snprintf(line, sizeof(line),
                "%-28s %5s %4s | %-12s %-12s | %5s %5s %5s %5s | %5s %5s %5s %5s | %-7s %-7s | "
                "%-5s %-5s %-5s |\n",
                "", "", "", "span RMSdeg", "span RMS", "x rot", "x pos", "cv r", "cv p", "x rot",
                "x pos", "cv r", "cv p", "rot/pos", "rot/pos", "rot", "pos", "scale");
  s << line;
  Counts auto_counts, gls_counts, online_counts;
  int online_13 = 0, online_scored = 0;
  for (const auto& r : results) {
    const PolicyFigures* a = r.Find("auto");
    const PolicyFigures* g = r.Find("gls");
    const PolicyFigures* o = r.Find("online");
    const PolicyFigures* d = g != nullptr ? g : a;  // the default batch solve (gls)
    const PolicyFigures* br = r.best_rot >= 0 ? &r.policies[r.best_rot] : nullptr;
    const PolicyFigures* bp = r.best_pos >= 0 ? &r.policies[r.best_pos] : nullptr;
    auto best = [](const PolicyFigures* f, double v) {
      return f ? std::to_string(f->span) + " " + SignificantText(v, 2) : std::string("-");
    };
    auto x = [&](const PolicyFigures* f, double PolicyFigures::*m, const PolicyFigures* b) {
      return Ratio(f ? f->*m : kNotAvailable, b ? b->*m : kNotAvailable);
    };
    std::snprintf(
        line, sizeof(line),
        "%-28s %5d %4.0f | %-12s %-12s | %5s %5s %5s %5s | %5s %5s %5s %5s | %-7s %-7s | %-5s "
        "%-5s %-5s | %s%s\n",
        r.name.c_str(), r.poses, r.rate_hz, best(br, br ? br->rot_rms_deg : 0).c_str(),
        best(bp, bp ? bp->pos_rms : 0).c_str(), x(a, &PolicyFigures::rot_rms_deg, br).c_str(),
        x(a, &PolicyFigures::pos_rms, bp).c_str(),
        Ratio(a ? a->rot_rms_deg : kNotAvailable, r.cv_rot_rms_deg).c_str(),
        Ratio(a ? a->pos_rms : kNotAvailable, r.cv_pos_rms).c_str(),
        x(g, &PolicyFigures::rot_rms_deg, br).c_str(), x(g, &PolicyFigures::pos_rms, bp).c_str(),
        Ratio(g ? g->rot_rms_deg : kNotAvailable, r.cv_rot_rms_deg).c_str(),
        Ratio(g ? g->pos_rms : kNotAvailable, r.cv_pos_rms).c_str(), Z(a).c_str(), Z(g).c_str(),
        o && d ? Ratio(o->rot_rms_deg, d->rot_rms_deg).c_str() : "-",
        o && d ? Ratio(o->pos_rms, d->pos_rms).c_str() : "-",
        o && d ? Ratio(o->scale_rms_pct, d->scale_rms_pct).c_str() : "-",
        a && a->failed > 0 ? ("FAILED " + std::to_string(a->failed) + " ").c_str() : "",
        a ? a->chosen.c_str() : "");
    s << line;
    auto_counts.Add(r, a);
    gls_counts.Add(r, g);
    online_counts.Add(r, o);
    if (o && d && std::isfinite(o->rot_rms_deg)) {
      ++online_scored;
      const double worst = std::max({o->rot_rms_deg / d->rot_rms_deg,
                                     std::isfinite(o->pos_rms) ? o->pos_rms / d->pos_rms : 0.0,
                                     o->scale_rms_pct / d->scale_rms_pct});
      if (worst <= 1.3) ++online_13;
    }
  }
  s << "\n" << auto_counts.Text("auto");
  if (gls_counts.scored > 0) s << gls_counts.Text("gls (the default)");
  if (online_scored > 0) {
    s << "online within 1.3x of the batch " << (gls_counts.scored > 0 ? "gls" : "auto")
      << " (rotation, position, scale): " << online_13 << "/" << online_scored << "\n";
    s << online_counts.ZText("online");
  }
  return s.str();
}

std::string PairCsv(const std::vector<PairScenarioResult>& results) {
  std::ostringstream s;
  s << "scenario,noise,poses,rate_hz,policy,span,results,failed,rot_rms_deg,pos_rms,scale_rms_pct,"
       "rot_sigma_rms_deg,pos_sigma_rms\n";
  for (const auto& r : results) {
    for (const auto& p : r.policies) {
      s << r.name << "," << r.noise << "," << r.poses << "," << ShortestText(r.rate_hz) << ","
        << p.policy << "," << p.span << "," << p.results << "," << p.failed << ","
        << ShortestText(p.rot_rms_deg) << "," << ShortestText(p.pos_rms) << ","
        << ShortestText(p.scale_rms_pct) << "," << ShortestText(p.rot_sigma_rms_deg) << ","
        << ShortestText(p.pos_sigma_rms) << "\n";
    }
  }
  return s.str();
}

}  // namespace rigcal::research
