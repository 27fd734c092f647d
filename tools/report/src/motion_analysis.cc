// SPDX-License-Identifier: Apache-2.0
#include "motion_analysis.h"

#include <algorithm>
#include <numeric>

#include "rigcal/calib/error_model.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::report::internal {
namespace {

// The camera's poses in time order with one pose per stamp (the first of duplicates).
TimedTrajectory Trajectory(const std::string& name, const CameraPoses& in) {
  std::vector<size_t> order(in.t_ns.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return in.t_ns[a] < in.t_ns[b]; });
  TimedTrajectory out;
  out.name = name;
  for (size_t k : order) {
    if (!out.t_ns.empty() && out.t_ns.back() == in.t_ns[k]) continue;
    out.t_ns.push_back(in.t_ns[k]);
    out.poses.push_back(in.poses[k]);
    out.segment.push_back(in.segment[k]);
  }
  return out;
}

int64_t MedianStep(const std::vector<int64_t>& t) {
  if (t.size() < 2) return 0;
  std::vector<int64_t> steps;
  for (size_t k = 1; k < t.size(); ++k) steps.push_back(t[k] - t[k - 1]);
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return steps[steps.size() / 2];
}

// The final estimate of `slave` with the scale of `segment` when the result has one for it.
Similarity EstimateFor(const SlaveCalibration& slave, int segment) {
  Similarity rig = slave.estimate;
  for (const SegmentScale& s : slave.scales) {
    if (s.segment == segment) rig.scale = s.scale;
  }
  return rig;
}

}  // namespace

Expected<MotionAnalysis> AnalyseMotions(const std::map<std::string, CameraPoses>& poses,
                                        const ReportData& data, const std::string& source) {
  auto trajectory_of = [&](const std::string& name) -> Expected<TimedTrajectory> {
    const auto it = poses.find(name);
    if (it == poses.end() || it->second.t_ns.empty()) {
      return Error{source + " has no RIGCAL_POSE_" + name + " poses"};
    }
    return Trajectory(name, it->second);
  };
  auto master = trajectory_of(data.master);
  if (!master) return master.status();
  std::vector<TimedTrajectory> slaves;
  for (const std::string& name : data.slaves) {
    auto slave = trajectory_of(name);
    if (!slave) return slave.status();
    slaves.push_back(std::move(*slave));
  }
  auto recording =
      io::MatchTrajectories(*master, slaves, std::max<int64_t>(1, MedianStep(master->t_ns) / 2));
  if (!recording) return Error{source + ": " + recording.error()};

  MotionAnalysis analysis;
  analysis.source = source;
  PairOptions pair_options;
  pair_options.policy = PairOptions::Policy::kWalk;
  analysis.pairs = PairsText(pair_options);
  const std::vector<IndexPair> pairs = SelectPairs(*recording, pair_options);
  for (size_t i = 0; i < data.slaves.size(); ++i) {
    const std::string& name = data.slaves[i];
    const auto final_slave =
        std::find_if(data.final_result.slaves.begin(), data.final_result.slaves.end(),
                     [&](const SlaveCalibration& s) { return s.name == name; });
    if (final_slave == data.final_result.slaves.end()) continue;
    const std::vector<RigMotion> motions = MotionsForSlave(*recording, static_cast<int>(i), pairs);
    std::vector<Eigen::Vector3d> translations;
    for (const RigMotion& m : motions) translations.push_back(m.slave.C);
    SlaveMotions out;
    out.scale_threshold = 3.0 * ScaleDotEpsilon(0.0, translations);  // (4.23)
    out.reference_scale = final_slave->estimate.scale;
    for (const RigMotion& m : motions) {
      const ConstraintResidual r = ResidualOf(m, EstimateFor(*final_slave, m.segment));
      MotionSample sample;
      sample.t_s = 1e-9 * static_cast<double>((m.t_a_ns + m.t_b_ns) / 2 - data.t0_ns);
      sample.rotation_deg = r.rotation_deg;
      sample.position_dir_deg = r.position_dir_deg;
      sample.position_abs = r.position_abs;
      sample.master_axis_dot = r.master_axis_dot;
      sample.slave_axis_dot = r.slave_axis_dot;
      sample.measured_scale = r.measured_scale;
      sample.scale_used = std::abs(r.slave_axis_dot) > out.scale_threshold;
      out.samples.push_back(sample);
    }
    analysis.slaves.emplace(name, std::move(out));
  }
  return analysis;
}

}  // namespace rigcal::report::internal
