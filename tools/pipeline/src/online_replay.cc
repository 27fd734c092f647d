// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/online_replay.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "rigcal/base/format.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal::pipeline {
namespace {

int64_t MedianStep(const std::vector<int64_t>& t) {
  if (t.size() < 2) return 50'000'000;
  std::vector<int64_t> d;
  for (size_t k = 1; k < t.size(); ++k) d.push_back(t[k] - t[k - 1]);
  return std::max<int64_t>(UpperMedian(std::move(d)), 1);
}

}  // namespace

OnlineReplayResult ReplayOnline(const RigRecording& recording, const OnlineReplayOptions& options,
                                const std::map<std::string, Similarity>* truth) {
  std::vector<std::string> names = {recording.master.name};
  for (const auto& s : recording.slaves) names.push_back(s.name);
  SyncOptions sync_options;
  sync_options.num_cameras = static_cast<int>(names.size());
  sync_options.frame_period_ns = MedianStep(recording.t_ns);
  SyncBuffer sync(sync_options);
  RigEstimator estimator(names, options.estimator);
  OnlineReplayResult out;
  if (recording.size() == 0) return out;

  const int64_t t0 = recording.t_ns.front();
  const auto every = static_cast<int64_t>(options.report_every_s * 1e9);
  int64_t next_report = t0 + every;
  MatchedSet set;
  auto record = [&](int64_t t_ns) {
    const RigEstimate& e = estimator.Estimate();
    for (size_t i = 0; i < e.rig.slaves.size(); ++i) {
      const SlaveCalibration& s = e.rig.slaves[i];
      ConvergencePoint p;
      p.t_s = static_cast<double>(t_ns - t0) * 1e-9;
      p.slave = s.name;
      p.estimate = s.estimate;
      p.rot_std_deg = s.rot_std_deg;
      p.motions_used = s.motions.used;
      p.state = e.rig.slaves[i].state;
      p.flags = e.online[i].flags;
      if (truth && truth->count(s.name) && s.solved()) {
        p.error = CompareToTruth(s.estimate, truth->at(s.name));
      }
      out.history.push_back(p);
    }
  };
  auto drain = [&] {
    while (sync.TryPop(&set)) estimator.AddSet(set.t_ns, set.poses);
  };
  for (size_t k = 0; k < recording.size(); ++k) {
    for (int camera = 0; camera <= static_cast<int>(recording.slaves.size()); ++camera) {
      sync.Push(recording.PoseAt(camera, k));
    }
    drain();
    if (every > 0 && recording.t_ns[k] >= next_report) {
      record(recording.t_ns[k]);
      next_report += every;
    }
  }
  sync.Flush();
  drain();
  if (options.refine_at_end) {
    for (size_t i = 0; i < recording.slaves.size(); ++i) {
      const RefinementJob job = estimator.MakeRefinementJob(static_cast<int>(i), /*final=*/true);
      if (job.start.solved() && static_cast<int>(job.motions.size()) + job.prior.motions >= 10) {
        estimator.ApplyRefinement(job, RefineWindow(job));
      }
    }
  }
  record(recording.t_ns.back());
  out.estimate = estimator.Estimate();
  out.sync = sync.stats();
  return out;
}

std::string FormatConvergence(const std::vector<ConvergencePoint>& history) {
  std::ostringstream s;
  char line[256];
  std::snprintf(line, sizeof(line), "%8s  %-10s %7s %9s  %-30s %s\n", "t [s]", "slave", "motions",
                "σ rot[deg]", "state", "errors (rot deg, C, scale %)");
  s << line;
  for (const auto& p : history) {
    std::snprintf(line, sizeof(line), "%8.1f  %-10s %7d %9s  %-30s", p.t_s, p.slave.c_str(),
                  p.motions_used,
                  std::isfinite(p.rot_std_deg) ? FixedText(p.rot_std_deg, 4).c_str() : "unknown",
                  StateText(p.state, p.flags).c_str());
    s << line;
    if (p.error) {
      std::snprintf(line, sizeof(line), " %.4f  %.5f  %.3f", p.error->rot_deg, p.error->trans_err,
                    p.error->scale_pct);
      s << line;
    }
    s << "\n";
  }
  return s.str();
}

}  // namespace rigcal::pipeline
